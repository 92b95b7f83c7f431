#!/usr/bin/env python3
"""Do the six channels of a static log wander together? And would it move the hour's pitch?

imudrift's sensor model draws every channel independently (docs/model.md §2.3, §5). This script
measures how far the ADIS16405 runs 1-6 are from that (docs/drift.md, "A wander the channels
share"):

1. **Correlation.** Per run and averaging time tau: the six channels' tau-averages (outliers
   beyond 8 robust sd replaced by the median), their first differences (the increments the Allan
   variance squares), and the 15 pairwise correlations r_ij of those increments. Printed per
   group of pairs (below): their mean r and z = mean r / its sd under independent channels. The sd is Bartlett's
   (Box, Jenkins & Reinsel, *Time Series Analysis*, 4th ed., §11.1.3, eq. 11.1.7): for two
   independent series var(r_ij) = (1/n) sum_k rho_i(k) rho_j(k) over lags k (here |k| <= 20), each
   series' own autocorrelation rho estimated from the log; the 15 pairs' r are uncorrelated under
   independence, so var(mean r) = sum var(r_ij) / n_pairs^2; per group of pairs: the three
   gyro pairs, the three accelerometer pairs, the nine gyro-accelerometer pairs. `--null N`
   checks that z on N logs generated from `--model` (channels independent): mean 0, sd 1.
2. **`--experiment N`** (needs `pip install ./python` and `--model`, a sensor TOML such as the six
   runs' fitted model): the between-log statistic of the hour's attitude (D, the variance over the
   six runs of ln mean square over each run's two 1 h segments, log mean removed, attitude from a
   quaternion integration of 0.1 s rotation vectors) for the measured runs and for N simulated
   experiments of six runs, with the model's gyros as they are (rho = 0) and with a shared
   wander mixed in: g_c = sqrt(1 - rho) A_c + sqrt(rho) l_c B_x, A a run of the model, B_x the gx of
   another, l_c the channel's bias-instability coefficient over gx's (`--loadings`; 1, 0.98, 0.70
   for the six-run fit). p = (1 + #{D_sim >= D_measured}) / (N + 1) per axis. A sensitivity check, not a model:
   B_x's white noise is shared too (it does not reach the hour's attitude).

    IMUDRIFT_DATA=<folder of the real logs> python3 scripts/channel_correlation.py
        [--model FITTED.toml [--null 40] [--experiment 60]]
"""
import argparse
import gzip
import os
import pathlib
import sys

import numpy as np

RUNS = [f"adis16405_imudata/adis16405_imu{i}.csv.gz" for i in range(1, 7)]
NAMES = ["gx", "gy", "gz", "ax", "ay", "az"]
SAMPLES = 1_000_000
RATE_HZ = 100.0
SEGMENT = 360_000
BLOCK = 10


def load(path):
    return np.loadtxt(gzip.open(path, "rt"), delimiter=",", skiprows=2)[:SAMPLES]


def autocorr(x, lags):
    x = x - x.mean()
    v = x @ x
    return np.array([1.0] + [(x[:-k] @ x[k:]) / v for k in range(1, lags + 1)])


GROUPS = {"gyro": [(0, 1), (0, 2), (1, 2)], "accel": [(3, 4), (3, 5), (4, 5)],
          "gyro-accel": [(i, j) for i in range(3) for j in range(3, 6)]}


def correlation(log, m):
    """Per group of channel pairs: mean r of the tau-average increments, and its z."""
    med = np.median(log, 0)
    mad = 1.4826 * np.median(np.abs(log - med), 0)
    clean = np.where(np.abs(log - med) > 8 * mad, med, log)
    n_blocks = clean.shape[0] // m
    d = np.diff(clean[: n_blocks * m].reshape(n_blocks, m, 6).mean(1), axis=0)
    r = np.corrcoef(d.T)
    lags = min(20, d.shape[0] // 4)
    rho = [autocorr(d[:, c], lags) for c in range(6)]
    out = {}
    for name, pairs in GROUPS.items():
        var = [(1 + 2 * (rho[i][1:] @ rho[j][1:])) / d.shape[0] for i, j in pairs]
        rs = np.array([r[i, j] for i, j in pairs])
        out[name] = (rs.mean(), rs.mean() / (np.sqrt(np.sum(var)) / len(pairs)))
    return out


def quat_mul(q, r):
    w1, x1, y1, z1 = np.moveaxis(q, -1, 0)
    w2, x2, y2, z2 = np.moveaxis(r, -1, 0)
    return np.stack([w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2,
                     w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2,
                     w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2,
                     w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2], -1)


def rotation(v):
    a = np.linalg.norm(v, axis=-1, keepdims=True)
    s = np.where(a > 1e-12, np.sin(a / 2) / np.where(a > 1e-12, a, 1.0), 0.5)
    return np.concatenate([np.cos(a / 2), v * s], -1)


def hour_attitude(g):
    """g: (runs, samples, 3) rad/s, log mean removed -> (runs, 2 segments, roll/pitch/yaw)."""
    n = g.shape[0]
    inc = g[:, : 2 * SEGMENT].reshape(n, 2, SEGMENT // BLOCK, BLOCK, 3).sum(3) / RATE_HZ
    q = np.zeros((n, 2, 4))
    q[..., 0] = 1.0
    for k in range(SEGMENT // BLOCK):
        q = quat_mul(q, rotation(inc[:, :, k]))
    w, x, y, z = np.moveaxis(q, -1, 0)
    return np.stack([np.arctan2(2 * (w * x + y * z), 1 - 2 * (x * x + y * y)),
                     np.arcsin(np.clip(2 * (w * y - z * x), -1, 1)),
                     np.arctan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))], -1)


def between_logs(att):
    return np.var(np.log((att ** 2).mean(1)), axis=0, ddof=1)


RHOS = (0.0, 0.25, 0.45)


def experiment(job):
    import imudrift
    model, e, loading = job
    a, b = [], []
    for r in range(6):
        a.append(imudrift.generate(model, duration_s=SAMPLES / RATE_HZ, rate_hz=RATE_HZ, seed=10 + e,
                                   run=r, only="gyro")[["gx", "gy", "gz"]].values)
        b.append(imudrift.generate(model, duration_s=SAMPLES / RATE_HZ, rate_hz=RATE_HZ,
                                   seed=500_000 + e, run=r, only="gyro")["gx"].values)
    a, b = np.array(a), np.array(b)
    out = {}
    for rho in RHOS:
        g = np.sqrt(1 - rho) * a + np.sqrt(rho) * b[:, :, None] * loading[None, None, :]
        out[rho] = between_logs(hour_attitude(g - g.mean(1, keepdims=True)))
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--experiment", type=int, default=0, metavar="N")
    ap.add_argument("--null", type=int, default=0, metavar="N",
                    help="z of N logs generated from --model (its channels independent)")
    ap.add_argument("--model", help="sensor TOML for --null and --experiment")
    ap.add_argument("--loadings", default="1,0.9817,0.6949",
                    help="l_c of gx, gy, gz (default: the six-run fit's bias-instability "
                    "coefficients B, 33.92, 33.30, 23.57 deg/h, over gx's)")
    args = ap.parse_args()
    try:
        loading = np.array([float(v) for v in args.loadings.split(",")])
    except ValueError:
        loading = np.array([])
    if loading.shape != (3,) or not np.all(np.isfinite(loading)):
        sys.exit(f"--loadings: three finite numbers for gx, gy, gz (got {args.loadings!r})")
    data = os.environ.get("IMUDRIFT_DATA")
    if not data:
        sys.exit("set IMUDRIFT_DATA to the folder that holds adis16405_imudata/")
    paths = [pathlib.Path(data) / r for r in RUNS]
    missing = [str(p) for p in paths if not p.is_file()]
    if missing:
        sys.exit(f"IMUDRIFT_DATA: no ADIS16405 log at {', '.join(missing)}")
    if (args.null or args.experiment) and not (args.model and pathlib.Path(args.model).is_file()):
        sys.exit(f"--null and --experiment need --model, a sensor TOML (got {args.model!r})")
    logs = [load(p) for p in paths]
    taus = (100, 1000, 10000)
    print("mean r of the pairs' increments (z against independent channels), per tau-average")
    print("| run | " + " | ".join(f"{m / RATE_HZ:g} s: " + ", ".join(GROUPS) for m in taus) + " |")
    print("|---|" + "---|" * len(taus))
    for i, log in enumerate(logs):
        cells = [correlation(log, m) for m in taus]
        print(f"| {i + 1} | " + " | ".join(
            ", ".join(f"{c[g][0]:.2f} ({c[g][1]:.1f})" for g in GROUPS) for c in cells) + " |")
    if args.null:
        import imudrift
        zs = {(g, m): [] for g in GROUPS for m in taus}
        for k in range(args.null):
            df = imudrift.generate(args.model, duration_s=SAMPLES / RATE_HZ, rate_hz=RATE_HZ,
                                   seed=900_000 + k)
            sim = df[NAMES].values
            for m in taus:
                for g, (_, z) in correlation(sim, m).items():
                    zs[(g, m)].append(z)
        print(f"\nnull: {args.null} logs of the model (independent channels), z mean / sd:")
        for m in taus:
            print(f"  {m / RATE_HZ:g} s: " + ", ".join(
                f"{g} {np.mean(zs[(g, m)]):+.2f} / {np.std(zs[(g, m)], ddof=1):.2f}" for g in GROUPS))
    if args.experiment:
        from multiprocessing import Pool
        g = np.array([np.deg2rad(log[:, :3] - log[:, :3].mean(0)) for log in logs])
        measured = between_logs(hour_attitude(g))
        with Pool(os.cpu_count()) as pool:
            sims = pool.map(experiment, [(args.model, e, loading) for e in range(args.experiment)])
        print(f"\nhour's attitude between logs, D (roll, pitch, heading) measured: "
              f"{np.round(measured, 3).tolist()}")
        for rho in RHOS:
            d = np.array([s[rho] for s in sims])
            p = (1 + (d >= measured).sum(0)) / (len(sims) + 1)
            print(f"shared wander rho = {rho}: p = {np.round(p, 3).tolist()}, "
                  f"median simulated D {np.round(np.median(d, 0), 3).tolist()}")


if __name__ == "__main__":
    main()
