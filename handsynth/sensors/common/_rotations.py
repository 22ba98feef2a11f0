"""Small, vectorised rotation helpers shared by the sensor modules.

Conventions used everywhere in :mod:`handsynth.sensors`:

* a rotation matrix ``R`` of a sensor maps sensor-frame coordinates to
  transmitter-frame coordinates (``x_tx = R @ x_sensor + t``);
* rotation vectors (axis-angle) are ``angle * unit_axis`` in radians;
* quaternions are scalar-first ``(w, x, y, z)``.

Conversions to and from Euler angles and quaternions are delegated to
:class:`scipy.spatial.transform.Rotation`.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

__all__ = [
    "axis_angle_matrix",
    "check_rotations",
    "matrix_to_rotvec",
    "rotation_error",
    "rotvec_to_matrix",
]

#: Largest accepted ``max |R^T R - I|`` (and ``|det R - 1|``) of an input
#: rotation.  Text exports with 4-5 significant digits reach about 1e-4.
ROTATION_TOLERANCE = 1e-3


def _as_float_array(value, name: str, shape: str, tail: tuple[int, ...], *, finite: bool = True,
                    error=None) -> np.ndarray:
    """`value` as a float64 array whose last axes are `tail` (all finite unless not `finite`),
    else `error` (InvalidInputError by default) naming `name`."""
    from ..._checks import short_repr
    from ...errors import InvalidInputError

    error = error or InvalidInputError
    try:
        a = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise error(f"{name} must be a {shape} array of numbers, got "
                    f"{type(value).__name__} {short_repr(value)}") from None
    if a.ndim < len(tail) or a.shape[a.ndim - len(tail):] != tail:
        raise error(f"{name} must have shape {shape}, got shape {a.shape}")
    if finite and not np.isfinite(a).all():
        idx = tuple(int(i) for i in np.argwhere(~np.isfinite(a))[0])
        raise error(f"{name} must be finite, got {a[idx]} at index {idx}")
    return a


def rotation_error(rotations: np.ndarray) -> np.ndarray:
    """Return how far each matrix is from a proper rotation.

    Parameters
    ----------
    rotations : (..., 3, 3) array_like of float

    Returns
    -------
    error : (...) ndarray of float64
        ``max(max |R^T R - I|, |det R - 1|)`` per matrix; NaN propagates.

    Raises
    ------
    InvalidInputError
        `rotations` not an array of numbers of shape (..., 3, 3).
    """
    return _rotation_error(_as_float_array(rotations, "rotations", "(..., 3, 3)", (3, 3),
                                           finite=False))


def _rotation_error(r: np.ndarray) -> np.ndarray:
    gram = np.einsum("...ji,...jk->...ik", r, r) - np.eye(3)
    ortho = np.abs(gram).max(axis=(-2, -1))
    det = np.abs(np.linalg.det(r) - 1.0)
    return np.maximum(ortho, det)


def check_rotations(rotations: np.ndarray, *, name: str = "rotations") -> None:
    """Raise if any matrix is not a proper rotation.

    Parameters
    ----------
    rotations : (..., 3, 3) ndarray of float64
    name : str
        Argument name used in the error message.

    Raises
    ------
    RecordingError
        Naming the first offending index and its error; or `rotations` not an
        array of numbers of shape (..., 3, 3), naming `name` and the shape.
    """
    from ...errors import RecordingError

    err = _rotation_error(_as_float_array(rotations, name, "(..., 3, 3)", (3, 3), finite=False,
                                          error=RecordingError))
    bad = ~(err <= ROTATION_TOLERANCE)
    if bad.any():
        idx = tuple(int(i) for i in np.argwhere(bad)[0])
        raise RecordingError(
            f"{name}: {int(bad.sum())} matrices are not rotations "
            f"(first at index {idx}: max |R^T R - I| or |det R - 1| = "
            f"{float(err[idx]):.3g} > {ROTATION_TOLERANCE:g})"
        )


def rotvec_to_matrix(rotvec: np.ndarray) -> np.ndarray:
    """Rotation vectors ``(..., 3)`` in radians to matrices ``(..., 3, 3)``.

    Parameters
    ----------
    rotvec : (..., 3) array_like of float
        ``angle * unit_axis``, radians.

    Returns
    -------
    (..., 3, 3) ndarray of float64
        The matrices (:meth:`scipy.spatial.transform.Rotation.from_rotvec`).

    Raises
    ------
    InvalidInputError
        `rotvec` not of shape (..., 3), with a NaN or infinite value, or a
        vector whose length overflows (``1e300``: its matrix would be NaN).
    """
    from ...errors import InvalidInputError

    v = _as_float_array(rotvec, "rotvec", "(..., 3)", (3,))
    with np.errstate(over="ignore"):
        length = np.linalg.norm(v, axis=-1)
    if not np.isfinite(length).all():
        idx = tuple(int(i) for i in np.argwhere(~np.isfinite(length))[0])
        raise InvalidInputError(f"rotvec must have a finite length (radians), got one too long "
                                f"to rotate by at index {idx}: {v[idx].tolist()}")
    return _rotvec_to_matrix(v)


def _rotvec_to_matrix(rotvec: np.ndarray) -> np.ndarray:
    """:func:`rotvec_to_matrix` unchecked, for the package's own finite (..., 3) vectors."""
    v = np.asarray(rotvec, dtype=np.float64)
    flat = Rotation.from_rotvec(v.reshape(-1, 3)).as_matrix()
    return flat.reshape(v.shape[:-1] + (3, 3))


def matrix_to_rotvec(rotations: np.ndarray) -> np.ndarray:
    """Rotation matrices ``(..., 3, 3)`` to rotation vectors ``(..., 3)`` (rad).

    Parameters
    ----------
    rotations : (..., 3, 3) array_like of float
        Not checked to be rotations (see :func:`check_rotations`): scipy's
        :meth:`~scipy.spatial.transform.Rotation.from_matrix` orthogonalises a
        matrix that is not orthogonal.

    Returns
    -------
    (..., 3) ndarray of float64
        ``angle * unit_axis``, radians, angle in [0, pi].

    Raises
    ------
    InvalidInputError
        `rotations` not of shape (..., 3, 3), with a NaN or infinite value, or
        a matrix with a non-positive determinant (a reflection or a singular
        matrix: no rotation is near it), naming the first such index.
    """
    from ...errors import InvalidInputError

    r = _as_float_array(rotations, "rotations", "(..., 3, 3)", (3, 3))
    det = np.linalg.det(r)
    if not (det > 0).all():
        idx = tuple(int(i) for i in np.argwhere(~(det > 0))[0])
        raise InvalidInputError(f"rotations must have a positive determinant, got {float(det[idx]):.3g} "
                                f"at index {idx}")
    return _matrix_to_rotvec(r)


def _matrix_to_rotvec(rotations: np.ndarray) -> np.ndarray:
    """:func:`matrix_to_rotvec` unchecked, for the package's own (..., 3, 3) rotations."""
    r = np.asarray(rotations, dtype=np.float64)
    flat = Rotation.from_matrix(r.reshape(-1, 3, 3)).as_rotvec()
    return flat.reshape(r.shape[:-2] + (3,))


def axis_angle_matrix(axis: np.ndarray, angle: np.ndarray) -> np.ndarray:
    """Rotation about unit `axis` by `angle` (Rodrigues), vectorised.

    Parameters
    ----------
    axis : (..., 3) array_like of float
        Unit axes (normalised here).
    angle : (...) array_like of float
        Angles in radians, broadcast against ``axis[..., 0]``.

    Returns
    -------
    (..., 3, 3) ndarray of float64

    Raises
    ------
    InvalidInputError
        `axis` not of shape (..., 3), a zero axis (no direction to turn
        about) or one whose length overflows, `angle` not numbers, a NaN or
        infinite value in either, or shapes that do not broadcast.
    """
    from ...errors import InvalidInputError

    a = _as_float_array(axis, "axis", "(..., 3)", (3,))
    with np.errstate(over="ignore"):
        norm = np.linalg.norm(a, axis=-1)
    if not (np.isfinite(norm) & (norm > 0)).all():
        idx = tuple(int(i) for i in np.argwhere(~(np.isfinite(norm) & (norm > 0)))[0])
        raise InvalidInputError(f"axis must be nonzero with a finite length, got {a[idx].tolist()} "
                                f"at index {idx}")
    th = _as_float_array(angle, "angle", "(...)", ())
    try:
        np.broadcast_shapes(a.shape, th.shape + (1,))
    except ValueError:
        raise InvalidInputError(f"angle of shape {th.shape} does not broadcast against axis[..., 0] "
                                f"of shape {a.shape[:-1]}") from None
    return _axis_angle_matrix(a, th)


def _axis_angle_matrix(axis: np.ndarray, angle: np.ndarray) -> np.ndarray:
    """:func:`axis_angle_matrix` unchecked, for the package's own nonzero axes."""
    a = np.asarray(axis, dtype=np.float64)
    a = a / np.linalg.norm(a, axis=-1, keepdims=True)
    th = np.asarray(angle, dtype=np.float64)
    a, th = np.broadcast_arrays(a, th[..., None])
    return _rotvec_to_matrix(a * th)
