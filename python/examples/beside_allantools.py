#!/usr/bin/env python3
"""imudrift beside allantools on a real log: the overlapping Allan deviation of the ADIS16405
run 1 z gyro, repeated to a 4.32 M-sample float64 array (12 h at 100 Hz), timed in this process
with both libraries on the same array and the same taus ('octave', data_type="freq", rate=100),
best of 3 each. Prints both times, the ratio and the largest relative difference of the devs.

Usage: python3 beside_allantools.py PATH/adis16405_imu1.csv.gz [samples]
"""

import gzip
import sys
import time

import allantools
import numpy as np

import imudrift.allantools as ia

RATE_HZ = 100.0
REPEATS = 3


def gyro_z(path):
    with gzip.open(path, "rt") if path.endswith(".gz") else open(path) as f:
        for line in f:
            if not line.startswith("#"):
                col = line.strip().split(",").index("gyro_z_dps")
                break
        return np.loadtxt(f, delimiter=",", comments="#", usecols=col, dtype=np.float64)


def best_of(f, data):
    """Best wall-clock time and best CPU time of this process (all threads) over REPEATS calls."""
    best, best_cpu, result = float("inf"), float("inf"), None
    for _ in range(REPEATS):
        t0, c0 = time.perf_counter(), time.process_time()
        result = f(data, rate=RATE_HZ, data_type="freq", taus="octave")
        best = min(best, time.perf_counter() - t0)
        best_cpu = min(best_cpu, time.process_time() - c0)
    return best, best_cpu, result


def main():
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    samples = int(sys.argv[2]) if len(sys.argv) > 2 else 4_320_000
    run1 = gyro_z(sys.argv[1])
    data = np.resize(run1, samples)  # run 1 repeated end to end
    print(f"{len(run1)} samples of gyro_z_dps repeated to {len(data)} float64 samples at {RATE_HZ:g} Hz")
    t_ours, cpu_ours, ours = best_of(ia.oadev, data)
    t_ref, cpu_ref, ref = best_of(allantools.oadev, data)
    assert np.array_equal(ours[0], ref[0]) and np.array_equal(ours[3], ref[3])
    worst = np.max(np.abs(ours[1] - ref[1]) / ref[1])
    print(f"imudrift.allantools.oadev: {t_ours * 1e3:.1f} ms (best of {REPEATS}; CPU {cpu_ours * 1e3:.1f} ms)")
    print(f"allantools.oadev:          {t_ref * 1e3:.1f} ms (best of {REPEATS}; CPU {cpu_ref * 1e3:.1f} ms)")
    print(f"ratio: {t_ref / t_ours:.1f}x (CPU time {cpu_ref / cpu_ours:.1f}x); {len(ours[0])} taus; "
          f"largest relative difference {worst:.1e}")


if __name__ == "__main__":
    main()
