//! The modules of the `imudrift` command (see `main.rs`), compiled as a library too. Not a
//! stable API: the stable interfaces are the command line and its JSON. (The log reader, which
//! the fuzz targets and the property tests exercise, is its own crate, `crates/logio`.)

/// `eprintln!` that never panics: standard error closed (`2>&-`), full (`2>/dev/full`) or a pipe
/// whose reader has gone (`2>&1 | head -1`) loses the line, never the command's result (which
/// goes to stdout, where a failed write is an error the command reports with status 1).
#[macro_export]
macro_rules! tell {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        let _ = writeln!(std::io::stderr().lock(), $($arg)*);
    }};
}

pub mod cli;
pub mod cmd_allan;
pub mod cmd_diagnose;
pub mod cmd_drift;
pub mod cmd_generate;
pub mod cmd_merge;
pub mod cmd_plan;
pub mod cmd_simulate;
pub mod cmd_spec;
pub mod effect_text;
pub mod experiment_run;
pub mod files;
pub mod fmt;
pub mod log_input;
pub mod model_notes;
pub mod noise_out;
pub mod output;
pub mod plausibility;
pub mod plot;
pub mod progress;
pub mod spec_plot;
