//! End-to-end tests of `imudrift generate`: bytes are a function of the seed only (not of the thread
//! count), the CSV holds the library's values exactly, term switches work, and bad input gives an
//! error naming the file and key without leaving an output file.

use nalgebra::Vector3;
use noise::{ImuErrors, Sensor, TermFilter, TermSelector};
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

mod common;
use common::{command, ok, root};

fn mtx() -> PathBuf {
    root().join("configs/sensors/mtx.toml")
}

fn generate(args: &[&str]) -> Output {
    command()
        .arg("generate")
        .args(args)
        .output()
        .expect("run imudrift")
}

fn path_str(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// `imudrift generate configs/sensors/mtx.toml --duration SECONDS --rate 100 -o OUT EXTRA...`, which must succeed.
fn mtx_100hz(out: &Path, seconds: &str, extra: &[&str]) -> Output {
    let cfg = mtx();
    let mut args = vec![
        path_str(&cfg),
        "--duration",
        seconds,
        "--rate",
        "100",
        "-o",
        path_str(out),
    ];
    args.extend_from_slice(extra);
    ok(generate(&args))
}

/// 70 000 samples: more than two generation blocks.
const SECONDS: &str = "700";

#[test]
fn same_seed_same_bytes_for_any_thread_count() {
    let dir = tempfile::tempdir().unwrap();
    let run = |name: &str, seed: &str, threads: &str| {
        let p = dir.path().join(name);
        mtx_100hz(&p, SECONDS, &["--seed", seed, "--threads", threads]);
        std::fs::read(p).unwrap()
    };
    let a = run("a.csv", "5", "1");
    let b = run("b.csv", "5", "2");
    let c = run("c.csv", "5", "3");
    let d = run("d.csv", "6", "2");
    assert_eq!(a, b, "1 vs 2 threads");
    assert_eq!(a, c, "1 vs 3 threads");
    assert_ne!(a, d, "seeds 5 and 6 gave the same log");
}

fn read_csv(path: &Path) -> (Vec<String>, Vec<Vec<f64>>) {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines().filter(|l| !l.starts_with('#'));
    let header = lines.next().unwrap().split(',').map(String::from).collect();
    let rows = lines
        .map(|l| l.split(',').map(|v| v.parse::<f64>().unwrap()).collect())
        .collect();
    (header, rows)
}

#[test]
fn csv_holds_the_library_values_exactly() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("log.csv");
    let out = mtx_100hz(&p, SECONDS, &["--seed", "11", "--json"]);
    let doc: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(doc["seed"], 11);
    assert_eq!(doc["samples"], 70_000);
    let text = std::fs::read_to_string(&p).unwrap();
    assert!(text.starts_with("# imudrift generate: sensor \"Xsens MTx\""));
    assert!(text.lines().next().unwrap().contains("seed 11"));
    let (header, rows) = read_csv(&p);
    assert_eq!(header, ["t", "gx", "gy", "gz", "ax", "ay", "az", "temp"]);
    assert_eq!(rows.len(), 70_000);

    let model = imudrift::files::sensor_model(&mtx()).unwrap();
    let mut errors = ImuErrors::new(&model, 0.01, 11, 0);
    let level = noise::StaticLevel::STANDARD;
    let (w, f) = (level.triad(Sensor::Gyro), level.triad(Sensor::Accel));
    let mut az_sum = 0.0;
    for (k, row) in rows.iter().enumerate() {
        assert_eq!(row[0], k as f64 / 100.0);
        let (g, a) = errors.corrupt(k as u64, &w, &f);
        for i in 0..3 {
            assert_eq!(row[1 + i].to_bits(), g[i].to_bits(), "row {k} gyro {i}");
            assert_eq!(row[4 + i].to_bits(), a[i].to_bits(), "row {k} accel {i}");
        }
        assert_eq!(row[7], 25.0);
        az_sum += row[6];
    }
    // Gravity on the accelerometers: the mean of az is -g within 6 standard errors of the white noise
    // (0.004 m/s^2/sqrt(Hz) over 700 s: 1.5e-4 m/s^2).
    let az_mean = az_sum / rows.len() as f64;
    assert!(
        (az_mean + 9.80665).abs() < 6.0 * 0.004 / 700f64.sqrt(),
        "{az_mean}"
    );
}

#[test]
fn only_and_without_switch_terms() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("only.csv");
    mtx_100hz(&p, "10", &["--only", "gyro.white_noise"]);
    let (_, rows) = read_csv(&p);
    for row in &rows {
        assert_eq!(&row[4..7], &[0.0, 0.0, -9.80665]);
    }
    // The gyro columns are the white-noise stream alone: the same bits as the library with that filter.
    let filter = TermFilter::new(
        Some(&[TermSelector::parse("gyro.white_noise").unwrap()]),
        &[],
    );
    let model = imudrift::files::sensor_model(&mtx())
        .unwrap()
        .filtered(&filter);
    let mut errors = ImuErrors::new(&model, 0.01, 1, 0);
    for (k, row) in rows.iter().enumerate() {
        let (g, _) = errors.corrupt(k as u64, &Vector3::zeros(), &Vector3::zeros());
        assert_eq!(row[1].to_bits(), g.x.to_bits());
    }

    let p = dir.path().join("without.csv");
    mtx_100hz(&p, "10", &["--without", "gyro,accel.white_noise"]);
    let (_, rows) = read_csv(&p);
    for row in &rows {
        assert_eq!(&row[1..7], &[0.0, 0.0, 0.0, 0.0, 0.0, -9.80665]);
    }
}

fn fails_with(args: &[&str], needles: &[&str]) {
    let out = generate(args);
    assert!(!out.status.success(), "expected failure for {args:?}");
    let err = String::from_utf8_lossy(&out.stderr);
    for n in needles {
        assert!(err.contains(n), "stderr lacks `{n}`: {err}");
    }
    assert!(!err.contains("panicked"), "{err}");
}

#[test]
fn bad_input_names_the_place_and_leaves_no_file() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out.csv");
    let o = path_str(&out);
    let write = |name: &str, text: &str| {
        let p = dir.path().join(name);
        std::fs::write(&p, text).unwrap();
        p
    };
    let unknown = write(
        "unknown.toml",
        "name = \"x\"\n[gyro.x]\nwhite_nosie = \"1 deg/sqrt(h)\"\n",
    );
    fails_with(
        &[
            path_str(&unknown),
            "--duration",
            "1",
            "--rate",
            "100",
            "-o",
            o,
        ],
        &["unknown.toml", "white_nosie"],
    );
    let unit = write(
        "unit.toml",
        "name = \"x\"\n[accel.all]\nwhite_noise = \"0.004 deg/s\"\n",
    );
    fails_with(
        &[path_str(&unit), "--duration", "1", "--rate", "100", "-o", o],
        &["unit.toml", "accel.all.white_noise", "m/s^2/sqrt(Hz)"],
    );
    let negative = write(
        "neg.toml",
        "name = \"x\"\n[gyro.z]\nrate_random_walk = \"-1 deg/h/sqrt(h)\"\n",
    );
    fails_with(
        &[
            path_str(&negative),
            "--duration",
            "1",
            "--rate",
            "100",
            "-o",
            o,
        ],
        &["neg.toml", "gyro.z.rate_random_walk", ">= 0"],
    );
    fails_with(
        &[
            path_str(&mtx()),
            "--duration",
            "1",
            "--rate",
            "100",
            "-o",
            o,
            "--only",
            "gyro.wite_noise",
        ],
        &["--only", "wite_noise"],
    );
    fails_with(
        &[
            path_str(&mtx()),
            "--duration",
            "-5",
            "--rate",
            "100",
            "-o",
            o,
        ],
        &["--duration"],
    );
    fails_with(
        &[
            path_str(&mtx()),
            "--duration",
            "1",
            "--rate",
            "NaN",
            "-o",
            o,
        ],
        &["--rate"],
    );
    fails_with(
        &[
            path_str(&dir.path().join("missing.toml")),
            "--duration",
            "1",
            "--rate",
            "100",
            "-o",
            o,
        ],
        &["missing.toml"],
    );
    assert!(!out.exists(), "an output file was left behind");
    // An unwritable destination: error, nothing left in the directory.
    fails_with(
        &[
            path_str(&mtx()),
            "--duration",
            "1",
            "--rate",
            "100",
            "-o",
            path_str(&dir.path().join("no/such/dir/x.csv")),
        ],
        &["no/such/dir"],
    );
    let left: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().to_string())
        .filter(|n| !n.ends_with(".toml"))
        .collect();
    assert!(left.is_empty(), "left behind: {left:?}");
}

/// A FIFO (like /dev/null or /dev/stdout) is written into, not replaced by a regular file.
#[cfg(unix)]
#[test]
fn special_files_are_written_not_replaced() {
    use std::os::unix::fs::FileTypeExt;
    let dir = tempfile::tempdir().unwrap();
    let fifo = dir.path().join("pipe");
    let made = Command::new("mkfifo").arg(&fifo).status();
    if !made.is_ok_and(|s| s.success()) {
        eprintln!("mkfifo not available: skipped");
        return;
    }
    let reader = {
        let fifo = fifo.clone();
        std::thread::spawn(move || std::fs::read(fifo).unwrap().len())
    };
    mtx_100hz(&fifo, "10", &[]);
    let bytes = reader.join().unwrap();
    assert!(bytes > 100_000, "{bytes} bytes through the FIFO");
    assert!(std::fs::metadata(&fifo).unwrap().file_type().is_fifo());
}

#[test]
fn temperature_column_and_bias_follow_the_profile() {
    let dir = tempfile::tempdir().unwrap();
    let cfg = dir.path().join("warm.toml");
    std::fs::write(
        &cfg,
        "name = \"warm\"\n[temperature]\nprofile = \"warmup\"\nstart = \"20 degC\"\nend = \"40 degC\"\ntime_constant = \"5 s\"\nreference = \"25 degC\"\n[gyro.z]\ntemperature_bias = \"0.01 rad/s/degC\"\n",
    )
    .unwrap();
    let p = dir.path().join("log.csv");
    ok(generate(&[
        path_str(&cfg),
        "--duration",
        "30",
        "--rate",
        "10",
        "-o",
        path_str(&p),
    ]));
    let (_, rows) = read_csv(&p);
    for row in &rows {
        let t = row[0];
        let temp = 40.0 + (20.0 - 40.0) * (-t / 5.0).exp();
        assert!(
            (row[7] - temp).abs() < 1e-12,
            "t {t}: temp {} vs {temp}",
            row[7]
        );
        assert!(
            (row[3] - 0.01 * (temp - 25.0)).abs() < 1e-12,
            "t {t}: gz {}",
            row[3]
        );
        assert_eq!(row[1], 0.0);
    }
}

#[test]
fn runs_differ_and_repeat() {
    let dir = tempfile::tempdir().unwrap();
    let run = |name: &str, run: &str| {
        let p = dir.path().join(name);
        mtx_100hz(&p, "5", &["--run", run]);
        read_csv(&p).1
    };
    assert_eq!(run("a.csv", "3"), run("b.csv", "3"));
    assert_ne!(run("c.csv", "3"), run("d.csv", "4"));
}
