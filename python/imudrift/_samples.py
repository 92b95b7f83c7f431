"""Turn what a user passes as samples into the 1-D float64 array the Rust side reads."""

import numpy as np

from ._imudrift import InvalidInput


def as_samples(data, name="data"):
    """A contiguous 1-D float64 array of ``data`` (no copy when it already is one): real numbers
    (floats, integers, booleans, or objects that are numbers), never None, texts or complex
    numbers. Whether the values are usable is the library's rule (``request::allan``)."""
    if data is None:
        raise InvalidInput(f"{name}: expected an array of numbers, got None")
    try:
        a = np.asarray(data)
    except (TypeError, ValueError) as e:
        raise InvalidInput(f"{name}: expected an array of numbers ({e})") from None
    if a.dtype.kind not in "biufO":
        raise InvalidInput(f"{name}: expected an array of numbers, got dtype {a.dtype}")
    try:
        a = np.ascontiguousarray(a, dtype=np.float64)
    except (TypeError, ValueError, OverflowError) as e:
        raise InvalidInput(f"{name}: expected an array of real numbers ({e})") from None
    if a.ndim != 1:
        raise InvalidInput(f"{name}: expected a 1-D array, got shape {a.shape}")
    return a
