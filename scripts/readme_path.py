#!/usr/bin/env python3
"""Run the README as a new user does, on a fresh clone, and time it.

Clones the repository into a new directory, makes a new virtual environment and a new home
directory, then runs every command of the README's ```sh blocks and every ```python block, in
the README's order, from the clone's root, as written. The README's placeholders are files the
script makes first: LOG.csv, LOG1.csv, LOG2.csv (`imudrift generate` of the ADIS16405 model, 20
min at 100 Hz, seeds 1-3, after the install step) and SENSOR.toml (the shipped ADIS16405 model).
`cargo run --release -- ...`, which the README mentions in its text, runs last, to show it
compiles nothing more.

For each step it prints the time, the exit status and the crates cargo compiled; at the end,
every library compiled in more than one step: a library whose compiled file (`lib<name>-<hash>`
in target/release/deps, the hash standing for its features and settings) is made new in two
steps was compiled twice (there should be none: the CLI, the tests and the Python module share
one build). Exit 1 if a step fails or a library is compiled twice.

    python3 scripts/readme_path.py [--repo URL-OR-DIR] [--work DIR] [--data DIR] [--skip-tests]

--data is passed to the tests as IMUDRIFT_DATA (the real logs; without it those tests are
reported as ignored). The cargo registry and toolchains are the user's (CARGO_HOME, RUSTUP_HOME);
everything else (installed binaries, home directory, venv) lives under --work.
"""

import argparse
import os
import re
import resource
import shlex
import subprocess
import sys
import tempfile
import time
from pathlib import Path

COMPILING = re.compile(r"^\s*Compiling (\S+) v(\S+)( \(.*\))?$", re.M)


def blocks(readme):
    """The README's fenced blocks as (language, text), in order."""
    out, lang, lines = [], None, []
    for line in readme.splitlines():
        if lang is None:
            m = re.match(r"^```(\w*)\s*$", line)
            if m:
                lang, lines = m.group(1), []
        elif line.startswith("```"):
            out.append((lang, "\n".join(lines)))
            lang = None
        else:
            lines.append(line)
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repo", default=str(Path(__file__).resolve().parent.parent))
    ap.add_argument("--work", default=None, help="work directory (default: a new temporary one)")
    ap.add_argument("--data", default=None, help="IMUDRIFT_DATA for the tests")
    ap.add_argument("--skip-tests", action="store_true", help="do not run `cargo test`")
    args = ap.parse_args()

    work = Path(args.work or tempfile.mkdtemp(prefix="imudrift-readme-")).resolve()
    work.mkdir(parents=True, exist_ok=True)
    clone, home, venv, root = work / "imudrift", work / "home", work / "venv", work / "cargo-root"
    home.mkdir(exist_ok=True)
    env = dict(os.environ)
    real_home = Path(os.environ.get("HOME", "~")).expanduser()
    env.setdefault("CARGO_HOME", str(real_home / ".cargo"))
    env.setdefault("RUSTUP_HOME", str(real_home / ".rustup"))
    env.update(
        HOME=str(home),
        CARGO_INSTALL_ROOT=str(root),
        VIRTUAL_ENV=str(venv),
        PATH=f"{root / 'bin'}:{venv / 'bin'}:{Path(env['CARGO_HOME']) / 'bin'}:{env['PATH']}",
        PIP_DISABLE_PIP_VERSION_CHECK="1",
    )
    env.pop("IMUDRIFT_DATA", None)
    env.pop("CARGO_TARGET_DIR", None)

    steps = []  # (name, seconds, status, compiled crates)

    deps = clone / "target" / "release" / "deps"
    made_in = {}  # library name -> steps in which a new compiled file of it appeared

    def libraries():
        if not deps.is_dir():
            return set()
        return {p.name for p in deps.iterdir() if p.suffix in (".rlib", ".so") and p.name.startswith("lib")}

    def run(name, command, cwd, extra_env=None):
        before = libraries()
        cpu0 = resource.getrusage(resource.RUSAGE_CHILDREN)
        start = time.monotonic()
        proc = subprocess.run(
            ["bash", "-c", command],
            cwd=cwd,
            env={**env, **(extra_env or {})},
            stdout=subprocess.PIPE,
            stderr=subprocess.STDOUT,
            text=True,
        )
        seconds = time.monotonic() - start
        cpu1 = resource.getrusage(resource.RUSAGE_CHILDREN)
        cpu = (cpu1.ru_utime - cpu0.ru_utime) + (cpu1.ru_stime - cpu0.ru_stime)
        compiled = COMPILING.findall(proc.stdout)
        # Registry crates by name and version (two versions of one crate, e.g. rand 0.8 and a
        # dev-dependency's rand 0.10, are two crates); workspace crates (a path in the line) by
        # their library files, since a test step prints "Compiling" for their test harnesses too.
        for crate, version, path in COMPILING.findall(proc.stdout):
            if not path:
                made_in.setdefault(f"{crate} v{version}", []).append(name)
        for new in libraries() - before:
            lib = new[3:].rsplit("-", 1)[0].split(".")[0]
            if lib.replace("_", "-").startswith("imudrift"):
                made_in.setdefault(lib, []).append(name)
        steps.append((name, seconds, cpu, proc.returncode, compiled))
        print(f"[{seconds:7.1f} s, CPU {cpu:7.1f} s] exit {proc.returncode}, {len(compiled):3d} crates compiled: {name}",
              flush=True)
        if proc.returncode != 0:
            print(proc.stdout[-3000:])
        return proc.returncode

    run(f"git clone {args.repo}", f"git clone -q {shlex.quote(args.repo)} {shlex.quote(str(clone))}", work)
    run("python3 -m venv (a new environment)", f"{shlex.quote(sys.executable)} -m venv {shlex.quote(str(venv))}", work)
    readme = (clone / "README.md").read_text()
    made_inputs = False
    for lang, text in blocks(readme):
        if lang == "python":
            script = work / f"readme-example-{len(steps)}.py"
            script.write_text(text + "\n")
            run(f"python: {text.splitlines()[0]} ...", f"python {shlex.quote(str(script))}", clone)
            continue
        if lang != "sh":
            continue
        for line in text.splitlines():
            command = line.split("  #")[0].strip() if not line.lstrip().startswith("#") else ""
            if not command:
                continue
            if command.startswith("cargo test"):
                if args.skip_tests:
                    continue
                extra = {"IMUDRIFT_DATA": args.data} if args.data else None
                run(line.strip(), command, clone, extra)
                continue
            if not made_inputs and command.startswith("imudrift ") and "install" not in command:
                # The README's placeholders, made with the command just installed.
                made_inputs = True
                for i, name in enumerate(["LOG.csv", "LOG1.csv", "LOG2.csv"], start=1):
                    run(f"(placeholder) {name}",
                        f"imudrift generate configs/sensors/adis16405.toml --duration 20min "
                        f"--rate 100 --seed {i} -o {name}", clone)
                run("(placeholder) SENSOR.toml", "cp configs/sensors/adis16405.toml SENSOR.toml", clone)
            run(line.strip(), command, clone)
    run("cargo run --release -- --help (the README's text)", "cargo run --release -- --help", clone)

    print("\n| step | time | CPU | exit | crates compiled |\n|---|---|---|---|---|")
    for name, seconds, cpu, status, compiled in steps:
        print(f"| `{name}` | {seconds:.1f} s | {cpu:.1f} s | {status} | {len(compiled)} |")
    wall = sum(s[1] for s in steps if s[4])
    cpu = sum(s[2] for s in steps if s[4])
    print(f"\nsteps that compiled: {wall / 60:.1f} min, {cpu / 60:.1f} min of CPU")
    twice = {lib: names for lib, names in made_in.items() if len(set(names)) > 1}
    failed = [s for s in steps if s[3] != 0]
    for lib, names in sorted(twice.items()):
        print(f"{lib} compiled in more than one step: " + "; ".join(sorted(set(names))))
    if not twice:
        print(f"no library compiled in more than one step ({len(made_in)} libraries)")
    return 1 if failed or twice else 0


if __name__ == "__main__":
    sys.exit(main())
