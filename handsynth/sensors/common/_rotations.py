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


def rotation_error(rotations: np.ndarray) -> np.ndarray:
    """Return how far each matrix is from a proper rotation.

    Parameters
    ----------
    rotations : (..., 3, 3) array_like of float

    Returns
    -------
    error : (...) ndarray of float64
        ``max(max |R^T R - I|, |det R - 1|)`` per matrix; NaN propagates.
    """
    r = np.asarray(rotations, dtype=np.float64)
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
        Naming the first offending index and its error.
    """
    from ...errors import RecordingError

    err = rotation_error(rotations)
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
    """
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
    ValueError
        (scipy's) a matrix with a non-positive determinant.
    """
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
    """
    a = np.asarray(axis, dtype=np.float64)
    a = a / np.linalg.norm(a, axis=-1, keepdims=True)
    th = np.asarray(angle, dtype=np.float64)
    a, th = np.broadcast_arrays(a, th[..., None])
    return rotvec_to_matrix(a * th)
