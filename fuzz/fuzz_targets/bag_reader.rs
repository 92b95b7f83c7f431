//! The ROS 1 bag and ROS 2 MCAP reader (`logio::read_log` on a file, crates/logio/src/bag.rs) on
//! arbitrary bytes: the bytes are written to a file (the readers map files) and read as a log,
//! with and without a topic; the message decoders also get the bytes themselves.
#![no_main]
use libfuzzer_sys::fuzz_target;
use logio::{read_log, ReadOptions};
use std::path::PathBuf;
use std::sync::OnceLock;

/// One file per fuzzing process, rewritten for each input (in memory-backed /dev/shm when there).
fn scratch() -> &'static PathBuf {
    static PATH: OnceLock<PathBuf> = OnceLock::new();
    PATH.get_or_init(|| {
        let shm = PathBuf::from("/dev/shm");
        let dir = if shm.is_dir() { shm } else { std::env::temp_dir() };
        dir.join(format!("imudrift-fuzz-bag-{}", std::process::id()))
    })
}

fuzz_target!(|data: &[u8]| {
    let _ = logio::bag::decode_ros1(data);
    let _ = logio::bag::decode_cdr(data);
    // Only bags and MCAP files: other bytes are the CSV reader's (the log_reader target).
    if logio::bag::format_of(&data[..data.len().min(16)]).is_none() {
        return;
    }
    let path = scratch();
    if std::fs::write(path, data).is_err() {
        return;
    }
    let _ = read_log(path, &ReadOptions::default());
    let opts = ReadOptions {
        topic: Some("/imu".to_string()),
        ..ReadOptions::default()
    };
    let _ = read_log(path, &opts);
});
