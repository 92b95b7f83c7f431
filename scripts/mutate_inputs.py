#!/usr/bin/env python3
"""Mutation run of the log readers through the CLI (issue 27): damaged ROS 1 bags, ROS 2 MCAP
files and CSV logs given to `allan`, `diagnose` and `drift`.

Seeds are made here: CSV logs by the release binary's `imudrift generate`, bags and MCAP files
written by this script (minimal valid files: ROS 1 bag v2.0 as wiki.ros.org/Bags/Format/2.0
describes it, one uncompressed chunk and its index; MCAP as mcap.dev/spec describes it, messages
outside chunks or in one uncompressed chunk, with or without its CRC). Each mutated file is
given to each command with a timeout, and the run fails when

- a command exits 0 and its --json output holds a null, NaN or inf where a number is expected
  (a JSON path that is never null in the seeds' outputs), or is not JSON;
- a command crashes: exit 101 (a Rust panic), a signal, or a status other than 0 and 1;
- a command takes longer than the timeout.

Deterministic: the same --seed gives the same files in the same order. Stdlib only. Prints the
counts (files, runs, exit 0, refused, failures by kind) and keeps each failing input in
--keep DIR with the command that failed.

    python3 scripts/mutate_inputs.py --bags 5000 --csvs 3000 --seed 1
"""

import argparse
import concurrent.futures
import json
import math
import os
import random
import shutil
import struct
import subprocess
import sys
import tempfile
import time
import zlib

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
MODEL = os.path.join(ROOT, "configs", "sensors", "mtx.toml")
RATE_HZ = 100
SAMPLES = 1000

IMU_DEFINITION = (
    b"std_msgs/Header header\ngeometry_msgs/Quaternion orientation\nfloat64[9] orientation_covariance\n"
    b"geometry_msgs/Vector3 angular_velocity\nfloat64[9] angular_velocity_covariance\n"
    b"geometry_msgs/Vector3 linear_acceleration\nfloat64[9] linear_acceleration_covariance\n"
)

# Values a damaged or hostile file may hold where a number is.
BAD_FLOATS = [
    float("nan"),
    float("inf"),
    float("-inf"),
    1e300,
    -1e300,
    1e150,
    1e100,
    -1e100,
    1.7976931348623157e308,
    5e-324,
    -0.0,
]
BAD_TEXTS = [
    "nan", "NaN", "inf", "-inf", "Infinity", "1e300", "-1e300", "1e150", "1e100", "1e400",
    "-1e400", "1e-400", "", " ", "null", "0x10", "1,5", "--1", "1e", ".", "+", "9" * 400,
]


# ---------------------------------------------------------------------------------------------
# Seed logs: a static IMU (white noise on the gyros, gravity plus noise on the accelerometers).

def samples(rng, n=SAMPLES):
    """n static samples at RATE_HZ: (t_ns, gyro[3], accel[3])."""
    out = []
    t0 = 1_700_000_000 * 10**9 + rng.randrange(10**9)
    for k in range(n):
        g = [rng.gauss(0.0, 0.01) for _ in range(3)]
        a = [rng.gauss(0.0, 0.02), rng.gauss(0.0, 0.02), -9.81 + rng.gauss(0.0, 0.02)]
        out.append((t0 + k * (10**9 // RATE_HZ), g, a))
    return out


def imu_body(gyro, accel):
    """orientation, its covariance, angular velocity, its covariance, linear acceleration, its
    covariance (37 little-endian f64); also the offsets of the six values in the body."""
    vals = [0.0, 0.0, 0.0, 1.0] + [0.0] * 9 + list(gyro) + [0.0] * 9 + list(accel) + [0.0] * 9
    offsets = [8 * (13 + i) for i in range(3)] + [8 * (25 + i) for i in range(3)]
    return struct.pack("<37d", *vals), offsets


def ros1_message(seq, t_ns, gyro, accel, frame=b"imu"):
    secs, nsecs = divmod(t_ns, 10**9)
    head = struct.pack("<IIII", seq, secs, nsecs, len(frame)) + frame
    body, offsets = imu_body(gyro, accel)
    return head + body, [len(head) + o for o in offsets], 4


def cdr_message(t_ns, gyro, accel, frame=b"imu"):
    secs, nsecs = divmod(t_ns, 10**9)
    b = b"\x00\x01\x00\x00" + struct.pack("<iII", secs, nsecs, len(frame) + 1) + frame + b"\x00"
    while (len(b) - 4) % 8:
        b += b"\x00"
    body, offsets = imu_body(gyro, accel)
    return b + body, [len(b) + o for o in offsets], 4


def field(name, value):
    item = name + b"=" + value
    return struct.pack("<I", len(item)) + item


def ros1_record(header, data):
    return struct.pack("<I", len(header)) + header + struct.pack("<I", len(data)) + data


def ros1_time(t_ns):
    s, n = divmod(t_ns, 10**9)
    return struct.pack("<II", s, n)


def write_rosbag(smp, topic=b"/imu"):
    """A ROS 1 bag v2.0: bag header (padded to 4096 bytes), one uncompressed chunk (connection
    and messages), its index data, then the index section (connection, chunk info). Returns the
    bytes and the file positions of each message's stamp and six values."""
    conn = struct.pack("<I", 0)

    def connection():
        h = field(b"op", b"\x07") + field(b"conn", conn) + field(b"topic", topic)
        d = (field(b"topic", topic) + field(b"type", b"sensor_msgs/Imu")
             + field(b"md5sum", b"6a62c6daae103f4ff57a132d6f95cec2")
             + field(b"message_definition", IMU_DEFINITION))
        return ros1_record(h, d)

    chunk = bytearray(connection())
    offsets = []
    spots = []  # (stamp position, [value positions]) relative to the chunk data
    for i, (t, g, a) in enumerate(smp):
        offsets.append(len(chunk))
        h = field(b"op", b"\x02") + field(b"conn", conn) + field(b"time", ros1_time(t))
        msg, vals, stamp = ros1_message(i, t, g, a)
        at = len(chunk) + 4 + len(h) + 4
        spots.append((at + stamp, [at + v for v in vals]))
        chunk += ros1_record(h, msg)

    def bag_header(index_pos):
        h = (field(b"op", b"\x03") + field(b"index_pos", struct.pack("<Q", index_pos))
             + field(b"conn_count", struct.pack("<I", 1)) + field(b"chunk_count", struct.pack("<I", 1)))
        pad = 4096 - 4 - len(h) - 4
        return ros1_record(h, b" " * pad)

    out = bytearray(b"#ROSBAG V2.0\n")
    header_at = len(out)
    out += bag_header(0)
    chunk_pos = len(out)
    h = field(b"op", b"\x05") + field(b"compression", b"none") + field(b"size", struct.pack("<I", len(chunk)))
    data_at = len(out) + 4 + len(h) + 4
    out += ros1_record(h, bytes(chunk))
    h = (field(b"op", b"\x04") + field(b"ver", struct.pack("<I", 1)) + field(b"conn", conn)
         + field(b"count", struct.pack("<I", len(smp))))
    d = b"".join(ros1_time(t) + struct.pack("<I", off) for (t, _, _), off in zip(smp, offsets))
    out += ros1_record(h, d)
    index_pos = len(out)
    out += connection()
    start = min(t for t, _, _ in smp)
    end = max(t for t, _, _ in smp)
    h = (field(b"op", b"\x06") + field(b"ver", struct.pack("<I", 1))
         + field(b"chunk_pos", struct.pack("<Q", chunk_pos)) + field(b"start_time", ros1_time(start))
         + field(b"end_time", ros1_time(end)) + field(b"count", struct.pack("<I", 1)))
    out += ros1_record(h, conn + struct.pack("<I", len(smp)))
    patched = bag_header(index_pos)
    out[header_at:header_at + len(patched)] = patched
    spots = [(data_at + s, [data_at + v for v in vs]) for s, vs in spots]
    return bytes(out), spots, "ros1"


MCAP_MAGIC = b"\x89MCAP0\r\n"


def mcap_record(op, content):
    return bytes([op]) + struct.pack("<Q", len(content)) + content


def mcap_str(s):
    return struct.pack("<I", len(s)) + s


def write_mcap(smp, chunked, crc, topic=b"/imu"):
    """An MCAP file: header, schema, channel, the messages (outside chunks, or in one
    uncompressed chunk with or without its CRC), data end, footer. Returns the bytes and the
    file positions of each message's stamp and six values."""
    out = bytearray(MCAP_MAGIC)
    out += mcap_record(0x01, mcap_str(b"ros2") + mcap_str(b"imudrift-mutate"))
    out += mcap_record(0x03, struct.pack("<H", 1) + mcap_str(b"sensor_msgs/msg/Imu")
                       + mcap_str(b"ros2msg") + mcap_str(IMU_DEFINITION))
    out += mcap_record(0x04, struct.pack("<HH", 1, 1) + mcap_str(topic) + mcap_str(b"cdr")
                       + struct.pack("<I", 0))
    records = bytearray()
    spots = []
    for i, (t, g, a) in enumerate(smp):
        msg, vals, stamp = cdr_message(t, g, a)
        at = len(records) + 9 + 2 + 4 + 8 + 8
        spots.append((at + stamp, [at + v for v in vals]))
        records += mcap_record(0x05, struct.pack("<HIQQ", 1, i, t, t) + msg)
    if chunked:
        start = min(t for t, _, _ in smp)
        end = max(t for t, _, _ in smp)
        head = struct.pack("<QQQI", start, end, len(records), zlib.crc32(records) if crc else 0)
        head += mcap_str(b"") + struct.pack("<Q", len(records))
        base = len(out) + 9 + len(head)
        out += mcap_record(0x06, head + records)
    else:
        base = len(out)
        out += records
    out += mcap_record(0x0F, struct.pack("<I", 0))
    out += mcap_record(0x02, struct.pack("<QQI", 0, 0, 0))
    out += MCAP_MAGIC
    spots = [(base + s, [base + v for v in vs]) for s, vs in spots]
    kind = "mcap-chunk-crc" if chunked and crc else "mcap-chunk" if chunked else "mcap"
    return bytes(out), spots, kind


# ---------------------------------------------------------------------------------------------
# Mutations.

def flip_bits(rng, b, lo=0):
    b = bytearray(b)
    for _ in range(rng.randint(1, 8)):
        i = rng.randrange(lo, len(b))
        b[i] ^= 1 << rng.randrange(8)
    return bytes(b)


def bag_mutation(rng, seed):
    """One mutated bag or MCAP file from `seed` (bytes, spots, kind) and a label saying how."""
    data, spots, kind = seed
    b = bytearray(data)
    how = rng.choice([
        "bit flips", "bit flips in messages", "bad value", "bad values", "bad stamp", "truncated",
        "huge length", "random bytes", "zeroed range", "duplicated range", "removed range", "two",
    ])
    if how == "two":
        first, a = bag_mutation(rng, seed)
        second, c = bag_mutation(rng, (first, spots, kind))
        return second, f"{a} + {c}"
    if how == "bit flips":
        return flip_bits(rng, b), how
    if how == "bit flips in messages":
        return flip_bits(rng, b, lo=spots[0][0]), how
    if how in ("bad value", "bad values"):
        for _ in range(1 if how == "bad value" else rng.randint(2, 50)):
            _, vals = rng.choice(spots)
            at = rng.choice(vals)
            b[at:at + 8] = struct.pack("<d", rng.choice(BAD_FLOATS))
        return bytes(b), how
    if how == "bad stamp":
        stamp, _ = rng.choice(spots)
        other, _ = rng.choice(spots)
        choice = rng.randrange(4)
        if choice == 0:
            b[stamp:stamp + 8] = b[other:other + 8]  # a repeated or out-of-order stamp
        elif choice == 1:
            b[stamp:stamp + 4] = struct.pack("<I", 0xFFFFFFFF)
        elif choice == 2:
            b[stamp + 4:stamp + 8] = struct.pack("<I", 0xFFFFFFFF)  # nanoseconds >= 1e9
        else:
            b[stamp:stamp + 8] = bytes(8)
        return bytes(b), how
    if how == "truncated":
        return bytes(b[:rng.randrange(len(b))]), how
    if how == "huge length":
        at = rng.randrange(0, len(b) - 8)
        width = rng.choice([4, 8])
        value = rng.choice([0xFFFFFFFF, 0x7FFFFFFF, 0x80000000, 0, 1 << 40, (1 << 64) - 1])
        b[at:at + width] = struct.pack("<Q" if width == 8 else "<I", value & ((1 << (8 * width)) - 1))
        return bytes(b), how
    if how == "random bytes":
        at = rng.randrange(len(b))
        n = rng.randint(1, 64)
        b[at:at + n] = bytes(rng.randrange(256) for _ in range(n))
        return bytes(b), how
    at = rng.randrange(len(b))
    n = rng.randint(1, 4096)
    if how == "zeroed range":
        b[at:at + n] = bytes(len(b[at:at + n]))
    elif how == "duplicated range":
        b[at:at] = b[at:at + n]
    else:
        del b[at:at + n]
    return bytes(b), how


def csv_rows(text):
    lines = text.split("\n")
    head = [i for i, l in enumerate(lines) if l and not l.startswith("#")][0]
    return lines, head


def csv_mutation(rng, seed):
    """One mutated CSV log from the text of a generated one, and a label saying how."""
    lines, head = csv_rows(seed)
    body = list(range(head + 1, len(lines) - (1 if lines[-1] == "" else 0)))
    how = rng.choice([
        "bad field", "bad fields", "bad column", "duplicated column", "removed column",
        "renamed column", "swapped header", "constant column", "truncated", "rows removed",
        "rows repeated", "rows shuffled", "bit flips", "huge field", "nul bytes", "not utf-8",
        "crlf", "t in ms", "two",
    ])
    if how == "two":
        first, a = csv_mutation(rng, seed)
        second, c = csv_mutation(rng, first)
        return second, f"{a} + {c}"
    cells = lambda i: lines[i].split(",")
    ncols = len(cells(head))
    if how in ("bad field", "bad fields", "huge field"):
        for _ in range(1 if how != "bad fields" else rng.randint(2, 50)):
            i = rng.choice(body)
            row = cells(i)
            j = rng.randrange(len(row))
            row[j] = "1" * rng.randint(1000, 200000) if how == "huge field" else rng.choice(BAD_TEXTS)
            lines[i] = ",".join(row)
    elif how == "bad column":
        j = rng.randrange(ncols)
        v = rng.choice(BAD_TEXTS)
        for i in body:
            row = cells(i)
            if j < len(row):
                row[j] = v
                lines[i] = ",".join(row)
    elif how in ("duplicated column", "removed column", "constant column"):
        j = rng.randrange(ncols)
        const = rng.choice(["0", "-9.81", "0.5", "1e-300", "1e99"])
        for i in [head] + body:
            row = cells(i)
            if j >= len(row):
                continue
            if how == "duplicated column":
                row.insert(j, row[j])
            elif how == "removed column":
                del row[j]
            elif i != head:
                row[j] = const
            lines[i] = ",".join(row)
    elif how == "renamed column":
        row = cells(head)
        row[rng.randrange(ncols)] = rng.choice(["t", "gx", "az", "temp", "time", "x", "", "gyro_x_dps", "acc_z_g", "t_ms"])
        lines[head] = ",".join(row)
    elif how == "swapped header":
        row = cells(head)
        j, k = rng.randrange(ncols), rng.randrange(ncols)
        row[j], row[k] = row[k], row[j]
        lines[head] = ",".join(row)
    elif how == "truncated":
        text = "\n".join(lines)
        return text[:rng.randrange(len(text))], how
    elif how == "rows removed":
        a = rng.choice(body)
        n = rng.randint(1, 600)
        del lines[a:min(a + n, body[-1] + 1)]
    elif how == "rows repeated":
        a = rng.choice(body)
        lines[a:a] = lines[a:a + rng.randint(1, 20)]
    elif how == "rows shuffled":
        a = rng.choice(body)
        part = lines[a:a + rng.randint(2, 50)]
        rng.shuffle(part)
        lines[a:a + len(part)] = part
    elif how == "bit flips":
        return flip_bits(rng, "\n".join(lines).encode()).decode("latin-1"), how
    elif how == "nul bytes":
        i = rng.choice(body)
        lines[i] = lines[i][: len(lines[i]) // 2] + "\0" + lines[i][len(lines[i]) // 2:]
    elif how == "not utf-8":
        i = rng.choice(body)
        lines[i] = lines[i] + "\udcff"
    elif how == "crlf":
        return "\r\n".join(lines), how
    elif how == "t in ms":
        for i in body:
            row = cells(i)
            try:
                row[0] = repr(float(row[0]) * 1000.0)
            except ValueError:
                pass
            lines[i] = ",".join(row)
    return "\n".join(lines), how


def csv_bytes(text):
    return text.encode("utf-8", "surrogateescape") if "\udcff" in text else text.encode("latin-1", "replace")


# ---------------------------------------------------------------------------------------------
# Running the commands and judging their output.

def commands(path, threads):
    t = ["--threads", str(threads)]
    return {
        "allan": ["allan", path, "--json"] + t,
        "diagnose": ["diagnose", path, "--model", MODEL, "--seeds", "2", "--rounds", "1",
                     "--horizons", "1", "--json"] + t,
        "drift": ["drift", path, path, "--model", MODEL, "--replicates", "10", "--horizons", "1,5",
                  "--json"] + t,
    }


def json_paths(value, path=""):
    """(path, value) of every leaf; array indices are written [] (one path for every element)
    and channel names * (`.channels.*.fit.q`: a renamed column gives the same paths). The nulls
    of an entry that says it has no value are not leaves: `"verdict": "not_informed"` (drift's
    quantities the logs lack a channel for, or a horizon no log is as long as, with a note
    saying which) and `"segments": 0` (diagnose's drift at a horizon longer than the log: an RMS
    over no segments, printed "-" with "segments: 0" in the text)."""
    if isinstance(value, dict):
        declared = value.get("verdict") == "not_informed" or value.get("segments") == 0
        for k, v in value.items():
            if declared and v is None:
                continue
            yield from json_paths(v, f"{path}.{'*' if path.endswith('.channels') else k}")
    elif isinstance(value, list):
        for v in value:
            yield from json_paths(v, f"{path}[]")
    else:
        yield path, value


def bad_numbers(doc, nullable):
    """Paths of nulls where the seeds' outputs never have one, and of NaN or inf numbers."""
    bad = []
    for path, v in json_paths(doc):
        if v is None and path not in nullable:
            bad.append(f"{path} = null")
        elif isinstance(v, float) and not math.isfinite(v):
            bad.append(f"{path} = {v}")
    return bad


def run(binary, args, timeout):
    start = time.monotonic()
    try:
        p = subprocess.run([binary] + args, capture_output=True, timeout=timeout, cwd=ROOT)
    except subprocess.TimeoutExpired:
        return None, b"", b"", time.monotonic() - start
    return p.returncode, p.stdout, p.stderr, time.monotonic() - start


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--bin", default=os.path.join(ROOT, "target", "release", "imudrift"))
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--bags", type=int, default=5000, help="mutated bag and MCAP files")
    ap.add_argument("--csvs", type=int, default=3000, help="mutated CSV logs")
    ap.add_argument("--timeout", type=float, default=120.0, help="seconds per command")
    ap.add_argument("--threads", type=int, default=1, help="--threads of each command")
    ap.add_argument("--jobs", type=int, default=1, help="files checked at a time")
    ap.add_argument("--keep", default=None, help="directory for the failing inputs")
    ap.add_argument("--recheck", default=None,
                    help="instead of mutating, run the inputs a --keep directory holds again")
    args = ap.parse_args()
    rng = random.Random(args.seed)
    work = tempfile.mkdtemp(prefix="imudrift-mutate-")
    keep = args.keep
    failures = []
    counts = {"files": 0, "runs": 0, "exit 0": 0, "refused (exit 1)": 0}
    kinds = {"bad numbers": 0, "crash": 0, "timeout": 0, "other status": 0, "not json": 0}
    started = time.monotonic()
    try:
        # Seeds: two generated CSV logs, and bags / MCAP files of two sample sets each.
        csv_seeds = []
        seed_files = []
        for s in (1, 2):
            out = os.path.join(work, f"seed{s}.csv")
            seed_files.append(out)
            code, _, err, _ = run(args.bin, ["generate", MODEL, "--duration", str(SAMPLES / RATE_HZ),
                                             "--rate", str(RATE_HZ), "--seed", str(s), "-o", out], 300)
            if code != 0:
                sys.exit(f"imudrift generate failed: {err.decode(errors='replace')}")
            with open(out) as f:
                csv_seeds.append(f.read())
        bag_seeds = []
        for _ in range(2):
            smp = samples(rng)
            bag_seeds += [write_rosbag(smp), write_mcap(smp, False, False),
                          write_mcap(smp, True, False), write_mcap(smp, True, True)]
        # The seeds themselves must pass every command; their nulls are the allowed ones.
        nullable = set()
        for i, (data, _, kind) in enumerate(bag_seeds):
            p = os.path.join(work, f"seed{i}.{'bag' if kind == 'ros1' else 'mcap'}")
            with open(p, "wb") as f:
                f.write(data)
            seed_files.append(p)
        for p in seed_files:
            for name, cmd in commands(p, args.threads).items():
                code, out, err, _ = run(args.bin, cmd, args.timeout)
                if code != 0:
                    sys.exit(f"seed {p}: {name} failed: {err.decode(errors='replace')[-2000:]}")
                for path, v in json_paths(json.loads(out)):
                    if v is None:
                        nullable.add(path)
        print(f"seeds: {len(bag_seeds)} bags/MCAP, {len(csv_seeds)} CSV; paths null in the seeds' outputs: {sorted(nullable)}")

        plan = [("bag", i) for i in range(args.bags)] + [("csv", i) for i in range(args.csvs)]
        if args.recheck:
            plan = []
            for name in sorted(os.listdir(args.recheck)):
                if name.endswith(".txt"):
                    continue
                src = os.path.join(args.recheck, name)
                path = os.path.join(work, name)
                shutil.copy(src, path)
                plan.append(("kept", path))

        def check(n, path, how):
            """Run the three commands on one file: (counts, failures) of its runs."""
            c = {"runs": 0, "exit 0": 0, "refused (exit 1)": 0}
            found = []
            for name, cmd in commands(path, args.threads).items():
                code, out, err, _ = run(args.bin, cmd, args.timeout)
                c["runs"] += 1
                problem = None
                if code is None:
                    problem = ("timeout", f"no end within {args.timeout} s")
                elif code == 0:
                    c["exit 0"] += 1
                    try:
                        bad = bad_numbers(json.loads(out), nullable)
                        if bad:
                            problem = ("bad numbers", "; ".join(bad[:5]))
                    except ValueError as e:
                        problem = ("not json", str(e))
                elif code == 1:
                    c["refused (exit 1)"] += 1
                elif code == 101 or code < 0:
                    problem = ("crash", f"status {code}: {err.decode(errors='replace')[-300:]}")
                else:
                    problem = ("other status", f"status {code}: {err.decode(errors='replace')[-300:]}")
                if problem:
                    found.append((n, name, how, problem, cmd))
                    if keep:
                        os.makedirs(keep, exist_ok=True)
                        shutil.copy(path, os.path.join(keep, os.path.basename(path)))
                        with open(os.path.join(keep, os.path.basename(path) + ".txt"), "a") as f:
                            f.write(f"{' '.join(cmd)}\n{how}\n{problem}\n")
            os.remove(path)
            return c, found

        # Files are made in order from the one generator (deterministic); the commands run on
        # --jobs files at a time.
        with concurrent.futures.ThreadPoolExecutor(max_workers=args.jobs) as pool:
            pending = []
            for n, (family, i) in enumerate(plan):
                if family == "kept":
                    counts["files"] += 1
                    pending.append(pool.submit(check, n, i, f"kept {os.path.basename(i)}"))
                elif family == "bag":
                    seed = bag_seeds[rng.randrange(len(bag_seeds))]
                    data, how = bag_mutation(rng, seed)
                    ext = "bag" if seed[2] == "ros1" else "mcap"
                    how = f"{seed[2]}: {how}"
                else:
                    text, how = csv_mutation(rng, csv_seeds[rng.randrange(len(csv_seeds))])
                    data, ext = csv_bytes(text), "csv"
                if family != "kept":
                    path = os.path.join(work, f"m{n:05d}.{ext}")
                    with open(path, "wb") as f:
                        f.write(data)
                    counts["files"] += 1
                    pending.append(pool.submit(check, n, path, how))
                if len(pending) >= 4 * args.jobs or n + 1 == len(plan):
                    for fut in pending:
                        c, found = fut.result()
                        for k, v in c.items():
                            counts[k] += v
                        for f in found:
                            kinds[f[3][0]] += 1
                            failures.append(f)
                            print(f"FAIL {f[0]} {f[1]} ({f[2]}): {f[3][0]}: {f[3][1]}", flush=True)
                    pending = []
                if (n + 1) % 250 == 0:
                    print(f"{n + 1}/{len(plan)} files, {counts['runs']} runs, {len(failures)} failures, "
                          f"{time.monotonic() - started:.0f} s", flush=True)
    finally:
        shutil.rmtree(work, ignore_errors=True)
    what = f"the inputs of {args.recheck}" if args.recheck else f"{args.bags} bag/MCAP files and {args.csvs} CSV logs"
    print(f"seed {args.seed}: {what}, "
          f"{counts['runs']} runs in {time.monotonic() - started:.0f} s")
    for k, v in list(counts.items()) + list(kinds.items()):
        print(f"  {k}: {v}")
    sys.exit(1 if failures else 0)


if __name__ == "__main__":
    main()
