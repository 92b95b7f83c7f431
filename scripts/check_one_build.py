#!/usr/bin/env python3
"""Check that the README's three builds compile each crate once.

`cargo install --locked --path .` (the CLI), `cargo test --workspace --release` (every crate and the
dev-dependencies) and `pip install ./python` (maturin: the `imudrift-python` cdylib) share one
target directory and one profile (release). Cargo reuses a compiled crate only when its features
are the same, and unifies features over the packages each command builds; a crate compiled with
other features by one of the three is compiled again, with everything that depends on it. This
script asks cargo (nightly's `--unit-graph`, which compiles nothing) for the units of each
command and lists every crate whose features differ between two of them. Exit 1 if any does:
add the union to crates/workspace-hack/Cargo.toml.

Usage: python3 scripts/check_one_build.py   (needs `rustup toolchain install nightly`)
"""

import json
import subprocess
import sys

COMMANDS = {
    "cargo install --path .": ["build", "--release", "--locked", "-p", "imudrift", "--bins"],
    "cargo test --workspace --release": ["test", "--workspace", "--release", "--locked", "--no-run"],
    "pip install ./python": ["build", "--release", "--locked", "-p", "imudrift-python", "--lib"],
    "cargo run --release": ["build", "--release", "--locked", "-p", "imudrift", "--bin", "imudrift"],
}


def units(args):
    run = subprocess.run(
        ["cargo", "+nightly", *args, "--unit-graph", "-Z", "unstable-options"],
        capture_output=True,
        text=True,
    )
    if run.returncode != 0:
        sys.exit(f"cargo {' '.join(args)} failed:\n{run.stderr}")
    out = run.stdout
    seen = {}
    for unit in json.loads(out)["units"]:
        kinds = unit["target"]["kind"]
        if unit["mode"] != "build" or not any(k in kinds for k in ("lib", "rlib", "proc-macro")):
            continue
        # Host units (build scripts' and proc-macros' dependencies) are built apart from the
        # target's, with their own features: keep them apart.
        host = unit["profile"]["opt_level"] == "0"
        key = (unit["pkg_id"], "host" if host else "target")
        seen.setdefault(key, set()).update(unit["features"])
    return seen


def main():
    graphs = {name: units(args) for name, args in COMMANDS.items()}
    differ = 0
    for key in sorted(set().union(*graphs.values())):
        present = {name: g[key] for name, g in graphs.items() if key in g}
        if len({frozenset(v) for v in present.values()}) > 1:
            differ += 1
            pkg = key[0].split("#")[-1]
            print(f"{pkg} ({key[1]}): compiled more than once")
            for name, features in present.items():
                print(f"    {name}: {sorted(features)}")
    if differ:
        print(f"{differ} crates compiled more than once; add the union of their features to "
              "crates/workspace-hack/Cargo.toml")
        return 1
    print(f"every crate is compiled once across: {', '.join(COMMANDS)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
