"""Input checks shared by the feature extractors of :mod:`handsynth.db`.

The features of SPEC.md section 1 are defined on the 64x64 silhouette that
preprocessing produces.  Every public function of this package funnels its
image arguments through :func:`as_silhouette` or :func:`as_silhouette_batch`
so that a wrong shape, dtype or value is refused with one message format.
"""

from __future__ import annotations

import numpy as np

from ..errors import InvalidInputError

__all__ = ["IMAGE_SIZE", "as_silhouette", "as_silhouette_batch"]

#: Side length in pixels of the square silhouette (SPEC.md section 1, "Preprocessing").
IMAGE_SIZE: int = 64


def _describe(arr: np.ndarray) -> str:
    return f"array of shape {arr.shape} and dtype {arr.dtype}"


def _to_bool(arr: np.ndarray, name: str) -> np.ndarray:
    """Return `arr` as a C-contiguous bool array; numbers must be exactly 0 or 1."""
    if arr.dtype == np.bool_:
        return np.ascontiguousarray(arr)
    if arr.dtype.kind not in "biuf":
        raise InvalidInputError(
            f"{name} must be a bool array (or numbers 0/1), got {_describe(arr)}"
        )
    if arr.dtype.kind == "f":
        bad = ~np.isfinite(arr)
        if bad.any():
            where = tuple(int(i) for i in np.argwhere(bad)[0])
            raise InvalidInputError(
                f"{name} must be finite 0/1 values, got {arr[where].item()!r} at index {where}"
            )
    bad = (arr != 0) & (arr != 1)
    if bad.any():
        where = tuple(int(i) for i in np.argwhere(bad)[0])
        raise InvalidInputError(
            f"{name} must contain only 0 and 1, got {arr[where].item()!r} at index {where}"
        )
    return np.ascontiguousarray(arr != 0)


def as_silhouette(value, name: str = "silhouette") -> np.ndarray:
    """Check one silhouette and return it as a contiguous bool array.

    Parameters
    ----------
    value : array_like, shape (64, 64)
        bool, or integers/floats that are exactly 0 or 1.
    name : str
        Argument name used in error messages.

    Returns
    -------
    ndarray of bool, shape (64, 64), C-contiguous
        A view of `value` when it already is a contiguous bool array.

    Raises
    ------
    InvalidInputError
        Wrong shape, non-numeric dtype, NaN/inf or a value other than 0/1.
    """
    arr = np.asarray(value)
    if arr.shape != (IMAGE_SIZE, IMAGE_SIZE):
        raise InvalidInputError(
            f"{name} must have shape ({IMAGE_SIZE}, {IMAGE_SIZE}), got {_describe(arr)}"
        )
    return _to_bool(arr, name)


def as_silhouette_batch(value, name: str = "silhouettes") -> np.ndarray:
    """Check a stack of silhouettes; like :func:`as_silhouette` with shape (N, 64, 64)."""
    arr = np.asarray(value)
    if arr.ndim != 3 or arr.shape[1:] != (IMAGE_SIZE, IMAGE_SIZE):
        raise InvalidInputError(
            f"{name} must have shape (N, {IMAGE_SIZE}, {IMAGE_SIZE}), got {_describe(arr)}"
        )
    return _to_bool(arr, name)
