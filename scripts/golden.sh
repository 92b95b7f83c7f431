#!/usr/bin/env bash
# Byte-identity check of the user-visible outputs across a refactor.
#
#   scripts/golden.sh capture DIR   run the commands below with the release binary, store every output in DIR
#   scripts/golden.sh check DIR     run them again into a temporary directory and compare byte for byte with DIR
#
# Covers: `simulate` of every shipped scenario (--json and --out), `allan` on ADIS16405 run 1
# (--json and --out), `spec` of every shipped sensor (--json), `generate` (a short log), and
# `diagnose` on ADIS16405 run 1 (--json and --out), `drift` on ADIS16405 runs 1-2 (--json and --out). The real logs are read from $IMUDRIFT_DATA.
# Human text on stderr is not compared (it holds progress and timings). `check` compares every
# byte except the JSON `trajectory` value, the diagnosed model's [fitted_on] table and the
# simulate JSON's `earth` object where the reference predates it (see below).
set -euo pipefail
cd "$(dirname "$0")/.."
mode=${1:?usage: golden.sh capture|check DIR}
ref=${2:?usage: golden.sh capture|check DIR}
data=${IMUDRIFT_DATA:?set IMUDRIFT_DATA to the directory of the real IMU logs}
# IMUDRIFT_BIN: another binary (e.g. the previous main's, to capture its outputs); else this build.
if [ -n "${IMUDRIFT_BIN:-}" ]; then bin=$IMUDRIFT_BIN; else cargo build --release --quiet; bin=$PWD/target/release/imudrift; fi
if [ "$mode" = capture ]; then out=$ref; mkdir -p "$out"; else out=$(mktemp -d); trap 'rm -rf "$out"' EXIT; fi
run() { # name, then the command's arguments
  local name=$1; shift
  mkdir -p "$out/$name"
  "$bin" "$@" --json --out "$out/$name/files" >"$out/$name/stdout.json" 2>"$out/$name.stderr" || { echo "golden: $name failed:" >&2; cat "$out/$name.stderr" >&2; exit 1; }
  rm -f "$out/$name.stderr"
}
for s in configs/scenarios/*.toml; do
  n=$(basename "$s" .toml)
  run "simulate-$n" simulate "$s" --threads 2
done
adis=$data/adis16405_imudata
cols=gx=gyro_x_dps,gy=gyro_y_dps,gz=gyro_z_dps,ax=acc_x_g,ay=acc_y_g,az=acc_z_g
run allan-adis1 allan "$adis/adis16405_imu1.csv.gz" --rate 100 --gyro-unit deg/s --accel-unit g --col "$cols"
mkdir -p "$out/spec"
"$bin" spec configs/sensors/*.toml --readback --json >"$out/spec/stdout.json" 2>/dev/null
mkdir -p "$out/generate"
"$bin" generate configs/sensors/mtx.toml --duration 20 --rate 100 --seed 7 -o "$out/generate/mtx.csv" 2>/dev/null
run diagnose-adis1 diagnose "$adis/adis16405_imu1.csv.gz" --model configs/sensors/adis16405.toml \
  --rate 100 --gyro-unit deg/s --accel-unit g --col "$cols" --horizons 60,3600
run drift-adis12 drift "$adis/adis16405_imu1.csv.gz" "$adis/adis16405_imu2.csv.gz" \
  --model configs/sensors/adis16405.toml --rate 100 --gyro-unit deg/s --accel-unit g --col "$cols" \
  --horizons 60,600 --replicates 10 --calibration window:60 --init level:60
if [ "$mode" = check ]; then
  # The JSON `trajectory` changed from a Rust debug string to an object on 2026-11-25 (docs/cli.md,
  # "Contract changes"): a capture taken before then differs in that one value by design; so does
  # the diagnosed model's [fitted_on] table (added on 2026-11-25), cut from both sides below. Both
  # sides are copied and that value alone is replaced by `null` (the value's extent found by a
  # JSON decoder, the rest of each file left as it is), so every other byte is still compared.
  # The drift check's p50 / p95 are computed by the one shared type-7 quantile since 2026-11-25
  # (docs/cli.md, "Contract changes"), `a + f (b - a)` where drift had its own copy, `a (1 - f) +
  # b f`: the same number up to rounding, so in the drift outputs (drift-*) alone these two keys
  # are compared to 14 significant digits; everything else stays byte for byte.
  norm=$(mktemp -d); trap 'rm -rf "$out" "$norm"' EXIT
  cp -r "$ref" "$norm/ref"; cp -r "$out" "$norm/out"
  python3 - "$norm/ref" "$norm/out" <<'PY'
import json, pathlib, re, sys
key = '"trajectory": '
# The diagnosed model's [fitted_on] table (added 2026-11-25, docs/cli.md "Contract changes") is
# cut from the TOML file and from the JSON `corrected_model_toml` string on both sides.
fitted = "\n[fitted_on]\n"
toml_key = '"corrected_model_toml": '
for root in sys.argv[1:]:
    for path in pathlib.Path(root).rglob("*.toml"):
        path.write_text(path.read_text().split(fitted)[0])
    for path in pathlib.Path(root).rglob("*.json"):
        text = path.read_text()
        out, pos = [], 0
        while (at := text.find(key, pos)) >= 0:
            start = at + len(key)
            _, end = json.JSONDecoder().raw_decode(text, start)
            out += [text[pos:start], "null"]
            pos = end
        text = "".join(out) + text[pos:]
        out, pos = [], 0
        while (at := text.find(toml_key, pos)) >= 0:
            start = at + len(toml_key)
            value, end = json.JSONDecoder().raw_decode(text, start)
            out += [text[pos:start], json.dumps(value.split(fitted)[0], ensure_ascii=False)]
            pos = end
        text = "".join(out) + text[pos:]
        # The simulate JSON's `earth` object (added with the round Earth, docs/cli.md "Contract
        # changes") is cut where the reference has none; every other byte is still compared.
        if root == sys.argv[2]:
            ref_path = pathlib.Path(sys.argv[1]) / path.relative_to(root)
            if ref_path.exists() and '"earth": {' not in ref_path.read_text():
                text = re.sub(r'\n  "earth": \{[^}]*\},', '', text)
        if any(part.startswith("drift-") for part in path.parts):
            text = re.sub(r'("p(?:50|95)": )(-?[0-9.eE+-]+)', lambda m: m[1] + f"{float(m[2]):.13e}", text)
        path.write_text(text)
PY
  if diff -r -x .imudrift.lock "$norm/ref" "$norm/out" >/dev/null; then
    echo "golden: every output byte-identical to $ref (the trajectory value and drift p50/p95 rounding aside)"
  else
    diff -rq -x .imudrift.lock "$norm/ref" "$norm/out" || true
    echo "golden: outputs differ from $ref" >&2
    exit 1
  fi
else
  echo "golden: captured into $ref"
fi
