"""Checks of the arguments of the tracker API: numbers, 3-vectors and arrays.

The number and array checks are the package's own (:func:`handsynth._checks.check_number`,
:func:`~handsynth._checks.check_integer`, :func:`~handsynth._checks.check_array`), re-exported here beside the
tracker-only ones.  Each check names the argument and repeats the value received in its
:class:`~handsynth.errors.InvalidInputError`, so that a wrong option fails
where it is given and not later inside numpy or scipy.  Numbers are real
numbers of any kind (``int``, ``float``, numpy scalars, 0-d numpy arrays)
but never ``bool``: ``True`` is a flag, not the number 1.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..._checks import check_array, check_integer, check_number
from ...errors import InvalidInputError

__all__ = ["check_array", "check_integer", "check_interval", "check_number", "check_vector3"]


def check_interval(value: Any, name: str) -> tuple[float, float]:
    """Two finite real numbers ``(low, high)`` with ``low < high``.

    Raises
    ------
    InvalidInputError
        If `value` is not a pair of finite real numbers in increasing order.
    """
    try:
        pair: tuple[Any, ...] = tuple(value)
    except TypeError:
        pair = ()
    if len(pair) != 2:
        raise InvalidInputError(f"{name} must be (low, high), two numbers, got {value!r}")
    try:
        lo, hi = (check_number(v, f"{name}[{i}]") for i, v in enumerate(pair))
    except InvalidInputError:
        raise InvalidInputError(f"{name} must be (low, high), two finite numbers, got "
                                f"{value!r}") from None
    if not lo < hi:
        raise InvalidInputError(f"{name} must be (low, high) with low < high, got {value!r}")
    return lo, hi


def check_vector3(value: Any, name: str, *, nonzero: bool = False) -> np.ndarray:
    """Three finite numbers as a ``(3,)`` float64 array (a new one).

    Parameters
    ----------
    value : array_like
    name : str
        Name of the argument, for the message.
    nonzero : bool
        Also refuse the zero vector, and return the direction scaled so that its
        largest component is +-1 (its norm then neither overflows, for ``1e300``,
        nor underflows to zero, for ``1e-300``).

    Raises
    ------
    InvalidInputError
        If `value` is not 3 finite numbers (or is zero when `nonzero`).
    """
    want = "a non-zero 3-vector" if nonzero else "3 finite numbers"
    if isinstance(value, (str, bytes)):
        raise InvalidInputError(f"{name}: expected {want}, got {value!r}")
    try:
        a = np.array(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise InvalidInputError(f"{name}: expected {want}, got {value!r}") from None
    if a.shape != (3,) or not np.isfinite(a).all() or (nonzero and not np.abs(a).max() > 0):
        raise InvalidInputError(f"{name}: expected {want}, got {value!r}")
    return a / np.abs(a).max() if nonzero else a
