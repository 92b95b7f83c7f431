#!/usr/bin/env python3
"""Horizontal position error on the round, rotating Earth against Woodman's flat one, per sensor.

For each shipped sensor (MTx, ADIS16405, GG1320AN, GG5300): `imudrift simulate`, static and
level, 2 h at 20 Hz, 200 runs, seed 1, checkpoints 1, 10, 30, 60 and 120 min, once on the
WGS-84 Earth at 45 deg N with the height held and once on the flat Earth. Prints a markdown
table of the Monte Carlo rms on each Earth, their ratio round / flat, and the round Earth's law
beside the flat law where the small-angle laws hold.

    python3 scripts/earth_ratio_table.py [--bin target/release/imudrift] [--runs 200]
"""
import argparse, json, pathlib, subprocess, sys, tempfile

root = pathlib.Path(__file__).resolve().parent.parent
ap = argparse.ArgumentParser()
ap.add_argument("--bin", default=str(root / "target/release/imudrift"))
ap.add_argument("--runs", type=int, default=200)
a = ap.parse_args()
times = [60.0, 600.0, 1800.0, 3600.0, 7200.0]
earths = {"round": '[earth]\nmodel = "wgs84"\nlatitude_deg = 45.0\n',
          "flat": '[earth]\nmodel = "flat"\n'}


def fmt(m):
    if m is None:
        return "n/a"
    return f"{m / 1000:.3g} km" if m >= 1000 else f"{m:.3g} m"


print("| sensor | t | rms, round Earth | rms, flat Earth | round / flat | law round / law flat |")
print("|---|---|---|---|---|---|")
with tempfile.TemporaryDirectory() as tmp:
    for name in ["mtx", "adis16405", "gg1320an", "gg5300"]:
        res = {}
        for earth, table in earths.items():
            s = pathlib.Path(tmp) / f"{name}-{earth}.toml"
            s.write_text(
                f'sensor = "{root / "configs/sensors" / (name + ".toml")}"\n'
                f"duration_s = 7200.0\nrate_hz = 20.0\nruns = {a.runs}\nseed = 1\n{table}"
                f"[checkpoints]\ntimes_s = {times}\n")
            out = subprocess.run([a.bin, "simulate", str(s), "--json"], capture_output=True,
                                 text=True)
            if out.returncode != 0:
                sys.exit(out.stderr)
            res[earth] = json.loads(out.stdout)
        label = res["round"]["sensor"]
        for i, t in enumerate(times):
            r = res["round"]["checkpoints"][i]["channels"]["pos_horizontal_m"]
            f = res["flat"]["checkpoints"][i]["channels"]["pos_horizontal_m"]
            laws = "n/a (beyond the small-angle laws)"
            if r.get("law_rms") and r.get("flat_law_rms"):
                laws = f"{fmt(r['law_rms'])} / {fmt(r['flat_law_rms'])} = {r['law_rms'] / r['flat_law_rms']:.3f}"
            print(f"| {label} | {t / 60:g} min | {fmt(r['rms'])} | {fmt(f['rms'])} | "
                  f"{r['rms'] / f['rms']:.3f} | {laws} |", flush=True)
