"""A Monte Carlo drift job split into shards on a Dask cluster, merged into exactly the result one
process computes.

    python python/examples/dask_shards.py [SCENARIO] [RUNS] [SHARDS]

Each shard is `imudrift.simulate_shard(scenario, i, k, ...)` on a worker process (the bytes of a
shard file, the same as `imudrift simulate --shard i/k` writes); `imudrift.merge` puts them
together in run-index order. Any scheduler works the same way (Ray, a Slurm array writing shard
files, concurrent.futures): a shard depends only on (scenario, runs, seed, i, k).
Needs `pip install "dask[distributed]"`.
"""

import logging
import os
import sys
import time

import imudrift
from dask.distributed import Client, LocalCluster

HERE = os.path.dirname(os.path.abspath(__file__))
DEFAULT = os.path.join(HERE, "..", "..", "configs", "scenarios", "mtx-static-60s.toml")


def run_on_dask(scenario, runs, shards, seed=None, n_workers=2):
    """The job's shards on a LocalCluster of worker processes, merged."""
    # One single-threaded worker per process: each shard runs on one core of its own.
    with LocalCluster(n_workers=n_workers, threads_per_worker=1, processes=True,
                      dashboard_address=None, silence_logs=logging.CRITICAL) as cluster, Client(cluster) as client:
        futures = [
            client.submit(imudrift.simulate_shard, scenario, i, shards, runs=runs, seed=seed,
                          threads=1, pure=False)
            for i in range(shards)
        ]
        return imudrift.merge(client.gather(futures))


def main():
    scenario = os.path.abspath(sys.argv[1] if len(sys.argv) > 1 else DEFAULT)
    runs = int(sys.argv[2]) if len(sys.argv) > 2 else 500
    shards = int(sys.argv[3]) if len(sys.argv) > 3 else 4
    t0 = time.perf_counter()
    merged = run_on_dask(scenario, runs, shards)
    t1 = time.perf_counter()
    single = imudrift.simulate(scenario, runs=runs)
    t2 = time.perf_counter()
    same = merged.to_dict() == single.to_dict() and (merged.values == single.values).all()
    h = merged.checkpoints[-1]["channels"]["pos_horizontal_m"]
    print(f"{scenario}: {runs} runs in {shards} shards on 2 Dask worker processes: {t1 - t0:.1f} s; "
          f"one process: {t2 - t1:.1f} s")
    print(f"horizontal error at {merged.t[-1]:g} s: mean {h['mean']:.2f} m, p95 {h['p95']:.2f} m")
    print("merged result identical to the single-process one:", same)
    return 0 if same else 1


if __name__ == "__main__":
    sys.exit(main())
