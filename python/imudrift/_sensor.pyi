"""Type stubs of imudrift.Sensor (python/imudrift/_sensor.py)."""

import os
from typing import Any, Dict, Optional, Union

class Sensor:
    name: str
    def __init__(
        self, x: Union[str, "os.PathLike[str]", Dict[str, Any], "Sensor"], source: Optional[str] = None
    ) -> None: ...
    @classmethod
    def from_toml(cls, text: str) -> "Sensor": ...
    @classmethod
    def from_kalibr(cls, path_or_text: Union[str, "os.PathLike[str]"]) -> "Sensor": ...
    def to_toml(self) -> str: ...
    def to_kalibr(self, rate_hz: float, rostopic: str = "/imu0", flavor: str = "kalibr") -> str: ...
    def to_dict(self) -> Dict[str, Any]: ...

def plan(
    sensor: Union[Sensor, str, "os.PathLike[str]", Dict[str, Any]],
    uncertainty: Union[float, str] = 0.1,
    duration_s: Optional[float] = None,
    rate_hz: float = 100.0,
) -> Dict[str, Any]: ...
