//! The sensor and scenario TOML loaders on arbitrary text (bytes that are not UTF-8 go through the
//! same UTF-8 check the command uses).
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(text) = noise::utf8_text(data.to_vec(), "fuzz.toml") {
        let _ = noise::SensorModel::from_toml_str(&text, "fuzz.toml");
        let _ = montecarlo::scenario::Scenario::from_toml_str(&text, "fuzz.toml");
    }
});
