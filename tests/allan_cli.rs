//! End-to-end tests of `imudrift allan`: reading CSV and gzip CSV, units, column mapping,
//! outputs (table, JSON fields of docs/cli.md, CSV, SVG), errors with line numbers, and the
//! stop at Stable32's largest averaging time or not (the real ADIS16405 log: allan_adis.rs).

mod common;
use common::command;

use std::io::Write;
use std::path::Path;

/// A static gyro log in deg/s with a time column: white noise of known level (SplitMix64 +
/// Box-Muller, deterministic).
fn write_log(path: &Path, n: usize, gz: bool) {
    let mut rng = testkit::SplitMix64::new(7);
    let mut text = String::from("# test log\n# gyro in deg/s\ntime_s,wx,temp\n");
    for k in 0..n {
        let g = rng.normal();
        text.push_str(&format!("{},{},{}\n", k as f64 * 0.01, 0.5 * g, 25.0));
    }
    let file = std::fs::File::create(path).unwrap();
    if gz {
        let mut e = flate2::write::GzEncoder::new(file, flate2::Compression::fast());
        e.write_all(text.as_bytes()).unwrap();
        e.finish().unwrap();
    } else {
        std::io::BufWriter::new(file)
            .write_all(text.as_bytes())
            .unwrap();
    }
}

#[test]
fn json_csv_svg_outputs_and_units() {
    let dir = tempfile::tempdir().unwrap();
    let log = dir.path().join("log.csv.gz");
    write_log(&log, 200_000, true);
    let out = dir.path().join("out");
    let o = command()
        .args([
            "allan",
            log.to_str().unwrap(),
            "--gyro-unit",
            "deg/s",
            "--col",
            "t=time_s,gx=wx",
        ])
        .args(["--json", "--out", out.to_str().unwrap()])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let doc: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert!((doc["rate_hz"].as_f64().unwrap() - 100.0).abs() < 1e-6);
    let gx = &doc["channels"]["gx"];
    // temp is not analysed by default
    assert!(doc["channels"].get("temp").is_none());
    let col = |k: &str| -> Vec<f64> {
        gx[k]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap())
            .collect()
    };
    let (tau, adev, lo, hi) = (col("tau_s"), col("adev"), col("adev_lo"), col("adev_hi"));
    assert_eq!(tau.len(), adev.len());
    assert!(tau.len() >= 10);
    for i in 0..tau.len() {
        assert!(lo[i] < adev[i] && adev[i] < hi[i]);
    }
    // White noise of 0.5 deg/s per sample at 100 Hz: N = 0.5 deg/s * sqrt(0.01 s), in rad.
    // The fitted N must agree within 3 of its stated standard errors (plus 1 % for the
    // generator's finite sample, far below the fit's own uncertainty here).
    let n_true = 0.5f64.to_radians() * 0.1;
    let n = gx["fit"]["n"].as_f64().unwrap();
    let n_sigma = gx["fit_sigma"]["n"].as_f64().unwrap();
    assert!(
        (n - n_true).abs() < 3.0 * n_sigma + 0.01 * n_true,
        "{n} +- {n_sigma} vs {n_true}"
    );
    for f in ["allan.csv", "allan.json", "allan_gx.svg"] {
        assert!(out.join(f).exists(), "{f}");
    }
    let csv = std::fs::read_to_string(out.join("allan.csv")).unwrap();
    assert!(csv.starts_with("channel,tau_s,m,n_terms,bins,alpha,edf,adev_lo,adev,adev_hi"));
    assert_eq!(csv.lines().count(), 1 + tau.len());
    let svg = std::fs::read_to_string(out.join("allan_gx.svg")).unwrap();
    assert!(svg.contains("confidence interval") && svg.contains("IEEE 952 fit"));
}

#[test]
fn bad_row_is_reported_by_line_and_no_output_is_written() {
    let dir = tempfile::tempdir().unwrap();
    let log = dir.path().join("bad.csv");
    std::fs::write(&log, "# c\ngx,gy\n1,2\n3,4\n5,x7\n").unwrap();
    let out = dir.path().join("out");
    let o = command()
        .args([
            "allan",
            log.to_str().unwrap(),
            "--rate",
            "10",
            "--out",
            out.to_str().unwrap(),
        ])
        .output()
        .unwrap();
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("bad.csv:5") && err.contains("\"gy\"") && err.contains("x7"),
        "{err}"
    );
    assert!(!out.join("allan.json").exists());
}

#[test]
fn thread_count_does_not_change_results() {
    let dir = tempfile::tempdir().unwrap();
    let log = dir.path().join("log.csv");
    write_log(&log, 100_000, false);
    let run = |threads: &str| {
        let o = command()
            .args([
                "allan",
                log.to_str().unwrap(),
                "--col",
                "t=time_s,gx=wx",
                "--json",
            ])
            .args(["--threads", threads, "--grid", "5/decade"])
            .output()
            .unwrap();
        assert!(o.status.success());
        o.stdout
    };
    assert_eq!(run("1"), run("2"));
}

/// Issue 45's estimators through the command: the JSON contract's fields, Theo1's tau 0.75 m tau0,
/// TheoH's two parts, an interval around every deviation, no fit, and the same bytes for 1 and
/// 2 threads (the subsequence sums are merged in a fixed order).
#[test]
fn total_family_and_theo_estimators() {
    let dir = tempfile::tempdir().unwrap();
    let log = dir.path().join("log.csv");
    write_log(&log, 6_000, false);
    for est in ["mtotdev", "htotdev", "theo1", "theoh"] {
        let run = |threads: &str| {
            let o = command()
                .args([
                    "allan",
                    log.to_str().unwrap(),
                    "--col",
                    "t=time_s,gx=wx",
                    "--json",
                    "--estimator",
                    est,
                    "--threads",
                    threads,
                ])
                .output()
                .unwrap();
            assert!(
                o.status.success(),
                "{est}: {}",
                String::from_utf8_lossy(&o.stderr)
            );
            o.stdout
        };
        let out = run("2");
        assert_eq!(out, run("1"), "{est}");
        let j: serde_json::Value = serde_json::from_slice(&out).unwrap();
        assert_eq!(j["estimator"], est);
        let c = &j["channels"]["gx"];
        let f = |k: &str| -> Vec<f64> {
            c[k].as_array()
                .unwrap()
                .iter()
                .map(|v| v.as_f64().unwrap())
                .collect()
        };
        let (tau, dev, lo, hi, m) = (f("tau_s"), f("adev"), f("adev_lo"), f("adev_hi"), f("m"));
        assert!(tau.len() >= 5, "{est}: {} taus", tau.len());
        for i in 0..tau.len() {
            assert!(lo[i] < dev[i] && dev[i] < hi[i], "{est} tau {}", tau[i]);
            // Theo1's tau is 0.75 m tau0 (SP 1065 eq (30)); TheoH's from a tenth of the record
            // (0.1 * 6000 sample intervals) on; the others m tau0.
            let theo = est == "theo1" || (est == "theoh" && m[i] >= 600.0);
            let want = if theo {
                0.75 * (m[i] * 0.01)
            } else {
                m[i] * 0.01
            };
            assert!(
                (tau[i] / want - 1.0).abs() < 1e-12,
                "{est}: tau {} m {}",
                tau[i],
                m[i]
            );
        }
        assert!(
            c["fit"].as_object().unwrap().values().all(|v| v.is_null()),
            "{est}"
        );
    }
}

/// The issue-24 case through the commands: a white-noise-only sensor (N = 0.5833 deg/sqrt(h) on
/// every gyro, 0.12 m/s/sqrt(h) on every accelerometer), `imudrift generate` 10 min at 200 Hz,
/// then `imudrift allan --json`: every white-noise reading holds its truth within its stated
/// interval, and no bias-instability or random-walk value is claimed, only bounds (`null` with
/// `<name>_bound`), in the JSON and the text alike. Tolerance: the intervals are asked at the
/// level 1 - 0.01/6 for the 6 readings (Bonferroni: family-wise false-positive rate 1 %).
#[test]
fn white_noise_readings_are_right_and_claim_no_bias_instability() {
    let dir = tempfile::tempdir().unwrap();
    let sensor = dir.path().join("white.toml");
    std::fs::write(
        &sensor,
        "name = \"white\"\n[gyro.all]\nwhite_noise = \"0.5833 deg/sqrt(h)\"\n[accel.all]\nwhite_noise = \"0.12 m/s/sqrt(h)\"\n",
    )
    .unwrap();
    let log = dir.path().join("white.csv");
    let o = command()
        .args(["generate", sensor.to_str().unwrap()])
        .args(["--duration", "10min", "--rate", "200", "--seed", "5", "-o"])
        .arg(&log)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let confidence = format!("{}", 1.0 - 0.01 / 6.0);
    let o = command()
        .args(["allan", log.to_str().unwrap(), "--json", "--confidence"])
        .arg(&confidence)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let doc: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let truth = |ch: &str| {
        if ch.starts_with('g') {
            (0.5833f64 / 60.0).to_radians()
        } else {
            0.12 / 60.0
        }
    };
    for ch in ["gx", "gy", "gz", "ax", "ay", "az"] {
        let r = &doc["channels"][ch]["readings"];
        let (v, lo, hi) = (
            r["arw_at_1s"].as_f64().unwrap(),
            r["arw_at_1s_lo"].as_f64().unwrap(),
            r["arw_at_1s_hi"].as_f64().unwrap(),
        );
        assert!(
            lo <= truth(ch) && truth(ch) <= hi,
            "{ch}: {v} [{lo}, {hi}] vs {}",
            truth(ch)
        );
        for name in ["bi_min", "bi_ieee", "rrw_at_3s"] {
            assert!(r[name].is_null(), "{ch}: {name} = {} claimed", r[name]);
            assert!(
                r[format!("{name}_bound")].as_f64().unwrap() > 0.0,
                "{ch}: {r}"
            );
        }
        for term in ["b", "k", "r"] {
            let resolved = &doc["channels"][ch]["fit_resolved"][term];
            assert_eq!(
                resolved,
                &serde_json::json!(false),
                "{ch}: fitted {term} given as a value"
            );
        }
    }
    // The text (on stderr with --json) says the same: bounds, no minimum.
    let text = String::from_utf8_lossy(&o.stderr);
    assert!(
        text.matches("Allan minimum (bias inst.) not resolved: <")
            .count()
            == 6,
        "{text}"
    );
}

/// Unit plausibility (issue 24): a gyro logged in deg/s under the name `gx` (read as rad/s, the
/// canonical name's default) and an accelerometer logged in g read as m/s^2 each draw a warning
/// naming the flag that fixes it; the analysis still runs. The noise (0.5 deg/s per sample at
/// 100 Hz: 0.05 deg/s/sqrt(Hz), 2.9 "deg/s/sqrt(Hz)" when read as rad/s) and the magnitude (1 g
/// read as 1 m/s^2) are each far beyond the warning's thresholds (1 deg/s/sqrt(Hz); a factor
/// 1.25 around standard gravity), so no tolerance question arises.
#[test]
fn wrong_units_draw_a_plausibility_warning() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("units.csv");
    let mut rng = testkit::SplitMix64::new(3);
    let mut text = String::from("gx,ax,ay,az\n");
    for _ in 0..20_000 {
        let n = 0.002 * rng.normal();
        text.push_str(&format!("{},{n},{n},{}\n", 0.5 * rng.normal(), -1.0 + n));
    }
    std::fs::write(&path, text).unwrap();
    let o = command()
        .args(["allan", path.to_str().unwrap(), "--rate", "100"])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("warning:")
            && err.contains("gx reads a white noise of")
            && err.contains("--gyro-unit deg/s"),
        "{err}"
    );
    assert!(
        err.contains("near 1, as a log in g reads") && err.contains("--accel-unit g"),
        "{err}"
    );
    // Stated right, no warning.
    let o = command()
        .args(["allan", path.to_str().unwrap(), "--rate", "100"])
        .args(["--gyro-unit", "deg/s", "--accel-unit", "g"])
        .output()
        .unwrap();
    assert!(o.status.success());
    assert!(!String::from_utf8_lossy(&o.stderr).contains("warning:"));
}

#[test]
fn no_stable32_stop_goes_on_to_the_last_tau_with_two_terms() {
    // N = 1000 rate samples are N + 1 phase points; oadev at m has N + 1 - 2m terms, so the last
    // m with 2 or more is (N - 1) / 2 = 499 (allantools' last tau for taus="all"); Stable32 stops
    // at floor(N / 4) = 250 (SP 1065 / Riley's stop ratio 4).
    let dir = tempfile::tempdir().unwrap();
    let log = dir.path().join("log.csv");
    write_log(&log, 1000, false);
    let last = |extra: &[&str]| {
        let o = command()
            .args(["allan", log.to_str().unwrap(), "--col", "t=time_s,gx=wx"])
            .args(["--grid", "all", "--json"])
            .args(extra)
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let doc: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        let gx = &doc["channels"]["gx"];
        let m = gx["m"]
            .as_array()
            .unwrap()
            .last()
            .unwrap()
            .as_u64()
            .unwrap();
        let lo = gx["adev_lo"].as_array().unwrap().last().unwrap().as_f64();
        let hi = gx["adev_hi"].as_array().unwrap().last().unwrap().as_f64();
        (m, lo, hi, doc["stable32_stop"].as_bool())
    };
    let (m, _, _, stop) = last(&[]);
    assert_eq!((m, stop), (250, Some(true)));
    let (m, lo, hi, stop) = last(&["--no-stable32-stop"]);
    assert_eq!((m, stop), (499, Some(false)));
    let (lo, hi) = (lo.unwrap(), hi.unwrap());
    assert!(lo > 0.0 && hi > lo && hi.is_finite(), "{lo} {hi}");
}
