"""Type stubs of imudrift.spec, diagnose, drift (python/imudrift/_analyse.py)."""

import os
from typing import Any, Dict, List, Mapping, Optional, Sequence, Union

import numpy as np
import numpy.typing as npt

from ._sensor import Sensor

_Model = Union[Sensor, str, "os.PathLike[str]", Dict[str, Any]]
_Time = Union[float, str]
_Times = Union[_Time, Sequence[_Time]]
_Terms = Union[str, Sequence[str], None]
# A path (any format read_log reads), a read_log DataFrame, a dict of SI channels
# (gx gy gz ax ay az [temp]) or an n x 6 array (gx gy gz ax ay az).
_Log = Union[str, "os.PathLike[str]", Any, Mapping[str, npt.ArrayLike], npt.NDArray[np.float64]]
_Logs = Union[_Log, Sequence[_Log]]

class SpecResult:
    seed: int
    readback_duration_s: Optional[float]
    readback_rate_hz: float
    readback_confidence: float
    drift_rate_hz: float
    sensors: List[Dict[str, Any]]
    def to_dict(self) -> Dict[str, Any]: ...
    def to_pandas(self) -> Any: ...
    def requirements(self) -> Any: ...

class DiagnoseResult:
    corrected: Sensor
    log: str
    model: str
    seed: int
    channels: Dict[str, Any]
    drift: List[Dict[str, Any]]
    @property
    def effects(self) -> List[Dict[str, Any]]: ...
    def to_dict(self) -> Dict[str, Any]: ...
    def to_pandas(self) -> Any: ...

class DriftResult:
    logs: List[str]
    model: str
    seed: int
    replicates: int
    protocol_text: str
    horizons: List[Dict[str, Any]]
    def to_dict(self) -> Dict[str, Any]: ...
    def to_pandas(self) -> Any: ...

def spec(
    sensors: Union[_Model, Sequence[_Model]],
    times: Optional[_Times] = None,
    require: _Terms = None,
    runs: Optional[int] = None,
    seed: int = 1,
    rate_hz: float = 100.0,
    readback: bool = False,
    readback_duration_s: Optional[float] = None,
    only: _Terms = None,
    without: _Terms = None,
    threads: Optional[int] = None,
) -> SpecResult: ...
def diagnose(
    logs: _Logs,
    model: _Model,
    rate: Optional[float] = None,
    gyro_unit: Optional[str] = None,
    accel_unit: Optional[str] = None,
    time_unit: Optional[str] = None,
    columns: Optional[Mapping[str, str]] = None,
    topic: Optional[str] = None,
    seed: int = 1,
    seeds: int = 16,
    rounds: int = 6,
    horizons: _Times = (60.0, 3600.0),
    min_delta_bic: float = 16.0,
    tau_min: float = 0.0,
    check: Optional[_Logs] = None,
    drift_check: bool = False,
    calibration: Optional[str] = None,
    init: Optional[str] = None,
    threads: Optional[int] = None,
) -> DiagnoseResult: ...
def drift(
    logs: _Logs,
    model: _Model,
    rate: Optional[float] = None,
    gyro_unit: Optional[str] = None,
    accel_unit: Optional[str] = None,
    time_unit: Optional[str] = None,
    columns: Optional[Mapping[str, str]] = None,
    topic: Optional[str] = None,
    calibration: str = "log-mean",
    init: str = "perfect",
    horizons: _Times = (10.0, 60.0, 600.0, 3600.0),
    overlap: bool = False,
    replicates: int = 40,
    exact_parameters: bool = False,
    seed: int = 1,
    threads: Optional[int] = None,
) -> DriftResult: ...
