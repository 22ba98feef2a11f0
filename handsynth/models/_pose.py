"""Validation of joint angles and the named standard poses."""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from ..errors import InvalidPoseError
from ._joints import JOINT_LIMITS_DEG, JOINT_NAMES, joint_index

__all__ = ["NAMED_POSES", "as_angles", "named_pose"]

#: Tolerance on joint limits, degrees: angles this far outside are clipped
#: silently (float round-off from conversions), farther is an error.
_LIMIT_TOL_DEG = 1e-6


def as_angles(angles, *, argname: str = "angles", check_limits: bool = True) -> np.ndarray:
    """Validate joint angles and return them as float64 degrees.

    Parameters
    ----------
    angles : array_like, shape (20,) or (N, 20), or mapping of str to float
        Joint angles in degrees in canonical order (:data:`JOINT_NAMES`), or a
        mapping from joint names to degrees; joints missing from a mapping
        are 0 (the open hand).
    argname : str, keyword-only
        Name used for `angles` in error messages.
    check_limits : bool, keyword-only
        Refuse angles outside :data:`JOINT_LIMITS_DEG`.

    Returns
    -------
    ndarray, shape (20,) or (N, 20), float64
        A new array.

    Raises
    ------
    InvalidPoseError
        For an unknown joint name, a wrong shape, a NaN or infinite value, or
        an angle outside its joint's limits; the message names the joint and
        the value.
    """
    if isinstance(angles, Mapping):
        out = np.zeros(len(JOINT_NAMES))
        for name, value in angles.items():
            out[joint_index(name)] = _scalar(value, f"{argname}[{name!r}]")
        arr = out
    else:
        if np.iscomplexobj(angles):  # the conversion would drop the imaginary parts
            raise InvalidPoseError(f"{argname} must be real joint angles, got complex values")
        try:
            arr = np.array(angles, dtype=np.float64)
        except (TypeError, ValueError) as exc:
            raise InvalidPoseError(f"{argname} must be numeric joint angles: {exc}") from None
        if arr.ndim not in (1, 2) or arr.shape[-1] != len(JOINT_NAMES):
            raise InvalidPoseError(
                f"{argname} must have shape (20,) or (N, 20) in canonical joint order, "
                f"got shape {arr.shape}"
            )
    bad = ~np.isfinite(arr)
    if bad.any():
        idx = np.argwhere(bad)[0]
        raise InvalidPoseError(
            f"{argname}: {JOINT_NAMES[idx[-1]]} is {arr[tuple(idx)]!r}"
            + (f" in row {idx[0]}" if arr.ndim == 2 else "")
        )
    if check_limits:
        lo, hi = JOINT_LIMITS_DEG[:, 0], JOINT_LIMITS_DEG[:, 1]
        out_of = (arr < lo - _LIMIT_TOL_DEG) | (arr > hi + _LIMIT_TOL_DEG)
        if out_of.any():
            idx = np.argwhere(out_of)[0]
            j = idx[-1]
            raise InvalidPoseError(
                f"{argname}: {JOINT_NAMES[j]}={arr[tuple(idx)]:g} deg is outside its "
                f"limits [{lo[j]:g}, {hi[j]:g}]"
                + (f" in row {idx[0]}" if arr.ndim == 2 else "")
            )
        np.clip(arr, lo, hi, out=arr)
    return arr


def _scalar(value, name: str) -> float:
    try:
        return float(value)
    except (TypeError, ValueError):
        raise InvalidPoseError(f"{name} must be a number of degrees, got {value!r}") from None


def _pose(thumb, index, middle, ring, little) -> np.ndarray:
    return np.array([*thumb, *index, *middle, *ring, *little], dtype=np.float64)


#: Standard poses in degrees, canonical order.  They are also the keyframes
#: of the MJCF model.  ``pinch`` brings the thumb and index fingertips
#: together on the standard hand (within 5 mm, checked by a test).
NAMED_POSES: dict[str, np.ndarray] = {
    "open": np.zeros(len(JOINT_NAMES)),
    "spread": _pose((-15, 35, 0, 0), (0, 15, 0, 0), (0, 3, 0, 0), (0, -10, 0, 0), (0, -20, 0, 0)),
    "fist": _pose((35, 35, 40, 35), (85, 0, 95, 60), (85, 0, 95, 60), (85, 0, 95, 60), (85, 0, 95, 60)),
    "point": _pose((35, 35, 40, 35), (0, 0, 0, 0), (85, 0, 95, 60), (85, 0, 95, 60), (85, 0, 95, 60)),
    "pinch": _pose((36, 24, 4, 9), (46, 0, 41, 27), (15, 0, 20, 13), (15, 0, 20, 13), (15, 0, 20, 13)),
    "grasp": _pose((20, 50, 15, 15), (45, 0, 50, 33), (45, 0, 50, 33), (45, 0, 50, 33), (45, 0, 50, 33)),
}
for _p in NAMED_POSES.values():
    _p.setflags(write=False)


def named_pose(name: str) -> np.ndarray:
    """Return a copy of the named standard pose (degrees, canonical order).

    Parameters
    ----------
    name : str
        A key of :data:`NAMED_POSES` (``"open"``, ``"spread"``, ``"fist"``,
        ``"point"``, ``"pinch"``, ``"grasp"``).

    Returns
    -------
    ndarray, shape (20,), float64
        Degrees, canonical order; a writable copy.

    Raises
    ------
    InvalidPoseError
        If `name` is not one of :data:`NAMED_POSES`.
    """
    try:
        return NAMED_POSES[name].copy()
    except KeyError:
        raise InvalidPoseError(
            f"unknown pose name {name!r}; expected one of {', '.join(NAMED_POSES)}"
        ) from None
