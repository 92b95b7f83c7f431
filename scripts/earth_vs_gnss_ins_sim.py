#!/usr/bin/env python3
"""imudrift's round, rotating Earth beside an independent mechanisation: gnss-ins-sim's free
integration (Aceinna/gnss-ins-sim, `demo_algorithms/free_integration.py`, NED frame with Earth
rotation: `ref_frame=0`).

Both integrate an ideal static, level, north-facing IMU at 45 deg N, 10 Hz, once without errors
and once with a constant x-gyro bias of 0.1 deg/h; the difference of the two solutions is the
bias's position error, so each mechanisation's own integration error cancels. imudrift runs the
same experiment as a user would: `imudrift simulate` of a scenario with `[earth] model = "wgs84"`,
`latitude_deg = 45`, a sensor whose only error is `[gyro.x] constant_bias = "0.1 deg/h"` (its
static mechanisation is exact to rounding, so the error is the bias's). gnss-ins-sim leaves the
vertical channel free, so the scenario says `vertical = "free"` too; it is also run with the height
held (the default), for the closed form R eps (t - sin(w_s t) / w_s). Pass: imudrift's horizontal
error within 2 % of gnss-ins-sim's at 10 min, 30 min and 1 h.

gnss-ins-sim is not vendored: pass a checkout (`git clone https://github.com/Aceinna/gnss-ins-sim`;
the figures in docs/strapdown.md used commit 966ff27). Needs numpy (and what gnss-ins-sim imports).

Usage: python3 scripts/earth_vs_gnss_ins_sim.py --gnss-ins-sim /path/to/gnss-ins-sim [--hours 1]
"""
import argparse
import json
import math
import os
import subprocess
import sys
import tempfile
import time

LAT_DEG = 45.0
RATE_HZ = 10.0
BIAS_DEG_H = 0.1
A = 6378137.0
E2 = 1.0 / 298.257223563 * (2.0 - 1.0 / 298.257223563)


def gnss_ins_sim_positions(path, duration_s, bias_deg_h):
    """gnss-ins-sim's free-integration solution (lat rad, lon rad, alt m per sample) of a static
    level IMU facing north at LAT_DEG with an x-gyro bias, and the reference."""
    sys.path.insert(0, path)
    import numpy as np
    from gnss_ins_sim.sim import imu_model, ins_sim
    from demo_algorithms import free_integration

    zeros = np.zeros(3)
    imu_err = {
        'gyro_b': np.array([bias_deg_h, 0.0, 0.0]),   # deg/h
        'gyro_arw': zeros, 'gyro_b_stability': zeros, 'gyro_b_corr': np.array([math.inf] * 3),
        'accel_b': zeros, 'accel_vrw': zeros, 'accel_b_stability': zeros,
        'accel_b_corr': np.array([math.inf] * 3),
    }
    imu = imu_model.IMU(accuracy=imu_err, axis=6, gps=False)
    with tempfile.TemporaryDirectory() as tmp:
        motion = os.path.join(tmp, 'static.csv')
        with open(motion, 'w') as f:
            f.write('ini lat (deg),ini lon (deg),ini alt (m),ini vx_body (m/s),ini vy_body (m/s),'
                    'ini vz_body (m/s),ini yaw (deg),ini pitch (deg),ini roll (deg)\n')
            f.write('%g,0,0,0,0,0,0,0,0\n' % LAT_DEG)
            f.write('command type,yaw (deg),pitch (deg),roll (deg),vx_body (m/s),vy_body (m/s),'
                    'vz_body (m/s),command duration (s),GPS visibility\n')
            f.write('1,0,0,0,0,0,0,%g,0\n' % duration_s)
        ini = np.array([LAT_DEG * math.pi / 180.0, 0, 0, 0, 0, 0, 0, 0, 0], dtype=float)
        algo = free_integration.FreeIntegration(ini)
        sim = ins_sim.Sim([RATE_HZ, 0.0, 0.0], motion, ref_frame=0, imu=imu, mode=None,
                          env=None, algorithm=algo)
        sim.run(1)
        pos = sim.get_data(['pos'])[0]
        (_, p), = pos.items() if isinstance(pos, dict) else [(0, pos)]
        return np.asarray(p)


def metres(dlat, dlon, lat):
    s2 = math.sin(lat) ** 2
    rn = A * (1 - E2) / (1 - E2 * s2) ** 1.5
    re = A / math.sqrt(1 - E2 * s2)
    return dlat * rn, dlon * re * math.cos(lat)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument('--gnss-ins-sim', required=True, help='checkout of Aceinna/gnss-ins-sim')
    ap.add_argument('--hours', type=float, default=1.0)
    args = ap.parse_args()
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    duration = args.hours * 3600.0
    times = [t for t in (600.0, 1800.0, 3600.0, 5400.0, 7200.0) if t <= duration + 1e-9]
    gis = os.path.abspath(args.gnss_ins_sim)
    here = os.getcwd()
    os.chdir(gis)
    t0 = time.perf_counter()
    # One second beyond the last time: row k of its output is the solution at t = k / RATE_HZ.
    ideal = gnss_ins_sim_positions(gis, duration + 1.0, 0.0)
    biased = gnss_ins_sim_positions(gis, duration + 1.0, BIAS_DEG_H)
    wall = time.perf_counter() - t0
    os.chdir(here)
    lat0 = LAT_DEG * math.pi / 180.0
    ref = {}
    for t in times:
        k = int(round(t * RATE_HZ))
        n, e = metres(biased[k, 0] - ideal[k, 0], biased[k, 1] - ideal[k, 1], lat0)
        ref[t] = math.hypot(n, e)
    ours = {}
    subprocess.run(['cargo', 'build', '--release', '-q'], cwd=root, check=True)
    binary = os.path.join(root, 'target', 'release', 'imudrift')
    with tempfile.TemporaryDirectory() as tmp:
        sensor = os.path.join(tmp, 'biased.toml')
        with open(sensor, 'w') as f:
            f.write('name = "x gyro bias"\n[gyro.x]\nconstant_bias = "%g deg/h"\n' % BIAS_DEG_H)
        for vertical in ('free', 'held'):
            scenario = os.path.join(tmp, 'earth-%s.toml' % vertical)
            with open(scenario, 'w') as f:
                f.write('sensor = "biased.toml"\nduration_s = %g\nrate_hz = %g\nruns = 1\n'
                        '[earth]\nmodel = "wgs84"\nlatitude_deg = %g\nvertical = "%s"\n'
                        '[checkpoints]\ntimes_s = [%s]\n'
                        % (duration, RATE_HZ, LAT_DEG, vertical, ', '.join('%g' % t for t in times)))
            out = subprocess.run([binary, 'simulate', scenario, '--json'], check=True,
                                 capture_output=True, text=True).stdout
            doc = json.loads(out)
            ours[vertical] = {round(c['t_s']): c['channels']['pos_horizontal_m']['mean']
                              for c in doc['checkpoints']}
    g = 9.8062  # normal gravity at 45 deg N, for the closed forms' printout only
    r = math.sqrt(A * (1 - E2) / (1 - E2 * 0.5) ** 1.5 * A / math.sqrt(1 - E2 * 0.5))
    ws = math.sqrt(g / r)
    eps = BIAS_DEG_H / 3600.0 * math.pi / 180.0
    print('x-gyro bias %g deg/h at %g deg N, %g Hz; gnss-ins-sim %.1f s for two runs'
          % (BIAS_DEG_H, LAT_DEG, RATE_HZ, wall))
    print('| t | gnss-ins-sim (free vertical) | imudrift free vertical | ratio | imudrift height held '
          '| R eps (t - sin(w_s t)/w_s) | flat g eps t^3/6 |')
    print('|---|---|---|---|---|---|---|')
    ok = True
    for t in times:
        ratio = ours['free'][round(t)] / ref[t]
        if t <= 3600.0 and abs(ratio - 1.0) > 0.02:
            ok = False
        print('| %g min | %.1f m | %.1f m | %.4f | %.1f m | %.1f m | %.1f m |'
              % (t / 60, ref[t], ours['free'][round(t)], ratio, ours['held'][round(t)],
                 r * eps * (t - math.sin(ws * t) / ws), g * eps * t ** 3 / 6))
    print('within 2 % at 10, 30 and 60 min:', 'yes' if ok else 'NO')
    sys.exit(0 if ok else 1)


if __name__ == '__main__':
    main()
