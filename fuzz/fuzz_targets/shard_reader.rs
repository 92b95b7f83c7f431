//! Shard files as `merge` reads them: JSON into `ShardFile`, then its consistency check against an
//! experiment of a few shapes.
#![no_main]
use libfuzzer_sys::fuzz_target;
use montecarlo::shard::ShardFile;

fuzz_target!(|data: &[u8]| {
    if let Ok(f) = serde_json::from_slice::<ShardFile>(data) {
        for (runs, checkpoints) in [(0, 0), (10, 25), (u64::MAX, 1)] {
            let _ = f.check(runs, checkpoints, 11);
        }
    }
});
