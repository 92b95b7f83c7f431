#!/usr/bin/env python3
"""Time every `imudrift` command's whole run, an older binary beside the new build.

Each command is run as a user types it (a fresh process; wall clock from start to exit, with
its CPU time from the kernel's accounting) with the two binaries ALTERNATING
old, new, old, new, ... for --repeat rounds, so that both see the same machine load. The script
then prints a Markdown table for docs/performance.md: the exact command lines (paths replaced by
placeholders), each binary's runs and their median, the ratio old/new of the medians, and for
each command the spread (max/min) of one binary's runs: the machine's own noise. The largest of
those spreads is printed as the "machine spread"; a ratio old/new inside it is no difference.

Two rows compare with Python, outside the old/new table:
  python-allan  a fresh `python3 -c "import imudrift ..."` process calling imudrift.allan(x, 100.0)
                on 100 000 samples: the whole process, and the first call alone (timed inside the
                process with time.perf_counter). Only the Python package `import imudrift` finds
                (the new build, if installed); skipped with a note if it is not importable.
  allantools    a fresh Python process doing pandas.read_csv of the synthetic CSV and
                allantools.oadev(y, rate=100, data_type="freq", taus="octave"), alternating with
                the new binary's `imudrift allan` of the same CSV; the ratio printed is
                allantools seconds / imudrift seconds (medians): "imudrift is Nx faster".

Inputs
  * the synthetic CSV: one column `gx`, 4 320 000 samples at 100 Hz (12 h; 100 000 with --quick),
    white noise plus a random walk, numpy seed 20261121, written with 17 significant digits;
    generated once and cached in --cache DIR (default /tmp/imudrift-timing);
  * the real ADIS16405 logs, from the folder in $IMUDRIFT_DATA (required: the folder holding
    `adis16405_imudata/`, the six static ADIS16405 runs of the SMAC-Group imudata package as
    gzip CSV, docs/validation.md): adis16405_imudata/adis16405_imu1.csv.gz .. imu6 (with --quick: the first 100 000
    samples of runs 1 and 2, copied into the cache);
  * the shipped configs/ (the commands run with the repository root as working directory);
  * the shards for `merge`: written once before timing by the new binary's `simulate --shard
    i/4`; if the old binary cannot merge them, each binary merges shards it wrote itself.
Every run's stdout and stderr go to files in a temporary directory (kept when a run fails or
with --keep). A run that exits non-zero stops the script with the command and its stderr.

Usage (from anywhere; paths are resolved against the repository root):
  python3 scripts/time_commands.py --old /path/to/old/imudrift
      [--new target/release/imudrift] [--repeat 3] [--only allan,drift] [--quick]
      [--json results.json] [--cache /tmp/imudrift-timing] [--python python3] [--keep]

  --only takes command names: allan-csv, allan-adis, simulate, generate, spec, plan, diagnose,
  merge, drift, python-allan, allantools (`allan` means allan-csv and allan-adis).
  --quick uses small inputs (a smoke test of the script, not a measurement).

Needs numpy (for the synthetic CSV); pandas and allantools for the allantools row (skipped with
a note when missing). A full run takes about (sum of the commands' times) x 2 x --repeat.
"""

import argparse
import hashlib
import json
import os
import platform
import re
import shlex
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass, field
from datetime import datetime, timezone
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
RATE_HZ = 100
SEED = 20261121
SYNTH_SAMPLES = 4_320_000          # 12 h at 100 Hz
SYNTH_SAMPLES_QUICK = 100_000
ADIS_QUICK_SAMPLES = 100_000       # --quick: the first 1000 s of each ADIS16405 run
ADIS_RUNS = (1, 2, 3, 4, 5, 6)     # drift pools these runs
ADIS_RUNS_QUICK = (1, 2)
SHARDS = 4
PY_ALLAN_SAMPLES = 100_000

SCENARIO = "configs/scenarios/mtx-static-60s.toml"
MTX = "configs/sensors/mtx.toml"
ADIS = "configs/sensors/adis16405.toml"
# The ADIS16405 logs' columns in explicit form (the names already say the units; the flags keep
# the commands the same as docs/performance.md's earlier tables and work with older binaries).
ADIS_FLAGS = ["--rate", "100", "--gyro-unit", "deg/s", "--accel-unit", "g",
              "--col", "gx=gyro_x_dps,gy=gyro_y_dps,gz=gyro_z_dps,ax=acc_x_g,ay=acc_y_g,az=acc_z_g"]

CLI_COMMANDS = ["allan-csv", "allan-adis", "simulate", "generate", "spec", "plan", "diagnose",
                "merge", "drift"]
PY_COMMANDS = ["python-allan", "allantools"]
ALL_COMMANDS = CLI_COMMANDS + PY_COMMANDS

# The Python one-liners (run with `python3 -c CODE ARGS...` in a fresh process).
PY_ALLAN_CODE = (
    "import time; t0 = time.perf_counter()\n"
    "import json, sys, numpy as np, imudrift\n"
    "x = np.random.default_rng(20261121).standard_normal(int(sys.argv[1]))\n"
    "t1 = time.perf_counter(); r = imudrift.allan(x, 100.0); t2 = time.perf_counter()\n"
    "print(json.dumps({'import_s': t1 - t0, 'first_call_s': t2 - t1, 'module': imudrift.__file__}))"
)
ALLANTOOLS_CODE = (
    "import sys, pandas as pd, allantools\n"
    "y = pd.read_csv(sys.argv[1], comment='#')['gx'].to_numpy()\n"
    "allantools.oadev(y, rate=100, data_type='freq', taus='octave')"
)


class TimingError(RuntimeError):
    """A failure the user must see: a missing file, a command that failed (run_dir: its
    outputs, kept for a look)."""

    def __init__(self, msg, run_dir=None):
        super().__init__(msg)
        self.run_dir = run_dir


def log(msg):
    print(msg, file=sys.stderr, flush=True)


# ---------------------------------------------------------------- runs

@dataclass
class Run:
    wall_s: float
    cpu_s: float          # user + system of the process (all its threads)
    run_dir: str


def run_timed(argv, run_dir, cwd, env=None, check_json=True):
    """Run argv once, stdout/stderr to files in run_dir; wall clock of the whole process.

    Raises TimingError (with the stderr's tail) unless the exit status is 0 and, when
    check_json, stdout holds one JSON document."""
    run_dir = Path(run_dir)
    run_dir.mkdir(parents=True, exist_ok=True)
    out_path, err_path = run_dir / "stdout", run_dir / "stderr"
    with open(out_path, "wb") as out, open(err_path, "wb") as err:
        t0 = time.perf_counter()
        proc = subprocess.Popen(argv, stdout=out, stderr=err, stdin=subprocess.DEVNULL,
                                cwd=cwd, env=env)
        _, status, usage = os.wait4(proc.pid, 0)
        wall = time.perf_counter() - t0
    proc.returncode = os.waitstatus_to_exitcode(status)  # reaped by wait4, tell Popen
    if proc.returncode != 0:
        tail = err_path.read_text(errors="replace").strip().splitlines()[-15:]
        raise TimingError(
            f"command failed with exit status {proc.returncode}:\n  {shlex.join(map(str, argv))}\n"
            f"  (cwd {cwd}; stdout/stderr in {run_dir})\n  stderr ends:\n    "
            + "\n    ".join(tail or ["(empty)"]), run_dir=run_dir)
    if check_json:
        try:
            with open(out_path) as f:
                json.load(f)
        except (ValueError, UnicodeDecodeError) as e:
            raise TimingError(f"stdout is not one JSON document ({e}):\n  "
                              f"{shlex.join(map(str, argv))}\n  see {out_path}")
    # (ru_maxrss is not reported: after a fork it includes this Python process's own memory)
    return Run(wall, usage.ru_utime + usage.ru_stime, str(run_dir))


# ---------------------------------------------------------------- commands

@dataclass
class Command:
    """One command of the table. argv(binary, out_dir) gives the arguments of one run."""
    name: str
    argv: object                      # callable (binary: str, out: Path) -> list[str]
    check: object = None              # callable (out: Path) -> None, raises TimingError
    json_out: bool = True
    per_binary_inputs: dict = field(default_factory=dict)  # notes on inputs (merge shards)


def build_commands(ctx):
    """The CLI commands, with the inputs ctx prepared. Returns {name: Command}."""
    q = ctx.quick
    adis = [str(p) for p in ctx.adis_logs]

    def allan_csv(b, out):
        return [b, "allan", str(ctx.synth_csv), "--rate", "100", "--json"]

    def allan_adis(b, out):
        return [b, "allan", adis[0], "--rate", "100", "--json"]

    def simulate(b, out):  # the scenario's 500 runs and its ablation table, as shipped
        return [b, "simulate", ctx.scenario_for(b), "--json"] + (["--runs", "48"] if q else [])

    def generate(b, out):
        return [b, "generate", MTX, "--duration", "10min" if q else "1h", "--rate", "100",
                "-o", str(out / "mtx.csv"), "--json"]

    def generate_check(out):
        p = out / "mtx.csv"
        if not p.is_file() or p.stat().st_size == 0:
            raise TimingError(f"generate wrote no log at {p}")
        p.unlink()  # 50 MB a run: not kept

    def spec(b, out):
        return [b, "spec", MTX, ADIS, "--json"] + (["--runs", "20", "--times", "60"] if q else [])

    def plan(b, out):
        return [b, "plan", ADIS, "--duration", "2h", "--json"]

    def diagnose(b, out):
        return [b, "diagnose", adis[0], "--model", ADIS] + ADIS_FLAGS + [
            "--out", str(out / "diagnose"), "--json"]

    def diagnose_check(out):
        if not (out / "diagnose" / "diagnose.json").is_file():
            raise TimingError(f"diagnose wrote no {out / 'diagnose' / 'diagnose.json'}")

    def merge(b, out):
        return [b, "merge"] + [str(p) for p in ctx.shards[b]] + ["--json"]

    def drift(b, out):
        return [b, "drift"] + adis + ["--model", ADIS] + ADIS_FLAGS + [
            "--horizons", "10s,1min" if q else "60s,10min,1h", "--json"]

    return {
        "allan-csv": Command("allan-csv", allan_csv),
        "allan-adis": Command("allan-adis", allan_adis),
        "simulate": Command("simulate", simulate),
        "generate": Command("generate", generate, generate_check),
        "spec": Command("spec", spec),
        "plan": Command("plan", plan),
        "diagnose": Command("diagnose", diagnose, diagnose_check),
        "merge": Command("merge", merge),
        "drift": Command("drift", drift),
    }


# ---------------------------------------------------------------- inputs

class Context:
    """Paths and prepared inputs shared by the commands."""

    def __init__(self, args):
        self.quick = args.quick
        self.old = resolve_binary(args.old, "--old")
        self.new = resolve_binary(args.new, "--new")
        self.python = args.python
        self.cache = Path(args.cache).resolve()
        data_env = os.environ.get("IMUDRIFT_DATA")
        if not data_env:
            sys.exit("time_commands.py: set IMUDRIFT_DATA to the folder holding adis16405_imudata/ "
                     "(the real logs the allan, diagnose and drift rows read)")
        self.data = Path(data_env).resolve()
        self.data_from = "$IMUDRIFT_DATA"
        self.tmp = Path(tempfile.mkdtemp(prefix="imudrift-timing-run-"))
        self.synth_csv = None
        self.adis_logs = []
        self.shards = {}
        self.notes = []
        self.scenarios = {}

    def scenario_for(self, binary):
        """The shipped scenario, or for a binary older than the `[earth]` table (which refuses
        it) the same file without its `[earth] model = "flat"` table: the same experiment on
        that binary's only Earth, the flat one."""
        if binary not in self.scenarios:
            probe = subprocess.run([binary, "simulate", SCENARIO, "--runs", "1", "--json",
                                    "--no-ablation"], capture_output=True, text=True)
            if probe.returncode == 0 or "unknown field `earth`" not in probe.stderr:
                self.scenarios[binary] = SCENARIO
            else:
                text = Path(SCENARIO).read_text()
                flat = "[earth]\nmodel = \"flat\"\n"
                if flat not in text:
                    raise TimingError(f"{binary} refuses {SCENARIO}'s [earth] table")
                copy = self.tmp / "mtx-static-60s-before-earth.toml"
                copy.write_text(text.replace(flat, "").replace(
                    'sensor = "../sensors/mtx.toml"',
                    f'sensor = "{Path(MTX).resolve()}"'))
                self.scenarios[binary] = str(copy)
                self.notes.append(f"simulate and merge: {SCENARIO} has `[earth] model = \"flat\"`, "
                                  "which the old binary does not know: it runs the same file "
                                  "without that table ($TMP/mtx-static-60s-before-earth.toml), "
                                  "the same experiment on its only Earth, the flat one.")
        return self.scenarios[binary]

    def shard_argv(self, binary, i, out):
        """`simulate --shard i/4` of the scenario (48 runs with --quick)."""
        return [binary, "simulate", self.scenario_for(binary), "--shard", f"{i}/{SHARDS}",
                "--out", str(out)] \
            + (["--runs", "48"] if self.quick else [])

    def placeholders(self):
        """(path, placeholder) pairs for printing command lines, longest path first."""
        pairs = [(str(self.tmp), "$TMP"), (str(self.cache), "$CACHE"),
                 (str(self.data), "$IMUDRIFT_DATA"),
                 (self.old, "imudrift"), (self.new, "imudrift")]
        return sorted(pairs, key=lambda p: -len(p[0]))


def resolve_binary(path, flag):
    p = Path(path)
    if not p.is_absolute():
        p = (Path.cwd() / p) if (Path.cwd() / p).exists() else (REPO / p)
    if not p.is_file():
        hint = " (build it with `cargo build --release --bin imudrift`, or pass --new PATH)" \
            if flag == "--new" else ""
        raise TimingError(f"{flag}: no binary at {p}{hint}")
    if not os.access(p, os.X_OK):
        raise TimingError(f"{flag}: {p} is not executable")
    return str(p.resolve())


def binary_info(path):
    """Version string, sha256 prefix and mtime of a binary (also reads it into the page cache)."""
    try:
        v = subprocess.run([path, "--version"], capture_output=True, text=True, timeout=60)
    except (OSError, subprocess.TimeoutExpired) as e:
        raise TimingError(f"{path} --version failed: {e}")
    version = v.stdout.strip()
    if v.returncode != 0 or not version.startswith("imudrift"):
        raise TimingError(f"{path} does not look like an imudrift binary: `--version` exited "
                          f"{v.returncode} and printed {(version or v.stderr.strip())[:200]!r}")
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for chunk in iter(lambda: f.read(1 << 20), b""):
            h.update(chunk)
    mtime = datetime.fromtimestamp(os.path.getmtime(path), timezone.utc)
    return {"path": path, "version": version, "sha256": h.hexdigest()[:16],
            "mtime_utc": mtime.strftime("%Y-%m-%d %H:%M:%S")}


def require_file(p, what):
    p = Path(p)
    if not p.is_file():
        raise TimingError(f"{what}: no file at {p}")
    return p


def warm(p):
    """Read a file once so the first timed run does not pay for the disk."""
    with open(p, "rb") as f:
        while f.read(1 << 22):
            pass


def make_synthetic_csv(cache, n):
    """The one-column `gx` CSV at 100 Hz (white noise plus a random walk), cached."""
    path = cache / f"gx-100hz-{n}-seed{SEED}.csv"
    if path.is_file() and path.stat().st_size > 0:
        return path
    try:
        import numpy as np
    except ImportError:
        raise TimingError("numpy is needed to write the synthetic CSV: pip install numpy")
    log(f"writing {path} ({n} samples; once, then cached)")
    rng = np.random.default_rng(SEED)
    dt = 1.0 / RATE_HZ
    y = 1e-3 / np.sqrt(dt) * rng.standard_normal(n)               # white, N = 1e-3 rad/s/sqrt(Hz)
    y += np.cumsum(3e-6 * np.sqrt(dt) * rng.standard_normal(n))   # rate random walk, K = 3e-6
    cache.mkdir(parents=True, exist_ok=True)
    part = path.with_suffix(".csv.part")
    with open(part, "w") as f:
        f.write(f"# synthetic gyro rate, rad/s, {RATE_HZ} Hz, {n} samples: white noise N = 1e-3 "
                f"plus random walk K = 3e-6, numpy default_rng({SEED})\ngx\n")
        np.savetxt(f, y, fmt="%.17g")                             # every double exactly
    os.replace(part, path)
    return path


def adis_head_copy(src, cache, n):
    """The first n samples of a gzip ADIS16405 log as a plain CSV in the cache (for --quick)."""
    import gzip
    dst = cache / f"{src.name.removesuffix('.csv.gz')}-head{n}.csv"
    if dst.is_file() and dst.stat().st_size > 0:
        return dst
    cache.mkdir(parents=True, exist_ok=True)
    part = dst.with_suffix(".csv.part")
    with gzip.open(src, "rt") as fin, open(part, "w") as fout:
        rows = 0
        for line in fin:
            fout.write(line)
            if not line.startswith("#") and "," in line and not line[0].isalpha():
                rows += 1
                if rows >= n:
                    break
    os.replace(part, dst)
    return dst


def prepare_shards(ctx, binary, label):
    """`simulate --shard i/4 --out DIR` for i = 0..3 with `binary`; the shard files."""
    out = ctx.tmp / f"shards-{label}"
    for i in range(SHARDS):
        run_timed(ctx.shard_argv(binary, i, out), ctx.tmp / "prepare" / f"shard-{label}-{i}",
                  REPO, check_json=False)
    files = sorted(out.glob("shard-*.json"))
    if len(files) != SHARDS:
        raise TimingError(f"simulate --shard wrote {len(files)} shard files in {out}, "
                          f"expected {SHARDS}")
    return files


def prepare(ctx, selected):
    """Check and write every input the selected commands need, before any timing."""
    for cfg in (SCENARIO, MTX, ADIS):
        require_file(REPO / cfg, "shipped config")
    needs_adis = {"allan-adis", "diagnose", "drift"} & set(selected)
    if needs_adis:
        folder = ctx.data / "adis16405_imudata"
        if not folder.is_dir():
            raise TimingError(
                f"no ADIS16405 logs at {folder} (data dir from {ctx.data_from}); set "
                "IMUDRIFT_DATA to the folder holding adis16405_imudata/, or leave out "
                "allan-adis, diagnose and drift with --only")
        runs = ADIS_RUNS_QUICK if ctx.quick else (ADIS_RUNS if "drift" in selected else (1,))
        logs = [require_file(folder / f"adis16405_imu{i}.csv.gz", "ADIS16405 log") for i in runs]
        if ctx.quick:
            logs = [adis_head_copy(p, ctx.cache, ADIS_QUICK_SAMPLES) for p in logs]
        ctx.adis_logs = logs
        for p in logs:
            warm(p)
    if {"allan-csv", "allantools"} & set(selected):
        ctx.synth_csv = make_synthetic_csv(
            ctx.cache, SYNTH_SAMPLES_QUICK if ctx.quick else SYNTH_SAMPLES)
        warm(ctx.synth_csv)
    if "merge" in selected:
        log("writing the merge shards with the new binary")
        new_shards = prepare_shards(ctx, ctx.new, "new")
        ctx.shards[ctx.new] = new_shards
        try:  # can the old binary read the new one's shards?
            run_timed([ctx.old, "merge"] + [str(p) for p in new_shards] + ["--json"],
                      ctx.tmp / "prepare" / "merge-compat", REPO)
            ctx.shards[ctx.old] = new_shards
            ctx.notes.append("merge: both binaries merge the same 4 shards, written before the "
                             "timing by the new binary: `" + display(
                                 ctx.shard_argv(ctx.new, "{0..3}", ctx.tmp / "shards-new"), ctx)
                             + "`.")
        except TimingError as e:
            log(f"the old binary cannot merge the new shards; it gets its own:\n{e}")
            ctx.shards[ctx.old] = prepare_shards(ctx, ctx.old, "old")
            ctx.notes.append("merge: the old binary could not read the new binary's shards, so "
                             "each binary merges 4 shards it wrote itself.")
        if ctx.old == ctx.new:
            ctx.shards[ctx.old] = new_shards


def python_has(python, modules):
    """Whether `python -c "import m1, m2"` works (in a neutral directory); the error if not."""
    r = subprocess.run([python, "-c", "import " + ", ".join(modules)], capture_output=True,
                       text=True, cwd=tempfile.gettempdir())
    if r.returncode == 0:
        return True, ""
    last = (r.stderr.strip().splitlines() or ["exit status %d" % r.returncode])[-1]
    return False, last


# ---------------------------------------------------------------- statistics and display

def median(xs):
    return statistics.median(xs) if xs else None


def spread(xs):
    return max(xs) / min(xs) if len(xs) >= 2 and min(xs) > 0 else None


def secs(x):
    if x is None:
        return "-"
    return f"{x:.3f}" if x < 1 else f"{x:.2f}"


def runs_text(xs):
    return ", ".join(secs(x) for x in xs) if xs else "-"


def ratio_text(x):
    return "-" if x is None else f"{x:.2f}"


def collapse_ranges(words):
    """Collapse args differing only in one integer counting up by 1 into bash `{a..b}` form
    (`imu1.csv.gz imu2.csv.gz imu3.csv.gz` -> `imu{1..3}.csv.gz`)."""
    def step(a, b):
        """The index of the one integer token of a that is 1 less in b, else None."""
        ta, tb = re.split(r"(\d+)", a), re.split(r"(\d+)", b)
        if len(ta) != len(tb):
            return None
        diff = [i for i, (x, y) in enumerate(zip(ta, tb)) if x != y]
        if len(diff) == 1 and diff[0] % 2 == 1 and int(tb[diff[0]]) == int(ta[diff[0]]) + 1:
            return diff[0]
        return None

    out, i = [], 0
    while i < len(words):
        j, at = i, None
        while j + 1 < len(words):
            s = step(words[j], words[j + 1])
            if s is None or (at is not None and s != at):
                break
            at, j = s, j + 1
        if j > i:
            tok = re.split(r"(\d+)", words[i])
            tok[at] = "{%s..%s}" % (tok[at], re.split(r"(\d+)", words[j])[at])
            out.append("".join(tok))
        else:
            out.append(words[i])
        i = j + 1
    return out


def display(argv, ctx, run_dir=None):
    """A command line as printed in the docs: paths replaced by placeholders."""
    words = []
    for a in map(str, argv):
        if run_dir is not None:
            a = a.replace(str(run_dir), "$OUT")
        for path, ph in ctx.placeholders():
            a = a.replace(path, ph)
        words.append(a)
    words = collapse_ranges(words)
    # keep the $PLACEHOLDERS and {a..b} readable: quote only what needs it otherwise
    return " ".join(w if re.fullmatch(r"[\w$./{},=:@%+-]+", w) else shlex.quote(w) for w in words)


def md_escape(s):
    return s.replace("|", "\\|")


# ---------------------------------------------------------------- main

def parse_args():
    ap = argparse.ArgumentParser(
        description="Time every imudrift command, an old binary beside the new build, "
                    "alternating; print a Markdown table.",
        formatter_class=argparse.RawDescriptionHelpFormatter, epilog=__doc__)
    ap.add_argument("--old", required=True, help="the older imudrift binary")
    ap.add_argument("--new", default="target/release/imudrift",
                    help="the new binary (default target/release/imudrift of the repository)")
    ap.add_argument("--repeat", type=int, default=3, help="rounds of old, new (default 3)")
    ap.add_argument("--only", default=None,
                    help="comma list of commands: " + ", ".join(ALL_COMMANDS) + " (allan = both)")
    ap.add_argument("--quick", action="store_true", help="small inputs: a smoke test")
    ap.add_argument("--json", metavar="FILE", default=None, help="write the results as JSON")
    ap.add_argument("--cache", metavar="DIR", default="/tmp/imudrift-timing",
                    help="where the synthetic CSV (and --quick's log excerpts) are kept")
    ap.add_argument("--python", default=sys.executable,
                    help="Python for the python-allan and allantools rows (default this one)")
    ap.add_argument("--keep", action="store_true", help="keep the runs' temporary directory")
    args = ap.parse_args()
    if args.repeat < 1:
        ap.error("--repeat must be at least 1")
    if args.only:
        selected = []
        for name in (n.strip() for n in args.only.split(",")):
            names = ["allan-csv", "allan-adis"] if name == "allan" else [name]
            for n in names:
                if n not in ALL_COMMANDS:
                    ap.error(f"--only: unknown command {name!r}; known: {', '.join(ALL_COMMANDS)}")
                if n not in selected:
                    selected.append(n)
        args.selected = [n for n in ALL_COMMANDS if n in selected]
    else:
        args.selected = list(ALL_COMMANDS)
    return args


def main():
    args = parse_args()
    ctx = Context(args)
    try:
        measure(args, ctx)
    except TimingError as e:
        if e.run_dir is None and not args.keep:
            shutil.rmtree(ctx.tmp, ignore_errors=True)
        else:
            e.args = (f"{e}\n  (the runs' outputs are kept in {ctx.tmp})",)
        raise
    except BaseException:
        log(f"(the runs' outputs so far are in {ctx.tmp})")
        raise


def measure(args, ctx):
    """Prepare the inputs, time the commands, print the table (and write --json)."""
    started = datetime.now(timezone.utc)
    load_start = os.getloadavg()
    info = {"old": binary_info(ctx.old), "new": binary_info(ctx.new)}
    log(f"old: {ctx.old} ({info['old']['version']}, sha256 {info['old']['sha256']})")
    log(f"new: {ctx.new} ({info['new']['version']}, sha256 {info['new']['sha256']})")
    if ctx.old == ctx.new:
        ctx.notes.append("old and new are the same file: the ratios measure only the machine.")
    prepare(ctx, args.selected)

    commands = build_commands(ctx)
    cli = [n for n in args.selected if n in CLI_COMMANDS]
    total = len(cli) * 2 * args.repeat
    k = 0
    results = {}
    for name in cli:
        cmd = commands[name]
        series = {"old": [], "new": []}
        lines = {}
        for rnd in range(1, args.repeat + 1):
            for label, binary in (("old", ctx.old), ("new", ctx.new)):
                k += 1
                out = ctx.tmp / name / f"{label}-{rnd}"
                out.mkdir(parents=True, exist_ok=True)
                argv = cmd.argv(binary, out)
                lines[label] = display(argv, ctx, out)
                r = run_timed(argv, out, REPO, check_json=cmd.json_out)
                if cmd.check:
                    cmd.check(out)
                series[label].append(r)
                log(f"[{k}/{total}] {name:10s} {label} round {rnd}: {r.wall_s:8.3f} s wall, "
                    f"{r.cpu_s:8.2f} s CPU")
        old_w = [r.wall_s for r in series["old"]]
        new_w = [r.wall_s for r in series["new"]]
        results[name] = {
            "command": lines["new"],
            "command_old": lines["old"] if lines["old"] != lines["new"] else None,
            "old_s": old_w, "new_s": new_w,
            "old_cpu_s": [r.cpu_s for r in series["old"]],
            "new_cpu_s": [r.cpu_s for r in series["new"]],
            "old_median_s": median(old_w), "new_median_s": median(new_w),
            "ratio_old_new": median(old_w) / median(new_w) if median(new_w) else None,
            "spread_old": spread(old_w), "spread_new": spread(new_w),
        }

    python_rows = {}
    if "python-allan" in args.selected:
        python_rows["python-allan"] = time_python_allan(ctx, args.repeat)
    if "allantools" in args.selected:
        python_rows["allantools"] = time_allantools(ctx, args.repeat)

    finished = datetime.now(timezone.utc)
    load_end = os.getloadavg()
    meta = {
        "started_utc": started.strftime("%Y-%m-%d %H:%M:%S"),
        "finished_utc": finished.strftime("%H:%M:%S"),
        "host": platform.node(), "cpu": cpu_model(), "cores": os.cpu_count(),
        "load_start": load_start, "load_end": load_end,
        "repeat": args.repeat, "quick": args.quick,
        "binaries": info, "repo_head": git_head(),
        "data": str(ctx.data), "cache": str(ctx.cache), "tmp": str(ctx.tmp),
        "python": args.python,
    }
    spreads = machine_spreads(results, python_rows)
    print(markdown(meta, results, python_rows, spreads, ctx))
    if args.json:
        doc = {"meta": meta, "commands": results, "python": python_rows,
               "machine_spread": spreads, "notes": ctx.notes}
        Path(args.json).write_text(json.dumps(doc, indent=2) + "\n")
        log(f"wrote {args.json}")
    if args.keep:
        log(f"kept the runs' outputs in {ctx.tmp}")
    else:
        shutil.rmtree(ctx.tmp, ignore_errors=True)


def time_python_allan(ctx, repeat):
    """Fresh Python processes calling imudrift.allan on 100 000 samples (the new build only)."""
    ok, why = python_has(ctx.python, ["numpy", "imudrift"])
    if not ok:
        ctx.notes.append(f"python-allan skipped: `{Path(ctx.python).name} -c 'import numpy, "
                         f"imudrift'` fails ({why}); install the package (maturin) to time it.")
        log(ctx.notes[-1])
        return {"skipped": why}
    argv = [ctx.python, "-c", PY_ALLAN_CODE, str(PY_ALLAN_SAMPLES)]
    walls, first, module = [], [], None
    for rnd in range(1, repeat + 1):
        out = ctx.tmp / "python-allan" / f"run-{rnd}"
        r = run_timed(argv, out, tempfile.gettempdir(), check_json=True)
        inner = json.loads((out / "stdout").read_text())
        walls.append(r.wall_s)
        first.append(inner["first_call_s"])
        module = inner["module"]
        log(f"python-allan round {rnd}: {r.wall_s:.3f} s process, first call "
            f"{inner['first_call_s']:.3f} s ({module})")
    return {"command": "python3 -c CODE 100000 (CODE below)", "code": PY_ALLAN_CODE,
            "process_s": walls, "first_call_s": first, "module": module,
            "process_median_s": median(walls), "first_call_median_s": median(first),
            "spread_process": spread(walls), "spread_first_call": spread(first)}


def time_allantools(ctx, repeat):
    """pandas + allantools on the synthetic CSV, alternating with the new `imudrift allan`."""
    ok, why = python_has(ctx.python, ["pandas", "allantools"])
    if not ok:
        ctx.notes.append(f"allantools skipped: `{Path(ctx.python).name} -c 'import pandas, "
                         f"allantools'` fails ({why}); pip install pandas allantools.")
        log(ctx.notes[-1])
        return {"skipped": why}
    py_argv = [ctx.python, "-c", ALLANTOOLS_CODE, str(ctx.synth_csv)]
    ours_argv = [ctx.new, "allan", str(ctx.synth_csv), "--rate", "100", "--json"]
    theirs, ours = [], []
    for rnd in range(1, repeat + 1):
        r = run_timed(py_argv, ctx.tmp / "allantools" / f"allantools-{rnd}", REPO,
                      check_json=False)
        theirs.append(r.wall_s)
        log(f"allantools round {rnd}: {r.wall_s:.3f} s")
        r = run_timed(ours_argv, ctx.tmp / "allantools" / f"imudrift-{rnd}", REPO)
        ours.append(r.wall_s)
        log(f"allantools round {rnd}: imudrift allan (new) {r.wall_s:.3f} s")
    return {"command": "python3 -c CODE $CACHE/" + ctx.synth_csv.name + " (CODE below)",
            "code": ALLANTOOLS_CODE,
            "imudrift_command": display(ours_argv, ctx),
            "allantools_s": theirs, "imudrift_s": ours,
            "allantools_median_s": median(theirs), "imudrift_median_s": median(ours),
            "ratio_allantools_imudrift": median(theirs) / median(ours),
            "spread_allantools": spread(theirs), "spread_imudrift": spread(ours)}


def machine_spreads(results, python_rows):
    """The largest same-binary spread: over every series, and over series of runs >= 1 s."""
    series = []
    for name, r in results.items():
        for label in ("old", "new"):
            xs = r[f"{label}_s"]
            if spread(xs) is not None:
                series.append((spread(xs), min(xs), f"{name}, {label}"))
    for name, r in python_rows.items():
        for key, xs in r.items():
            if isinstance(xs, list) and key.endswith("_s") and spread(xs) is not None:
                series.append((spread(xs), min(xs), f"{name}, {key.removesuffix('_s')}"))
    if not series:
        return {"all": None, "runs_of_1s_or_more": None}

    def top(ss):
        if not ss:
            return None
        s, _, where = max(ss)
        return {"spread": s, "where": where}
    return {"all": top(series), "runs_of_1s_or_more": top([s for s in series if s[1] >= 1.0])}


def cpu_model():
    try:
        for line in open("/proc/cpuinfo"):
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "unknown"


def git_head():
    try:
        r = subprocess.run(["git", "-C", str(REPO), "describe", "--always", "--dirty"],
                           capture_output=True, text=True, timeout=30)
        return r.stdout.strip() or None
    except (OSError, subprocess.TimeoutExpired):
        return None


def markdown(meta, results, python_rows, spreads, ctx):
    b = meta["binaries"]
    la = lambda t: ", ".join(f"{x:.2f}" for x in t)
    out = []
    out.append(f"Measured {meta['started_utc']}-{meta['finished_utc']} UTC on `{meta['host']}` "
               f"(`uname -n`; {meta['cpu']}, {meta['cores']} cores), load average "
               f"{la(meta['load_start'])} at the start and {la(meta['load_end'])} at the end; "
               f"{meta['repeat']} round(s), each command run by the old then the new binary "
               f"(alternating), wall clock of the whole process"
               + (" (**--quick: small inputs, a smoke test, not a measurement**)" if meta["quick"]
                  else "") + ".")
    out.append("")
    out.append(f"- old: `{b['old']['path']}` ({b['old']['version']}, sha256 "
               f"{b['old']['sha256']}, built {b['old']['mtime_utc']} UTC)")
    out.append(f"- new: `{b['new']['path']}` ({b['new']['version']}, sha256 "
               f"{b['new']['sha256']}, built {b['new']['mtime_utc']} UTC; repository at "
               f"{meta['repo_head']})")
    out.append("- `$IMUDRIFT_DATA`: the real-data folder; `$CACHE`: the synthetic CSV's cache "
               "(`scripts/time_commands.py --cache`); `$OUT`, `$TMP`: temporary directories. "
               "Commands run from the repository root.")
    out.append("")
    if results:
        out.append("| command | old runs (s) | old median | new runs (s) | new median | "
                   "old/new | spread old, new |")
        out.append("|---|---|---|---|---|---|---|")
        for name, r in results.items():
            cmd = f"`{md_escape(r['command'])}`"
            if r["command_old"]:
                cmd += f" (old: `{md_escape(r['command_old'])}`)"
            out.append(f"| {cmd} | {runs_text(r['old_s'])} | {secs(r['old_median_s'])} | "
                       f"{runs_text(r['new_s'])} | {secs(r['new_median_s'])} | "
                       f"**{ratio_text(r['ratio_old_new'])}** | "
                       f"{ratio_text(r['spread_old'])}, {ratio_text(r['spread_new'])} |")
        out.append("")
    a, big = spreads["all"], spreads["runs_of_1s_or_more"]
    if a is None:
        out.append("machine spread: - (one run per binary and command: use --repeat 2 or more)")
    else:
        line = f"machine spread (largest max/min of one binary's runs of one command): " \
               f"**{a['spread']:.2f}** ({a['where']})"
        if big and big["where"] != a["where"]:
            line += f"; over runs of 1 s or more: **{big['spread']:.2f}** ({big['where']})"
        out.append(line + ". A ratio old/new within it is no difference.")
    if python_rows:
        out.append("")
        out.append("| beside Python | runs (s) | median | note |")
        out.append("|---|---|---|---|")
        pa = python_rows.get("python-allan")
        if pa is not None:
            if "skipped" in pa:
                out.append(f"| python-allan | - | - | skipped: {md_escape(pa['skipped'])} |")
            else:
                out.append(f"| python-allan: whole process (`python3 -c PY_ALLAN "
                           f"{PY_ALLAN_SAMPLES}`) | {runs_text(pa['process_s'])} | "
                           f"{secs(pa['process_median_s'])} | module `{pa['module']}` |")
                out.append(f"| python-allan: first `imudrift.allan` call | "
                           f"{runs_text(pa['first_call_s'])} | {secs(pa['first_call_median_s'])}"
                           f" | timed inside the process |")
        at = python_rows.get("allantools")
        if at is not None:
            if "skipped" in at:
                out.append(f"| allantools | - | - | skipped: {md_escape(at['skipped'])} |")
            else:
                out.append(f"| pandas + allantools (`python3 -c ALLANTOOLS "
                           f"$CACHE/{ctx.synth_csv.name}`) | {runs_text(at['allantools_s'])} | "
                           f"{secs(at['allantools_median_s'])} | alternating with the row below |")
                out.append(f"| `{md_escape(at['imudrift_command'])}` (new) | "
                           f"{runs_text(at['imudrift_s'])} | {secs(at['imudrift_median_s'])} | "
                           f"allantools / imudrift = **{at['ratio_allantools_imudrift']:.1f}x** |")
        out.append("")
        if pa is not None and "skipped" not in pa:
            out.append("PY_ALLAN:")
            out.append("```python")
            out.append(PY_ALLAN_CODE)
            out.append("```")
        if at is not None and "skipped" not in at:
            out.append("ALLANTOOLS:")
            out.append("```python")
            out.append(ALLANTOOLS_CODE)
            out.append("```")
    if ctx.notes:
        out.append("")
        out.extend(f"- {n}" for n in ctx.notes)
    return "\n".join(out)


if __name__ == "__main__":
    try:
        main()
    except TimingError as e:
        sys.exit(f"time_commands.py: error: {e}")
    except KeyboardInterrupt:
        sys.exit("time_commands.py: interrupted")
