"""Fields of a calibration file's entries and the arrays of the public calls, checked as
they are read.

A calibration file is JSON a user may edit by hand, and an array handed to a
public function may have any shape; a value of the wrong shape would
otherwise broadcast into silently wrong angles or fail deep in numpy.  Every
reader of an entry (``from_dict``) takes its fields through
:func:`array_field` and :func:`number_field`, and every constructor and
public function its arrays through :func:`as_array`, :func:`as_number` and
:func:`as_sensors`; each names the field or argument and what was found.
"""

from __future__ import annotations

import numpy as np

from ..._checks import check_number, short_repr
from ...errors import InvalidInputError

__all__ = ["array_field", "as_array", "as_number", "as_sensors", "number_field"]


def as_array(value, what: str, shape: tuple[int | None, ...], *,
             allow_nan: bool = False) -> np.ndarray:
    """`value` as a float array of `shape` (None: any length on that axis).

    Parameters
    ----------
    value : array_like
    what : str
        Name of the value in messages (``"field 'centre'"``, ``"angles"``, ...).
    shape : tuple of int or None
    allow_nan : bool, keyword-only
        Let NaN through (infinities are always refused).

    Raises
    ------
    InvalidInputError
        Not numbers, another shape, or a NaN or infinity where none may be.
    """
    try:
        a = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise InvalidInputError(f"{what} must be numbers, got {short_repr(value, 40)}") from None
    if a.ndim != len(shape) or any(n is not None and n != m for n, m in zip(shape, a.shape)):
        want = "(" + ", ".join("N" if n is None else str(n) for n in shape) + \
            ("," if len(shape) == 1 else "") + ")"
        raise InvalidInputError(f"{what} must have shape {want}, got {a.shape}")
    bad = np.isinf(a) if allow_nan else ~np.isfinite(a)
    if bad.any():
        raise InvalidInputError(f"{what} holds {a[bad][0]} at index "
                                f"{tuple(int(i) for i in np.argwhere(bad)[0])}")
    return a


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
    return as_array(d[key], f"field {key!r}", shape, allow_nan=allow_nan)


def as_number(value, what: str) -> float:
    """`value` as a finite float (not a bool, nor a string that reads as one).

    Raises
    ------
    InvalidInputError
        Anything else; the message names `what` and the value.
    """
    return check_number(value, what)


def number_field(d: dict, key: str) -> float:
    """``d[key]`` as a finite float (not a string that reads as one)."""
    return as_number(d[key], f"field {key!r}")


def as_sensors(sensors, what: str = "sensors") -> np.ndarray:
    """Readings as a float array (N, 5); one reading (5,) becomes one row.

    NaN (a dropped sample) passes; an infinite reading does not.

    Raises
    ------
    InvalidInputError
        Another shape, not numbers, or an infinite reading (the row is named).
    """
    try:
        s = np.asarray(sensors, dtype=np.float64)
    except (TypeError, ValueError):
        raise InvalidInputError(f"{what} must be numbers, got {short_repr(sensors, 40)}") from None
    if s.ndim == 1:
        s = s[None]
    if s.ndim != 2 or s.shape[1] != 5:
        raise InvalidInputError(f"{what} must have shape (N, 5), got {np.shape(sensors)}")
    if np.isinf(s).any():
        row = int(np.argwhere(np.isinf(s))[0, 0])
        raise InvalidInputError(f"{what}: row {row} has an infinite reading")
    return s
