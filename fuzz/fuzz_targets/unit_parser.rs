//! The unit parser on arbitrary text, for every kind of quantity a config uses.
#![no_main]
use libfuzzer_sys::fuzz_target;
use noise::units::{parse_quantity, Quantity, Signal};

fuzz_target!(|data: &[u8]| {
    if let Ok(text) = std::str::from_utf8(data) {
        for sig in [Signal::AngularRate, Signal::Acceleration] {
            for q in [
                Quantity::Signal(sig),
                Quantity::NoiseDensity(sig),
                Quantity::RandomWalk(sig),
                Quantity::Ramp(sig),
                Quantity::Integrated(sig),
                Quantity::PerDegree(sig),
            ] {
                let _ = parse_quantity(text, q);
            }
        }
        for q in [
            Quantity::Angle,
            Quantity::Ratio,
            Quantity::Time,
            Quantity::Frequency,
            Quantity::Temperature,
            Quantity::TemperatureRate,
        ] {
            let _ = parse_quantity(text, q);
        }
    }
});
