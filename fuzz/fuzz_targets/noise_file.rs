//! The Kalibr / OpenVINS / VINS-Fusion IMU noise-file reader (`noise::noise_file`, a YAML
//! parser's events) on arbitrary text (bytes that are not UTF-8 go through the same UTF-8 check
//! the command uses), directly and through the sensor-model dispatch a command uses.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(text) = noise::utf8_text(data.to_vec(), "fuzz.yaml") {
        let _ = noise::noise_file::is_noise_file(&text);
        let _ = noise::noise_file::read_noise_file(&text, "fuzz.yaml");
        let _ = noise::SensorModel::from_text(&text, "fuzz.yaml");
    }
});
