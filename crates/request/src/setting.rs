//! The settings a request has, named in messages by each front end in its own words.

/// A setting of a request, as a message names it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Setting {
    /// Monte Carlo runs (`--runs`, `runs`).
    Runs,
    /// Master seed.
    Seed,
    /// Length of a run or log, s.
    Duration,
    /// Sample rate, Hz.
    Rate,
    /// Worker threads.
    Threads,
    /// Terms kept.
    Only,
    /// Terms switched off.
    Without,
    /// A shard of the runs (the CLI's `--shard i/k`, Python's `simulate_shard`).
    Shard,
    /// Merging shards (the CLI's `imudrift merge`, Python's `merge`).
    Merge,
    /// The generated log's output (the CLI's `-o FILE`; Python returns a DataFrame).
    Output,
    /// The column mapping of a log (`--col`, `columns`).
    Columns,
    /// The channels to analyse (`--channels`, `channels`).
    Channels,
    /// Simulated logs per band.
    Seeds,
    /// Add-and-resimulate rounds.
    Rounds,
    /// BIC improvement an effect needs.
    MinDeltaBic,
    /// Shortest tau used.
    TauMin,
    /// Drift horizons.
    Horizons,
    /// Where the logs were recorded.
    Latitude,
    /// Simulated experiments of a drift band.
    Replicates,
    /// A confidence level.
    Confidence,
    /// Samples given as an array.
    Data,
    /// The averaging times of an Allan analysis (the CLI's `--grid` of factors, Python's
    /// `taus` in seconds).
    Taus,
}

impl Setting {
    /// The library's own name of a setting (a request's field), for a front end with no names of
    /// its own.
    pub fn name(self) -> &'static str {
        match self {
            Setting::Runs => "runs",
            Setting::Seed => "seed",
            Setting::Duration => "duration_s",
            Setting::Rate => "rate_hz",
            Setting::Threads => "threads",
            Setting::Only => "only",
            Setting::Without => "without",
            Setting::Shard => "shard",
            Setting::Merge => "merge",
            Setting::Output => "output",
            Setting::Columns => "columns",
            Setting::Channels => "channels",
            Setting::Seeds => "seeds",
            Setting::Rounds => "rounds",
            Setting::MinDeltaBic => "min_delta_bic",
            Setting::TauMin => "tau_min",
            Setting::Horizons => "horizons",
            Setting::Latitude => "latitude",
            Setting::Replicates => "replicates",
            Setting::Confidence => "confidence",
            Setting::Data => "data",
            Setting::Taus => "taus",
        }
    }
}

/// How a message names a setting: [`Setting::name`], or a front end's own words.
pub type Names<'a> = &'a dyn Fn(Setting) -> &'static str;
