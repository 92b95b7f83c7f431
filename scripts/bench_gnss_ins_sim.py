#!/usr/bin/env python3
"""Throughput of imudrift against gnss-ins-sim (Aceinna, the Python simulator) on one scenario:
Woodman's MTx experiment, static and level, 100 Hz, 60 s, free (strapdown) integration, many runs.

gnss-ins-sim is not vendored: pass the path of a checkout (e.g. `git clone
https://github.com/Aceinna/gnss-ins-sim`; the figures in docs/performance.md used commit 966ff27). This script only
drives it through its public API (imu_model.IMU, ins_sim.Sim, demo_algorithms.free_integration).

Both simulators run on one core (gnss-ins-sim is single-threaded Python/numpy; imudrift with
--threads 1) one after the other in the same session; throughput = runs x samples / wall time.

MTx error model given to gnss-ins-sim (its closest terms; its `pathgen.gyro_gen` / `acc_gen` have a
constant bias, white noise and a bias drift that is a first-order Gauss-Markov process (white with
an infinite correlation time), no flicker noise or rate random walk, and optional vibration): gyro ARW from Woodman Table 4 (0.075, 0.078, 0.079 deg/sqrt(s) = 4.5, 4.68, 4.74
deg/sqrt(h)), bias drift as a first-order Gauss-Markov with Table 4's bias instability (36, 32.4,
43.2 deg/h) and correlation times at the Allan minimum (620, 530, 270 s); accelerometer VRW
0.004 m/s^2/sqrt(Hz) = 0.24 m/s/sqrt(h) (MTx manual). imudrift runs configs/scenarios/mtx-static-60s.toml
(configs/sensors/mtx.toml: white noise, flicker bias instability as 7 Gauss-Markov components per
axis, 0.1 s .. 1e5 s, the four slowest advanced every 10 .. 10 000 samples; rate random walk;
accelerometer white noise), i.e. more noise processes per sample.

imudrift is measured twice: with the full MTx model, and with exactly gnss-ins-sim's terms
(white noise + one Gauss-Markov bias per gyro axis + accelerometer white noise; the script writes that
sensor file and a copy of the scenario into a temporary directory): the like-for-like ratio.

Usage: python3 scripts/bench_gnss_ins_sim.py --gnss-ins-sim <gnss-ins-sim checkout> [--runs 20] [--imudrift-runs 2000]
"""
import argparse
import json
import math
import os
import subprocess
import sys
import tempfile
import time

FS_HZ = 100.0
DURATION_S = 60.0


def bench_gnss_ins_sim(path, runs):
    sys.path.insert(0, path)
    import numpy as np
    from gnss_ins_sim.sim import imu_model, ins_sim
    from demo_algorithms import free_integration

    d2r = math.pi / 180.0
    imu_err = {
        'gyro_b': np.zeros(3),
        'gyro_arw': np.array([0.075, 0.078, 0.079]) * 60.0,          # deg/sqrt(h)
        'gyro_b_stability': np.array([0.010, 0.009, 0.012]) * 3600.0,  # deg/h
        'gyro_b_corr': np.array([620.0, 530.0, 270.0]),                # s
        'accel_b': np.zeros(3),
        'accel_vrw': np.array([0.24, 0.24, 0.24]),                     # m/s/sqrt(h)
        'accel_b_stability': np.zeros(3),
        'accel_b_corr': np.array([float('inf')] * 3),
    }
    imu = imu_model.IMU(accuracy=imu_err, axis=6, gps=False)
    with tempfile.TemporaryDirectory() as tmp:
        motion = os.path.join(tmp, 'static60.csv')
        with open(motion, 'w') as f:
            f.write('ini lat (deg),ini lon (deg),ini alt (m),ini vx_body (m/s),ini vy_body (m/s),'
                    'ini vz_body (m/s),ini yaw (deg),ini pitch (deg),ini roll (deg)\n')
            f.write('0,0,0,0,0,0,0,0,0\n')
            f.write('command type,yaw (deg),pitch (deg),roll (deg),vx_body (m/s),vy_body (m/s),'
                    'vz_body (m/s),command duration (s),GPS visibility\n')
            f.write('1,0,0,0,0,0,0,%g,0\n' % DURATION_S)
        ini = np.array([0.0, 0.0, 0.0, 0, 0, 0, 0, 0, 0]) * d2r
        algo = free_integration.FreeIntegration(ini)
        # ref_frame=1: virtual inertial frame (no Earth rotation), as imudrift's flat non-rotating Earth.
        sim = ins_sim.Sim([FS_HZ, 0.0, 0.0], motion, ref_frame=1, imu=imu, mode=None, env=None,
                          algorithm=algo)
        t0 = time.perf_counter()
        sim.run(runs)
        wall = time.perf_counter() - t0
        # Sanity check that the runs integrated noisy data: mean horizontal error at the end.
        ref = sim.get_data(['ref_pos'])[0]
        pos = sim.get_data(['pos'])[0]
        # Algorithm outputs are keyed by '<algorithm index>_<run index>' (or by run index).
        ends = [v[-1, :2] for _, v in sorted(pos.items(), key=lambda kv: str(kv[0]))]
        horiz = [float(np.hypot(*(e - ref[-1, :2]))) for e in ends]
    samples = int(round(FS_HZ * DURATION_S)) + 1
    return {'runs': runs, 'wall_s': wall, 'steps': runs * samples,
            'steps_per_s': runs * samples / wall, 'runs_per_s': runs / wall,
            'mean_horizontal_60s_m': sum(horiz) / len(horiz)}


# The gnss-ins-sim error model above in imudrift's sensor format: white noise plus one first-order
# Gauss-Markov bias per gyro axis (gnss-ins-sim's bias_drift has stationary std b_stability and
# correlation time b_corr: pathgen.bias_drift), accelerometer white noise. Same terms, same numbers.
EQUIVALENT_SENSOR = """name = "Xsens MTx (gnss-ins-sim terms)"
[gyro.x]
white_noise = "0.075 deg/sqrt(s)"
gauss_markov = { sigma = "0.010 deg/s", time_constant = "620 s" }
[gyro.y]
white_noise = "0.078 deg/sqrt(s)"
gauss_markov = { sigma = "0.009 deg/s", time_constant = "530 s" }
[gyro.z]
white_noise = "0.079 deg/sqrt(s)"
gauss_markov = { sigma = "0.012 deg/s", time_constant = "270 s" }
[accel.all]
white_noise = "0.004 m/s^2/sqrt(Hz)"
"""


def equivalent_scenario(tmp, scenario):
    """Copy of the scenario pointing at the gnss-ins-sim-equivalent sensor."""
    sensor = os.path.join(tmp, 'mtx-gnss-ins-sim-terms.toml')
    with open(sensor, 'w') as f:
        f.write(EQUIVALENT_SENSOR)
    lines = open(scenario).read().splitlines()
    out = os.path.join(tmp, 'scenario.toml')
    with open(out, 'w') as f:
        for line in lines:
            if line.startswith('sensor ='):
                line = 'sensor = "%s"' % sensor
            f.write(line + '\n')
    return out


def bench_imudrift(binary, scenario, runs, threads):
    t0 = time.perf_counter()
    out = subprocess.run([binary, 'simulate', scenario, '--runs', str(runs), '--threads', str(threads),
                          '--json', '--no-ablation'], check=True, capture_output=True)
    wall = time.perf_counter() - t0
    doc = json.loads(out.stdout)
    samples = int(round(doc['rate_hz'] * doc['duration_s']))
    return {'runs': runs, 'threads': threads, 'wall_s': wall, 'steps': runs * samples,
            'steps_per_s': runs * samples / wall, 'runs_per_s': runs / wall,
            'mean_horizontal_60s_m': doc['checkpoints'][-1]['channels']['pos_horizontal_m']['mean']}


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument('--gnss-ins-sim', required=True, help='path of a gnss-ins-sim checkout')
    ap.add_argument('--runs', type=int, default=20, help='gnss-ins-sim runs')
    ap.add_argument('--imudrift', default='target/release/imudrift')
    ap.add_argument('--scenario', default='configs/scenarios/mtx-static-60s.toml')
    ap.add_argument('--imudrift-runs', type=int, default=2000)
    args = ap.parse_args()
    here = os.getcwd()
    os.chdir(args.gnss_ins_sim)
    g = bench_gnss_ins_sim(os.path.abspath(args.gnss_ins_sim), args.runs)
    os.chdir(here)
    i = bench_imudrift(args.imudrift, args.scenario, args.imudrift_runs, 1)
    with tempfile.TemporaryDirectory() as tmp:
        e = bench_imudrift(args.imudrift, equivalent_scenario(tmp, args.scenario), args.imudrift_runs, 1)
    print(json.dumps({'gnss_ins_sim': g,
                      'imudrift_mtx_model': i,
                      'imudrift_same_terms_as_gnss_ins_sim': e,
                      'ratio_one_core_mtx_model': i['steps_per_s'] / g['steps_per_s'],
                      'ratio_one_core_same_terms': e['steps_per_s'] / g['steps_per_s']}, indent=2))


if __name__ == '__main__':
    main()
