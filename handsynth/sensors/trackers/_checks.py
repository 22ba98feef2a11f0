"""Checks of the arguments of the tracker API: numbers, 3-vectors and arrays.

The number checks are the package's own (:func:`handsynth._checks.check_number`,
:func:`~handsynth._checks.check_integer`), re-exported here beside the
tracker-only ones.  Each check names the argument and repeats the value received in its
:class:`~handsynth.errors.InvalidInputError`, so that a wrong option fails
where it is given and not later inside numpy or scipy.  Numbers are real
numbers of any kind (``int``, ``float``, numpy scalars, 0-d numpy arrays)
but never ``bool``: ``True`` is a flag, not the number 1.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..._checks import check_integer, check_number
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


def check_array(value: Any, name: str, shape: tuple[int | None, ...], *,
                min_rows: int = 1, rows: str = "rows") -> np.ndarray:
    """A finite float64 array of `shape` (``None``: any length along that axis).

    Parameters
    ----------
    value : array_like
    name : str
        Name of the argument, for the message.
    shape : tuple of int or None
        Expected shape (at least one axis); ``None`` for any length.
    min_rows : int
        Fewest rows (length of the first axis) accepted.
    rows : str
        What a row is, for the message (``"frames"``).

    Raises
    ------
    InvalidInputError
        If `value` is not numeric, has another shape or fewer rows, or holds
        NaN or inf (naming the first rows that do).
    """
    want = "(" + ", ".join("n" if s is None else str(s) for s in shape) + ")"
    try:
        a = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise InvalidInputError(
            f"{name}: expected a numeric array of shape {want}, got {type(value).__name__}"
        ) from None
    if a.ndim != len(shape) or any(s is not None and s != d for s, d in zip(shape, a.shape)):
        raise InvalidInputError(f"{name}: expected shape {want}, got {a.shape}")
    if a.shape[0] < min_rows:
        raise InvalidInputError(f"{name}: expected at least {min_rows} {rows}, got {a.shape[0]}")
    bad = ~np.isfinite(a).all(axis=tuple(range(1, a.ndim)))
    if bad.any():
        where = np.flatnonzero(bad)
        raise InvalidInputError(
            f"{name}: {where.size} of {a.shape[0]} {rows} contain NaN or inf "
            f"(first {rows} {where[:5].tolist()})"
        )
    return a
