//! What a new user does from the README on a fresh clone (issue 45 item 6): the man-page step
//! as the README writes it, shipped sensors by name from any directory, negative numbers reaching
//! the options' own checks.

mod common;
use common::{binary, root};
use std::process::Command;

/// The README's man-page line, run as written with `~` a fresh home whose `~/.cargo/bin` is on
/// PATH (where `cargo install --path .` puts `imudrift`): `man imudrift-allan` then finds the
/// page. man-db derives the manual path from PATH (`~/.cargo/bin` gives `~/.cargo/share/man`,
/// where that directory exists); the step wrote into `~/.local/share/man/man1`, which it finds
/// only with `~/.local/bin` on PATH. Skipped (with a note) on a machine without `man`.
#[test]
fn the_readme_man_step_makes_man_find_the_pages() {
    let readme = std::fs::read_to_string(root().join("README.md")).unwrap();
    let line = readme
        .lines()
        .find(|l| l.trim_start().starts_with("imudrift man --out "))
        .expect("the README's man step");
    let dir_arg = line
        .split_whitespace()
        .nth(3)
        .expect("imudrift man --out DIR");
    let home = tempfile::tempdir().unwrap();
    let home = home.path();
    std::fs::create_dir_all(home.join(".cargo/bin")).unwrap();
    let dir = dir_arg.replacen('~', home.to_str().unwrap(), 1);
    let path = format!("{}:/usr/bin:/bin", home.join(".cargo/bin").display());
    let env = |c: &mut Command| {
        c.env("HOME", home)
            .env("PATH", &path)
            .env_remove("MANPATH")
            .current_dir(home);
    };
    let mut gen = Command::new(binary());
    gen.args(["man", "--out", &dir]);
    env(&mut gen);
    let out = gen.output().unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    // The command says nothing about the man path when man will find the pages.
    assert!(
        !String::from_utf8_lossy(&out.stderr).contains("does not find"),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let mut man = Command::new("man");
    man.args(["-w", "imudrift-allan"]);
    env(&mut man);
    let Ok(found) = man.output() else {
        eprintln!("note: no `man` on this machine: the step is not checked");
        return;
    };
    assert!(
        found.status.success(),
        "man does not find imudrift-allan after `{line}`: {}",
        String::from_utf8_lossy(&found.stderr)
    );
    assert!(String::from_utf8_lossy(&found.stdout).contains("imudrift-allan.1"));
    // A directory man does not search gets a note that says how to read the pages.
    let mut elsewhere = Command::new(binary());
    let other = home.join("pages");
    elsewhere.args(["man", "--out", other.to_str().unwrap()]);
    env(&mut elsewhere);
    let err = String::from_utf8(elsewhere.output().unwrap().stderr).unwrap();
    assert!(
        err.contains("man -l") && err.contains("imudrift-allan.1"),
        "{err}"
    );
}

/// The README's Python example `Sensor("mtx")` and `imudrift simulate mtx` work from any
/// directory: a shipped sensor's name reads the TOML the repository ships (a file of that name
/// in the directory would win). A name that is neither is refused with the shipped names.
#[test]
fn shipped_sensors_are_found_by_name_from_anywhere() {
    let away = tempfile::tempdir().unwrap();
    let run = |args: &[&str]| {
        Command::new(binary())
            .args(args)
            .current_dir(away.path())
            .output()
            .unwrap()
    };
    let out = run(&[
        "simulate",
        "mtx",
        "--runs",
        "10",
        "--duration",
        "5",
        "--json",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let doc: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(doc["runs"], 10);
    // The same numbers as the file in the repository.
    let file = Command::new(binary())
        .args([
            "simulate",
            "configs/sensors/mtx.toml",
            "--runs",
            "10",
            "--duration",
            "5",
            "--json",
        ])
        .current_dir(root())
        .output()
        .unwrap();
    let by_path: serde_json::Value = serde_json::from_slice(&file.stdout).unwrap();
    assert_eq!(doc["checkpoints"], by_path["checkpoints"]);
    let spec = run(&["spec", "bmi088", "adis16405", "--json"]);
    assert!(
        spec.status.success(),
        "{}",
        String::from_utf8_lossy(&spec.stderr)
    );
    let missing = run(&["simulate", "nosuchsensor"]);
    assert_eq!(missing.status.code(), Some(1));
    let err = String::from_utf8_lossy(&missing.stderr);
    assert!(err.contains("nosuchsensor"), "{err}");
}

/// A negative number given to a numeric option reaches that option's check, which says what it
/// expects, with status 1; clap alone read `-5` as an unknown flag ("unexpected argument '-5'
/// found", status 2). A negative latitude is a value, as it was.
#[test]
fn negative_numbers_reach_the_options_checks() {
    let out = common::imudrift(&["simulate", "configs/sensors/mtx.toml", "--rate", "-5"]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(
        err.contains("--rate") && err.contains("> 0") && err.contains("-5"),
        "{err}"
    );
    assert!(!err.contains("unexpected argument"), "{err}");
    for args in [
        &["simulate", "configs/sensors/mtx.toml", "--runs", "-3"][..],
        &[
            "generate",
            "configs/sensors/mtx.toml",
            "--duration",
            "-10",
            "--rate",
            "100",
            "-o",
            "x.csv",
        ][..],
        &["plan", "configs/sensors/mtx.toml", "--rate", "-100"][..],
    ] {
        let out = common::imudrift(args);
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!err.contains("unexpected argument"), "{args:?}: {err}");
        assert_ne!(out.status.code(), Some(0), "{args:?}");
    }
}
