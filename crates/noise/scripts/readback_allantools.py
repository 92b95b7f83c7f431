"""Read a generated 12 h MTx log with allantools (overlapping ADEV, octave taus) and compare with Woodman Table 4.

Usage: imudrift generate configs/sensors/mtx.toml --duration 12h --rate 100 -o mtx.csv --seed 1
       python3 crates/noise/scripts/readback_allantools.py mtx.csv      (pip install numpy allantools)
"""
import sys, numpy as np, allantools
path = sys.argv[1]
data = np.loadtxt(path, delimiter=",", comments="#", skiprows=3, usecols=(1, 2, 3))
rate = 100.0
arw = [0.075, 0.078, 0.079]; bimin = [0.010, 0.009, 0.012]
print("allantools", allantools.__version__, "samples", data.shape[0])
for i, name in enumerate("xyz"):
    y = np.degrees(data[:, i])
    t1, a1, _, _ = allantools.oadev(y, rate=rate, data_type="freq", taus=[1.0])
    taus, ad, _, _ = allantools.oadev(y, rate=rate, data_type="freq", taus="octave")
    ok = taus <= data.shape[0] / rate / 9  # Woodman: at least 9 bins
    j = np.argmin(np.where(ok, ad, np.inf))
    print(f"g{name}: ADEV(1 s) {a1[0]:.5f} deg/s ({100*(a1[0]/arw[i]-1):+.2f} % vs ARW {arw[i]}), "
          f"min {ad[j]:.5f} deg/s at {taus[j]:.2f} s ({100*(ad[j]/bimin[i]-1):+.1f} % vs {bimin[i]})")
