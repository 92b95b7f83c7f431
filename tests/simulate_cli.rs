//! End-to-end `imudrift simulate` / `merge`: determinism across thread counts and shard splits,
//! output files, errors naming file and key.

use std::path::Path;

mod common;
use common::{command, imudrift, ok, root};

const SCENARIO: &str = "configs/scenarios/mtx-static-60s.toml";

#[test]
fn one_and_four_threads_and_merged_shards_give_identical_json() {
    let base = [
        "simulate",
        SCENARIO,
        "--runs",
        "70",
        "--seed",
        "11",
        "--json",
        "--no-ablation",
    ];
    let one = ok(imudrift(&[&base[..], &["--threads", "1"]].concat())).stdout;
    let four = ok(imudrift(&[&base[..], &["--threads", "4"]].concat())).stdout;
    assert!(!one.is_empty());
    let text = |b: &[u8]| String::from_utf8_lossy(b).into_owned();
    assert!(
        one == four,
        "1 and 4 threads differ:\n{}\n{}",
        text(&one),
        text(&four)
    );
    let doc: serde_json::Value = serde_json::from_slice(&one).unwrap();
    assert_eq!(doc["seed"], 11);
    assert_eq!(doc["runs"], 70);
    let ch = &doc["checkpoints"][0]["channels"]["pos_horizontal_m"];
    for key in ["mean", "std", "rms", "p50", "p95", "law_std", "ratio"] {
        assert!(ch.get(key).is_some(), "missing {key}");
    }

    let dir = tempfile::tempdir().unwrap();
    let d = dir.path().to_str().unwrap();
    let mut shards = Vec::new();
    for i in 0..4 {
        let shard = format!("{i}/4");
        ok(imudrift(&[
            "simulate",
            SCENARIO,
            "--runs",
            "70",
            "--seed",
            "11",
            "--threads",
            "2",
            "--shard",
            &shard,
            "--out",
            d,
            "--no-ablation",
        ]));
        shards.push(format!("{d}/shard-{i}-of-4.json"));
    }
    let mut merge_args = vec!["merge", "--json"];
    merge_args.extend(shards.iter().map(String::as_str));
    let merged = ok(imudrift(&merge_args)).stdout;
    assert!(
        merged == one,
        "4 merged shards differ from one run:\n{}\n{}",
        text(&merged),
        text(&one)
    );
    // A missing shard is an error, not a partial result.
    let bad = imudrift(&["merge", "--json", &shards[0], &shards[1], &shards[2]]);
    assert!(!bad.status.success());
    assert!(String::from_utf8_lossy(&bad.stderr).contains("missing"));
}

#[test]
fn woodman_experiment_prints_reference_and_ablation() {
    let out = ok(imudrift(&["simulate", SCENARIO, "--runs", "40", "--json"]));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("published 152.7 m"), "{err}");
    assert!(
        err.contains("ablation") && err.contains("gyro.white_noise"),
        "{err}"
    );
    let doc: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(doc["reference"]["value"], 152.67);
    let rows = doc["ablation"].as_array().unwrap();
    assert_eq!(rows.len(), doc["active_terms"].as_array().unwrap().len());
    // Shares of independent terms add up to the whole mean square (to Monte Carlo noise: the
    // terms use their own streams, so the sum is within a few standard errors of 1 at 40 runs).
    let total: f64 = rows.iter().map(|r| r["only_share"].as_f64().unwrap()).sum();
    assert!((total - 1.0).abs() < 0.5, "{total}");
}

#[test]
fn every_shipped_scenario_runs() {
    let dir = root().join("configs/scenarios");
    let mut n = 0;
    for entry in std::fs::read_dir(&dir).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().and_then(|e| e.to_str()) == Some("toml") {
            let p = path.to_str().unwrap();
            let out = ok(imudrift(&[
                "simulate",
                p,
                "--runs",
                "2",
                "--no-ablation",
                "--json",
            ]));
            let doc: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
            assert_eq!(doc["runs_ok"], 2, "{p}");
            n += 1;
        }
    }
    assert!(n >= 4, "only {n} scenarios");
}

#[test]
fn moving_profile_says_no_law_instead_of_a_number() {
    let out = ok(imudrift(&[
        "simulate",
        "configs/scenarios/mtx-turns-60s.toml",
        "--runs",
        "6",
        "--json",
    ]));
    let doc: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let last = doc["checkpoints"]
        .as_array()
        .unwrap()
        .last()
        .unwrap()
        .clone();
    for ch in ["pos_horizontal_m", "yaw_rad", "pos_north_m"] {
        let c = &last["channels"][ch];
        assert!(c["ratio"].is_null() && c["law_std"].is_null(), "{ch}: {c}");
        assert!(
            c["law_note"].as_str().unwrap().contains("motion"),
            "{ch}: {c}"
        );
    }
}

#[test]
fn out_dir_gets_csv_json_svg() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path().to_str().unwrap();
    ok(imudrift(&[
        "simulate",
        SCENARIO,
        "--runs",
        "8",
        "--out",
        d,
        "--only",
        "gyro.white_noise",
    ]));
    for f in ["drift.json", "drift.csv", "drift.svg"] {
        let p = Path::new(d).join(f);
        let text = std::fs::read_to_string(&p).unwrap();
        assert!(text.len() > 100, "{f} too short");
    }
    let csv = std::fs::read_to_string(Path::new(d).join("drift.csv")).unwrap();
    assert!(csv.lines().nth(1).unwrap().starts_with("t_s,channel,mean"));
    // The heading is `heading_rad` as in every command (issue 45 item 6), its row repeated under
    // the older `yaw_rad` with the same numbers.
    let rest = |name: &str| -> Vec<String> {
        csv.lines()
            .filter(|l| l.split(',').nth(1) == Some(name))
            .map(|l| l.split_once(name).unwrap().1.to_string())
            .collect()
    };
    let (heading, yaw) = (rest("heading_rad"), rest("yaw_rad"));
    assert!(!heading.is_empty() && heading == yaw, "{csv}");
    let svg = std::fs::read_to_string(Path::new(d).join("drift.svg")).unwrap();
    assert!(svg.contains("<svg") && svg.contains("law rms") && svg.contains("p5-p95"));
    let doc: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(Path::new(d).join("drift.json")).unwrap())
            .unwrap();
    assert_eq!(doc["active_terms"], serde_json::json!(["gyro.white_noise"]));
}

#[test]
fn bad_inputs_name_file_and_key() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("bad.toml");
    std::fs::write(
        &p,
        "sensor = \"x.toml\"\nduration_s = 1.0\nrate_hz = 0.0\nruns = 3\nseed = 1\n",
    )
    .unwrap();
    let out = imudrift(&["simulate", p.to_str().unwrap()]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("bad.toml") && err.contains("rate_hz"), "{err}");
    let out = imudrift(&["simulate", SCENARIO, "--runs", "100000000000"]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("--shard"));
    let out = imudrift(&["simulate", SCENARIO, "--only", "gyro.whitenoise"]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("whitenoise"));
    let out = imudrift(&[
        "simulate",
        SCENARIO,
        "--shard",
        "4/4",
        "--out",
        dir.path().to_str().unwrap(),
    ]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("--shard"));
}

/// A sensor TOML alone runs with the default static scenario; `--duration` and `--rate` shape it;
/// the JSON has the contract fields and every law-bearing channel beside its law; the result is
/// the same as an explicit minimal scenario that names only the sensor (every other key defaults).
#[test]
fn a_sensor_toml_runs_with_the_default_static_scenario() {
    let args = [
        "simulate",
        "configs/sensors/mtx.toml",
        "--duration",
        "1 min",
        "--rate",
        "50",
        "--runs",
        "40",
        "--json",
    ];
    let out = ok(imudrift(&args));
    let doc: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(doc["runs"], 40);
    assert_eq!(doc["seed"], 1, "default seed");
    let last = doc["checkpoints"]
        .as_array()
        .unwrap()
        .last()
        .unwrap()
        .clone();
    assert_eq!(last["t_s"], 60.0);
    let h = &last["channels"]["pos_horizontal_m"];
    assert!(h["law_std"].as_f64().unwrap() > 0.0 && h["ratio"].as_f64().is_some());
    // The same through a scenario file that gives only the sensor (and the two edited keys).
    let dir = tempfile::tempdir().unwrap();
    let scenario = dir.path().join("minimal.toml");
    let sensor = root().join("configs/sensors/mtx.toml");
    std::fs::write(
        &scenario,
        format!(
            "sensor = {:?}\nduration_s = 60.0\nrate_hz = 50.0\n",
            sensor.display().to_string()
        ),
    )
    .unwrap();
    let explicit = ok(imudrift(&[
        "simulate",
        scenario.to_str().unwrap(),
        "--runs",
        "40",
        "--json",
    ]));
    let e: serde_json::Value = serde_json::from_slice(&explicit.stdout).unwrap();
    assert_eq!(e["checkpoints"], doc["checkpoints"]);
    // A scenario without a sensor says what is missing and how to give it.
    std::fs::write(&scenario, "runs = 10\n").unwrap();
    let out = imudrift(&["simulate", scenario.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("key `sensor`") && err.contains("sensor = "),
        "{err}"
    );
}

/// The ablation table survives sharding: `merge` of k shards gives the single run's JSON (with
/// its ablation rows) and the same --out files, byte for byte.
#[test]
fn merged_shards_carry_the_ablation_table() {
    let dir = tempfile::tempdir().unwrap();
    let single_out = dir.path().join("single");
    let base = [
        "simulate", SCENARIO, "--runs", "24", "--seed", "5", "--json",
    ];
    let single = ok(imudrift(
        &[&base[..], &["--out", single_out.to_str().unwrap()]].concat(),
    ))
    .stdout;
    let doc: serde_json::Value = serde_json::from_slice(&single).unwrap();
    let rows = doc["ablation"]
        .as_array()
        .expect("the scenario asks for ablation");
    assert!(rows.len() >= 3, "{rows:?}");
    let shard_dir = dir.path().join("shards");
    let mut merge_args = vec!["merge".to_string(), "--json".to_string()];
    for i in 0..3 {
        ok(imudrift(&[
            "simulate",
            SCENARIO,
            "--runs",
            "24",
            "--seed",
            "5",
            "--shard",
            &format!("{i}/3"),
            "--out",
            shard_dir.to_str().unwrap(),
        ]));
        merge_args.push(format!("{}/shard-{i}-of-3.json", shard_dir.display()));
    }
    let merged_out = dir.path().join("merged");
    merge_args.extend(["--out".to_string(), merged_out.display().to_string()]);
    let args: Vec<&str> = merge_args.iter().map(String::as_str).collect();
    let merged = ok(imudrift(&args)).stdout;
    assert!(merged == single, "merge differs from the single run");
    for f in ["drift.json", "drift.csv", "drift.svg"] {
        let a = std::fs::read(single_out.join(f)).unwrap();
        let b = std::fs::read(merged_out.join(f)).unwrap();
        assert!(a == b, "{f} differs");
    }
    // A shard without the ablation cannot be merged with shards that have it.
    ok(imudrift(&[
        "simulate",
        SCENARIO,
        "--runs",
        "24",
        "--seed",
        "5",
        "--shard",
        "2/3",
        "--no-ablation",
        "--out",
        dir.path().join("plain").to_str().unwrap(),
    ]));
    let mut mixed: Vec<String> = merge_args[2..4].to_vec();
    mixed.push(format!("{}/plain/shard-2-of-3.json", dir.path().display()));
    let mut args = vec!["merge"];
    args.extend(mixed.iter().map(String::as_str));
    let out = imudrift(&args);
    assert_eq!(out.status.code(), Some(1));
}

/// Progress reaches a log that is not a terminal: plain lines on stderr (never stdout).
#[test]
fn progress_lines_when_stderr_is_not_a_terminal() {
    let out = ok(command()
        .args([
            "simulate",
            SCENARIO,
            "--runs",
            "200",
            "--no-ablation",
            "--json",
        ])
        .env("IMUDRIFT_PROGRESS_INTERVAL_S", "0")
        .output()
        .unwrap());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.lines()
            .any(|l| l.starts_with("simulate: ") && l.contains(" runs (")),
        "{err}"
    );
    serde_json::from_slice::<serde_json::Value>(&out.stdout).expect("stdout is only the JSON");
}
