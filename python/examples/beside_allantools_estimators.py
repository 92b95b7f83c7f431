#!/usr/bin/env python3
"""imudrift beside allantools for the estimators of issue 45 (mtotdev, ttotdev, htotdev, theo1,
mtie, tierms, gradev) on the ADIS16405 run 1 z gyro (data_type="freq", rate 100 Hz, octave
taus), whole calls timed in this process, the two libraries alternating call by call. Prints, per
function and record length, the median wall time of each, the ratio of the medians and the
largest relative difference of the deviations.

allantools computes the total estimators and Theo1 with Python loops (O(N m) per tau): they are
timed on the first `short` samples (default 2000; at 1,000,000 samples allantools would take
days), MTIE on the first 20,000 (allantools' window view is O(N m) per tau too), TIE rms and gradev
on the whole log.

Usage: python3 beside_allantools_estimators.py PATH/adis16405_imu1.csv.gz [short] [repeats]
"""

import sys
import time

import allantools
import numpy as np

import imudrift.allantools as ia
from beside_allantools import gyro_z  # the same reader of the ADIS log (this directory)

RATE_HZ = 100.0


def timed(f, data):
    t0 = time.perf_counter()
    result = f(data, rate=RATE_HZ, data_type="freq", taus="octave")
    return time.perf_counter() - t0, result


def compare(name, data, repeats):
    ours_t, ref_t = [], []
    for _ in range(repeats):
        w, ours = timed(getattr(ia, name), data)
        ours_t.append(w)
        w, ref = timed(getattr(allantools, name), data)
        ref_t.append(w)
    assert np.array_equal(ours[3], ref[3]), name
    diff = np.max(np.abs(ours[1] / ref[1] - 1.0))
    o, r = np.median(ours_t), np.median(ref_t)
    print(f"{name:8s} N={len(data):8d}  imudrift {1e3 * o:9.2f} ms  allantools {1e3 * r:10.1f} ms"
          f"  ratio {r / o:8.1f}x  max rel diff {diff:.1e}  ({len(ours[0])} taus, {repeats} calls each)")


def main():
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    short = int(sys.argv[2]) if len(sys.argv) > 2 else 2000
    repeats = int(sys.argv[3]) if len(sys.argv) > 3 else 3
    gz = gyro_z(sys.argv[1])
    for name in ["mtotdev", "ttotdev", "htotdev", "theo1"]:
        compare(name, gz[:short], repeats)
    compare("mtie", gz[:20_000], repeats)
    compare("tierms", gz, repeats)
    compare("gradev", gz, repeats)


if __name__ == "__main__":
    main()
