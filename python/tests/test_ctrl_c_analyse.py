"""Ctrl-C stops imudrift.diagnose and imudrift.drift within a second: a child process starts
one on a long simulated log, SIGINT is sent once the work is under way, and the child must
raise KeyboardInterrupt and exit. The time measured is from the signal to the child's exit
(the interpreter's start and the log's generation come before the signal and are not in it)."""

import os
import signal
import subprocess
import sys
import time

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..")
MTX = os.path.join(ROOT, "configs", "sensors", "mtx.toml")

# The stop itself (SIGINT to KeyboardInterrupt) must land within 1 s; the child's exit after it
# (the interpreter's shutdown: numpy, pandas) is allowed this much on top, on a busy machine
# (0.9 s measured at a load of 13 on 2 cores).
EXIT_MARGIN_S = 1.5

CHILD = r"""
import sys, time, imudrift
import signal
# A parent started in the background passes SIGINT on as ignored: take Python's default back.
signal.signal(signal.SIGINT, signal.default_int_handler)
which, model = sys.argv[1], sys.argv[2]
log = imudrift.generate(imudrift.Sensor(model), duration_s=3600, rate_hz=100, seed=3)
log = log[["gx", "gy", "gz", "ax", "ay", "az"]].to_numpy()
print("start", flush=True)
try:
    if which == "diagnose":
        imudrift.diagnose(log, model, rate=100, seeds=2000, threads=2)
    else:
        imudrift.drift(log, model, rate=100, replicates=20000, threads=2)
    print("finished", flush=True)
except KeyboardInterrupt:
    print(f"interrupted {time.monotonic():.6f}", flush=True)
"""


def interrupted(which, after_s):
    """Run `which` in a child, SIGINT `after_s` after it started the work: the child's output,
    seconds from the signal to the child's KeyboardInterrupt and to its exit."""
    p = subprocess.Popen([sys.executable, "-c", CHILD, which, MTX], stdout=subprocess.PIPE,
                         text=True)
    assert p.stdout.readline().strip() == "start"
    time.sleep(after_s)
    t0 = time.monotonic()
    p.send_signal(signal.SIGINT)
    try:
        out, _ = p.communicate(timeout=60)
    except subprocess.TimeoutExpired:
        p.kill()
        raise
    exited = time.monotonic() - t0
    raised = None
    for line in out.splitlines():
        if line.startswith("interrupted"):
            # time.monotonic is one clock for every process (CLOCK_MONOTONIC on Linux).
            raised = float(line.split()[1]) - t0
    return out, raised, exited


def check(which):
    # 6 s in: past diagnose's detectors and measurement of the log (which have no stop inside)
    # and the drift check's measured segments, in the simulations.
    out, raised, exited = interrupted(which, 6.0)
    print(f"{which}: SIGINT to KeyboardInterrupt {raised} s, to exit {exited:.3f} s, "
          f"load {os.getloadavg()[0]:.1f}")
    assert "finished" not in out, "the work ended before the signal: make the input longer"
    assert raised is not None, out
    assert raised < 1.0
    assert exited < 1.0 + EXIT_MARGIN_S


def test_ctrl_c_stops_a_long_diagnosis():
    check("diagnose")


def test_ctrl_c_stops_a_long_drift_check():
    check("drift")
