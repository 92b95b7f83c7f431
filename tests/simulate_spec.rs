//! `imudrift spec configs/sensors/mtx.toml` reproduces Woodman's Table 4 (docs/model.md §1.4): the ARW
//! and bias instability read back from a simulated 12 h, 100 Hz static log (Woodman's method)
//! contain the table's values inside the readback's 99 % interval, per axis. Six intervals at 99 %:
//! family-wise false-positive rate ~6 % for a fresh seed (10 seeds tried after the level was fixed:
//! 9 cover all six values); the seed is fixed (1, the default), so the test is deterministic.

mod common;
use common::command;

/// Run `imudrift spec ARGS... --json` in the workspace root; stdout on success.
fn spec_json(args: &[&str]) -> Vec<u8> {
    let out = command()
        .arg("spec")
        .args(args)
        .arg("--json")
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    out.stdout
}

#[test]
fn mtx_spec_reproduces_woodman_table_4() {
    let stdout = spec_json(&[
        "configs/sensors/mtx.toml",
        "--readback",
        "--runs",
        "20",
        "--times",
        "60",
    ]);
    let doc: serde_json::Value = serde_json::from_slice(&stdout).unwrap();
    let g = &doc["sensors"][0]["gyro"];
    // Table 4: ARW deg/sqrt(s) and bias instability (Allan minimum) deg/s, axes x, y, z.
    let arw = [0.075, 0.078, 0.079];
    let bi = [0.010, 0.009, 0.012];
    for a in 0..3 {
        let get = |k: &str| {
            g[k][a]
                .as_f64()
                .unwrap_or_else(|| panic!("{k}[{a}] is null: {g}"))
                .to_degrees()
        };
        assert!(
            get("arw_sim_lo") <= arw[a] && arw[a] <= get("arw_sim_hi"),
            "ARW axis {a}: {g}"
        );
        assert!(
            get("bi_sim_lo") <= bi[a] && bi[a] <= get("bi_sim_hi"),
            "BI axis {a}: {g}"
        );
    }
    // The drift row at 60 s has both law and simulation.
    let d = &doc["sensors"][0]["drift"][0];
    assert_eq!(d["t_s"], 60.0);
    assert!(
        d["horizontal_mean_law_m"].as_f64().is_some()
            && d["horizontal_mean_sim_m"].as_f64().is_some()
    );
}

#[test]
fn spec_is_identical_for_any_thread_count() {
    let run = |threads: &str| {
        spec_json(&[
            "configs/sensors/gg5300.toml",
            "--runs",
            "6",
            "--times",
            "10,60",
            "--readback-duration",
            "3600",
            "--threads",
            threads,
        ])
    };
    assert!(
        run("1") == run("3"),
        "spec output depends on the thread count"
    );
}

/// Run `imudrift spec ARGS...` expecting failure; its stderr.
fn spec_error(args: &[&str]) -> String {
    let out = command().arg("spec").args(args).output().unwrap();
    assert!(!out.status.success(), "expected a failure for {args:?}");
    assert_eq!(
        out.status.code(),
        Some(1),
        "an error, not a panic: {args:?}"
    );
    String::from_utf8_lossy(&out.stderr).into_owned()
}

/// `--require` answers per sensor with a verdict that agrees with the statistic, its Monte Carlo
/// interval and the margin; the requirement's time is simulated even when --times does not list
/// it; no readback runs unless asked (the readback values are null, the spec values are given);
/// a gyro-only model carries the note that its accelerometers are assumed perfect.
#[test]
fn spec_require_answers_pass_fail_with_margin() {
    let stdout = spec_json(&[
        "configs/sensors/mtx.toml",
        "configs/sensors/gg1320an.toml",
        "--runs",
        "200",
        "--require",
        "pos_horizontal_m < 10 m @ 300 s",
        "--require",
        "p50 heading_rad < 1 deg @ 1 min",
    ]);
    let doc: serde_json::Value = serde_json::from_slice(&stdout).unwrap();
    assert!(doc["readback_duration_s"].is_null());
    for s in doc["sensors"].as_array().unwrap() {
        let g = &s["gyro"];
        assert!(g["arw_spec"][0].as_f64().unwrap() > 0.0, "{g}");
        assert!(g["arw_sim"][0].is_null(), "no readback unless asked: {g}");
        let times: Vec<f64> = s["drift"]
            .as_array()
            .unwrap()
            .iter()
            .map(|d| d["t_s"].as_f64().unwrap())
            .collect();
        assert_eq!(times, [60.0, 300.0], "{}", s["name"]);
        let reqs = s["requirements"].as_array().unwrap();
        assert_eq!(reqs.len(), 2);
        for r in reqs {
            let (value, lo, hi, thr) = (
                r["value"].as_f64().unwrap(),
                r["value_lo"].as_f64().unwrap(),
                r["value_hi"].as_f64().unwrap(),
                r["threshold"].as_f64().unwrap(),
            );
            assert!(lo <= value && value <= hi, "{r}");
            assert!((r["margin"].as_f64().unwrap() - (thr - value)).abs() < 1e-9 * thr);
            let expected = if hi < thr {
                "pass"
            } else if lo >= thr {
                "fail"
            } else {
                "undecided"
            };
            assert_eq!(r["verdict"], expected, "{r}");
            assert_eq!(r["pass"], value < thr, "{r}");
        }
    }
    let mtx = &doc["sensors"][0];
    let gg = &doc["sensors"][1];
    // MTx at 5 min drifts kilometres (Woodman: 150 m at 1 min, growing as t^3): a clear fail.
    assert_eq!(mtx["requirements"][0]["verdict"], "fail");
    // Its only note: the accelerometers have no long-term term at the 5 min horizon (issue 24's
    // one rule for missing model parts); nothing is assumed perfect.
    let mtx_notes = mtx["model_notes"].as_array().unwrap();
    assert!(
        mtx_notes.len() == 1
            && mtx_notes[0]
                .as_str()
                .unwrap()
                .contains("accelerometer model has no long-term term"),
        "{mtx_notes:?}"
    );
    // The RLG's heading at 1 min is about 1e-3 deg: a clear pass.
    assert_eq!(gg["requirements"][1]["verdict"], "pass");
    let notes = gg["model_notes"].as_array().unwrap();
    assert!(
        notes
            .iter()
            .any(|n| n.as_str().unwrap().contains("no accelerometer")),
        "{notes:?}"
    );
}

#[test]
fn spec_bad_requirements_are_errors_showing_the_form() {
    for (req, needle) in [
        ("pos_horizontal_m < 10", "no `@ TIME`"),
        ("bearing < 2 deg @ 60 s", "unknown channel"),
        ("pos_horizontal_m < 10 deg @ 60 s", "does not fit"),
    ] {
        let e = spec_error(&["configs/sensors/mtx.toml", "--require", req]);
        assert!(e.contains(needle) && e.contains("e.g."), "{req}: {e}");
    }
    for d in ["1e300", "1e8"] {
        let e = spec_error(&["configs/sensors/mtx.toml", "--readback-duration", d]);
        assert!(
            e.contains("--readback-duration") && e.contains("2e9 samples"),
            "{e}"
        );
    }
    for (args, needle) in [
        (&["--times", "0"][..], "--times"),
        (&["--runs", "0"][..], "--runs"),
        (&["--rate", "0"][..], "--rate"),
        (&["--times", "0.001"][..], "shorter than one sample"),
        (&["--times", "1e9"][..], "mechanisation steps"),
        (
            &["--require", "pos_horizontal_m < 1 @ 1e12 s"][..],
            "mechanisation steps",
        ),
    ] {
        let mut all = vec!["configs/sensors/mtx.toml"];
        all.extend_from_slice(args);
        let e = spec_error(&all);
        assert!(e.contains(needle), "{args:?}: {e}");
    }
}
