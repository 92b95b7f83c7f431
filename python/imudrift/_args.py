"""Python arguments turned into the types the compiled module takes, each refusal an
:class:`imudrift.InvalidInput` naming the argument (never a ``TypeError`` or ``OverflowError``
from the conversion). Only the types are checked here: what a value may be (a rate's range, a
number of runs) is the request layer's rule (crates/request), the same for the command line."""

import math
import numbers
import operator

import numpy as np

from ._imudrift import InvalidInput

# The widest integer the compiled module takes (Rust's u64 and, on 64-bit machines, usize).
INT_MAX = 2**64 - 1


def _kind(value):
    return "None" if value is None else type(value).__name__


def integer(name, value, lo=0, hi=INT_MAX):
    """``value`` as a Python int from ``lo`` to ``hi``: an integer (numpy's too, or a bool) or a
    float with an integral value."""
    if isinstance(value, (float, np.floating)):
        if not (math.isfinite(value) and float(value).is_integer()):
            raise InvalidInput(f"{name} {value}: expected an integer from {lo} to {hi}")
        value = int(value)
    else:
        try:
            value = operator.index(value)
        except TypeError:
            raise InvalidInput(
                f"{name}: expected an integer from {lo} to {hi}, got {_kind(value)}") from None
    if not lo <= value <= hi:
        raise InvalidInput(f"{name} {value}: expected an integer from {lo} to {hi}")
    return value


def optional_integer(name, value, lo=0, hi=INT_MAX):
    return None if value is None else integer(name, value, lo, hi)


def number(name, value):
    """``value`` as a float: a real number (an int, a float, numpy's, or a text of one). Whether
    it is finite or in range is the request layer's rule."""
    if isinstance(value, (complex, np.complexfloating)) or isinstance(value, bool):
        raise InvalidInput(f"{name}: expected a real number, got {_kind(value)}")
    if isinstance(value, numbers.Real) or isinstance(value, str):
        try:
            return float(value)
        except (ValueError, OverflowError):
            raise InvalidInput(f"{name} {value!r}: expected a real number") from None
    if isinstance(value, np.ndarray) and value.size == 1 and value.dtype.kind in "iuf":
        return float(value.reshape(()))
    raise InvalidInput(f"{name}: expected a real number, got {_kind(value)}")


def optional_number(name, value):
    return None if value is None else number(name, value)


def text(name, value):
    """``value`` as a str (the library says whether it is one of the names it takes)."""
    if not isinstance(value, str):
        raise InvalidInput(f"{name}: expected a text, got {_kind(value)}")
    return value


def optional_text(name, value):
    return None if value is None else text(name, value)


def texts(name, value):
    """A text or a list of texts, as a list."""
    if isinstance(value, str):
        return [value]
    try:
        items = list(value)
    except TypeError:
        raise InvalidInput(f"{name}: expected a text or a list of texts, got {_kind(value)}") from None
    return [text(f"{name}[{i}]", v) for i, v in enumerate(items)]


def numbers_list(name, value):
    """A number or a sequence of numbers, as a list of floats (1-D)."""
    if value is None or isinstance(value, (str, bytes, dict)):
        raise InvalidInput(f"{name}: expected numbers, got {_kind(value)}")
    if isinstance(value, (complex, np.complexfloating)):
        raise InvalidInput(f"{name}: expected real numbers, got {_kind(value)}")
    if isinstance(value, (numbers.Real, np.ndarray)) and np.ndim(value) == 0:
        return [number(name, value)]
    try:
        items = list(value)
    except TypeError:
        raise InvalidInput(f"{name}: expected numbers, got {_kind(value)}") from None
    return [number(f"{name}[{i}]", v) for i, v in enumerate(items)]
