//! Every SVG the commands write keeps its text inside the canvas (issue 24): `allan`, `simulate`,
//! `spec`, `drift` and `diagnose` are run with `--out` on a generated log and shipped configs, and
//! each `<text>` of every SVG written is measured with a conservative glyph-width estimate, its
//! anchor and rotation taken into account, against the canvas's width and height. The same runs
//! check that no `--out` directory keeps a lock file.
//!
//! Glyph widths (per em, independent of the writer's own estimate in src/plot.rs): the widest of
//! DejaVu Sans, Liberation Sans / Arial and Helvetica in each class, rounded up: digits and lower
//! case 0.65 (DejaVu's widest lower case besides m and w: 0.634), upper case 0.8 (DejaVu: up to
//! 0.79 besides M and W), `m` `w` `M` `W` and anything non-ASCII 1.0, space and narrow marks 0.42.
//! A text's height is taken as its font size above the baseline and 0.3 of it below.

mod common;
use common::{command, ok};
use std::path::Path;

fn glyph_em(c: char) -> f64 {
    match c {
        'm' | 'w' | 'M' | 'W' => 1.0,
        'i' | 'j' | 'l' | 't' | 'f' | 'r' | '.' | ',' | ':' | ';' | '\'' | '!' | '|' | ' '
        | '(' | ')' | '[' | ']' => 0.42,
        c if c.is_ascii_uppercase() => 0.8,
        c if c.is_ascii() => 0.65,
        _ => 1.0,
    }
}

/// The value of attribute `name` in an element's opening tag.
fn attr<'a>(tag: &'a str, name: &str) -> Option<&'a str> {
    let key = format!(" {name}=\"");
    let start = tag.find(&key)? + key.len();
    let end = tag[start..].find('"')? + start;
    Some(&tag[start..end])
}

fn unescape(t: &str) -> String {
    t.replace("&lt;", "<")
        .replace("&gt;", ">")
        .replace("&amp;", "&")
}

/// Every text of one SVG outside its canvas, described.
fn texts_outside(svg: &str) -> Vec<String> {
    let head = &svg[..svg.find('>').expect("an <svg> tag")];
    let w: f64 = attr(head, "width").unwrap().parse().unwrap();
    let h: f64 = attr(head, "height").unwrap().parse().unwrap();
    let default_size: f64 = attr(head, "font-size").map_or(16.0, |v| v.parse().unwrap());
    let mut bad = Vec::new();
    let mut rest = svg;
    while let Some(at) = rest.find("<text") {
        let after = &rest[at..];
        let close = after.find('>').unwrap();
        let tag = &after[..close];
        let end = after.find("</text>").unwrap();
        let text = unescape(&after[close + 1..end]);
        rest = &after[end..];
        let x: f64 = attr(tag, "x").unwrap().parse().unwrap();
        let y: f64 = attr(tag, "y").unwrap().parse().unwrap();
        let size: f64 = attr(tag, "font-size").map_or(default_size, |v| v.parse().unwrap());
        let width: f64 = text.chars().map(glyph_em).sum::<f64>() * size;
        let (a0, a1) = match attr(tag, "text-anchor") {
            Some("middle") => (-width / 2.0, width / 2.0),
            Some("end") => (-width, 0.0),
            _ => (0.0, width),
        };
        // Along the text: [a0, a1]; across it: [-size, 0.3 size].
        let (x0, x1, y0, y1) =
            if attr(tag, "transform").is_some_and(|t| t.starts_with("rotate(-90")) {
                (x - size, x + 0.3 * size, y - a1, y - a0)
            } else {
                (x + a0, x + a1, y - size, y + 0.3 * size)
            };
        if x0 < 0.0 || y0 < 0.0 || x1 > w || y1 > h {
            bad.push(format!(
                "{text:?} spans x {x0:.0}..{x1:.0}, y {y0:.0}..{y1:.0} on a {w} x {h} canvas"
            ));
        }
    }
    bad
}

/// Check every SVG in `dir` (at least `min` of them) and that no lock file stayed.
fn check_dir(dir: &Path, min: usize) -> usize {
    let mut n = 0;
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        assert_ne!(
            path.file_name().unwrap(),
            ".imudrift.lock",
            "a lock file stayed in {}",
            dir.display()
        );
        if path.extension().is_some_and(|e| e == "svg") {
            let svg = std::fs::read_to_string(&path).unwrap();
            let bad = texts_outside(&svg);
            assert!(bad.is_empty(), "{}: {bad:#?}", path.display());
            n += 1;
        }
    }
    assert!(n >= min, "{}: {n} SVG files, expected {min}", dir.display());
    n
}

fn run(args: &[&str]) {
    ok(command().args(args).output().unwrap());
}

#[test]
fn every_svg_keeps_its_text_inside_the_canvas() {
    let dir = tempfile::tempdir().unwrap();
    let d = |name: &str| dir.path().join(name).to_str().unwrap().to_string();
    let log = d("log.csv");
    run(&[
        "generate",
        "configs/sensors/adis16405.toml",
        "--duration",
        "10min",
        "--rate",
        "100",
        "--seed",
        "3",
        "-o",
        &log,
    ]);
    run(&["allan", &log, "--out", &d("allan")]);
    check_dir(&dir.path().join("allan"), 6);
    run(&[
        "simulate",
        "configs/scenarios/mtx-static-60s.toml",
        "--runs",
        "20",
        "--out",
        &d("simulate"),
    ]);
    check_dir(&dir.path().join("simulate"), 1);
    run(&[
        "spec",
        "configs/sensors/bmi088.toml",
        "configs/sensors/mtx.toml",
        "--runs",
        "20",
        "--require",
        "pos_horizontal_m < 10 m @ 300 s",
        "--require",
        "p50 heading_rad < 2 deg @ 10 min",
        "--require",
        "vel_horizontal_mps < 1 m/s @ 60 s",
        "--out",
        &d("spec"),
    ]);
    check_dir(&dir.path().join("spec"), 3);
    run(&[
        "drift",
        &log,
        "--model",
        "configs/sensors/adis16405.toml",
        "--horizons",
        "10s,1min",
        "--replicates",
        "10",
        "--out",
        &d("drift"),
    ]);
    check_dir(&dir.path().join("drift"), 1);
    run(&[
        "diagnose",
        &log,
        "--model",
        "configs/sensors/adis16405.toml",
        "--seeds",
        "4",
        "--rounds",
        "1",
        "--horizons",
        "1min",
        "--out",
        &d("diagnose"),
    ]);
    check_dir(&dir.path().join("diagnose"), 6);
}

#[test]
fn a_long_title_is_wrapped_inside_the_canvas() {
    // The drift title, 120 characters, on the 820 px canvas: it used to be cut at both sides.
    let plot = imudrift::plot::LogLogPlot {
        title: "heading_rad: measured vs model (bias = each channel's mean over the log; attitude perfect at each segment's start; consecutive segments)".into(),
        subtitle: "a subtitle".into(),
        notes: vec!["a note that is long enough to need wrapping as well, since it goes on and on about readings and bounds and intervals and more".into()],
        x_label: "t (s)".into(),
        y_label: "RMS error (deg)".into(),
        series: vec![imudrift::plot::Series::new("measured RMS", vec![1.0, 10.0], vec![1.0, 2.0], "#000000")],
        bands: Vec::new(),
    };
    let svg = plot.to_svg();
    assert!(svg.matches("<text").count() > 8, "{svg}");
    assert_eq!(texts_outside(&svg), Vec::<String>::new());
}
