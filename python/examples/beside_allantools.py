#!/usr/bin/env python3
"""imudrift beside allantools on a real log: the overlapping Allan deviation of the ADIS16405
run 1 z gyro, repeated to a 4.32 M-sample float64 array (12 h at 100 Hz), timed in this process
with both libraries on the same array and the same taus ('octave', data_type="freq", rate=100),
the two alternating call by call, 7 calls each. Prints both times (best and median), the ratio of
the medians, the range of the 7 same-moment ratios, and the largest relative difference of the
devs.

Usage: python3 beside_allantools.py PATH/adis16405_imu1.csv.gz [samples] [repeats]
"""

import gzip
import sys
import time

import allantools
import numpy as np

import imudrift.allantools as ia

RATE_HZ = 100.0
REPEATS = 7


def gyro_z(path):
    with gzip.open(path, "rt") if path.endswith(".gz") else open(path) as f:
        for line in f:
            if not line.startswith("#"):
                col = line.strip().split(",").index("gyro_z_dps")
                break
        return np.loadtxt(f, delimiter=",", comments="#", usecols=col, dtype=np.float64)


def timed(f, data):
    """Wall-clock and CPU time (all threads of this process) of one call, and its result."""
    t0, c0 = time.perf_counter(), time.process_time()
    result = f(data, rate=RATE_HZ, data_type="freq", taus="octave")
    return time.perf_counter() - t0, time.process_time() - c0, result


def alternating(data, repeats):
    """Both libraries called in turn, `repeats` times each: (wall, cpu) lists and the results."""
    ours_t, ref_t = [], []
    for _ in range(repeats):
        w, c, ours = timed(ia.oadev, data)
        ours_t.append((w, c))
        w, c, ref = timed(allantools.oadev, data)
        ref_t.append((w, c))
    return ours_t, ref_t, ours, ref


def main():
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    samples = int(sys.argv[2]) if len(sys.argv) > 2 else 4_320_000
    run1 = gyro_z(sys.argv[1])
    data = np.resize(run1, samples)  # run 1 repeated end to end
    print(f"{len(run1)} samples of gyro_z_dps repeated to {len(data)} float64 samples at {RATE_HZ:g} Hz")
    repeats = int(sys.argv[3]) if len(sys.argv) > 3 else REPEATS
    ours_t, ref_t, ours, ref = alternating(data, repeats)
    assert np.array_equal(ours[0], ref[0]) and np.array_equal(ours[3], ref[3])
    worst = np.max(np.abs(ours[1] - ref[1]) / ref[1])
    med = lambda xs: float(np.median(xs))
    for name, t in [("imudrift.allantools.oadev", ours_t), ("allantools.oadev", ref_t)]:
        w, c = [x[0] for x in t], [x[1] for x in t]
        print(f"{name + ':':27s}{med(w) * 1e3:7.1f} ms median, {min(w) * 1e3:7.1f} ms best of "
              f"{repeats} (CPU median {med(c) * 1e3:.1f} ms)")
    pairs = [r[0] / o[0] for o, r in zip(ours_t, ref_t)]
    cpu = med([r[1] for r in ref_t]) / med([o[1] for o in ours_t])
    print(f"ratio of the medians: {med([r[0] for r in ref_t]) / med([o[0] for o in ours_t]):.1f}x "
          f"(same-moment pairs {min(pairs):.1f}x to {max(pairs):.1f}x; CPU time {cpu:.1f}x); "
          f"{len(ours[0])} taus; largest relative difference {worst:.1e}")

if __name__ == "__main__":
    main()
