"""Type stubs of imudrift.simulate, simulate_shard, merge (python/imudrift/_simulate.py)."""

import os
from typing import Any, Dict, Iterable, List, Optional, Sequence, Union

import numpy as np
import numpy.typing as npt

from ._sensor import Sensor

_Scenario = Union[str, "os.PathLike[str]", Sensor]
_Terms = Union[str, Sequence[str], None]

class SimulateResult:
    values: npt.NDArray[np.float64]
    run_ids: npt.NDArray[np.uint64]
    t: npt.NDArray[np.float64]
    quantities: List[str]
    scenario: str
    sensor: str
    seed: int
    runs: int
    runs_ok: int
    checkpoints: List[Dict[str, Any]]
    def to_dict(self) -> Dict[str, Any]: ...
    def to_pandas(self) -> Any: ...

def simulate(
    scenario: _Scenario,
    runs: Optional[int] = None,
    seed: Optional[int] = None,
    threads: Optional[int] = None,
    duration_s: Optional[float] = None,
    rate_hz: Optional[float] = None,
    only: _Terms = None,
    without: _Terms = None,
    ablation: Optional[bool] = None,
) -> SimulateResult: ...
def simulate_shard(
    scenario: _Scenario,
    index: int,
    count: int,
    runs: Optional[int] = None,
    seed: Optional[int] = None,
    threads: Optional[int] = None,
    duration_s: Optional[float] = None,
    rate_hz: Optional[float] = None,
    only: _Terms = None,
    without: _Terms = None,
    ablation: Optional[bool] = None,
) -> bytes: ...
def merge(shards: Iterable[Union[bytes, str, "os.PathLike[str]"]]) -> SimulateResult: ...
