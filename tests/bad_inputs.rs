//! Input the commands cannot analyse meaningfully is refused with a message that says what is
//! needed (exit status 1, never a panic, never an empty result presented as one). Each case here
//! was accepted or crashed before its fix.
//!
//! To see them fail on an older build, point `IMUDRIFT_TEST_BIN` at its binary (the tests run it
//! in place of the one cargo builds): `IMUDRIFT_TEST_BIN=/path/to/old/imudrift cargo test
//! --release --test bad_inputs` (the outcome of commit 91afd1a is in docs/bad-inputs.md).

use std::path::Path;
use std::process::Command;

mod common;
use common::{command, imudrift, ok, root};

/// The command fails with exit status 1 and every `needle` in its message; nothing on stdout.
fn refused(args: &[&str], needles: &[&str]) {
    refused_out(imudrift(args), args, needles);
}

/// [`refused`] with the memory limit lowered to `limit` bytes (`IMUDRIFT_MEMORY_LIMIT`).
fn refused_with_memory(args: &[&str], limit: &str, needles: &[&str]) {
    let out = command()
        .args(args)
        .env("IMUDRIFT_MEMORY_LIMIT", limit)
        .output()
        .expect("run imudrift");
    refused_out(out, args, needles);
}

fn refused_out(out: std::process::Output, args: &[&str], needles: &[&str]) {
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{args:?}: {err}");
    assert!(out.stdout.is_empty(), "{args:?} printed a result");
    for n in needles {
        assert!(err.contains(n), "{args:?}: {n:?} not in {err}");
    }
}

fn write(dir: &Path, name: &str, bytes: &[u8]) -> String {
    let p = dir.join(name);
    std::fs::write(&p, bytes).unwrap();
    p.to_str().unwrap().to_string()
}

/// A log of `n` rows at 100 Hz: `t` and a pseudo-random (deterministic) gyro channel.
fn log_text(n: usize, newline: &str) -> String {
    let mut s = format!("t,gx{newline}");
    let mut x: u64 = 12345;
    for i in 0..n {
        x = x
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        let v = (x >> 11) as f64 / (1u64 << 53) as f64 - 0.5;
        s += &format!("{:.2},{v}{newline}", i as f64 * 0.01);
    }
    s
}

#[test]
fn allan_refuses_logs_too_short_or_constant() {
    let dir = tempfile::tempdir().unwrap();
    let short = write(dir.path(), "short.csv", log_text(3, "\n").as_bytes());
    refused(&["allan", &short, "--json"], &["3 samples", "longer log"]);
    let long = write(dir.path(), "long.csv", log_text(2000, "\n").as_bytes());
    refused(
        &["allan", &long, "--grid", "100000", "--json"],
        &["--grid has no averaging factor"],
    );
    let mut zero = String::from("t,gx\n");
    for i in 0..2000 {
        zero += &format!("{:.2},0\n", i as f64 * 0.01);
    }
    let zero = write(dir.path(), "zero.csv", zero.as_bytes());
    refused(&["allan", &zero, "--json"], &["channel gx is constant"]);
}

/// Issue 27, item 4: a channel constant at any value (az = -9.81 on every row) is refused by
/// `allan` as by `diagnose` and `drift`, with the one shared message (allan fitted a
/// quantisation of 2.8e-28 m/s to it).
#[test]
fn every_command_refuses_a_constant_channel_at_any_value() {
    let dir = tempfile::tempdir().unwrap();
    let mut text = String::from("t,gx,az\n");
    for (i, line) in log_text(3000, "\n").lines().skip(1).enumerate() {
        let v = line.split(',').nth(1).unwrap();
        text += &format!("{:.2},{v},-9.81\n", i as f64 * 0.01);
    }
    let log = write(dir.path(), "level.csv", text.as_bytes());
    let needles = ["channel az is constant (-9.81)", "no noise to analyse"];
    refused(&["allan", &log, "--json"], &needles);
    let model = "configs/sensors/mtx.toml";
    refused(&["diagnose", &log, "--model", model, "--json"], &needles);
    refused(&["drift", &log, &log, "--model", model, "--json"], &needles);
}

#[test]
fn diagnose_refuses_a_constant_channel() {
    let dir = tempfile::tempdir().unwrap();
    let mut text = String::from("t,gx,gy\n");
    for (i, line) in log_text(3000, "\n").lines().skip(1).enumerate() {
        let v = line.split(',').nth(1).unwrap();
        text += &format!("{:.2},{v},0\n", i as f64 * 0.01);
    }
    let log = write(dir.path(), "stuck.csv", text.as_bytes());
    refused(
        &[
            "diagnose",
            &log,
            "--model",
            "configs/sensors/mtx.toml",
            "--json",
        ],
        &["channel gy is constant"],
    );
}

#[test]
fn time_column_gaps_rates_and_tiny_steps_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    // Rows 1000..1500 missing: a 5 s gap that used to be averaged into a 66.7 Hz rate.
    let text: String = log_text(3000, "\n")
        .lines()
        .enumerate()
        .filter(|(i, _)| !(1001..1501).contains(i))
        .map(|(_, l)| format!("{l}\n"))
        .collect();
    let gap = write(dir.path(), "gap.csv", text.as_bytes());
    refused(&["allan", &gap], &["gap.csv:1002", "gap or irregular"]);
    let ok = write(dir.path(), "ok.csv", log_text(2000, "\n").as_bytes());
    refused(
        &["allan", &ok, "--rate", "50"],
        &["--rate 50.0000 Hz disagrees with the `t` column (100.000 Hz)"],
    );
    let tiny = write(dir.path(), "tiny.csv", b"t,gx\n0,1\n5e-324,2\n1e-323,3\n");
    refused(&["allan", &tiny], &["median step", "is `t` in seconds"]);
    // A rate no log has (it used to end in "no Allan point at or above --tau-min").
    refused(
        &[
            "diagnose",
            &tiny,
            "--model",
            "configs/sensors/mtx.toml",
            "--rate",
            "1e300",
        ],
        &["--rate 1.00000e300", "at most 1e9"],
    );
}

#[test]
fn byte_order_marks_and_cr_line_endings_are_read() {
    let dir = tempfile::tempdir().unwrap();
    let plain = log_text(2000, "\n");
    let reference = ok(imudrift(&[
        "allan",
        &write(dir.path(), "a.csv", plain.as_bytes()),
        "--json",
    ]));
    let mut bom = vec![0xef, 0xbb, 0xbf];
    bom.extend_from_slice(plain.as_bytes());
    let cr = log_text(2000, "\r");
    for (name, bytes) in [("bom.csv", bom), ("cr.csv", cr.into_bytes())] {
        let out = imudrift(&["allan", &write(dir.path(), name, &bytes), "--json"]);
        assert!(
            out.status.success(),
            "{name}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        // Same numbers as the plain file (the JSON names its source, so compare the channels).
        let a: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        let b: serde_json::Value = serde_json::from_slice(&reference.stdout).unwrap();
        assert_eq!(a["channels"], b["channels"], "{name}");
    }
}

/// CR-only line endings used to make reading quadratic (60 000 rows: 725 s): now linear.
#[test]
fn cr_only_logs_read_in_linear_time() {
    let dir = tempfile::tempdir().unwrap();
    let log = write(dir.path(), "cr.csv", log_text(60_000, "\r").as_bytes());
    let started = std::time::Instant::now();
    common::ok(imudrift(&["allan", &log, "--json"]));
    // Generous for a loaded 2-core machine: the read takes milliseconds.
    assert!(started.elapsed().as_secs_f64() < 10.0);
}

#[test]
fn a_narrow_confidence_level_gives_a_narrow_interval() {
    let dir = tempfile::tempdir().unwrap();
    let log = write(dir.path(), "a.csv", log_text(4000, "\n").as_bytes());
    let width = |level: &str| {
        let out = imudrift(&["allan", &log, "--confidence", level, "--json"]);
        assert!(out.status.success());
        let d: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        let c = &d["channels"]["gx"];
        c["adev_hi"][2].as_f64().unwrap() - c["adev_lo"][2].as_f64().unwrap()
    };
    assert!(width("0.3") < width("0.7"));
    refused(&["allan", &log, "--confidence", "1.5"], &["--confidence"]);
}

/// Sizes that used to abort, hang or allocate without bound are refused before any work.
#[test]
fn sizes_beyond_reason_are_refused_up_front() {
    let dir = tempfile::tempdir().unwrap();
    let mtx = root().join("configs/sensors/mtx.toml");
    let mtx = mtx.to_str().unwrap();
    // A flicker band of 600 decades (capacity overflow before) and 6000 components (minutes).
    for band in [
        "[\"1e-300 s\", \"1e300 s\"]",
        "[\"1e-150 s\", \"1e150 s\"], per_decade = 20",
    ] {
        let sensor = write(
            dir.path(),
            "band.toml",
            format!("name = \"b\"\n[gyro.all]\nwhite_noise = \"0.1 deg/sqrt(h)\"\nbias_instability = {{ value = \"10 deg/h\", convention = \"ieee\", band = {band} }}\n").as_bytes(),
        );
        refused(
            &["simulate", &sensor, "--runs", "2"],
            &[
                "band.toml:4",
                "bias_instability.band",
                "at most 100 components",
            ],
        );
    }
    // 1e13 checkpoints (allocation abort before).
    let scenario = write(
        dir.path(),
        "lc.toml",
        format!("sensor = {mtx:?}\n[checkpoints]\nlog_count = 10000000000000\n").as_bytes(),
    );
    refused(
        &["simulate", &scenario],
        &["checkpoints.log_count", "100000"],
    );
    // A diagnose band of 1e8 simulated logs, or 1e6 rounds: hours of work for nothing.
    let log = write(dir.path(), "ok.csv", log_text(2000, "\n").as_bytes());
    refused(
        &["diagnose", &log, "--model", mtx, "--seeds", "100000000"],
        &["--seeds 100000000", "at most 4096"],
    );
    refused(
        &["diagnose", &log, "--model", mtx, "--rounds", "1000000"],
        &["--rounds 1000000"],
    );
    // 10 000 threads (started, and hung, before).
    refused(
        &["simulate", mtx, "--threads", "10000", "--runs", "2"],
        &["--threads 10000", "at most"],
    );
    refused(&["spec", mtx, "--threads", "10000"], &["--threads 10000"]);
}

/// Every run failing is an error, not a table of zeros and NaN with exit status 0.
#[test]
fn every_run_failing_is_an_error() {
    let dir = tempfile::tempdir().unwrap();
    let sensor = write(
        dir.path(),
        "huge.toml",
        b"name = \"huge\"\n[gyro.all]\nconstant_bias = \"1e40 rad/s\"\n",
    );
    refused(
        &["simulate", &sensor, "--runs", "3", "--json"],
        &["every one of the 3 runs failed", "in one step"],
    );
    refused(
        &["spec", &sensor, "--runs", "3", "--times", "1"],
        &["every one of the 3 drift runs failed"],
    );
}

/// `merge` refuses corrupted, hand-edited or inconsistent shards with the reason (it panicked on
/// several before), and takes an explicit `--seed` equal to the scenario's own as the same run.
#[test]
fn merge_refuses_corrupted_shards_with_the_reason() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path().to_str().unwrap();
    let scenario = "configs/scenarios/mtx-static-60s.toml";
    for (i, seed) in [(0, None), (1, Some("2007"))] {
        let mut args = vec![
            "simulate",
            scenario,
            "--runs",
            "10",
            "--no-ablation",
            "--shard",
        ];
        let shard = format!("{i}/2");
        args.push(&shard);
        args.extend(["--out", d]);
        if let Some(s) = seed {
            args.extend(["--seed", s]);
        }
        common::ok(imudrift(&args));
    }
    let s0 = format!("{d}/shard-0-of-2.json");
    let s1 = format!("{d}/shard-1-of-2.json");
    // Explicit --seed 2007 (the scenario's own) on one shard: the same experiment.
    common::ok(imudrift(&["merge", &s0, &s1, "--json"]));
    let original: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&s1).unwrap()).unwrap();
    let corrupt = |name: &str, edit: &dyn Fn(&mut serde_json::Value)| {
        let mut v = original.clone();
        edit(&mut v);
        write(dir.path(), name, v.to_string().as_bytes())
    };
    let cases: Vec<(String, &str)> = vec![
        (
            corrupt("index.json", &|v| v["shard"]["index"] = 5.into()),
            "expected 0 <= index < count",
        ),
        (
            corrupt("count.json", &|v| v["shard"]["count"] = 0.into()),
            "got 1/0",
        ),
        (
            corrupt("values.json", &|v| {
                v["matrix"]["values"][3].as_array_mut().unwrap().pop();
            }),
            "series 3 has 4 values for 5 runs",
        ),
        (
            corrupt("runs.json", &|v| v["matrix"]["run_ids"][0] = 0.into()),
            "run 0 is outside this shard's runs 5..10",
        ),
        (
            corrupt("order.json", &|v| v["matrix"]["run_ids"][1] = 5.into()),
            "not strictly ascending",
        ),
        (
            corrupt("shape.json", &|v| v["matrix"]["checkpoints"] = 3.into()),
            "value series for 3 checkpoints",
        ),
        (
            write(dir.path(), "garbage.json", b"{\"format\": 7}"),
            "not an imudrift shard file",
        ),
        // A job of 1e12 runs (simulate itself refuses it for memory): refused before merging.
        (
            corrupt("huge.json", &|v| v["runs"] = 1_000_000_000_000u64.into()),
            "limit 8 GiB",
        ),
        // Issue 27, item 3: a value edited to 1e200 overflows the statistics (NaN, exit 0).
        (
            corrupt("overflow.json", &|v| {
                v["matrix"]["values"][5][0] = 1e200.into()
            }),
            "overflow the statistics",
        ),
    ];
    for (path, needle) in &cases {
        refused(&["merge", path, &s0], &[needle]);
    }
}

/// Issue 27, item 3: a simulation whose runs are finite but whose statistics overflow (gravity of
/// 1e300) is an error, not a table of NaN with exit 0. Issue 46, item 3: a model value beyond the
/// one bound of a sane value (`noise::limits`, 1e100 in SI units; a bias of 1e200 mg) is refused
/// where the model is read, by `simulate` and `spec` alike (it used to run, or fail run by run).
#[test]
fn simulations_whose_statistics_overflow_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let sensor = write(
        dir.path(),
        "big.toml",
        b"name = \"big\"\n[accel.all]\nwhite_noise = \"0.004 m/s^2/sqrt(Hz)\"\nconstant_bias = \"1e200 mg\"\n",
    );
    let too_large = [
        "big.toml: key `accel.all.constant_bias`",
        "expected a magnitude below 1e100 (SI units), found 9.8066e197",
    ];
    refused(
        &[
            "simulate",
            &sensor,
            "--runs",
            "5",
            "--duration",
            "10",
            "--json",
        ],
        &too_large,
    );
    refused(
        &["spec", &sensor, "--runs", "5", "--times", "10", "--json"],
        &too_large,
    );
    let flat = format!(
        "name = \"f\"\nsensor = {:?}\nduration_s = 10\n[earth]\nmodel = \"flat\"\n",
        sensor
    );
    let flat = write(dir.path(), "f.toml", flat.as_bytes());
    refused(&["simulate", &flat, "--runs", "5", "--json"], &too_large);
    let scenario = format!(
        "name = \"g\"\nsensor = {:?}\nduration_s = 10\ngravity_mps2 = 1e300\n[earth]\nmodel = \"flat\"\n",
        root().join("configs/sensors/mtx.toml")
    );
    let scenario = write(dir.path(), "g.toml", scenario.as_bytes());
    let out = imudrift(&["simulate", &scenario, "--runs", "5", "--json"]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(out.stdout.is_empty(), "printed a result: {err}");
}

/// `generate` never writes `inf` or `NaN` into a log: a model whose values overflow is an error
/// and no file is left behind.
#[test]
fn generate_refuses_values_that_overflow() {
    let dir = tempfile::tempdir().unwrap();
    let sensor = write(
        dir.path(),
        "ovf.toml",
        // Each value below the bound of a sane value; the sample, 10 degC from the reference,
        // beyond it (issue 46, item 3: `generate` wrote it and `allan` refused to read it).
        b"name = \"ovf\"\n[temperature]\nprofile = \"constant\"\nvalue = \"35 degC\"\nreference = \"25 degC\"\n[gyro.all]\ntemperature_bias = \"9e99 rad/s/degC\"\n",
    );
    let log = dir.path().join("o.csv");
    refused(
        &[
            "generate",
            &sensor,
            "--duration",
            "10",
            "--rate",
            "10",
            "-o",
            log.to_str().unwrap(),
        ],
        &[
            "at sample 0: beyond the magnitude a log can hold (1e100",
            "check their units",
        ],
    );
    assert!(!log.exists(), "a partial log was left behind");
    // 1e12 samples (about 200 TB) used to start writing; now refused up front with the sizes.
    refused(
        &[
            "generate",
            "configs/sensors/mtx.toml",
            "--duration",
            "1e5",
            "--rate",
            "1e6",
            "-o",
            log.to_str().unwrap(),
        ],
        &["of CSV", "free"],
    );
    refused(
        &[
            "generate",
            "configs/sensors/mtx.toml",
            "--duration",
            "1",
            "--rate",
            "1e12",
            "-o",
            log.to_str().unwrap(),
        ],
        &["--rate"],
    );
    let left: Vec<_> = std::fs::read_dir(dir.path()).unwrap().collect();
    assert_eq!(left.len(), 1, "temporary files left behind: {left:?}");
}

/// A config that is not UTF-8 names the line and column of the first bad byte; an `--out` that
/// cannot be written is refused before the work, not after it.
#[test]
fn non_utf8_configs_and_unwritable_out_are_refused_early() {
    let dir = tempfile::tempdir().unwrap();
    let cfg = write(dir.path(), "latin1.toml", b"name = \"caf\xe9\"\n");
    refused(
        &["simulate", &cfg],
        &["line 1, column 12", "0xe9 is not UTF-8"],
    );
    refused(&["plan", &cfg], &["line 1, column 12"]);
    let file = write(dir.path(), "a-file", b"");
    let started = std::time::Instant::now();
    refused(
        &[
            "simulate",
            "configs/scenarios/gg1320an-static-1h.toml",
            "--out",
            &format!("{file}/sub"),
        ],
        &["cannot create directory"],
    );
    // The 1 h, 200-run simulation takes seconds; the refusal comes before it.
    assert!(started.elapsed().as_secs_f64() < 1.0);
}

/// A binary file is refused at once (it used to be read whole into one header line).
#[test]
fn binary_files_are_not_logs() {
    let dir = tempfile::tempdir().unwrap();
    let nul = write(dir.path(), "nul.bin", &vec![0u8; 1 << 20]);
    refused(&["allan", &nul, "--rate", "100"], &["NUL bytes"]);
}

/// Columns whose names are no quantity imudrift reads are never analysed as unitless channels:
/// with nothing recognised the log is refused, naming the columns and the accepted forms; beside
/// recognised ones they are skipped and listed (text and JSON).
#[test]
fn unrecognised_columns_are_listed_never_analysed() {
    let dir = tempfile::tempdir().unwrap();
    let mut text = String::from("a.b,a_b,a b\n");
    let mut with_gyro = String::from("gyro_x_dps,a.b,pressure\n");
    for line in log_text(2000, "\n").lines().skip(1) {
        let v = line.split(',').nth(1).unwrap();
        text += &format!("{v},{v},{v}\n");
        with_gyro += &format!("{v},{v},{v}\n");
    }
    let log = write(dir.path(), "names.csv", text.as_bytes());
    refused(
        &["allan", &log, "--rate", "100"],
        &[
            "names.csv:1",
            "no gyro or accelerometer column recognised among a.b, a_b, a b",
            "--col gx=NAME",
        ],
    );
    let log = write(dir.path(), "gyro.csv", with_gyro.as_bytes());
    let res = common::ok(imudrift(&["allan", &log, "--rate", "100", "--json"]));
    let err = String::from_utf8_lossy(&res.stderr);
    assert!(
        err.contains("gyro_x_dps -> gx (deg/s, from the name)") && err.contains("skipped: a.b"),
        "{err}"
    );
    let doc: serde_json::Value = serde_json::from_slice(&res.stdout).unwrap();
    assert_eq!(doc["channels"].as_object().unwrap().len(), 1);
    assert_eq!(doc["columns"][0]["channel"], "gx");
    assert_eq!(doc["columns"][0]["unit"], "deg/s");
    assert_eq!(doc["skipped_columns"][1]["column"], "pressure");
}

/// Nothing lost: a termination signal during a long write leaves no temporary file; an output
/// that is a symbolic link is written through (the link stays); an existing file keeps its mode;
/// a second run on a locked --out is refused.
#[cfg(unix)]
#[test]
fn outputs_are_never_partial_mixed_or_left_behind() {
    use std::os::unix::fs::PermissionsExt;
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // SIGTERM while a 60 h log (about 15 GB of text, many seconds) is being written.
    let log = d.join("big.csv");
    let mut child = command()
        .args(["generate", "configs/sensors/mtx.toml", "--duration", "60h"])
        .args(["--rate", "100", "-o", log.to_str().unwrap()])
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    let started = std::time::Instant::now();
    while std::fs::read_dir(d).unwrap().count() == 0 && started.elapsed().as_secs() < 20 {
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    std::thread::sleep(std::time::Duration::from_millis(200));
    let killed = Command::new("kill")
        .args(["-TERM", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(killed.success());
    let status = child.wait().unwrap();
    assert_eq!(status.code(), Some(130), "{status:?}");
    let left: Vec<_> = std::fs::read_dir(d)
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    assert!(left.is_empty(), "left behind: {left:?}");

    // A symbolic link to a 0600 file: written through, the link kept, the mode kept.
    let out = d.join("out");
    std::fs::create_dir(&out).unwrap();
    let real = d.join("real.json");
    std::fs::write(&real, "old").unwrap();
    std::fs::set_permissions(&real, std::fs::Permissions::from_mode(0o600)).unwrap();
    std::os::unix::fs::symlink(&real, out.join("allan.json")).unwrap();
    let csv = write(d, "a.csv", log_text(2000, "\n").as_bytes());
    common::ok(imudrift(&["allan", &csv, "--out", out.to_str().unwrap()]));
    let link = std::fs::symlink_metadata(out.join("allan.json")).unwrap();
    assert!(link.file_type().is_symlink(), "the link was replaced");
    let text = std::fs::read_to_string(&real).unwrap();
    assert!(text.contains("\"channels\""), "the target was not written");
    let mode = std::fs::metadata(&real).unwrap().permissions().mode() & 0o777;
    assert_eq!(mode, 0o600);

    // A locked --out (another run writing it) is refused before any work.
    let lock = std::fs::OpenOptions::new()
        .create(true)
        .truncate(false)
        .write(true)
        .open(out.join(".imudrift.lock"))
        .unwrap();
    lock.try_lock().unwrap();
    refused(
        &["allan", &csv, "--out", out.to_str().unwrap()],
        &["another imudrift is writing to this directory"],
    );
}

/// Weak but meaningful results carry warnings, printed and in the JSON: a fit the five IEEE 952
/// terms cannot describe (a sinusoid dominating the curve here).
#[test]
fn weak_results_carry_warnings() {
    let dir = tempfile::tempdir().unwrap();
    let mut text = String::from("t,gx\n");
    for (i, line) in log_text(20000, "\n").lines().skip(1).enumerate() {
        let v: f64 = line.split(',').nth(1).unwrap().parse().unwrap();
        let t = i as f64 * 0.01;
        let s = 20.0 * (2.0 * std::f64::consts::PI * 0.37 * t).sin();
        text += &format!("{t:.2},{}\n", v + s);
    }
    let log = write(dir.path(), "sine.csv", text.as_bytes());
    let out = common::ok(imudrift(&["allan", &log, "--json"]));
    let doc: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let w = doc["channels"]["gx"]["warnings"].as_array().unwrap();
    assert!(
        w.iter()
            .any(|w| w.as_str().unwrap().contains("does not describe the curve")),
        "{w:?}"
    );
    assert!(String::from_utf8_lossy(&out.stderr).contains("warning: gx:"));
}

/// A log whose parsed values would not fit in the memory available is refused before parsing
/// (here with the limit lowered through `IMUDRIFT_MEMORY_LIMIT`), plain and gzip-compressed.
#[test]
fn logs_larger_than_memory_are_refused_up_front() {
    use std::io::Write as _;
    let dir = tempfile::tempdir().unwrap();
    let text = log_text(5000, "\n");
    let plain = write(dir.path(), "big.csv", text.as_bytes());
    let mut gz = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
    gz.write_all(text.as_bytes()).unwrap();
    let gz = write(dir.path(), "big.csv.gz", &gz.finish().unwrap());
    // diagnose: the simulated logs of the same length would not fit (the log itself does).
    let out = command()
        .args([
            "diagnose",
            &plain,
            "--model",
            "configs/sensors/mtx.toml",
            "--threads",
            "2",
        ])
        .env("IMUDRIFT_MEMORY_LIMIT", "500000")
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&out.stderr).contains("simulating logs of 5000 samples"));
    // spec: a readback log of 1 day would not fit in 100 MB.
    let out = command()
        .args([
            "spec",
            "configs/sensors/mtx.toml",
            "--readback-duration",
            "86400",
        ])
        .env("IMUDRIFT_MEMORY_LIMIT", "100000000")
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&out.stderr).contains("readback log needs about"));
    for (path, needle) in [(&plain, "need about"), (&gz, "decompresses to more than")] {
        let out = command()
            .args(["allan", path])
            .env("IMUDRIFT_MEMORY_LIMIT", "60000")
            .output()
            .unwrap();
        assert_eq!(out.status.code(), Some(1));
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains(needle), "{err}");
    }
}

/// Issue 27, item 2: values whose squares overflow, and a rate so low that the averaging times
/// do, are refused with the line and column (they gave null deviations with exit 0).
#[test]
fn values_and_rates_that_overflow_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let mut lines: Vec<String> = log_text(3000, "\n").lines().map(String::from).collect();
    lines[1001] = "10.00,1e300".to_string();
    let text = lines.join("\n");
    let huge = write(dir.path(), "huge.csv", text.as_bytes());
    for args in [
        vec!["allan", huge.as_str(), "--json"],
        vec![
            "diagnose",
            &huge,
            "--model",
            "configs/sensors/mtx.toml",
            "--json",
        ],
    ] {
        refused(&args, &["huge.csv:1002", "column \"gx\"", "1e300", "1e100"]);
    }
    let mut no_t = String::from("gx\n");
    for line in log_text(3000, "\n").lines().skip(1) {
        no_t += line.split(',').nth(1).unwrap();
        no_t.push('\n');
    }
    let no_t = write(dir.path(), "no_t.csv", no_t.as_bytes());
    refused(
        &["allan", &no_t, "--rate", "1e-300", "--json"],
        &["--rate", "1e-6"],
    );
    let long = format!("t,gx\n0,{}\n", "1".repeat(100_000));
    let long = write(dir.path(), "long.csv", long.as_bytes());
    let out = imudrift(&["allan", &long, "--rate", "100", "--json"]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(
        err.len() < 1000,
        "the 100 000-digit field was echoed: {} bytes",
        err.len()
    );
}

/// Issue 27, item 5: an output that is one of the command's inputs (the same path, another
/// spelling of it, or a link to it) is refused before any work and the input is left as it was.
#[test]
fn outputs_never_replace_an_input() {
    let dir = tempfile::tempdir().unwrap();
    let log = write(dir.path(), "victim.csv", log_text(3000, "\n").as_bytes());
    let before = std::fs::read(&log).unwrap();
    refused(
        &["allan", &log, "--kalibr", &log, "--json"],
        &["--kalibr", "same file as the input"],
    );
    let other_spelling = format!("{}/./victim.csv", dir.path().display());
    refused(
        &["allan", &log, "--kalibr", &other_spelling, "--json"],
        &["same file as the input"],
    );
    #[cfg(unix)]
    {
        let link = dir.path().join("link.yaml");
        std::os::unix::fs::symlink(&log, &link).unwrap();
        refused(
            &["allan", &log, "--kalibr", link.to_str().unwrap(), "--json"],
            &["same file as the input"],
        );
    }
    assert_eq!(std::fs::read(&log).unwrap(), before, "the log was replaced");
    let model = write(
        dir.path(),
        "mm.toml",
        &std::fs::read(root().join("configs/sensors/mtx.toml")).unwrap(),
    );
    let model_before = std::fs::read(&model).unwrap();
    refused(
        &[
            "generate",
            &model,
            "--duration",
            "1",
            "--rate",
            "100",
            "-o",
            &model,
        ],
        &["-o", "same file as the input"],
    );
    refused(
        &[
            "diagnose", &log, "--model", &model, "--kalibr", &model, "--json",
        ],
        &["same file as the input"],
    );
    assert_eq!(
        std::fs::read(&model).unwrap(),
        model_before,
        "the model was replaced"
    );
    // An input named as an output of `--out DIR`, inside DIR.
    let out = dir.path().join("out");
    std::fs::create_dir(&out).unwrap();
    let inside = write(&out, "allan.csv", log_text(3000, "\n").as_bytes());
    refused(
        &["allan", &inside, "--out", out.to_str().unwrap(), "--json"],
        &["--out", "same file as the input"],
    );
}

/// Issue 27, item 6: a shard directory holds the shards of one experiment; a shard of another
/// experiment is refused before any work and the first shard stays.
#[test]
fn a_shard_directory_holds_one_experiment() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path().to_str().unwrap();
    let shard = |scenario: &str, runs: &str| {
        imudrift(&[
            "simulate",
            scenario,
            "--runs",
            runs,
            "--duration",
            "5",
            "--no-ablation",
            "--shard",
            "0/2",
            "--out",
            d,
        ])
    };
    common::ok(shard("configs/sensors/mtx.toml", "4"));
    let first = std::fs::read(dir.path().join("shard-0-of-2.json")).unwrap();
    // The same shard of the same experiment again: allowed (the same values).
    common::ok(shard("configs/sensors/mtx.toml", "4"));
    for (scenario, runs) in [
        ("configs/sensors/adis16405.toml", "4"),
        ("configs/sensors/mtx.toml", "6"),
    ] {
        let out = shard(scenario, runs);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{err}");
        assert!(err.contains("shard of another experiment"), "{err}");
    }
    assert_eq!(
        std::fs::read(dir.path().join("shard-0-of-2.json")).unwrap(),
        first
    );
}

/// Issue 27, items 8-9: windows shorter than a sample or longer than the logs (they panicked in
/// protocol.rs), and horizons that are not a whole number of samples (0.014 s at 100 Hz was
/// computed as one sample and reported as 0.014 s), are refused naming the option, the value
/// and the sample interval.
#[test]
fn horizons_and_windows_must_fit_the_sampling() {
    let dir = tempfile::tempdir().unwrap();
    let mut text = String::from("t,gx,gy,gz,ax,ay,az\n");
    for (i, line) in log_text(6000, "\n").lines().skip(1).enumerate() {
        let v = line.split(',').nth(1).unwrap();
        let v: f64 = v.parse().unwrap();
        text += &format!(
            "{:.2},{v},{},{},{},{},{}\n",
            i as f64 * 0.01,
            -v,
            v * 0.5,
            v * 0.01,
            -v * 0.01,
            -9.81 + v * 0.01
        );
    }
    let log = write(dir.path(), "still.csv", text.as_bytes());
    let model = "configs/sensors/mtx.toml";
    let drift = |extra: &[&str], needles: &[&str]| {
        let mut args = vec!["drift", &log, "--model", model, "--json"];
        args.extend_from_slice(extra);
        refused(&args, needles);
    };
    for w in ["0.001", "0.004", "1e-300"] {
        let init = format!("level:{w}");
        drift(
            &["--init", &init],
            &["--init level:", "shorter than one sample", "0.01 s"],
        );
        let cal = format!("window:{w}");
        drift(
            &["--calibration", &cal],
            &["--calibration window:", "shorter than one sample"],
        );
    }
    drift(&["--init", "level:1e19"], &["longer than the longest log"]);
    drift(
        &["--calibration", "window:1e20"],
        &["longer than the longest log"],
    );
    drift(
        &["--horizons", "0.01,0.014"],
        &["--horizons 0.014", "1.4 samples", "whole number"],
    );
    drift(
        &["--horizons", "0.004"],
        &["--horizons 0.004", "shorter than one sample"],
    );
    refused(
        &[
            "diagnose",
            &log,
            "--model",
            model,
            "--horizons",
            "0.014",
            "--json",
        ],
        &["--horizons 0.014", "whole number"],
    );
}

/// Issue 27, item 12: standard output on a full disk (`/dev/full`) ends every command with an
/// error line and status 1 (allan, diagnose and drift panicked "failed printing to stdout").
#[cfg(target_os = "linux")]
#[test]
fn a_full_stdout_is_an_error_line_in_every_command() {
    let dir = tempfile::tempdir().unwrap();
    let log = write(dir.path(), "ok.csv", log_text(3000, "\n").as_bytes());
    let gen = dir.path().join("g.csv");
    let model = "configs/sensors/mtx.toml";
    let cases: Vec<Vec<&str>> = vec![
        vec!["allan", &log],
        vec!["allan", &log, "--json"],
        vec!["diagnose", &log, "--model", model, "--json"],
        vec!["drift", &log, "--model", model, "--json", "--horizons", "1"],
        vec![
            "generate",
            model,
            "--duration",
            "1",
            "--rate",
            "100",
            "-o",
            gen.to_str().unwrap(),
            "--json",
        ],
        vec![
            "simulate",
            model,
            "--runs",
            "4",
            "--duration",
            "5",
            "--json",
        ],
        vec!["plan", model, "--json"],
    ];
    for args in cases {
        let full = std::fs::OpenOptions::new()
            .write(true)
            .open("/dev/full")
            .unwrap();
        let out = command().args(&args).stdout(full).output().unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{args:?}: {err}");
        assert!(
            err.contains("cannot write to standard output"),
            "{args:?}: {err}"
        );
        assert!(!err.contains("panicked"), "{args:?}: {err}");
    }
}

/// Issue 27, items 11 and 14: one work limit (runs x samples x output-filter decimation) for
/// simulate, spec and generate, checked before any work; long numbers are not echoed whole.
#[test]
fn work_beyond_the_limit_is_refused_before_it_starts() {
    let dir = tempfile::tempdir().unwrap();
    let model = "configs/sensors/mtx.toml";
    let started = std::time::Instant::now();
    refused(
        &["simulate", model, "--rate", "1e9", "--json"],
        &["samples of work", "limit 1e11"],
    );
    refused(
        &["simulate", model, "--duration", "1e6 h", "--json"],
        &["samples of work"],
    );
    let fast = write(
        dir.path(),
        "fast.toml",
        format!(
            "name = \"f\"\nsensor = {:?}\nrate_hz = 1e10\nduration_s = 60\n",
            root().join(model)
        )
        .as_bytes(),
    );
    refused(&["simulate", &fast, "--json"], &["samples of work"]);
    // 1000 samples behind a filter decimating by 1e6 are 1e9 internal samples per run.
    let decimated = write(
        dir.path(),
        "dec.toml",
        b"name = \"d\"\n[gyro.all]\nwhite_noise = \"0.05 deg/s/sqrt(Hz)\"\noutput_filter = { kind = \"moving_average\", taps = 4, decimation = 1000000 }\n",
    );
    refused(
        &[
            "simulate",
            &decimated,
            "--rate",
            "100",
            "--duration",
            "10",
            "--runs",
            "200",
            "--json",
        ],
        &["decimation 1000000", "samples of work"],
    );
    assert!(
        started.elapsed().as_secs() < 20,
        "the refusals took {:?}",
        started.elapsed()
    );
    let out = imudrift(&["simulate", model, "--duration", "1e300", "--json"]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(err.len() < 400, "a 300-digit number was echoed: {err}");
    let out = imudrift(&[
        "generate",
        model,
        "--duration",
        "1",
        "--rate",
        "100",
        "-o",
        dir.path().to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(
        err.contains("is a directory") && !err.contains("(os error 21): Is a directory"),
        "{err}"
    );
}

/// Issue 27, item 13: the environment variables imudrift reads are validated with a named error
/// (1e300 panicked; abc, 1e3 and -5 were ignored silently), and the memory limit applies to
/// simulate's per-run values too.
#[test]
fn environment_variables_are_validated() {
    let model = "configs/sensors/mtx.toml";
    for (name, value) in [
        ("IMUDRIFT_PROGRESS_INTERVAL_S", "1e300"),
        ("IMUDRIFT_PROGRESS_INTERVAL_S", "abc"),
        ("IMUDRIFT_MEMORY_LIMIT", "abc"),
        ("IMUDRIFT_MEMORY_LIMIT", "1e3"),
        ("IMUDRIFT_MEMORY_LIMIT", "-5"),
    ] {
        let out = command()
            .args([
                "simulate",
                model,
                "--runs",
                "4",
                "--duration",
                "5",
                "--json",
            ])
            .env(name, value)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{name}={value}: {err}");
        assert!(
            err.contains(&format!("environment variable {name}=")),
            "{err}"
        );
        assert!(!err.contains("panicked"), "{err}");
    }
    refused_with_memory(
        &[
            "simulate",
            model,
            "--runs",
            "400",
            "--duration",
            "5",
            "--json",
        ],
        "1000",
        &["the memory available"],
    );
}

/// Issue 27, item 10: a device or a pipe given as a log is read with a bound (`/dev/zero` took
/// over 3 GB within seconds).
#[cfg(target_os = "linux")]
#[test]
fn devices_and_pipes_are_read_with_a_bound() {
    let started = std::time::Instant::now();
    refused_with_memory(
        &["allan", "/dev/zero", "--rate", "100", "--json"],
        "300000000",
        &["not a regular file"],
    );
    assert!(started.elapsed().as_secs() < 30, "{:?}", started.elapsed());
}

/// Issue 27, item 10: a file of 10 GiB (sparse: it takes no disk) given as a sensor model, a
/// scenario's sensor, a noise file or a shard is refused from its size before a byte is read
/// (`simulate`, `spec`, `plan`, `merge`, `diagnose --model` allocated over 6 GB first); a device
/// given as a config is read with the same 16 MiB bound (and `/dev/zero` is refused from its first
/// block).
#[cfg(target_os = "linux")]
#[test]
fn files_beyond_their_size_bound_are_refused_before_reading() {
    let dir = tempfile::tempdir().unwrap();
    let sparse = |name: &str| {
        let p = dir.path().join(name);
        std::fs::File::create(&p)
            .unwrap()
            .set_len(10 << 30)
            .unwrap();
        p.to_str().unwrap().to_string()
    };
    let toml = sparse("big.toml");
    let yaml = sparse("big.yaml");
    let shard = sparse("shard-0-of-2.json");
    let scenario = write(
        dir.path(),
        "scenario.toml",
        b"name = \"s\"\nsensor = \"big.toml\"\n",
    );
    let log = write(dir.path(), "ok.csv", log_text(3000, "\n").as_bytes());
    let started = std::time::Instant::now();
    let too_big = ["10.0 GiB, more than the 16.0 MiB read at most"];
    for model in [&toml, &yaml] {
        refused(&["simulate", model, "--json"], &too_big);
        refused(&["spec", model, "--json"], &too_big);
        refused(&["plan", model, "--json"], &too_big);
        refused(&["diagnose", &log, "--model", model, "--json"], &too_big);
        refused(&["drift", &log, &log, "--model", model, "--json"], &too_big);
    }
    refused(
        &["simulate", &scenario, "--json"],
        &["key `sensor`", "big.toml"],
    );
    // Refused from its first block since issue 46 (item 9), before the 16 MiB bound is reached.
    refused(
        &["simulate", "/dev/zero", "--json"],
        &["not a regular file", "contains NUL bytes"],
    );
    refused_with_memory(
        &["merge", &shard, "--json"],
        "3000000000",
        &["shard-0-of-2.json", "10.0 GiB"],
    );
    // A simulate writing shards into a directory holding a 10 GiB `shard-*.json`.
    refused_with_memory(
        &[
            "simulate",
            "configs/sensors/mtx.toml",
            "--runs",
            "4",
            "--duration",
            "5",
            "--shard",
            "0/2",
            "--out",
            dir.path().to_str().unwrap(),
        ],
        "3000000000",
        &["10.0 GiB"],
    );
    assert!(started.elapsed().as_secs() < 30, "{:?}", started.elapsed());
}

/// Issue 27, item 10: a gzip log that expands more than 100 times (a "gzip bomb": 64 MiB of
/// zeros in 64 KiB) is refused while it is decompressed, after 16 MiB, not after a third of the
/// memory (a 20 GiB bomb used 7.3 GiB before it was refused).
#[test]
fn gzip_bombs_are_refused_while_decompressing() {
    use std::io::Write as _;
    let dir = tempfile::tempdir().unwrap();
    let mut gz = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::best());
    gz.write_all(b"t,gx\n").unwrap();
    let zeros = vec![b'0'; 1 << 20];
    for _ in 0..64 {
        gz.write_all(&zeros).unwrap();
    }
    let bomb = write(dir.path(), "bomb.csv.gz", &gz.finish().unwrap());
    refused(
        &["allan", &bomb, "--json"],
        &[
            "bomb.csv.gz",
            "decompresses to more than 100 times its compressed size",
            "16.0 MiB",
        ],
    );
    // A log of many rows found too large for the memory while it is decompressed.
    let mut gz = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::best());
    gz.write_all(b"t,gx,gy,gz,ax,ay,az\n").unwrap();
    for i in 0..300_000 {
        writeln!(gz, "{i},1,2,3,4,5,6").unwrap();
    }
    let rows = write(dir.path(), "rows.csv.gz", &gz.finish().unwrap());
    refused_with_memory(
        &["allan", &rows, "--json"],
        "20000000",
        &["rows x 7 columns need at least about"],
    );
}

/// Issue 27, item 10: `/dev/urandom` and a pipe that never ends, given as a log, are read with a
/// bound (a third of the memory available, here lowered) and refused past it.
#[cfg(target_os = "linux")]
#[test]
fn endless_streams_are_read_with_a_bound() {
    let dir = tempfile::tempdir().unwrap();
    let fifo = dir.path().join("fifo.csv");
    let c = std::ffi::CString::new(fifo.to_str().unwrap()).unwrap();
    // SAFETY: a NUL-terminated path; mkfifo only creates the FIFO.
    assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0);
    let writer_path = fifo.clone();
    let writer = std::thread::spawn(move || {
        use std::io::Write as _;
        let mut f = std::fs::OpenOptions::new()
            .write(true)
            .open(writer_path)
            .unwrap();
        let mut block = b"t,gx\n".to_vec();
        block.extend_from_slice(&vec![b'0'; 1 << 16]);
        // Until the reader closes the pipe (a write error: EPIPE).
        while f.write_all(&block).is_ok() {}
    });
    for path in ["/dev/urandom", fifo.to_str().unwrap()] {
        let out = command()
            .args(["allan", path, "--rate", "100", "--json"])
            .env("IMUDRIFT_MEMORY_LIMIT", "30000000")
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{path}: {err}");
        assert!(err.contains("not a regular file"), "{path}: {err}");
    }
    writer.join().unwrap();
}

/// Found by the mutation run (scripts/mutate_inputs.py): a channel of values near 1e90 (below
/// the 1e100 a log may hold) had an IEEE 952 fit with no term at all and `allan` exited 0 with
/// every coefficient null (the fit's squared weights overflowed); values near 1e-90 likewise.
#[test]
fn channels_far_from_unit_scale_get_a_fit() {
    let dir = tempfile::tempdir().unwrap();
    for scale in ["1e90", "1e-90"] {
        let mut text = String::from("t,gx\n");
        for line in log_text(3000, "\n").lines().skip(1) {
            let (t, v) = line.split_once(',').unwrap();
            text += &format!("{t},{v}e{}\n", &scale[2..]);
        }
        let log = write(dir.path(), "scaled.csv", text.as_bytes());
        let out = ok(imudrift(&["allan", &log, "--json"]));
        let json: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        let n = &json["channels"]["gx"]["fit"]["n"];
        assert!(
            n.as_f64().is_some_and(f64::is_finite),
            "{scale}: fit.n = {n}"
        );
    }
}

/// A run stopped by Ctrl-C (SIGINT) or SIGTERM removes its `--out` lock file too (issue 24:
/// no `.imudrift.lock` is left behind), and exits with 130.
#[cfg(unix)]
#[test]
fn a_signal_leaves_no_lock_file() {
    for signal in ["-INT", "-TERM"] {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("out");
        // About 3.6e10 samples of work: minutes, so the signal arrives while it runs.
        let mut child = command()
            .args(["simulate", "configs/sensors/mtx.toml", "--runs", "100000"])
            .args(["--duration", "1h", "--out", out.to_str().unwrap()])
            .stderr(std::process::Stdio::null())
            .stdout(std::process::Stdio::null())
            .spawn()
            .unwrap();
        let lock = out.join(".imudrift.lock");
        let started = std::time::Instant::now();
        while !lock.exists() && started.elapsed().as_secs() < 20 {
            std::thread::sleep(std::time::Duration::from_millis(20));
        }
        assert!(lock.exists(), "{signal}: the run never locked --out");
        std::thread::sleep(std::time::Duration::from_millis(200));
        let sent = Command::new("kill")
            .args([signal, &child.id().to_string()])
            .status()
            .unwrap();
        assert!(sent.success());
        let status = child.wait().unwrap();
        assert_eq!(status.code(), Some(130), "{signal}: {status:?}");
        let left: Vec<_> = std::fs::read_dir(&out)
            .unwrap()
            .map(|e| e.unwrap().file_name())
            .collect();
        assert!(left.is_empty(), "{signal}: left behind in --out: {left:?}");
    }
}

/// Issue 46, item 11: a full disk while `--out DIR` is written left the files written before
/// (`allan.csv` without `allan.json`). The files of a command are one set: written into
/// temporaries and moved into place only when all are complete; here the file size limit
/// (`ulimit -f 4`: 4 KiB, with SIGXFSZ ignored so the write fails with EFBIG as on a full disk)
/// lets `allan.csv` (1.2 KB) be written and not `allan.json` (4.9 KB). No new file and no
/// temporary is left; the file already in the directory is untouched.
#[cfg(target_os = "linux")]
#[test]
fn a_failed_write_leaves_no_partial_out_set() {
    let dir = tempfile::tempdir().unwrap();
    let log = write(dir.path(), "ok.csv", log_text(2000, "\n").as_bytes());
    let out = dir.path().join("out");
    std::fs::create_dir(&out).unwrap();
    std::fs::write(out.join("notes.txt"), "mine").unwrap();
    let script = format!(
        "ulimit -f 4; trap '' XFSZ; exec '{}' allan '{log}' --out '{}'",
        common::binary().display(),
        out.display()
    );
    let run = Command::new("bash")
        .args(["-c", &script])
        .current_dir(root())
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&run.stderr);
    assert_eq!(run.status.code(), Some(1), "{err}");
    assert!(err.contains("File too large"), "{err}");
    let mut left: Vec<String> = std::fs::read_dir(&out)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    left.sort();
    assert_eq!(left, ["notes.txt"], "{err}");
    assert_eq!(
        std::fs::read_to_string(out.join("notes.txt")).unwrap(),
        "mine"
    );
}

/// Issue 46, item 13: `kill -9` during `generate -o` left a hidden temporary file (460 MB) that
/// no later run removed. Temporaries are named `.imudrift-partial-<pid>-<n>-<name>`; the next run
/// writing into the directory removes those whose process is gone, and never a live run's.
#[cfg(target_os = "linux")]
#[test]
fn a_killed_run_leaves_a_temporary_the_next_run_removes() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let spawn_generate = |name: &str| {
        command()
            .args(["generate", "configs/sensors/mtx.toml", "--duration", "60h"])
            .args(["--rate", "100", "-o", d.join(name).to_str().unwrap()])
            .stderr(std::process::Stdio::null())
            .spawn()
            .unwrap()
    };
    let names = || -> Vec<String> {
        let mut v: Vec<String> = std::fs::read_dir(d)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        v.sort();
        v
    };
    let wait_for_files = |n: usize| {
        let started = std::time::Instant::now();
        while names().len() < n && started.elapsed().as_secs() < 20 {
            std::thread::sleep(std::time::Duration::from_millis(20));
        }
        assert_eq!(names().len(), n, "{:?}", names());
    };
    let mut killed = spawn_generate("big.csv");
    wait_for_files(1);
    std::thread::sleep(std::time::Duration::from_millis(300));
    killed.kill().unwrap(); // SIGKILL
    killed.wait().unwrap();
    let leftover = names();
    assert_eq!(leftover.len(), 1, "{leftover:?}");
    assert!(leftover[0] != "big.csv", "{leftover:?}");
    let short = |name: &str| {
        ok(imudrift(&[
            "generate",
            "configs/sensors/mtx.toml",
            "--duration",
            "10",
            "--rate",
            "100",
            "-o",
            d.join(name).to_str().unwrap(),
        ]))
    };
    short("big.csv");
    assert_eq!(
        names(),
        ["big.csv"],
        "the dead run's {:?} was not removed",
        leftover[0]
    );
    let text = std::fs::read_to_string(d.join("big.csv")).unwrap();
    let rows = text.lines().filter(|l| !l.starts_with('#')).count();
    assert_eq!(rows, 1 + 1000, "10 s at 100 Hz and the header");
    // A run still writing into the directory keeps its temporary.
    let mut live = spawn_generate("live.csv");
    wait_for_files(2);
    let live_tmp = names();
    short("other.csv");
    let after = names();
    live.kill().unwrap();
    live.wait().unwrap();
    let mut expected = live_tmp;
    expected.push("other.csv".to_string());
    expected.sort();
    assert_eq!(after, expected, "a live run's temporary was removed");
}

/// Issue 46, item 9: a sparse file (`truncate -s 10G`: it takes no disk) given as a log was read
/// whole before it was refused (`allan`: 10.5 GB resident, killed at 120 s; `diagnose`: "contains
/// NUL bytes" after 55 s), and `merge /dev/zero` read 7.8 GB first. Every reader now checks the
/// first block of a file (64 KiB) for NUL bytes before reading the rest: refused at once, here
/// from a 3 GiB sparse file (the test's bound of 2 s each; the old build took about 16 s for the
/// first).
#[cfg(target_os = "linux")]
#[test]
fn sparse_files_and_zeros_are_refused_from_their_first_block() {
    use std::io::Write as _;
    let dir = tempfile::tempdir().unwrap();
    let sparse = |name: &str| {
        let p = dir.path().join(name);
        std::fs::File::create(&p).unwrap().set_len(3 << 30).unwrap();
        p.to_str().unwrap().to_string()
    };
    let log = sparse("sparse.csv");
    let toml = dir.path().join("zeros.toml");
    std::fs::write(&toml, vec![0u8; 8 << 20]).unwrap();
    let toml = toml.to_str().unwrap();
    let shard = sparse("shard-0-of-1.json");
    let mut gz = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
    gz.write_all(&vec![0u8; 4 << 20]).unwrap();
    let gz = write(dir.path(), "zeros.csv.gz", &gz.finish().unwrap());
    let model = "configs/sensors/mtx.toml";
    let cases: [(&[&str], &str); 7] = [
        (&["allan", &log, "--json"], "contains NUL bytes"),
        (
            &["diagnose", &log, "--model", model, "--json"],
            "contains NUL bytes",
        ),
        (&["merge", &shard, "--json"], "contains NUL bytes"),
        (&["merge", "/dev/zero", "--json"], "contains NUL bytes"),
        (
            &["allan", "/dev/zero", "--rate", "100", "--json"],
            "contains NUL bytes",
        ),
        (&["simulate", toml, "--json"], "contains NUL bytes"),
        (
            &["allan", &gz, "--json"],
            "decompresses to a text that contains NUL bytes",
        ),
    ];
    for (args, needle) in cases {
        let started = std::time::Instant::now();
        refused(args, &[needle]);
        let took = started.elapsed();
        assert!(took.as_secs_f64() < 2.0, "{args:?} took {took:?}");
    }
}

/// Issue 46, item 9: a log too large for the memory (`IMUDRIFT_MEMORY_LIMIT`) was counted row by
/// row to its end before it was refused (61 s for 10 GiB). Its size and the rows of its first
/// MiB estimate what it needs before the rest is read: a 3 GiB file (1 MiB of rows, then a
/// sparse tail) under a 1 GB limit is refused at once.
#[cfg(target_os = "linux")]
#[test]
fn logs_too_large_for_the_memory_are_refused_from_their_size() {
    let dir = tempfile::tempdir().unwrap();
    let mut text = log_text(60_000, "\n");
    assert!(text.len() > 1 << 20);
    text.truncate(text.rfind('\n').unwrap() + 1);
    let log = write(dir.path(), "big.csv", text.as_bytes());
    std::fs::OpenOptions::new()
        .write(true)
        .open(&log)
        .unwrap()
        .set_len(3 << 30)
        .unwrap();
    let started = std::time::Instant::now();
    refused_with_memory(
        &["allan", &log, "--json"],
        "1000000000",
        &["estimated from its size, 3.00 GiB", "954 MiB is available"],
    );
    let took = started.elapsed();
    assert!(took.as_secs_f64() < 2.0, "took {took:?}");
}
