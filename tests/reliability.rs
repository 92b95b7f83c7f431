//! Issue 46 (reliability, third pass): a closed or full standard error, channels whose
//! differences underflow, rotations no step can represent, one log given twice, long work that
//! says nothing. Each test failed on the build before its fix: run them against another build
//! with `IMUDRIFT_TEST_BIN=/path/to/old/imudrift cargo test --release --test reliability`.

use std::path::Path;
use std::process::Stdio;

mod common;
use common::{command, imudrift, root};

fn write(dir: &Path, name: &str, bytes: &[u8]) -> String {
    let p = dir.join(name);
    std::fs::write(&p, bytes).unwrap();
    p.to_str().unwrap().to_string()
}

/// A static six-channel log of `n` rows at 100 Hz (deterministic noise, gravity on az).
fn imu_log(n: usize) -> String {
    let mut s = String::from("t,gx,gy,gz,ax,ay,az\n");
    let mut x: u64 = 987654321;
    let mut next = || {
        x = x
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (x >> 11) as f64 / (1u64 << 53) as f64 - 0.5
    };
    for i in 0..n {
        let g: Vec<f64> = (0..3).map(|_| 1e-3 * next()).collect();
        let a: Vec<f64> = (0..3).map(|_| 1e-2 * next()).collect();
        s += &format!(
            "{:.2},{},{},{},{},{},{}\n",
            i as f64 * 0.01,
            g[0],
            g[1],
            g[2],
            a[0],
            a[1],
            a[2] - 9.80665
        );
    }
    s
}

/// The exit status and stdout of `imudrift ARGS` with stderr going where `stderr` sends it.
fn with_stderr(args: &[&str], stderr: Stdio) -> (Option<i32>, Vec<u8>) {
    let out = command()
        .args(args)
        .stderr(stderr)
        .output()
        .expect("run imudrift");
    (out.status.code(), out.stdout)
}

/// The exit status of `imudrift ARGS` whose stderr is a pipe closed before it writes (its reader
/// gone, as in `2>&1 | head -1`), stdout kept.
fn with_closed_stderr(args: &[&str]) -> (Option<i32>, Vec<u8>) {
    let mut child = command()
        .args(args)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("run imudrift");
    drop(child.stderr.take());
    let out = child.wait_with_output().unwrap();
    (out.status.code(), out.stdout)
}

/// Item 1: a closed or full stderr loses the notes, never the result (it panicked `allan`,
/// `diagnose` and `drift` with status 101: "failed printing to stderr").
#[test]
fn a_closed_or_full_stderr_is_not_a_panic() {
    let dir = tempfile::tempdir().unwrap();
    let log = write(dir.path(), "ok.csv", imu_log(6000).as_bytes());
    let model = root().join("configs/sensors/mtx.toml");
    let model = model.to_str().unwrap();
    let commands: [&[&str]; 5] = [
        &["allan", &log, "--json"],
        &[
            "diagnose", &log, "--model", model, "--seeds", "2", "--rounds", "1", "--json",
        ],
        &[
            "drift",
            &log,
            "--model",
            model,
            "--replicates",
            "10",
            "--json",
        ],
        &[
            "simulate",
            model,
            "--runs",
            "20",
            "--duration",
            "5",
            "--json",
        ],
        &["spec", model, "--runs", "20", "--times", "5", "--json"],
    ];
    for args in commands {
        let full = std::fs::OpenOptions::new()
            .write(true)
            .open("/dev/full")
            .unwrap();
        let (code, stdout) = with_stderr(args, Stdio::from(full));
        assert_eq!(code, Some(0), "{args:?} 2>/dev/full");
        assert!(stdout.starts_with(b"{"), "{args:?} 2>/dev/full: no JSON");
        let (code, stdout) = with_closed_stderr(args);
        assert_eq!(code, Some(0), "{args:?} with stderr closed");
        assert!(stdout.starts_with(b"{"), "{args:?} stderr closed: no JSON");
    }
}

/// Item 2: a channel whose values differ by amounts that underflow when squared (0 and 1e-160
/// alternating, one 1e-300 among zeros) is constant to an analysis; `allan` reported every
/// deviation 0, alpha 11990 and bounds of "< inf" with status 0.
#[test]
fn channels_whose_differences_underflow_are_refused_as_constant() {
    let dir = tempfile::tempdir().unwrap();
    let model = root().join("configs/sensors/mtx.toml");
    for (name, value) in [("alt.csv", "1e-160"), ("one.csv", "1e-300")] {
        let mut text = String::from("t,gx\n");
        for i in 0..4000 {
            let v = if (name == "alt.csv" && i % 2 == 1) || (name == "one.csv" && i == 500) {
                value
            } else {
                "0"
            };
            text += &format!("{:.2},{v}\n", i as f64 * 0.01);
        }
        let log = write(dir.path(), name, text.as_bytes());
        for args in [
            vec!["allan", &log, "--json"],
            vec!["diagnose", &log, "--model", model.to_str().unwrap()],
        ] {
            let out = imudrift(&args);
            let err = String::from_utf8_lossy(&out.stderr);
            assert_eq!(out.status.code(), Some(1), "{args:?}: {err}");
            assert!(out.stdout.is_empty(), "{args:?} printed a result");
            assert!(
                err.contains(&format!("channel gx is constant to within {value}"))
                    && err.contains("underflow"),
                "{args:?}: {err}"
            );
        }
    }
}

/// Item 3: a gyro bias of 1e40 rad/s turns 1e38 rad a step; `simulate` reported "roll 4.218 deg,
/// std 0" with status 0. Every run now fails, by name, and the command says so.
#[test]
fn rotations_no_step_can_represent_fail_the_runs() {
    let dir = tempfile::tempdir().unwrap();
    let sensor = write(
        dir.path(),
        "fast.toml",
        b"name = \"fast\"\n[gyro.all]\nconstant_bias = \"1e40 rad/s\"\n",
    );
    for args in [
        vec!["simulate", &sensor, "--runs", "9", "--duration", "1"],
        vec!["spec", &sensor, "--runs", "9", "--times", "1"],
    ] {
        let out = imudrift(&args);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{args:?}: {err}");
        assert!(out.stdout.is_empty(), "{args:?} printed a result");
        assert!(
            err.contains("runs failed")
                && err.contains("the gyros turn 1.732e38 rad in one step at t = 0 s"),
            "{args:?}: {err}"
        );
    }
    // A fast but real motion is not refused: 1000 deg/s turns 0.17 rad a step at 100 Hz.
    let fast = write(
        dir.path(),
        "spin.toml",
        format!(
            "name = \"spin\"\nsensor = {:?}\nduration_s = 1\nruns = 9\n[trajectory]\nkind = \"constant_rate\"\nrate_deg_s = [0.0, 0.0, 1000.0]\n",
            root().join("configs/sensors/mtx.toml")
        )
        .as_bytes(),
    );
    let out = imudrift(&["simulate", &fast, "--json"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// Item 12: one log given twice (or a hard link to it, or a copy) counted as two runs: `drift`
/// pooled 120 segments with a between-log spread of 0 and intervals sqrt(2) too narrow. Now
/// `drift` and `diagnose` refuse it by content; different logs still pass.
#[test]
fn one_log_given_twice_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let log = write(dir.path(), "run1.csv", imu_log(3000).as_bytes());
    let link = dir.path().join("link.csv");
    std::fs::hard_link(&log, &link).unwrap();
    let link = link.to_str().unwrap();
    let copy = write(dir.path(), "copy.csv", imu_log(3000).as_bytes());
    let other = imu_log(3001);
    let other = write(dir.path(), "run2.csv", other.as_bytes());
    let model = root().join("configs/sensors/mtx.toml");
    let model = model.to_str().unwrap();
    for (second, needle) in [
        (log.as_str(), "run1.csv is given twice".to_string()),
        (link, format!("{link} has the same samples as {log}")),
        (
            copy.as_str(),
            format!("{copy} has the same samples as {log}"),
        ),
    ] {
        for args in [
            vec![
                "drift",
                &log,
                second,
                "--model",
                model,
                "--replicates",
                "10",
            ],
            vec![
                "diagnose", &log, second, "--model", model, "--seeds", "2", "--rounds", "1",
            ],
        ] {
            let out = imudrift(&args);
            let err = String::from_utf8_lossy(&out.stderr);
            assert_eq!(out.status.code(), Some(1), "{args:?}: {err}");
            assert!(out.stdout.is_empty(), "{args:?} printed a result");
            assert!(
                err.contains(&needle) && err.contains("give each run once"),
                "{args:?}: {err}"
            );
        }
    }
    let out = imudrift(&[
        "drift",
        &log,
        &other,
        "--model",
        model,
        "--replicates",
        "10",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// Item 10: long work in `allan` says where it is. The resolved-term thresholds come from the
/// shipped null table for the default options (no simulation: a 5 M-sample log in under a
/// second); other options simulate the null logs and print a line per interval
/// (`IMUDRIFT_PROGRESS_INTERVAL_S`, 10 s by default) while they do.
#[test]
fn allan_null_simulation_prints_progress() {
    let dir = tempfile::tempdir().unwrap();
    let log = write(dir.path(), "ok.csv", imu_log(3000).as_bytes());
    let out = command()
        .args(["allan", &log, "--channels", "gx", "--edf", "simple"])
        .env("IMUDRIFT_PROGRESS_INTERVAL_S", "0")
        .output()
        .expect("run imudrift");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    assert!(
        err.contains("null logs for the resolved-term thresholds") && err.contains("/200 logs"),
        "{err}"
    );
}
