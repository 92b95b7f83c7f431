"""Type stubs of the compiled module imudrift._imudrift (python/src/lib.rs)."""

from typing import Any, Dict, List, Optional, Sequence, Tuple, Union

import numpy as np
import numpy.typing as npt

__version__: str

class InvalidInput(ValueError): ...
class LogUnreadable(OSError): ...

_F64 = npt.NDArray[np.float64]
_Taus = Union[str, Sequence[float], _F64]

CHANNELS: List[str]
TEMPERATURE: str
DIAGNOSE_DEFAULTS: Dict[str, Any]
DRIFT_DEFAULTS: Dict[str, Any]

def allantools_dev(
    data: _F64, rate: float, data_type: str, function: str, taus: Optional[_Taus] = None
) -> Tuple[_F64, _F64, _F64, _F64]: ...
def allantools_gradev(
    data: _F64,
    rate: float,
    data_type: str,
    taus: Optional[_Taus],
    ci: float,
    noisetype: str,
) -> Tuple[_F64, _F64, Tuple[_F64, _F64], _F64]: ...
def allan_analysis(
    data: _F64,
    rate: float,
    data_type: str,
    estimator: str,
    taus: _Taus,
    confidence: float,
    edf: str,
    stable32_stop: bool,
) -> Dict[str, Any]: ...
# reader: rate, gyro_unit, accel_unit, time_unit, columns [(channel, column)], topic.
def read_log_columns(path: str, reader: Dict[str, Any]) -> Dict[str, Any]: ...
def generate_columns(
    sensor_text: str,
    source: str,
    duration_s: float,
    rate_hz: float,
    seed: int,
    run: int,
    only: Optional[List[str]] = None,
    without: List[str] = ...,
) -> Dict[str, Any]: ...

# A scenario or sensor file path, or (sensor text, its source name).
_Subject = Union[str, Tuple[str, str]]

def simulate_run(subject: _Subject, settings: Dict[str, Any]) -> Dict[str, Any]: ...
def simulate_shard_bytes(
    subject: _Subject, index: int, count: int, settings: Dict[str, Any]
) -> bytes: ...
def merge_shards(shards: List[bytes]) -> Dict[str, Any]: ...
def sensor_parse(text: str, source: str) -> Dict[str, str]: ...
def sensor_source(arg: str, is_path: bool) -> Tuple[str, str]: ...
def sensor_toml_of_json(json: str) -> str: ...
def sensor_noise_file(
    text: str, source: str, flavor: str, rate_hz: float, rostopic: str
) -> str: ...
def sensor_plan(
    text: str, source: str, uncertainty: float, duration_s: Optional[float], rate_hz: float
) -> str: ...
def spec_run(sensors: List[Tuple[str, str]], settings: Dict[str, Any]) -> str: ...
def diagnose_run(
    logs: List[Any],
    model_arg: Tuple[str, str],
    reader: Dict[str, Any],
    settings: Dict[str, Any],
    check: List[Any],
) -> Dict[str, str]: ...
def drift_run(
    logs: List[Any], model_arg: Tuple[str, str], reader: Dict[str, Any], settings: Dict[str, Any]
) -> str: ...
def seconds_of(name: str, text: str) -> float: ...
