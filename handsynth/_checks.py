"""Checks of arguments that every layer takes alike.

One place for each check, so that every function refuses the same bad value
with the same message, naming the argument and the value received.
"""

from __future__ import annotations

import math
import numbers
import os
from pathlib import Path
from typing import Any, TypeVar

import numpy as np

from .errors import HandsynthError, InvalidInputError

__all__ = ["SIDES", "check_array", "check_instance", "check_integer", "check_number", "check_options",
           "check_path", "check_path_names", "check_side", "is_number", "short_repr"]

_T = TypeVar("_T")

#: The hands a device or a model can be on.
SIDES = ("right", "left")


def check_side(side, *, name: str = "side", error: type[HandsynthError] = InvalidInputError) -> str:
    """`side`, refused unless it is ``"right"`` or ``"left"`` (case matters).

    Parameters
    ----------
    side : object
        What was given.
    name : str, keyword-only
        The argument's name, for the message (``"EvalOptions.side"``).
    error : HandsynthError subclass, keyword-only
        Class of the error raised.

    Returns
    -------
    str

    Raises
    ------
    HandsynthError
        (`error`) anything else, named with the value received (``'Right'``
        is refused: a misspelt side would otherwise read as the other hand).
    """
    if side not in SIDES:
        raise error(f"{name} must be 'right' or 'left', got {side!r}")
    return side


def short_repr(value, limit: int = 60) -> str:
    """``repr(value)`` cut to `limit` characters (``...`` at the end), for messages."""
    text = repr(value)
    return text if len(text) <= limit else text[:limit - 3] + "..."


def check_options(options: object, cls: type[_T], *, name: str = "options",
                  error: type[HandsynthError] = InvalidInputError) -> _T:
    """`options` checked to be an instance of the dataclass `cls`; ``cls()`` for None.

    For any argument whose default is a configuration dataclass made with its
    defaults (options, ``shape`` as ``HandShape()``, an IMU ``placement``).

    Parameters
    ----------
    options : object
        What was given.
    cls : type
        The dataclass (``SearchOptions``); made with its defaults for None.
    name : str, keyword-only
        The argument's name, for the message.
    error : HandsynthError subclass, keyword-only
        Class of the error raised.

    Returns
    -------
    cls instance

    Raises
    ------
    HandsynthError
        (`error`) anything else, named with its type and value: a dict of
        fields (``{}`` is not the defaults), the fields' values alone, or
        options of another class.
    """
    if options is None:
        return cls()
    hint = f" (make one: {cls.__name__}(**fields))" if isinstance(options, dict) else ""
    return check_instance(options, cls, name=name, error=error, hint=hint)


def check_instance(value: object, cls: type[_T], *, name: str,
                   error: type[HandsynthError] = InvalidInputError, hint: str = "") -> _T:
    """`value`, refused unless it is an instance of `cls`.

    Parameters
    ----------
    value : object
        What was given.
    cls : type
        The class required (``HandShape``).
    name : str, keyword-only
        The argument's name, for the message (``"ChainEKF.model"``).
    error : HandsynthError subclass, keyword-only
        Class of the error raised.
    hint : str, keyword-only
        Appended to the message.

    Returns
    -------
    cls instance
        `value` itself.

    Raises
    ------
    HandsynthError
        (`error`) anything else, named with its type and value:
        ``shape must be a HandShape, got str 'L1.0'``.
    """
    if not isinstance(value, cls):
        article = "an" if cls.__name__[:1] in "AEIOU" else "a"
        raise error(f"{name} must be {article} {cls.__name__}, got {type(value).__name__} "
                    f"{short_repr(value)}{hint}")
    return value


def _number_kind(value: Any) -> str | None:
    """``"int"`` or ``"float"`` for a real number, else None (bool included).

    Numbers of any kind count (``int``, ``float``, numpy scalars, 0-d numpy
    arrays), but never ``bool``: ``True`` is a flag, not the number 1, and
    never a string that reads as a number.
    """
    if isinstance(value, (bool, np.bool_)):
        return None
    if isinstance(value, np.ndarray) and value.ndim == 0:
        kind = value.dtype.kind
        return "int" if kind in "iu" else "float" if kind == "f" else None
    if isinstance(value, numbers.Integral):
        return "int"
    if isinstance(value, numbers.Real):
        return "float"
    return None


def is_number(value: Any) -> bool:
    """`value` is a real number: ``int``, ``float``, a numpy scalar or 0-d array; not a
    bool, not a text that reads as a number."""
    return _number_kind(value) is not None


def _bounds_text(minimum, maximum, above, below) -> str:
    parts = []
    if minimum is not None:
        parts.append(f">= {minimum:g}")
    if above is not None:
        parts.append(f"> {above:g}")
    if maximum is not None:
        parts.append(f"<= {maximum:g}")
    if below is not None:
        parts.append(f"< {below:g}")
    return " " + " and ".join(parts) if parts else ""


def _refuse(what: str, name: str, value: Any, bounds: str, error: type[HandsynthError],
            kind_ok: bool) -> None:
    typed = "" if kind_ok else f" ({type(value).__name__})"
    raise error(f"{name} must be {what}{bounds}, got {value!r}{typed}")


def check_number(value: Any, name: str, *, minimum: float | None = None,
                 maximum: float | None = None, above: float | None = None,
                 below: float | None = None, allow_none: bool = False,
                 error: type[HandsynthError] = InvalidInputError) -> Any:
    """`value` as a finite ``float`` within bounds.

    Parameters
    ----------
    value : object
        What was given.
    name : str
        The argument's name, for the message (``"fps"``, ``"field 'gain'"``).
    minimum, maximum : float, keyword-only, optional
        Inclusive bounds.
    above, below : float, keyword-only, optional
        Exclusive bounds.
    allow_none : bool, keyword-only
        Pass None through (an option left unset).
    error : HandsynthError subclass, keyword-only
        Class of the error raised.

    Returns
    -------
    float, or None when `value` is None and `allow_none`

    Raises
    ------
    HandsynthError
        (`error`) not a real number (a string, a bool, an array; the type is
        named), NaN or infinite, or out of bounds: ``"fps must be a finite
        number > 0, got -1"``.
    """
    if value is None and allow_none:
        return None
    bounds = _bounds_text(minimum, maximum, above, below)
    kind_ok = _number_kind(value) is not None
    try:
        v = float(value) if kind_ok else math.nan
    except OverflowError:  # an int too large for a float
        v = math.inf
    ok = (math.isfinite(v) and (minimum is None or v >= minimum)
          and (maximum is None or v <= maximum) and (above is None or v > above)
          and (below is None or v < below))
    if not ok:
        _refuse("a finite number", name, value, bounds, error, kind_ok)
    return v


def check_integer(value: Any, name: str, *, minimum: int | None = None,
                  maximum: int | None = None, allow_none: bool = False,
                  error: type[HandsynthError] = InvalidInputError) -> Any:
    """`value` as an ``int`` within inclusive bounds (Python or numpy integers, not bool).

    Parameters
    ----------
    value : object
        What was given; ``2.0`` is refused (a count is not a measurement).
    name : str
        The argument's name, for the message.
    minimum, maximum : int, keyword-only, optional
        Inclusive bounds.
    allow_none : bool, keyword-only
        Pass None through.
    error : HandsynthError subclass, keyword-only
        Class of the error raised.

    Returns
    -------
    int, or None when `value` is None and `allow_none`

    Raises
    ------
    HandsynthError
        (`error`) not an integer, or out of bounds: ``"count must be an
        integer >= 2, got 1"``.
    """
    if value is None and allow_none:
        return None
    bounds = _bounds_text(minimum, maximum, None, None)
    kind_ok = _number_kind(value) == "int"
    v = int(value) if kind_ok else None
    if v is None or (minimum is not None and v < minimum) or (maximum is not None
                                                               and v > maximum):
        _refuse("an integer", name, value, bounds, error, _number_kind(value) is not None)
    return v


def check_path_names(named, *, kind: str = "file",
                     error: type[HandsynthError] = InvalidInputError) -> None:
    """Refuse an empty or blank path name, which would be read as the current folder.

    Parameters
    ----------
    named : iterable of (str, object)
        Each argument's or option's name and its value (a path or text; None,
        not given, is skipped).
    kind : str, keyword-only
        What the name must name, for the message (``"file"``, ``"folder"``).
    error : type of HandsynthError, keyword-only

    Raises
    ------
    HandsynthError
        (`error`) ``<name> must name a <kind>, got ''``, for the first empty one.
    """
    for name, value in named:
        if value is not None and not str(value).strip():
            raise error(f"{name} must name a {kind}, got {str(value)!r}")


def check_path(value: Any, name: str, *, kind: str = "file",
               error: type[HandsynthError] = InvalidInputError) -> Path:
    """A file or folder name given to a library function, as a :class:`pathlib.Path`.

    Parameters
    ----------
    value : str or os.PathLike
        The name as given.
    name : str
        The argument's name, for the message.
    kind : str, keyword-only
        What it must name (``"file"``, ``"folder"``), for the message.
    error : type of HandsynthError, keyword-only

    Returns
    -------
    pathlib.Path

    Raises
    ------
    HandsynthError
        (`error`) `value` is not a str or path-like (``None``, a number, an open file), or an
        empty or blank name (which would be read as the current folder), naming `name`.
    """
    if isinstance(value, bytes) or not isinstance(value, (str, os.PathLike)):
        got = "None" if value is None else f"{type(value).__name__} {short_repr(value)}"
        raise error(f"{name} must be a {kind} name (str or path), got {got}")
    check_path_names([(name, value)], kind=kind, error=error)
    return Path(value)


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
