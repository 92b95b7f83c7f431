#!/usr/bin/env bash
# Woodman's MTx experiment as a protocol on a log (docs/woodman.md): a simulated 12 h static MTx
# log at 100 Hz is cut into 60 s runs; before each run the bias is removed as the mean of the
# window before it (its white-noise error included), the run starts level; the mean horizontal
# error at 60 s is printed beside Woodman's measured 152.67 m, for each calibration.
#   scripts/woodman_protocol.sh [SEED]      (about 1 min on 2 cores; writes a 600 MB log in a temp dir)
set -euo pipefail
cd "$(dirname "$0")/.."
seed=${1:-2007}
cargo build --release --quiet
bin=$PWD/target/release/imudrift
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
"$bin" generate configs/sensors/mtx.toml --duration 12h --rate 100 --seed "$seed" -o "$tmp/mtx12h.csv" 2>/dev/null
printf '%-12s %8s %28s %14s\n' calibration runs "mean horizontal error at 60 s" "Woodman"
for cal in none log-mean window:10s window:60s; do
  "$bin" drift "$tmp/mtx12h.csv" --model configs/sensors/mtx.toml --horizons 60 --calibration "$cal" \
    --replicates 10 --seed "$seed" --json 2>/dev/null > "$tmp/d.json"
  python3 - "$cal" "$tmp/d.json" <<'PY'
import json, sys
d = json.load(open(sys.argv[2]))
h = d["horizons"][0]
m = h["channels"]["pos_horizontal_m"]["measured"]
print(f"{sys.argv[1]:<12} {h['segments']:>8} {m['mean']:>10.1f} m [{m['mean_lo']:.1f}, {m['mean_hi']:.1f}] {'152.67 m':>14}")
PY
done
