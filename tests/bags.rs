//! ROS 1 bags and ROS 2 MCAP files: the same samples as a bag, as MCAP and as CSV give the same
//! Allan result; topics are chosen or named; damaged files are refused without a panic.

mod common;
use common::imudrift;
use logio::bag::{write_mcap, write_rosbag, ImuSample};
use std::path::Path;

/// Deterministic samples at 200 Hz: white noise plus a slow random walk on every channel
/// (SplitMix64), stamps from an epoch-like start so the integer nanoseconds matter.
fn samples(n: usize) -> Vec<ImuSample> {
    let mut rng = testkit::SplitMix64::new(0x1234_5678);
    let mut next = || rng.centred();
    let mut walk = [0.0f64; 6];
    (0..n)
        .map(|k| {
            let mut v = [0.0; 6];
            for c in 0..6 {
                walk[c] += 1e-5 * next();
                v[c] = 1e-3 * next() + walk[c] + if c == 5 { -9.80665 } else { 0.0 };
            }
            ImuSample {
                t_ns: 1_700_000_000_000_000_000 + k as i64 * 5_000_000,
                gyro: [v[0], v[1], v[2]],
                accel: [v[3], v[4], v[5]],
            }
        })
        .collect()
}

fn write_csv(path: &Path, s: &[ImuSample]) {
    let mut t = String::from("t,gx,gy,gz,ax,ay,az\n");
    for (k, m) in s.iter().enumerate() {
        t += &format!(
            "{:?},{:?},{:?},{:?},{:?},{:?},{:?}\n",
            k as f64 * 0.005,
            m.gyro[0],
            m.gyro[1],
            m.gyro[2],
            m.accel[0],
            m.accel[1],
            m.accel[2]
        );
    }
    std::fs::write(path, t).unwrap();
}

fn allan(path: &Path, extra: &[&str]) -> serde_json::Value {
    let mut args = vec!["allan", path.to_str().unwrap(), "--json"];
    args.extend_from_slice(extra);
    let out = common::ok(imudrift(&args));
    serde_json::from_slice(&out.stdout).unwrap()
}

#[test]
fn bag_mcap_and_csv_give_the_same_allan_result() {
    let dir = tempfile::tempdir().unwrap();
    let s = samples(40_000);
    let (csv, bag, mcap) = (
        dir.path().join("imu.csv"),
        dir.path().join("imu.bag"),
        dir.path().join("imu.mcap"),
    );
    write_csv(&csv, &s);
    write_rosbag(&bag, "/imu0", &s).unwrap();
    write_mcap(&mcap, &[("/imu0", &s)]).unwrap();
    let reference = allan(&csv, &[]);
    for (name, path) in [("bag", &bag), ("mcap", &mcap)] {
        let doc = allan(path, &[]);
        assert!(
            (doc["rate_hz"].as_f64().unwrap() - 200.0).abs() < 1e-9,
            "{name}"
        );
        assert_eq!(doc["columns"][0]["channel_from"], "sensor_msgs/Imu");
        for ch in ["gx", "gy", "gz", "ax", "ay", "az"] {
            let a = doc["channels"][ch]["adev"].as_array().unwrap();
            let b = reference["channels"][ch]["adev"].as_array().unwrap();
            assert_eq!(a.len(), b.len(), "{name} {ch}");
            for (x, y) in a.iter().zip(b) {
                let (x, y) = (x.as_f64().unwrap(), y.as_f64().unwrap());
                assert!((x - y).abs() <= 1e-12 * y, "{name} {ch}: {x} vs {y}");
            }
        }
    }
}

#[test]
fn topics_are_chosen_or_named() {
    let dir = tempfile::tempdir().unwrap();
    let s = samples(3000);
    let both = dir.path().join("two.mcap");
    write_mcap(&both, &[("/imu/left", &s), ("/imu/right", &s[..2000])]).unwrap();
    let out = imudrift(&["allan", both.to_str().unwrap()]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(
        err.contains("/imu/left") && err.contains("/imu/right") && err.contains("--topic"),
        "{err}"
    );
    let doc = allan(&both, &["--topic", "/imu/right"]);
    assert_eq!(doc["samples"], 2000);
    let out = imudrift(&["allan", both.to_str().unwrap(), "--topic", "/cam"]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("--topic /cam") && err.contains("/imu/left (sensor_msgs/msg/Imu)"),
        "{err}"
    );
    let bag = dir.path().join("one.bag");
    write_rosbag(&bag, "/imu0", &s).unwrap();
    let out = imudrift(&["allan", bag.to_str().unwrap(), "--topic", "/imu1"]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("/imu0 (sensor_msgs/Imu)"), "{err}");
}

#[test]
fn damaged_or_irregular_bags_are_refused_without_a_panic() {
    let dir = tempfile::tempdir().unwrap();
    let s = samples(3000);
    let bag = dir.path().join("imu.bag");
    write_rosbag(&bag, "/imu0", &s).unwrap();
    let mcap = dir.path().join("imu.mcap");
    write_mcap(&mcap, &[("/imu0", &s)]).unwrap();
    for path in [&bag, &mcap] {
        let bytes = std::fs::read(path).unwrap();
        for cut in [20, 5000, bytes.len() / 2, bytes.len() - 7] {
            let damaged = dir.path().join(format!(
                "cut-{cut}.{}",
                path.extension().unwrap().to_str().unwrap()
            ));
            std::fs::write(&damaged, &bytes[..cut]).unwrap();
            let out = imudrift(&["allan", damaged.to_str().unwrap()]);
            let err = String::from_utf8_lossy(&out.stderr);
            assert_eq!(out.status.code(), Some(1), "{cut}: {err}");
            assert!(err.contains("cut-") && !err.contains("panicked"), "{err}");
        }
    }
    // Damaged length fields (the first record's, and bytes flipped through the file): errors,
    // never an attempt to allocate exabytes.
    let bytes = std::fs::read(&mcap).unwrap();
    let mut variants = Vec::new();
    let mut huge = bytes.clone();
    huge[9..17].copy_from_slice(&0xffff_ffff_ffff_ff00u64.to_le_bytes());
    variants.push(huge);
    for k in 1..40 {
        let mut v = bytes.clone();
        let at = k * bytes.len() / 40;
        for b in &mut v[at..(at + 8).min(bytes.len())] {
            *b = 0xff;
        }
        variants.push(v);
    }
    for (i, v) in variants.iter().enumerate() {
        let damaged = dir.path().join(format!("flip-{i}.mcap"));
        std::fs::write(&damaged, v).unwrap();
        let out = imudrift(&["allan", damaged.to_str().unwrap()]);
        let err = String::from_utf8_lossy(&out.stderr);
        // Exit 1 with a message, or (a flip inside a float) a valid analysis: never a crash.
        assert!(matches!(out.status.code(), Some(0) | Some(1)), "{i}: {err}");
        assert!(
            !err.contains("panicked") && !err.contains("memory allocation"),
            "{i}: {err}"
        );
    }
    // A gap of 10 samples is named by its message.
    let mut gap = s.clone();
    gap.drain(1000..1010);
    let gapped = dir.path().join("gap.mcap");
    write_mcap(&gapped, &[("/imu0", &gap)]).unwrap();
    let out = imudrift(&["allan", gapped.to_str().unwrap()]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("topic /imu0 message 1001") && err.contains("gap"),
        "{err}"
    );
}

/// The figure in docs/cli.md: a 2 h, 200 Hz bag (1.44 M messages) analysed by `allan` in under
/// 5 s on 2 cores, as a bag and as MCAP. Ignored in the suite (a timing on a shared machine);
/// run with `cargo test --release --test bags -- --ignored --nocapture`.
#[test]
#[ignore = "timing: run by hand"]
fn two_hour_200_hz_bag_in_under_five_seconds() {
    let dir = tempfile::tempdir().unwrap();
    let s = samples(1_440_000);
    let bag = dir.path().join("big.bag");
    let mcap = dir.path().join("big.mcap");
    write_rosbag(&bag, "/imu0", &s).unwrap();
    write_mcap(&mcap, &[("/imu0", &s)]).unwrap();
    for path in [&bag, &mcap] {
        let t0 = std::time::Instant::now();
        let doc = allan(path, &[]);
        let secs = t0.elapsed().as_secs_f64();
        println!(
            "{}: {} messages, allan in {secs:.2} s",
            path.display(),
            doc["samples"]
        );
        assert_eq!(doc["samples"], 1_440_000);
        assert!(secs < 5.0, "{secs} s");
    }
}

/// Issue 27, item 1: a NaN, an inf or a value whose square overflows inside a message is refused
/// as the CSV reader refuses it (file, message, field), by every command that reads the log.
#[test]
fn non_finite_or_huge_values_in_bags_and_mcap_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    for (k, (bad, needle)) in [
        (f64::NAN, "NaN"),
        (f64::INFINITY, "inf"),
        (-1e300, "-1.00e300"),
    ]
    .into_iter()
    .enumerate()
    {
        let mut s = samples(3000);
        s[1234].accel[1] = bad;
        let bag = dir.path().join(format!("bad{k}.bag"));
        let mcap = dir.path().join(format!("bad{k}.mcap"));
        write_rosbag(&bag, "/imu", &s).unwrap();
        write_mcap(&mcap, &[("/imu", &s)]).unwrap();
        for path in [&bag, &mcap] {
            let p = path.to_str().unwrap();
            for args in [
                vec!["allan", p, "--json"],
                vec![
                    "diagnose",
                    p,
                    "--model",
                    "configs/sensors/mtx.toml",
                    "--json",
                ],
            ] {
                let out = imudrift(&args);
                let err = String::from_utf8_lossy(&out.stderr);
                assert_eq!(out.status.code(), Some(1), "{args:?}: {err}");
                assert!(out.stdout.is_empty(), "{args:?} printed a result");
                for n in ["topic /imu message 1235", "linear_acceleration.y", needle] {
                    assert!(err.contains(n), "{args:?}: {n:?} not in {err}");
                }
            }
        }
    }
}

/// Found by the `bag_reader` fuzz target: an MCAP channel record whose topic length says 4 GiB
/// (in a record of a few bytes) was a 4 GiB allocation by the `mcap` crate before its read
/// failed; the length prefixes are checked against the record first. Here run under a 4 GiB
/// address-space limit (`prlimit`), where that allocation aborted the command.
#[cfg(target_os = "linux")]
#[test]
fn mcap_lengths_past_their_record_are_refused_before_allocating() {
    let dir = tempfile::tempdir().unwrap();
    let record = |b: &mut Vec<u8>, op: u8, content: &[u8]| {
        b.push(op);
        b.extend_from_slice(&(content.len() as u64).to_le_bytes());
        b.extend_from_slice(content);
    };
    let string = |x: &[u8]| [(x.len() as u32).to_le_bytes().as_slice(), x].concat();
    let mut b = b"\x89MCAP0\r\n".to_vec();
    record(&mut b, 0x01, &[string(b"ros2"), string(b"")].concat());
    let mut channel = vec![1, 0, 1, 0];
    channel.extend_from_slice(&0xFFFF_FFF0u32.to_le_bytes());
    channel.extend_from_slice(b"/imu");
    record(&mut b, 0x04, &channel);
    record(&mut b, 0x0F, &[0; 4]);
    record(&mut b, 0x02, &[0; 20]);
    b.extend_from_slice(b"\x89MCAP0\r\n");
    let path = dir.path().join("long-topic.mcap");
    std::fs::write(&path, &b).unwrap();
    let out = std::process::Command::new("prlimit")
        .arg("--as=4294967296")
        .arg(common::binary())
        .args(["allan", path.to_str().unwrap()])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(err.contains("runs past the record"), "{err}");
}
