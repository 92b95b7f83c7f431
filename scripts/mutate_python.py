#!/usr/bin/env python3
"""Mutation run of the Python package's inputs (issue 46): the mutation families of
scripts/mutate_inputs.py (a log's values and shapes: bad fields, bad columns, constant columns,
truncated, rows removed / repeated / shuffled, two at once), applied to arrays instead of files,
with every dtype and layout numpy has (float64, float32, integers, bool, object, complex, texts;
0-d, 1-d, N x 1, N x 3, 3 x N, N x 6, empty, non-contiguous, negative and huge strides), given
to `imudrift.allan`, the allantools functions, `drift`, `diagnose` (small sizes), `generate`,
`simulate`, `Sensor` and `plan` with mutated numeric arguments (rates, taus, runs, seeds,
durations: NaN, +-inf, 1e300, 5e-324, 2**70, negative, None, texts, complex).

A call passes when it returns only finite numbers (None where the documents have nulls; NaN
only in `lo`, `hi` (and `edf`) of `allan` where no interval is computed, as documented: with
`edf="none"`, or at a tau whose EDF the estimator's formula does not give, EDF 0) or raises one of the documented exceptions: `imudrift.InvalidInput` (a ValueError)
or `imudrift.LogUnreadable` (an OSError). Anything else is a failure: another exception (a
TypeError, OverflowError, a Rust panic's PanicException), a non-finite or missing number, an
empty result, or a crash of the process (the cases run in worker processes; a worker that dies
is a crash at the case it had started, and the run goes on after it).

Deterministic: case i of --seed s is a function of (s, i) alone. Numpy and the package only.

    nice -n 10 python3 scripts/mutate_python.py --cases 1000000 --seed 1
"""

import argparse
import json
import math
import os
import random
import subprocess
import sys
import tempfile
import time

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
MODEL = os.path.join(ROOT, "configs", "sensors", "mtx.toml")

# Values a damaged or hostile array may hold where a number is (scripts/mutate_inputs.py's
# BAD_FLOATS, and the values of issue 46).
BAD_FLOATS = [
    float("nan"), float("inf"), float("-inf"), 1e300, -1e300, 1e200, 1e150, 1e100, -1e100,
    1.7976931348623157e308, 5e-324, -0.0, 1e-160, 0.0,
]
CONSTANTS = [0.0, -9.81, 0.5, 1e-300, 1e99, 1e-160, 5e-324]
# Numeric arguments: good ones, and the ones a user or a bug may pass.
BAD_NUMBERS = [
    float("nan"), float("inf"), float("-inf"), 1e300, 1e-300, 5e-324, 0.0, -1.0, -0.0, 1e9, 1e10,
    2**70, -(2**70), 2**64, 2**63, 1.5, "100", "x", None, True, 1 + 2j, [], [1.0], np.float32(100.0),
    np.int64(-5), np.array([100.0]), np.array(np.nan),
]
# Each family's good choice is the likeliest, so that about half the calls reach the library's
# computation (the rest test its refusals).
VALUE_MUTATIONS = [
    "bad field", "bad fields", "bad column", "constant column", "truncated", "rows removed",
    "rows repeated", "rows shuffled", "scaled", "two",
] + ["none"] * 40
LAYOUTS = [
    "list", "tuple", "0-d", "N x 1", "N x 3", "3 x N", "N x 6", "empty", "empty 2-d",
    "every 3rd", "reversed", "huge stride", "fortran column", "None", "scalar",
] + ["1-d"] * 60
DTYPES = ["float32", "int64", "int8", "uint16", "bool", "object", "object with None", "complex",
          "str"] + ["float64"] * 60
SIZES = [0, 1, 2, 3, 5, 9, 20, 64, 100, 257, 300, 1000, 3000] + [300, 1000, 3000] * 10
# The seed logs (generated once per process; cases take slices and copies of them).
_SEEDS = []


# ---------------------------------------------------------------------------------------------
# Arrays: a seed log (static IMU, 6 channels), its values mutated, then its dtype and layout.

def seed_log(rng, n):
    """n static samples: white noise on the gyros, gravity plus noise on the accelerometers."""
    g = rng.normal(0.0, 0.01, (n, 3))
    a = rng.normal(0.0, 0.02, (n, 3))
    a[:, 2] += -9.81
    return np.concatenate([g, a], axis=1)


def a_seed_log(r, n):
    """n rows of one of two seed logs of 3000 samples, from a random row (a copy)."""
    if not _SEEDS:
        _SEEDS.extend(seed_log(np.random.default_rng(s), 3000) for s in (1, 2))
    x = _SEEDS[r.randrange(2)]
    a = r.randrange(len(x) - n + 1)
    return x[a: a + n].copy()


def mutate_values(r, x):
    """One mutation of a log's values (n x 6), and a label saying how."""
    how = r.choice(VALUE_MUTATIONS)
    n = len(x)
    if how == "two":
        x, a = mutate_values(r, x)
        x, b = mutate_values(r, x)
        return x, f"{a} + {b}"
    if how != "none":
        x = x.copy()
    if how == "bad field" and n:
        x[r.randrange(n), r.randrange(6)] = r.choice(BAD_FLOATS)
    elif how == "bad fields" and n:
        for _ in range(r.randint(2, 50)):
            x[r.randrange(n), r.randrange(6)] = r.choice(BAD_FLOATS)
    elif how == "bad column":
        x[:, r.randrange(6)] = r.choice(BAD_FLOATS)
    elif how == "constant column":
        x[:, r.randrange(6)] = r.choice(CONSTANTS)
    elif how == "truncated":
        x = x[: r.randrange(n + 1)]
    elif how == "rows removed" and n:
        a = r.randrange(n)
        x = np.delete(x, slice(a, a + r.randint(1, max(1, n // 2))), axis=0)
    elif how == "rows repeated" and n:
        a = r.randrange(n)
        x = np.insert(x, a, x[a: a + r.randint(1, 20)], axis=0)
    elif how == "rows shuffled" and n:
        a = r.randrange(n)
        k = min(n - a, r.randint(2, 50))
        order = list(range(k))
        r.shuffle(order)
        x[a: a + k] = x[a: a + k][order]
    elif how == "scaled":
        with np.errstate(all="ignore"):
            x = x * r.choice([1e-160, 1e-300, 1e99, 1e150, -1.0, 0.0])
    return x, how


def with_dtype(r, x, dtype):
    if dtype == "object":
        return x.astype(object)
    if dtype == "object with None":
        o = x.astype(object)
        if o.size:
            o.flat[r.randrange(o.size)] = None
        return o
    if dtype == "complex":
        return x.astype(np.complex128) + 1j
    if dtype == "str":
        return x.astype(str)
    with np.errstate(all="ignore"):
        return x.astype(dtype)


def layout(r, col, log, what):
    """A channel `col` (1-d) or the log (n x 6) given in layout `what`."""
    if what == "1-d":
        return col
    if what == "list":
        return col.tolist()
    if what == "tuple":
        return tuple(col.tolist()[:200])
    if what == "0-d":
        return col[0] if col.size else np.float64(1.0)
    if what == "N x 1":
        return col[:, None]
    if what == "N x 3":
        return log[:, :3]
    if what == "3 x N":
        return log[:, :3].T
    if what == "N x 6":
        return log
    if what == "empty":
        return col[:0]
    if what == "empty 2-d":
        return log[:0]
    if what == "every 3rd":
        return col[::3]
    if what == "reversed":
        return col[::-1]
    if what == "huge stride":
        # A view whose stride is far larger than an element (as_strided over a long buffer).
        base = np.resize(col, max(1, col.size) * 64)
        k = max(1, col.size // 2)
        return np.lib.stride_tricks.as_strided(base, shape=(k,), strides=(base.strides[0] * 64,))
    if what == "fortran column":
        return np.asfortranarray(log)[:, r.randrange(log.shape[1])] if log.ndim == 2 else col
    if what == "None":
        return None
    return r.choice([1.0, "abc", {"gx": 1}])


def an_array(r):
    """A mutated array (and the log it came from) with a label."""
    n = r.choice(SIZES)
    x, how = mutate_values(r, a_seed_log(r, n))
    dtype = r.choice(DTYPES)
    xd = with_dtype(r, x, dtype)
    col = xd[:, r.randrange(6)] if xd.ndim == 2 else xd
    what = r.choice(LAYOUTS)
    return layout(r, col, xd, what), xd, f"n={n} {how}, {dtype}, {what}"


# Values a long but legitimate simulation takes (a 1 s run at 1e9 Hz): left out of the
# simulation's settings, whose cases must stay cheap.
LONG_WORK = (1e9, 1e10)


def a_number(r, good, bad=BAD_NUMBERS):
    return good if r.random() < 0.9 else r.choice(bad)


def a_cheap_number(r, good):
    return a_number(r, good, [b for b in BAD_NUMBERS if not (isinstance(b, float) and b in LONG_WORK)])


# ---------------------------------------------------------------------------------------------
# What each call returns, checked: only finite numbers (None where a document has a null).

def bad_numbers(value, path="", allow_nan=()):
    """Paths of non-finite numbers in a result (numpy arrays, dicts, lists, numbers)."""
    out = []
    if isinstance(value, np.ndarray):
        if value.dtype.kind in "fc" and not np.all(np.isfinite(value)) and path not in allow_nan:
            out.append(path)
    elif isinstance(value, dict):
        for k, v in value.items():
            out += bad_numbers(v, f"{path}.{k}", allow_nan)
    elif isinstance(value, (list, tuple)):
        for i, v in enumerate(value):
            out += bad_numbers(v, f"{path}[{i}]", allow_nan)
    elif isinstance(value, float) and not math.isfinite(value) and path not in allow_nan:
        out.append(path)
    return out


def check_allan(r, kw):
    """Every column finite, except `lo`, `hi` and `edf` where no interval is computed (documented:
    `lo` and `hi` NaN there, never inf): `edf="none"` (edf NaN), or an averaging time whose EDF
    the estimator's formula does not give (edf 0: totdev's last tau of a short phase record);
    the fit's numbers finite. An N x k array gives a list of k results: each checked."""
    if isinstance(r, list):
        if not r:
            return ["empty list of results"]
        return [f"[{j}]{b}" for j, one in enumerate(r) for b in check_allan(one, kw)]
    if len(r) == 0:
        return ["empty result"]
    cols = {c: getattr(r, c) for c in r._COLUMNS}
    no_interval = np.isnan(r.edf) | (r.edf <= 0)
    bad = bad_numbers({c: v for c, v in cols.items() if c not in ("lo", "hi", "edf")})
    for c in ("lo", "hi"):
        v = cols[c]
        if not (np.all(np.isfinite(v[~no_interval])) and np.all(np.isnan(v[no_interval]))):
            bad.append("." + c)
    if np.any(np.isinf(r.edf)):
        bad.append(".edf")
    if kw.get("edf", "greenhall") != "none" and np.all(no_interval):
        bad.append(".edf: no interval at any tau")
    if r._fit is not None:
        bad += bad_numbers(r.fit().to_dict(), ".fit")
    return bad


def check_tuple(t):
    if len(t[0]) == 0:
        return ["empty result"]
    return bad_numbers(list(t))


def check_document(d):
    return bad_numbers(d.to_dict())


# ---------------------------------------------------------------------------------------------
# The cases.

def case(seed, i):
    """Case i of run `seed`: (label, function of no argument, checker of its result)."""
    import imudrift
    import imudrift.allantools as at

    r = random.Random(seed * 2**32 + i)
    # Weights: the cheap calls most (about 1 to 4 ms each), drift, diagnose, generate and
    # simulate (40 to 160 ms when they compute) a few per cent.
    family = r.choices(["allan", "allantools", "drift", "diagnose", "generate", "simulate",
                        "sensor"], weights=[460, 460, 20, 10, 15, 10, 25])[0]
    if family in ("allan", "allantools"):
        data, _, how = an_array(r)
        rate = a_number(r, r.choice([100.0, 100.0, 1.0, 1e-6, 1e9]))
        # The "all" and "N/decade" grids and the simple EDF have no shipped threshold table:
        # each log length then simulates 200 null logs (0.1 to 3 s on the "all" grid): "all" is
        # left out and the others are rare here (tests/test_strict_inputs.py has "all").
        taus = r.choice(["octave", "decade", "weekly", [], [0.01, 0.1], [0.0], [-1.0],
                         [float("nan")], [1e300], [5e-324], ["a"], 1.0, [[0.1]],
                         np.array([0.02, 0.04])] + [None] * 150 + ["4/decade"])
        data_type = r.choice(["freq"] * 40 + ["phase"] * 20 + ["angle", None])
        if family == "allan":
            kw = {"data_type": data_type}
            if taus is not None:
                kw["taus"] = taus
            if r.random() < 0.3:
                kw["estimator"] = r.choice(["adev", "oadev", "mdev", "hdev", "ohdev", "totdev"] * 4
                                           + ["tdev", "xdev"])
            if r.random() < 0.1:
                kw["confidence"] = r.choice([0.95, 0.5, 0.0, 1.0, float("nan"), 1e300, "95%"])
            if r.random() < 0.1:
                kw["edf"] = r.choice(["greenhall"] * 8 + ["simple", "none", "exact"])
            label = f"allan({how}, rate={rate!r}, {kw!r})"
            return label, lambda: imudrift.allan(data, rate, **kw), lambda res: check_allan(res, kw)
        fn = r.choice(["adev", "oadev", "mdev", "tdev", "hdev", "ohdev", "totdev"])
        label = f"allantools.{fn}({how}, rate={rate!r}, {data_type!r}, taus={taus!r})"
        return (label, lambda: getattr(at, fn)(data, rate, data_type, taus), check_tuple)
    if family in ("drift", "diagnose"):
        # Small sizes: 2000 to 3000 samples at 100 Hz, horizons of 5 s, few replicates / seeds.
        n = r.choice([2000, 3000])
        log, how = mutate_values(r, a_seed_log(r, n))
        dtype = r.choice(DTYPES[:7] + ["float64"] * 12)
        logd = with_dtype(r, log, dtype)
        form = r.choice(["dict", "dict unequal", "list of two", "T", "None", "dict 3 channels",
                         "column"] + ["array"] * 6)
        if form == "array":
            logs = logd
        elif form == "T":
            logs = logd.T
        elif form == "dict":
            logs = {c: logd[:, k] for k, c in enumerate(imudrift._analyse._CHANNELS)}
        elif form == "dict unequal":
            logs = {"gx": logd[:, 0], "gy": logd[: max(0, len(logd) - 100), 1]}
        elif form == "dict 3 channels":
            logs = {c: logd[:, k] for k, c in enumerate(["gx", "gy", "gz"])}
        elif form == "list of two":
            logs = [logd, logd[::-1]]
        elif form == "column":
            logs = logd[:, 0] if logd.ndim == 2 else logd
        else:
            logs = None
        rate = a_number(r, 100.0)
        horizons = r.choice([[0.0], [float("nan")], [1e300], ["5 s"], ["x"], 5.0, None, [-1.0]]
                            + [[5.0]] * 8)
        model = r.choice([os.path.dirname(MODEL), "no-such-model", "name = 1", 3] + [MODEL] * 8)
        seed_arg = a_number(r, 1)
        threads = r.choice([None, 0, -1, 2**70] + [1] * 8)
        label = f"{family}({how}, {dtype}, {form}, rate={rate!r}, horizons={horizons!r}, model={model!r})"
        if family == "drift":
            replicates = a_number(r, 10)
            kw = dict(rate=rate, horizons=horizons, replicates=replicates, seed=seed_arg,
                      threads=threads)
            label += f" replicates={replicates!r}"
            return label, lambda: imudrift.drift(logs, model, **kw), check_document
        seeds = a_number(r, 2)
        kw = dict(rate=rate, horizons=horizons, seeds=seeds, rounds=r.choice([0, 0, 0, -1]),
                  seed=seed_arg, threads=threads, tau_min=a_number(r, 0.0))
        label += f" seeds={seeds!r}"
        return label, lambda: imudrift.diagnose(logs, model, **kw), check_document
    if family == "generate":
        duration = a_number(r, r.choice([0.5, 1.0, 2.0]))
        rate = a_number(r, 100.0)
        seed_arg, run = a_number(r, 1), a_number(r, 0)
        sensor = r.choice([MODEL, MODEL, os.path.dirname(MODEL), "no-such-model", None])
        label = f"generate({sensor!r}, {duration!r}, {rate!r}, seed={seed_arg!r}, run={run!r})"

        def check(df):
            return bad_numbers(df.to_numpy(dtype=float)) + (["empty result"] if len(df) == 0 else [])
        return (label, lambda: imudrift.generate(sensor, duration, rate, seed=seed_arg, run=run),
                check)
    if family == "simulate":
        runs = a_cheap_number(r, r.choice([2, 3]))
        duration = a_cheap_number(r, r.choice([1.0, 2.0]))
        rate = a_cheap_number(r, r.choice([50.0, 100.0]))
        seed_arg, threads = a_number(r, 1), r.choice([1, None, 2**70, -1])
        label = f"simulate(runs={runs!r}, duration_s={duration!r}, rate_hz={rate!r}, seed={seed_arg!r}, threads={threads!r})"

        def run_sim():
            return imudrift.simulate(MODEL, runs=runs, duration_s=duration, rate_hz=rate,
                                     seed=seed_arg, threads=threads)

        def check(res):
            return bad_numbers(res.values) + check_document(res)
        return label, run_sim, check
    what = r.choice(["Sensor", "plan", "to_kalibr"])
    arg = r.choice([MODEL, os.path.dirname(MODEL), "no-such-model", "", "name = 1",
                    'name = "x"\n[gyro.all]\nwhite_noise = "0.1 deg/sqrt(h)"\n', None, 3,
                    {"name": "x"}, b"bytes"])
    rate = a_number(r, 100.0)
    label = f"{what}({arg!r}, rate={rate!r})"
    if what == "Sensor":
        return label, lambda: imudrift.Sensor(arg).to_toml(), lambda res: []
    if what == "plan":
        return (label, lambda: imudrift.plan(arg, uncertainty=a_number(r, 0.1), rate_hz=rate),
                lambda res: bad_numbers(res))
    return label, lambda: imudrift.Sensor(MODEL).to_kalibr(rate), lambda res: []


def run_case(seed, i):
    """None when case i passes, else (kind, label, detail)."""
    import imudrift
    import warnings

    label, call, check = case(seed, i)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            res = call()
    except (imudrift.InvalidInput, imudrift.LogUnreadable):
        return None
    except BaseException as e:  # noqa: B036 - a PanicException is a BaseException
        if isinstance(e, KeyboardInterrupt):
            raise
        return ("exception", label, f"{type(e).__module__}.{type(e).__name__}: {str(e)[:300]}")
    bad = check(res)
    if bad:
        return ("bad numbers", label, "; ".join(bad[:5]))
    return None


def worker(seed, start, stop):
    """Run cases start..stop, printing `started i` before each and one JSON line per failure."""
    for i in range(start, stop):
        print(f"started {i}", flush=True)
        f = run_case(seed, i)
        if f:
            print("FAIL " + json.dumps([i, *f]), flush=True)
    print("done", flush=True)


def run_block(seed, start, stop):
    """Cases start..stop in worker processes: (failures, crashes); a worker that dies is a crash
    at the case it had started, and a new worker goes on after it."""
    failures = []
    i = start
    while i < stop:
        p = subprocess.Popen([sys.executable, __file__, "--worker", str(seed), str(i), str(stop)],
                             stdout=subprocess.PIPE, text=True)
        last = i - 1
        for line in p.stdout:
            if line.startswith("started "):
                last = int(line.split()[1])
            elif line.startswith("FAIL "):
                f = json.loads(line[5:])
                failures.append(f)
                print(f"FAIL case {f[0]} {f[1]}: {f[2]}: {f[3]}", flush=True)
        code = p.wait()
        if code != 0:
            print(f"FAIL case {last} crash: worker status {code}", flush=True)
            failures.append([last, "crash", f"case {last}", f"status {code}"])
            i = last + 1
        else:
            i = stop
    return failures


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--cases", type=int, default=1_000_000)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--first", type=int, default=0, help="index of the first case")
    ap.add_argument("--block", type=int, default=20_000, help="cases per worker process")
    ap.add_argument("--jobs", type=int, default=2, help="worker processes at a time")
    ap.add_argument("--worker", nargs=3, type=int, help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.worker:
        worker(*args.worker)
        return
    import concurrent.futures

    started = time.monotonic()
    end = args.first + args.cases
    blocks = [(b, min(end, b + args.block)) for b in range(args.first, end, args.block)]
    failures, done = [], 0
    with concurrent.futures.ThreadPoolExecutor(max_workers=args.jobs) as pool:
        futures = {pool.submit(run_block, args.seed, a, b): (a, b) for a, b in blocks}
        for fut in concurrent.futures.as_completed(futures):
            a, b = futures[fut]
            failures += fut.result()
            done += b - a
            print(f"{done}/{args.cases} cases, {len(failures)} failures, "
                  f"{time.monotonic() - started:.0f} s", flush=True)
    kinds = {}
    for f in failures:
        kinds[f[1]] = kinds.get(f[1], 0) + 1
    print(f"seed {args.seed}: {args.cases} cases (executions) in {time.monotonic() - started:.0f} s, "
          f"{len(failures)} failures {kinds}")
    sys.exit(1 if failures else 0)


if __name__ == "__main__":
    main()
