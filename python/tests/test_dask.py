"""The Monte Carlo job on a dask.distributed LocalCluster of worker processes gives exactly the
single-process result (python/examples/dask_shards.py)."""

import os
import sys

import numpy as np
import pytest

import imudrift

pytest.importorskip("dask.distributed")

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "examples"))
from dask_shards import DEFAULT, run_on_dask  # noqa: E402

from test_simulate import assert_same  # noqa: E402


def test_local_cluster_equals_one_process():
    scenario = os.path.abspath(DEFAULT)
    merged = run_on_dask(scenario, runs=96, shards=4, seed=17)
    single = imudrift.simulate(scenario, runs=96, seed=17)
    assert_same(merged.to_dict(), single.to_dict())
    np.testing.assert_array_equal(merged.values, single.values)
    assert merged.values.shape[0] == 96
