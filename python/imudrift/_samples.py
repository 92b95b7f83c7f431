"""Turn what a user passes as samples into the 1-D float64 array the Rust side reads."""

import numpy as np

from ._imudrift import InvalidInput


def as_samples(data):
    """A contiguous 1-D float64 array of ``data`` (no copy when it already is one)."""
    try:
        a = np.ascontiguousarray(data, dtype=np.float64)
    except (TypeError, ValueError) as e:
        raise InvalidInput(f"data: expected an array of numbers ({e})") from None
    if a.ndim != 1:
        raise InvalidInput(f"data: expected a 1-D array, got shape {a.shape}")
    return a
