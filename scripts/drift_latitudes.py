#!/usr/bin/env python3
"""The ADIS16405 drift check on the round Earth at several latitudes and on the flat Earth.

The logs' latitude is unknown; this shows which verdicts depend on it. Runs `imudrift drift` on
ADIS16405 runs (default 1-6 pooled; `--runs 4,5,6`) against a model (default: the datasheet
model; e.g. one `imudrift diagnose` fitted on other runs) under the default
protocol and the window/levelled one, horizons 60 s, 10 min, 1 h, 40 simulated experiments,
seed 1, for --flat-earth and --latitude 0, 30, 45, 60, and prints a markdown table of the cells
(heading / roll / pitch / horizontal position: `in` or the verdict and measured/model rms) and the
joint test.

    IMUDRIFT_DATA=<folder of the real logs> python3 scripts/drift_latitudes.py [--model M.toml]
        [--runs 4,5,6] [--earths flat,0,30,45,60]
"""
import argparse, json, os, pathlib, subprocess, sys

root = pathlib.Path(__file__).resolve().parent.parent
data = os.environ.get("IMUDRIFT_DATA")
if not data:
    sys.exit("set IMUDRIFT_DATA to the folder holding adis16405_imudata/")
ap = argparse.ArgumentParser()
ap.add_argument("--model", default=str(root / "configs/sensors/adis16405.toml"))
ap.add_argument("--bin", default=str(root / "target/release/imudrift"))
ap.add_argument("--runs", default="1,2,3,4,5,6", help="which ADIS16405 runs, e.g. 4,5,6")
ap.add_argument("--earths", default="flat,0,30,45,60", help="flat and latitudes in deg")
a = ap.parse_args()
logs = [f"{data}/adis16405_imudata/adis16405_imu{i}.csv.gz" for i in a.runs.split(",")]
flags = ["--model", a.model, "--rate", "100", "--gyro-unit", "deg/s", "--accel-unit", "g",
         "--col", "gx=gyro_x_dps,gy=gyro_y_dps,gz=gyro_z_dps,ax=acc_x_g,ay=acc_y_g,az=acc_z_g",
         "--horizons", "60s,10min,1h", "--replicates", "40", "--seed", "1", "--json"]
protocols = {"log mean, perfect start": [],
             "window 60 s, levelled 60 s": ["--calibration", "window:60s", "--init", "level:60s"]}
earths = {("flat" if e == "flat" else f"{e} deg"):
          (["--flat-earth"] if e == "flat" else ["--latitude", e]) for e in a.earths.split(",")}
quantities = ["heading_rad", "roll_rad", "pitch_rad", "pos_horizontal_m"]
print("| protocol | Earth | 60 s | 10 min | 1 h | joint test |")
print("|---|---|---|---|---|---|")
for pname, pflags in protocols.items():
    for ename, eflags in earths.items():
        out = subprocess.run([a.bin, "drift", *logs, *flags, *pflags, *eflags],
                             capture_output=True, text=True)
        if out.returncode != 0:
            sys.exit(out.stderr)
        d = json.loads(out.stdout)
        cells = []
        for h in d["horizons"]:
            parts = []
            for q in quantities:
                c = h["channels"][q]
                v = c["verdict"]
                parts.append("in" if v == "inside" else f"**{v}** x{c['ratio']:.2f}")
            cells.append(" / ".join(parts))
        j = d["joint"]
        verdict = "consistent" if j["consistent"] else "rejected"
        joint = f"{j['outside']} of {j['cells']} out, p = {j['p_value']:.3f}, {verdict}"
        print(f"| {pname} | {ename} | " + " | ".join(cells) + f" | {joint} |", flush=True)
