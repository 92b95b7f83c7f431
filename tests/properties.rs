//! Property tests of the readers: arbitrary bytes and structured mutations of real inputs never
//! make the log reader, the config loaders, the unit parser or the shard check panic, hang or
//! allocate without bound; they return a value or an error. (The fuzz targets in `fuzz/` explore
//! the same functions far longer with coverage guidance; this keeps the guarantee in CI without a
//! nightly toolchain.) Cases per property: proptest's default 256, seeded deterministically.

use logio::{parse_log, ReadOptions};
use montecarlo::scenario::Scenario;
use montecarlo::shard::ShardFile;
use noise::units::{parse_quantity, Quantity, Signal};
use noise::SensorModel;
use proptest::prelude::*;

const SENSOR: &str = include_str!("../configs/sensors/adis16405.toml");
const SCENARIO: &str = include_str!("../configs/scenarios/mtx-static-60s-calibrated-window.toml");
const LOG: &str = "# comment\nt,gx,gy,gz,ax,ay,az,temp\n0,1e-3,2e-3,-1e-3,0.01,-0.02,-9.8,25\n0.01,2e-3,1e-3,0,0.02,-0.01,-9.81,25\n0.02,0,0,1e-3,0.0,0.0,-9.79,25.1\n0.03,-1e-3,1e-3,2e-3,0.01,0.01,-9.8,25.1\n";

/// A mutation of `base`: some bytes replaced, inserted or removed at positions drawn by proptest.
fn mutated(base: &'static str) -> impl Strategy<Value = Vec<u8>> {
    let len = base.len();
    prop::collection::vec((0..len, any::<u8>(), 0u8..3), 1..8).prop_map(move |edits| {
        let mut b = base.as_bytes().to_vec();
        for (pos, byte, kind) in edits {
            let pos = pos.min(b.len().saturating_sub(1));
            match kind {
                0 if !b.is_empty() => b[pos] = byte,
                1 => b.insert(pos, byte),
                _ if !b.is_empty() => {
                    b.remove(pos);
                }
                _ => {}
            }
        }
        b
    })
}

proptest! {
    #![proptest_config(ProptestConfig { failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn log_reader_never_panics_on_bytes(bytes in prop::collection::vec(any::<u8>(), 0..400)) {
        let _ = parse_log(&bytes, "fuzz.csv", &ReadOptions::default());
    }

    #[test]
    fn log_reader_never_panics_on_mutated_logs(bytes in mutated(LOG)) {
        let _ = parse_log(&bytes, "fuzz.csv", &ReadOptions::default());
        let opts = ReadOptions { rate_hz: Some(100.0), ..ReadOptions::default() };
        let _ = parse_log(&bytes, "fuzz.csv", &opts);
    }

    #[test]
    fn sensor_loader_never_panics(bytes in mutated(SENSOR)) {
        if let Ok(text) = std::str::from_utf8(&bytes) {
            let _ = SensorModel::from_toml_str(text, "fuzz.toml");
        }
    }

    #[test]
    fn scenario_loader_never_panics(bytes in mutated(SCENARIO)) {
        if let Ok(text) = std::str::from_utf8(&bytes) {
            let _ = Scenario::from_toml_str(text, "fuzz.toml");
        }
    }

    #[test]
    fn unit_parser_never_panics(text in "[0-9eE.+ -]{0,6}[a-zA-Z°µ√^/*()²0-9 -]{0,40}") {
        for q in [
            Quantity::NoiseDensity(Signal::AngularRate),
            Quantity::RandomWalk(Signal::Acceleration),
            Quantity::Time,
            Quantity::Ratio,
        ] {
            let _ = parse_quantity(&text, q);
        }
    }

    #[test]
    fn shard_check_never_panics(
        index in 0u64..6,
        count in 0u64..6,
        runs in 0u64..50,
        ids in prop::collection::vec(0u64..60, 0..8),
    ) {
        let text = format!(
            "{{\"format\":\"imudrift-shard/1\",\"scenario_source\":\"s\",\"scenario_toml\":\"\",\"sensor_source\":\"x\",\"sensor_toml\":\"\",\"runs\":null,\"seed\":null,\"only\":null,\"without\":[],\"shard\":{{\"index\":{index},\"count\":{count}}},\"matrix\":{{\"checkpoints\":1,\"channels\":2,\"run_ids\":{ids:?},\"values\":[[],[1.0]]}},\"failures\":[]}}"
        );
        if let Ok(f) = serde_json::from_str::<ShardFile>(&text) {
            let _ = f.check(runs, 1, 2);
        }
    }
}
