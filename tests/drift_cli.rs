//! `imudrift drift`: the JSON contract, pooled logs, channels a log cannot inform, determinism.

mod common;
use common::imudrift;

const MODEL: &str = r#"
name = "drift-cli"
[gyro.all]
white_noise = "0.5 deg/sqrt(h)"
bias_instability = "10 deg/h"
[accel.all]
white_noise = "100 ug/sqrt(Hz)"
"#;

fn generate(dir: &std::path::Path, name: &str, seed: &str) -> String {
    let model = dir.join("m.toml");
    std::fs::write(&model, MODEL).unwrap();
    let log = dir.join(name);
    common::ok(imudrift(&[
        "generate",
        model.to_str().unwrap(),
        "--duration",
        "10min",
        "--rate",
        "50",
        "--seed",
        seed,
        "-o",
        log.to_str().unwrap(),
    ]));
    log.to_str().unwrap().to_string()
}

#[test]
fn json_contract_pooling_and_verdicts() {
    let dir = tempfile::tempdir().unwrap();
    let a = generate(dir.path(), "a.csv", "11");
    let b = generate(dir.path(), "b.csv", "12");
    let model = dir.path().join("m.toml");
    let run = |threads: &str| {
        common::ok(imudrift(&[
            "drift",
            &a,
            &b,
            "--model",
            model.to_str().unwrap(),
            "--horizons",
            "10,60,1h",
            "--calibration",
            "window:20s",
            "--init",
            "level:20s",
            "--replicates",
            "20",
            "--json",
            "--threads",
            threads,
        ]))
    };
    let out = run("2");
    let doc: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(doc["protocol"]["calibration"]["kind"], "window");
    assert_eq!(doc["protocol"]["initialisation"]["kind"], "levelled");
    assert_eq!(doc["logs"].as_array().unwrap().len(), 2);
    let h = &doc["horizons"][0];
    assert_eq!(h["t_s"], 10.0);
    // Two 10 min logs, 20 s lead, 10 s segments: 58 each.
    assert_eq!(h["segments"], 116);
    for q in [
        "heading_rad",
        "roll_rad",
        "pitch_rad",
        "pos_horizontal_m",
        "vel_horizontal_mps",
    ] {
        let c = &h["channels"][q];
        for k in ["p50", "p95", "rms", "rms_lo", "rms_hi"] {
            assert!(c["measured"][k].as_f64().unwrap() > 0.0, "{q} measured {k}");
        }
        for k in ["p50", "p95", "rms", "band_lo", "band_hi"] {
            assert!(c["model"][k].as_f64().unwrap() > 0.0, "{q} model {k}");
        }
        let m = &c["measured"];
        assert!(
            m["rms_lo"].as_f64() < m["rms"].as_f64() && m["rms"].as_f64() < m["rms_hi"].as_f64()
        );
        let verdict = c["verdict"].as_str().unwrap();
        assert!(["inside", "above", "below"].contains(&verdict));
        // Outside the band the likely cause is named, inside it is not.
        assert_eq!(
            c["likely_cause"].is_string(),
            verdict != "inside",
            "{q}: {c}"
        );
    }
    // A horizon longer than the logs is not informed, with the reason.
    let long = &doc["horizons"][2]["channels"]["heading_rad"];
    assert_eq!(long["verdict"], "not_informed");
    assert!(long["note"].as_str().unwrap().contains("3600 s"));
    // Every informed cell judged together: the count outside is the verdicts', the p-value a
    // Monte Carlo rank among the 21 members (docs/drift.md, "Every cell at once").
    let j = &doc["joint"];
    assert_eq!(j["cells"], 10, "{j}");
    let outside = doc["horizons"]
        .as_array()
        .unwrap()
        .iter()
        .flat_map(|h| h["channels"].as_object().unwrap().values())
        .filter(|c| c["verdict"] == "above" || c["verdict"] == "below")
        .count();
    assert_eq!(j["outside"], outside as u64, "{j}");
    let p = j["p_value"].as_f64().unwrap();
    assert!((1.0 / 21.0 - 1e-12..=1.0).contains(&p), "{j}");
    assert_eq!(j["consistent"], p >= 0.05, "{j}");
    assert!(
        [10.0, 60.0].contains(&j["worst"]["t_s"].as_f64().unwrap()),
        "{j}"
    );
    // Same seed, other thread count: the same bytes.
    assert_eq!(out.stdout, run("1").stdout);
}

#[test]
fn channels_a_log_lacks_are_not_informed() {
    let dir = tempfile::tempdir().unwrap();
    // A gyro-x-only log (like the MTi-G one): roll is informed, nothing else.
    let mut text = String::from("gx\n");
    let mut s = 1u64;
    for _ in 0..30_000 {
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        text += &format!(
            "{:e}\n",
            ((s >> 11) as f64 / (1u64 << 53) as f64 - 0.5) * 1e-3
        );
    }
    let log = dir.path().join("gx.csv");
    std::fs::write(&log, text).unwrap();
    let model = dir.path().join("m.toml");
    std::fs::write(&model, MODEL).unwrap();
    let out = common::ok(imudrift(&[
        "drift",
        log.to_str().unwrap(),
        "--model",
        model.to_str().unwrap(),
        "--rate",
        "100",
        "--horizons",
        "10",
        "--replicates",
        "10",
        "--json",
    ]));
    let doc: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let c = &doc["horizons"][0]["channels"];
    assert_ne!(c["roll_rad"]["verdict"], "not_informed");
    for q in [
        "heading_rad",
        "pitch_rad",
        "pos_horizontal_m",
        "vel_horizontal_mps",
    ] {
        assert_eq!(c[q]["verdict"], "not_informed", "{q}");
        assert!(c[q]["note"].as_str().unwrap().contains("lack"), "{q}");
    }
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("not informed (the logs lack gz)"), "{err}");
}

#[test]
fn bad_protocols_are_refused_with_the_option_named() {
    for (flag, value, needle) in [
        ("--calibration", "median", "'median' for '--calibration"),
        ("--init", "level:soon", "--init"),
        ("--horizons", "0", "--horizons"),
        ("--replicates", "3", "--replicates 3"),
    ] {
        let out = imudrift(&[
            "drift",
            "x.csv",
            "--model",
            "configs/sensors/mtx.toml",
            flag,
            value,
        ]);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{flag}: {err}");
        assert!(err.contains(needle), "{flag}: {err}");
    }
}

/// A `[fitted_on]` spread entry that names a term the model lacks, or a value of the wrong type, is
/// refused naming the file, the table and the term or the line; `--exact-parameters` skips it.
#[test]
fn bad_spread_entries_are_refused_with_the_file_and_place_named() {
    let dir = tempfile::tempdir().unwrap();
    let a = generate(dir.path(), "a.csv", "31");
    let head = "\n[fitted_on]\nsample_interval_s = 0.02\nsamples = [30000, 30000]\nchannels = [\"gx\", \"gy\", \"gz\", \"ax\", \"ay\", \"az\"]\ntau_min_s = 0.0\nrun_to_run = [\n";
    for (entry, needle) in [
        (
            "    { channel = \"gy\", effects = [\"rate_random_walk\"], runs = 2, variance = 0.1, null_variance = 0.1 },\n",
            "\"rate_random_walk\"",
        ),
        (
            "    { channel = \"gy\", effects = [\"white_noise\"], runs = \"two\", variance = 0.1, null_variance = 0.1 },\n",
            "line",
        ),
    ] {
        let model = dir.path().join("spread.toml");
        let text = format!("{MODEL}{head}{entry}]\n");
        std::fs::write(&model, &text).unwrap();
        let line = text.lines().position(|l| l.contains("\"two\"")).map(|i| i + 1);
        let needle = match line {
            Some(l) => format!("line {l}:"),
            None => needle.to_string(),
        };
        let run = |extra: &[&str]| {
            let mut args = vec!["drift", &a, "--model", model.to_str().unwrap()];
            args.extend_from_slice(&["--horizons", "10", "--replicates", "10"]);
            args.extend_from_slice(extra);
            imudrift(&args)
        };
        let out = run(&[]);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{err}");
        assert!(err.contains("spread.toml") && err.contains("[fitted_on]"), "{err}");
        assert!(err.contains(&needle), "{needle} in {err}");
        common::ok(run(&["--exact-parameters"]));
    }
}

/// A model with `[[alternatives]]` (as `diagnose` writes them): the band is averaged over its
/// structures, the JSON says how (`structures[]`, the model's own first, replicates adding up),
/// `--one-structure` takes the model's own alone (no `structures`), and a broken entry is refused
/// naming the file, the entry and the key.
#[test]
fn alternatives_are_averaged_unless_one_structure_is_asked() {
    let dir = tempfile::tempdir().unwrap();
    let a = generate(dir.path(), "a.csv", "13");
    let with_alt = dir.path().join("alt.toml");
    let alternative = "\n[[alternatives]]\nchannel = \"gz\"\nweight = 0.25\ndelta_bic = 2.2\n\
         effects = [\"rate_random_walk\"]\nremoved = []\n[alternatives.terms]\n\
         white_noise = \"0.5 deg/sqrt(h)\"\nbias_instability = \"10 deg/h\"\n\
         rate_random_walk = \"30 deg/h/sqrt(h)\"\n";
    std::fs::write(&with_alt, format!("{MODEL}{alternative}")).unwrap();
    let run = |extra: &[&str], model: &std::path::Path| {
        let mut args = vec![
            "drift",
            a.as_str(),
            "--model",
            model.to_str().unwrap(),
            "--horizons",
            "60",
            "--replicates",
            "20",
            "--json",
        ];
        args.extend_from_slice(extra);
        imudrift(&args)
    };
    let out = common::ok(run(&[], &with_alt));
    let doc: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let s = doc["structures"].as_array().unwrap();
    assert_eq!(s.len(), 2);
    assert_eq!(s[0]["label"], "as fitted");
    assert_eq!(s[1]["label"], "gz: rate_random_walk");
    assert_eq!(
        s[0]["replicates"].as_u64().unwrap() + s[1]["replicates"].as_u64().unwrap(),
        20
    );
    assert!((s[1]["weight"].as_f64().unwrap() - 0.25).abs() < 1e-12);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("averages over the structures"), "{err}");
    let one = common::ok(run(&["--one-structure"], &with_alt));
    let doc: serde_json::Value = serde_json::from_slice(&one.stdout).unwrap();
    assert!(doc.get("structures").is_none());
    // --one-structure is the model without the table, byte for byte.
    let plain = dir.path().join("m.toml");
    let plain_doc: serde_json::Value =
        serde_json::from_slice(&common::ok(run(&[], &plain)).stdout).unwrap();
    let mut one_doc = doc.clone();
    one_doc["model"] = plain_doc["model"].clone();
    assert_eq!(one_doc, plain_doc);
    let bad = dir.path().join("bad.toml");
    std::fs::write(
        &bad,
        format!(
            "{MODEL}{}",
            alternative.replace("weight = 0.25", "weight = 2")
        ),
    )
    .unwrap();
    let out = run(&[], &bad);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("bad.toml") && err.contains("entry 1") && err.contains("weight"),
        "{err}"
    );
    // An alternative whose output filter cannot run at the log's rate (40 Hz cutoff, 50 Hz log):
    // refused naming the structure, no panic.
    let filt = dir.path().join("filter.toml");
    let with_filter = alternative.replace(
        "white_noise = \"0.5 deg/sqrt(h)\"\n",
        "white_noise = \"0.5 deg/sqrt(h)\"\noutput_filter = { kind = \"lowpass1\", cutoff = \"40 Hz\", decimation = 1 }\n",
    );
    assert_ne!(with_filter, alternative);
    std::fs::write(&filt, format!("{MODEL}{with_filter}")).unwrap();
    let out = run(&[], &filt);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(
        err.contains("[[alternatives]] structure \"gz: ") && err.contains("gyro.z"),
        "{err}"
    );
}

/// `drift --out` writes the table as drift.csv beside drift.json (issue 45 item 6), and the model
/// levels a `[fitted_on]` model's band draws are printed in spec-sheet units, as `diagnose`
/// writes them (they were bare SI numbers: "white_noise n 0.000145 [...]"); a run-to-run spread
/// the table records is drawn per experiment and listed.
#[test]
fn out_writes_the_table_as_csv_and_levels_in_sheet_units() {
    let dir = tempfile::tempdir().unwrap();
    let a = generate(dir.path(), "a.csv", "21");
    let model = dir.path().join("fitted.toml");
    std::fs::write(
        &model,
        format!(
            "{MODEL}\n[fitted_on]\nsample_interval_s = 0.02\nsamples = [30000]\nchannels = [\"gx\", \"gy\", \"gz\", \"ax\", \"ay\", \"az\"]\ntau_min_s = 0.0\nrun_to_run = [\n    {{ channel = \"gy\", effects = [\"white_noise\"], runs = 4, variance = 0.02, null_variance = 0.01 }},\n]\n"
        ),
    )
    .unwrap();
    let out = dir.path().join("out");
    let o = common::ok(imudrift(&[
        "drift",
        &a,
        "--model",
        model.to_str().unwrap(),
        "--horizons",
        "10,60",
        "--replicates",
        "10",
        "--out",
        out.to_str().unwrap(),
    ]));
    let text = String::from_utf8(o.stdout).unwrap();
    let levels: Vec<&str> = text
        .lines()
        .skip_while(|l| !l.starts_with("model levels"))
        .skip(1)
        .take_while(|l| l.starts_with("  "))
        .collect();
    assert!(!levels.is_empty(), "{text}");
    let gx = levels
        .iter()
        .find(|l| l.trim_start().starts_with("gx:"))
        .unwrap();
    // 0.5 deg/sqrt(h) and 10 deg/h as the model says them.
    assert!(
        gx.contains("n = 0.5 deg/sqrt(h)") || gx.contains("n = 0.500 deg/sqrt(h)"),
        "{gx}"
    );
    assert!(gx.contains("deg/h"), "{gx}");
    let ax = levels
        .iter()
        .find(|l| l.trim_start().starts_with("ax:"))
        .unwrap();
    assert!(
        ax.contains("ug/sqrt(Hz)") || ax.contains("m/s/sqrt(h)"),
        "{ax}"
    );
    let csv = std::fs::read_to_string(out.join("drift.csv")).expect("drift.csv");
    let doc: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("drift.json")).unwrap()).unwrap();
    // The spread [fitted_on] records is drawn per experiment: listed in the text and the JSON.
    let spread = text
        .lines()
        .skip_while(|l| !l.starts_with("run-to-run spreads"))
        .nth(1)
        .unwrap_or_else(|| panic!("no spread line in {text}"));
    assert!(
        spread.starts_with("  gy white_noise: 0 as fitted, drawn ["),
        "{spread}"
    );
    let drawn = &doc["parameters"]["run_to_run"][0];
    assert_eq!(drawn["channel"], "gy", "{drawn}");
    assert!(drawn["p97_5"].as_f64().unwrap() > 0.0, "{drawn}");
    let head: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
    assert_eq!(&head[..3], &["t_s", "segments", "quantity"]);
    // 2 horizons x 5 quantities; each row's measured rms is the JSON's.
    assert_eq!(csv.lines().count(), 1 + 2 * 5, "{csv}");
    let col = |n: &str| head.iter().position(|h| *h == n).unwrap();
    for row in csv.lines().skip(1) {
        let f: Vec<&str> = row.split(',').collect();
        let t: f64 = f[col("t_s")].parse().unwrap();
        let h = doc["horizons"]
            .as_array()
            .unwrap()
            .iter()
            .find(|h| h["t_s"].as_f64() == Some(t))
            .unwrap();
        let c = &h["channels"][f[col("quantity")]];
        assert_eq!(f[col("verdict")], c["verdict"].as_str().unwrap(), "{row}");
        if let Some(rms) = c["measured"]["rms"].as_f64() {
            assert_eq!(f[col("measured_rms")].parse::<f64>().unwrap(), rms, "{row}");
        }
    }
}
