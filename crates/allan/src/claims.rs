//! The family-wise level at which fitted terms are claimed (used by [`crate::null`]).

use serde::{Deserialize, Serialize};

/// The family-wise level of the resolved-term claims.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct ClaimLevel {
    /// Probability that any claim of the family is false under the null model (default 1 %).
    pub rate: f64,
    /// Number of claims in the family (default 30: 5 terms x 6 channels).
    pub family: usize,
    /// Null logs simulated (default 200; 0: no simulation, no term is resolved).
    pub replicates: usize,
}

impl Default for ClaimLevel {
    fn default() -> Self {
        ClaimLevel {
            rate: 0.01,
            family: 30,
            replicates: 200,
        }
    }
}
