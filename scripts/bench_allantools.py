#!/usr/bin/env python3
"""Benchmark `imudrift allan` beside allantools (the Python package) on the same channel.

Generates (or reads) one 4.32 M-sample rate channel (12 h at 100 Hz: white noise, a random walk
and a flicker-like sum of Gauss-Markov processes; numpy seed 20261121), writes it as a CSV with
one column `gx` (no time column), then times in one session:
  1. allantools.oadev(y, rate=100, data_type="freq", taus=<octave m list>) alone (data already in
     memory; reading the CSV is not counted for allantools),
  2. the whole command `imudrift allan LOG.csv --rate 100 --grid <same m list> --json`
     (reading and parsing the CSV, phase, deviations, noise identification, EDF, confidence
     intervals, fit, JSON), wall clock of the process,
and compares the deviations. The runs are interleaved (allantools, command, command with
--edf none, repeated) so both see the same load; best of --repeat runs each, and the
median of the per-pair ratios.

Usage: python3 scripts/bench_allantools.py [--bin target/release/imudrift] [--csv PATH] [--repeat 5]
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile
import time

import numpy as np
import allantools


def make_channel(n, rate_hz, seed):
    rng = np.random.default_rng(seed)
    dt = 1.0 / rate_hz
    y = 1e-3 / np.sqrt(dt) * rng.standard_normal(n)              # white, N = 1e-3 rad/s/sqrt(Hz)
    y += np.cumsum(3e-6 * np.sqrt(dt) * rng.standard_normal(n))  # rate random walk K = 3e-6
    # flicker-like: sum of Gauss-Markov processes (docs/model.md §3), B = 1e-4, 1 s .. 1e4 s
    rho = np.sqrt(10.0)
    for i in range(9):
        tc = 1.0 * rho ** i
        phi = np.exp(-dt / tc)
        var = (1e-4) ** 2 * np.log(rho) / np.pi
        w = np.sqrt(var * (1 - phi * phi)) * rng.standard_normal(n)
        # AR(1) filter via scipy-free recursion in chunks (lfilter equivalent)
        from scipy.signal import lfilter
        y += lfilter([1.0], [1.0, -phi], w)
    return y + 0.01  # a constant bias


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--bin", default="target/release/imudrift")
    ap.add_argument("--csv", default=None, help="existing one-column CSV (header gx) to use")
    ap.add_argument("--samples", type=int, default=4_320_000)
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--format", choices=["full", "adis"], default="full",
                    help="full: rad/s with 17 significant digits (exact doubles); adis: deg/s "
                         "quantised to the ADIS16405's 0.05 deg/s LSB and printed as the real "
                         "ADIS logs are (%%.10g, e.g. -0.35)")
    args = ap.parse_args()

    rate = 100.0
    tmpdir = tempfile.mkdtemp(prefix="bench_allan_")
    path = args.csv or os.path.join(tmpdir, "channel.csv")
    if args.csv is None:
        y = make_channel(args.samples, rate, 20261121)
        if args.format == "adis":
            # 20x the white noise so the 0.05 deg/s LSB is below the noise (as on the ADIS)
            y = np.round(np.degrees(20.0 * y) / 0.05) * 0.05
        with open(path, "w") as f:
            f.write("# benchmark channel, 100 Hz\ngx\n")
            np.savetxt(f, y, fmt="%.17g" if args.format == "full" else "%.10g")
    t0 = time.perf_counter()
    y = np.loadtxt(path, comments="#", skiprows=2 if args.csv is None else 1)
    t_load = time.perf_counter() - t0
    n = len(y)
    ms = [2 ** k for k in range(0, int(np.floor(np.log2(n + 1))) + 1) if 2 ** k < n + 1]
    taus = np.array(ms, dtype=float) / rate
    size_mb = os.path.getsize(path) / 1e6
    print(f"channel: {n} samples, CSV {size_mb:.1f} MB at {path}")
    print(f"taus: {len(ms)} octave averaging factors m = 1 .. {ms[-1]}")

    # Interleaved: one allantools run, then one run of the command, then one with --edf none,
    # repeated, so both sides see the same machine load (the machine is shared); best of each.
    grid = ",".join(str(m) for m in ms)
    cmd = [args.bin, "allan", path, "--rate", "100", "--grid", grid, "--json"]
    t_at, t_us, t_us_noci = [], [], []
    out = None
    for _ in range(args.repeat):
        t0 = time.perf_counter()
        at_taus, at_dev, _, at_n = allantools.oadev(y, rate=rate, data_type="freq", taus=taus)
        t_at.append(time.perf_counter() - t0)
        t0 = time.perf_counter()
        proc = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, check=True)
        t_us.append(time.perf_counter() - t0)
        out = proc.stdout
        t0 = time.perf_counter()
        subprocess.run(cmd + ["--edf", "none"], stdout=subprocess.DEVNULL,
                       stderr=subprocess.DEVNULL, check=True)
        t_us_noci.append(time.perf_counter() - t0)
    doc = json.loads(out)
    ch = doc["channels"]["gx"]
    ours = dict(zip([round(t / (1 / rate)) for t in ch["tau_s"]], ch["adev"]))
    diffs = []
    for m, d in zip(np.round(at_taus * rate).astype(int), at_dev):
        if m in ours:
            diffs.append(abs(ours[m] / d - 1.0))
    best_at, best_us = min(t_at), min(t_us)
    print(f"allantools {allantools.__version__} oadev alone: best {best_at*1e3:.1f} ms (runs: "
          + ", ".join(f"{t*1e3:.0f}" for t in t_at) + ")")
    print(f"imudrift allan whole command: best {best_us*1e3:.1f} ms (runs: "
          + ", ".join(f"{t*1e3:.0f}" for t in t_us) + ")")
    print(f"imudrift allan --edf none (no noise ID / intervals): best {min(t_us_noci)*1e3:.1f} ms")
    print(f"numpy.loadtxt of the same CSV (allantools has no reader): {t_load*1e3:.0f} ms")
    print(f"speed ratio allantools oadev alone / imudrift whole command: {best_at/best_us:.2f}x")
    print(f"speed ratio (numpy.loadtxt + oadev) / imudrift whole command: "
          f"{(t_load + best_at)/best_us:.1f}x")
    print(f"compared {len(diffs)} taus: max relative difference {max(diffs):.2e}")
    ratios = sorted(a / b for a, b in zip(t_at, t_us))
    print(f"per-pair ratios (same moment): median {ratios[len(ratios) // 2]:.2f}x, "
          f"best {ratios[-1]:.2f}x, worst {ratios[0]:.2f}x")
    print(f"load average during the runs: {' '.join(f'{v:.2f}' for v in os.getloadavg())}")
    if args.csv is None:
        os.remove(path)
        os.rmdir(tmpdir)
    return 0


if __name__ == "__main__":
    sys.exit(main())
