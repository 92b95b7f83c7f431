//! How diagnose works: its settings and their defaults.

/// Most simulated logs per band a front end lets a diagnosis ask for: the band's own error falls
/// as 1/sqrt(seeds), so beyond a few thousand logs it is negligible and the run only takes longer
/// (each log is as long as the measured one).
pub const MAX_SEEDS: usize = 4096;
/// Most add-and-resimulate rounds a front end lets a diagnosis ask for.
pub const MAX_ROUNDS: usize = 100;

/// Settings of the workflow. Errors about a setting name its field (e.g. `tau_min_s`); a front end
/// maps the field to its own option name when it reports them.
#[derive(Clone, Debug)]
pub struct Settings {
    /// Master seed of the simulated logs (written into the report).
    pub seed: u64,
    /// Simulated logs per band.
    pub seeds: usize,
    /// Add-and-resimulate rounds at most.
    pub max_rounds: usize,
    /// Drift horizons, seconds (docs/cli.md: 60 s and 1 h).
    pub horizons_s: Vec<f64>,
    /// An effect is named only if it lowers BIC by at least this much. Above 10 is "very strong"
    /// evidence on the Kass & Raftery (1995) scale; 16 sets the false-alarm rate: for one parameter and
    /// M ~ 15 taus it needs delta chi2 >= 18.7, a chi2_1 tail of 1.5e-5 if nothing is missing, so about
    /// 1e-3 per 6-channel log over the ~8 candidates per channel (measured on clean logs: see the
    /// hidden-effect tests; the tails of ln adev at small EDF are heavier than Gaussian).
    pub min_delta_bic: f64,
    /// Candidates whose BIC is within this of the best are reported as indistinguishable from it
    /// (below 6 the evidence for the best is not "strong", Kass & Raftery 1995).
    pub ambiguity_delta_bic: f64,
    /// Effects a channel may take in one round before the model is re-simulated.
    pub effects_per_round: usize,
    /// Taus below this are left out (e.g. where a sensor's internal anti-alias filter shapes the curve,
    /// an effect outside the candidate set), s.
    pub tau_min_s: f64,
    /// The drift protocol of the drift check in the loop (docs/diagnose.md, "Drift in the loop"),
    /// or None (no drift check).
    pub drift_protocol: Option<crate::protocol::Protocol>,
    /// The latitude of the round, rotating Earth the logs are dead-reckoned on (the drift step
    /// and the simulated logs; a drift protocol carries the same), deg; `None`: Woodman's flat
    /// Earth.
    pub latitude_deg: Option<f64>,
}

impl Default for Settings {
    fn default() -> Self {
        Settings {
            seed: 1,
            seeds: 16,
            max_rounds: 6,
            horizons_s: vec![60.0, 3600.0],
            min_delta_bic: 16.0,
            ambiguity_delta_bic: 6.0,
            effects_per_round: 3,
            tau_min_s: 0.0,
            drift_protocol: None,
            latitude_deg: Some(crate::protocol::DEFAULT_LATITUDE_DEG),
        }
    }
}
