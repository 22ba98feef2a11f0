"""Fields of a calibration file's entries, checked as they are read.

A calibration file is JSON a user may edit by hand; a field of the wrong
shape would otherwise broadcast into silently wrong angles or fail deep in
numpy.  Every reader of an entry (``from_dict``) takes its fields through
:func:`array_field` and :func:`number_field`, which name the field and what
was found.
"""

from __future__ import annotations

import math

import numpy as np

from ...errors import InvalidInputError

__all__ = ["array_field", "number_field"]


def array_field(d: dict, key: str, shape: tuple[int | None, ...], *,
                allow_nan: bool = False) -> np.ndarray:
    """``d[key]`` as a float array of `shape` (None: any length on that axis).

    Raises
    ------
    KeyError
        `key` is missing (the caller names the entry).
    InvalidInputError
        Not numbers, another shape, or a NaN or infinity where none may be.
    """
    value = d[key]
    try:
        a = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise InvalidInputError(f"field {key!r} must be numbers, got {_short(value)}") from None
    if a.ndim != len(shape) or any(n is not None and n != m for n, m in zip(shape, a.shape)):
        want = "(" + ", ".join("N" if n is None else str(n) for n in shape) + \
            ("," if len(shape) == 1 else "") + ")"
        raise InvalidInputError(f"field {key!r} must have shape {want}, got {a.shape}")
    bad = np.isinf(a) if allow_nan else ~np.isfinite(a)
    if bad.any():
        raise InvalidInputError(f"field {key!r} holds {a[bad][0]} at index "
                                f"{tuple(int(i) for i in np.argwhere(bad)[0])}")
    return a


def number_field(d: dict, key: str) -> float:
    """``d[key]`` as a finite float (not a string that reads as one)."""
    value = d[key]
    if isinstance(value, bool) or not isinstance(value, (int, float)) \
            or not math.isfinite(value):
        raise InvalidInputError(f"field {key!r} must be a finite number, got {_short(value)}")
    return float(value)


def _short(value) -> str:
    text = repr(value)
    return text if len(text) <= 40 else text[:37] + "..."
