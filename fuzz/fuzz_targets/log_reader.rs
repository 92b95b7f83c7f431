//! The CSV log reader (`logio::parse_log`, crates/logio) on arbitrary bytes, with and without a rate.
#![no_main]
use logio::{parse_log, ReadOptions};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let _ = parse_log(data, "fuzz.csv", &ReadOptions::default());
    let opts = ReadOptions {
        rate_hz: Some(100.0),
        ..ReadOptions::default()
    };
    let _ = parse_log(data, "fuzz.csv", &opts);
});
