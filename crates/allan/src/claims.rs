//! The family-wise level at which fitted terms are claimed (used by [`crate::null`]).

use serde::{Deserialize, Serialize};

/// The family-wise level of the resolved-term claims.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct ClaimLevel {
    /// Probability that any claim of the family is false under the null model (default 1 %).
    pub rate: f64,
    /// Number of claims in the family (default 30: 5 terms x 6 channels).
    pub family: usize,
    /// Null logs simulated where the shipped table does not cover the analysis (default 200;
    /// 0: no term is resolved).
    pub replicates: usize,
    /// Read the thresholds from the shipped table where it covers the analysis (default true;
    /// false: always simulate, as the table's own checks do).
    pub table: bool,
}

impl Default for ClaimLevel {
    fn default() -> Self {
        ClaimLevel {
            rate: 0.01,
            family: 30,
            replicates: 200,
            table: true,
        }
    }
}
