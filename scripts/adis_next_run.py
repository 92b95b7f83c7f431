#!/usr/bin/env python3
"""Does a model fitted on some ADIS16405 runs predict the drift of the next run?

The real-data acceptance of docs/drift.md, "The next run": on the six static ADIS16405 runs
(2.8 h at 100 Hz each) it

1. fits all six pooled with `imudrift diagnose` (from the datasheet model) and checks the fitted
   model on the same six runs with `imudrift drift` under both protocols (the default: log-mean
   calibration, perfect start; and `--calibration window:60s --init level:60s`), at the default
   horizons, with --replicates simulated experiments: the joint test's p-value, the cells out and
   the between-log test's flags;
2. leave one run out: for each run i, fits the other five and checks run i alone, both protocols;
   the six p-values, the count with p >= 0.05 and their Fisher combination
   (-2 sum ln p ~ chi-squared with 12 degrees of freedom under the model);
3. the split fits: runs 4-6 -> runs 1-3 and runs 1-3 -> runs 4-6, both protocols.

It prints markdown tables, the run-to-run spreads each fit estimated, and the wall time of every
command; --json FILE keeps every figure. Figures are from the release binary (--bin).

    IMUDRIFT_DATA=<folder of the real logs> python3 scripts/adis_next_run.py [--replicates 200]
        [--seed 1] [--latitude 45 | --flat-earth] [--skip loo,split] [--work DIR] [--json FILE]
"""
import argparse
import json
import math
import os
import pathlib
import subprocess
import sys
import tempfile
import time

ROOT = pathlib.Path(__file__).resolve().parent.parent
COLS = ["--rate", "100", "--gyro-unit", "deg/s", "--accel-unit", "g", "--col",
        "gx=gyro_x_dps,gy=gyro_y_dps,gz=gyro_z_dps,ax=acc_x_g,ay=acc_y_g,az=acc_z_g"]
PROTOCOLS = {"log mean, perfect start": [],
             "window 60 s, levelled 60 s": ["--calibration", "window:60s", "--init", "level:60s"]}


def chi2_sf_even(x, dof):
    """P(chi-squared with an even number of degrees of freedom > x): exact series."""
    k = dof // 2
    term, total = 1.0, 1.0
    for i in range(1, k):
        term *= (x / 2) / i
        total += term
    return math.exp(-x / 2) * total


def fisher(ps):
    """Fisher's combination of independent p-values: -2 sum ln p ~ chi2(2k)."""
    stat = -2.0 * sum(math.log(p) for p in ps)
    return stat, chi2_sf_even(stat, 2 * len(ps))


def run(argv, timings):
    t0 = time.perf_counter()
    out = subprocess.run(argv, capture_output=True, text=True, cwd=ROOT)
    dt = time.perf_counter() - t0
    timings.append((" ".join(pathlib.Path(a).name if "/" in a else a for a in argv[1:5]), dt))
    if out.returncode != 0:
        sys.exit(f"failed ({out.returncode}): {' '.join(argv)}\n{out.stderr}")
    return out.stdout, dt


def fit(a, runs, work, timings):
    out_dir = work / ("fit-" + "".join(map(str, runs)))
    argv = [a.bin, "diagnose", *[a.log(i) for i in runs], "--model", a.model, *COLS,
            "--seed", str(a.seed), "--out", str(out_dir), "--json", *a.earth]
    stdout, dt = run(argv, timings)
    doc = json.loads(stdout)
    model = next(out_dir.glob("*-diagnosed.toml"))
    return model, doc, dt


def check(a, model, runs, flags, timings):
    argv = [a.bin, "drift", *[a.log(i) for i in runs], "--model", str(model), *COLS,
            "--replicates", str(a.replicates), "--seed", str(a.seed), "--json", *flags, *a.earth]
    stdout, dt = run(argv, timings)
    return json.loads(stdout), dt


def spreads(toml_path):
    """The axes' `run_to_run` lines of a fitted model, as written (not [fitted_on]'s list of
    how they were estimated)."""
    return [ln.strip() for ln in pathlib.Path(toml_path).read_text().splitlines()
            if ln.strip().startswith("run_to_run = {") or ln.strip().startswith("[gyro.")
            or ln.strip().startswith("[accel.")]


def flagged(doc):
    """The (horizon, quantity) cells whose between-log test flags."""
    out = []
    for h in doc["horizons"]:
        for q, c in h["channels"].items():
            b = c.get("between_logs")
            if b and b.get("runs_differ"):
                out.append(f"{q} at {h['t_s']:g} s (p = {b['p_value']:.3f})")
    return out


def between_text(doc):
    """The between-log tests of every cell together (absent for one log)."""
    b = doc.get("between_logs_joint")
    if not b:
        return "-"
    verdict = "runs differ" if b["runs_differ"] else "consistent"
    return f"{b['flagged']} of {b['cells']} cells flagged, joint p = {b['p_value']:.3f}, {verdict}"


def joint_text(doc):
    j = doc.get("joint")
    if not j:
        return "no cell informed"
    verdict = "consistent" if j["consistent"] else "rejected"
    return f"{j['outside']} of {j['cells']} out, p = {j['p_value']:.3f}, {verdict}"


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--bin", default=str(ROOT / "target/release/imudrift"))
    ap.add_argument("--model", default=str(ROOT / "configs/sensors/adis16405.toml"))
    ap.add_argument("--replicates", type=int, default=200)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--latitude", default=None)
    ap.add_argument("--flat-earth", action="store_true")
    ap.add_argument("--skip", default="", help="comma list of: six, loo, split")
    ap.add_argument("--work", default=None)
    ap.add_argument("--json", default=None)
    a = ap.parse_args()
    data = os.environ.get("IMUDRIFT_DATA")
    if not data:
        sys.exit("set IMUDRIFT_DATA to the folder holding adis16405_imudata/")
    a.log = lambda i: f"{data}/adis16405_imudata/adis16405_imu{i}.csv.gz"
    a.earth = (["--flat-earth"] if a.flat_earth
               else (["--latitude", a.latitude] if a.latitude else []))
    skip = set(filter(None, a.skip.split(",")))
    work = pathlib.Path(a.work or tempfile.mkdtemp(prefix="adis-next-run-"))
    work.mkdir(parents=True, exist_ok=True)
    timings, result = [], {"replicates": a.replicates, "seed": a.seed, "earth": a.earth}
    print(f"work directory {work}; {a.replicates} simulated experiments, seed {a.seed}, "
          f"Earth {' '.join(a.earth) or 'default (45 deg)'}\n", flush=True)

    if "six" not in skip:
        model, _, dt = fit(a, [1, 2, 3, 4, 5, 6], work, timings)
        print(f"## Six runs pooled (diagnose {dt:.1f} s)\n")
        for ln in spreads(model):
            if ln.startswith("run_to_run"):
                print(f"    {ln}")
        print("\n| protocol | joint test | between-log, all cells | between-log flags | drift wall |")
        print("|---|---|---|---|---|")
        result["six"] = {}
        for pname, flags in PROTOCOLS.items():
            doc, dt = check(a, model, [1, 2, 3, 4, 5, 6], flags, timings)
            fl = flagged(doc)
            result["six"][pname] = {"joint": doc.get("joint"), "flags": fl, "seconds": dt,
                                    "between_logs_joint": doc.get("between_logs_joint")}
            print(f"| {pname} | {joint_text(doc)} | {between_text(doc)} | "
                  f"{', '.join(fl) or 'none'} | {dt:.1f} s |", flush=True)
        print()

    if "loo" not in skip:
        print("## Leave one run out (fit on the other five, check the sixth)\n")
        print("| run | " + " | ".join(PROTOCOLS) + " |")
        print("|---|" + "---|" * len(PROTOCOLS))
        ps = {p: [] for p in PROTOCOLS}
        result["loo"] = []
        for i in range(1, 7):
            others = [r for r in range(1, 7) if r != i]
            model, _, _ = fit(a, others, work, timings)
            row = {"run": i}
            cells = []
            for pname, flags in PROTOCOLS.items():
                doc, _ = check(a, model, [i], flags, timings)
                p = doc["joint"]["p_value"]
                ps[pname].append(p)
                row[pname] = doc["joint"]
                cells.append(joint_text(doc))
            result["loo"].append(row)
            print(f"| {i} | " + " | ".join(cells) + " |", flush=True)
        print()
        for pname in PROTOCOLS:
            stat, p = fisher(ps[pname])
            n_ok = sum(p_i >= 0.05 for p_i in ps[pname])
            result.setdefault("fisher", {})[pname] = {"statistic": stat, "p_value": p,
                                                       "consistent": n_ok}
            print(f"- {pname}: {n_ok} of 6 consistent; Fisher -2 sum ln p = {stat:.2f}, "
                  f"p = {p:.3f} (chi-squared, 12 degrees of freedom)")
        print()

    if "split" not in skip:
        print("## Split fits\n")
        print("| fit -> checked | " + " | ".join(PROTOCOLS) + " |")
        print("|---|" + "---|" * len(PROTOCOLS))
        result["split"] = []
        for fit_runs, checked in (([4, 5, 6], [1, 2, 3]), ([1, 2, 3], [4, 5, 6])):
            model, _, _ = fit(a, fit_runs, work, timings)
            cells, row = [], {"fit": fit_runs, "checked": checked,
                              "run_to_run": [ln for ln in spreads(model)
                                             if ln.startswith("run_to_run")]}
            for pname, flags in PROTOCOLS.items():
                doc, _ = check(a, model, checked, flags, timings)
                row[pname] = {"joint": doc.get("joint"), "flags": flagged(doc),
                              "between_logs_joint": doc.get("between_logs_joint")}
                cells.append(f"{joint_text(doc)}; between logs: {between_text(doc)}")
            result["split"].append(row)
            label = f"runs {'-'.join(map(str, fit_runs[::2]))} -> runs " \
                    f"{'-'.join(map(str, checked[::2]))}"
            print(f"| {label} | " + " | ".join(cells) + " |", flush=True)
            for ln in row["run_to_run"]:
                print(f"|   {ln} | | |")
        print()

    result["timings"] = timings
    if a.json:
        pathlib.Path(a.json).write_text(json.dumps(result, indent=1))
    print("wall times: " + "; ".join(f"{n}: {t:.1f} s" for n, t in timings))


if __name__ == "__main__":
    main()
