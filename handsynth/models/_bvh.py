"""Joint angles as a BVH motion file: the handsynth hand's skeleton, posed frame by frame.

BVH (Biovision Hierarchy) is the motion format animation and motion-capture tools read
(Blender's importer among them).  The skeleton is the handsynth hand of one shape and side
(:func:`~handsynth.models.hand_spec`):

* the root ``palm`` at the wrist joint centre, in the hand frame (+y toward the middle
  finger's MCP joint, +z out of the back of the hand); its six channels are zero in every
  frame, so the file's frame is the hand frame;
* one joint per segment (``thumb_metacarpal``, ``thumb_proximal``, ``thumb_distal``,
  ``<finger>_proximal``, ``<finger>_middle``, ``<finger>_distal``) whose ``OFFSET`` is its
  joint centre in its parent's frame, and an ``End Site`` at each fingertip.

A segment's rotation is its rest orientation followed by its joints' rotations about their
axes, composed as MuJoCo composes the hand model's (so the joint centres of the file are the
model's keypoints, which a test checks).  It is written as the channels ``Zrotation
Yrotation Xrotation`` (R = Rz Ry Rx, intrinsic, degrees): over every joint's range the
middle angle of this order stays within 49 deg (the thumb's metacarpal), where the other
five orders reach 57-90 deg, so no pose is near gimbal lock.
"""

from __future__ import annotations

import io
from pathlib import Path

import numpy as np

from .._checks import check_instance, check_number, check_side
from .._io import atomic_open
from ..errors import InvalidInputError, InvalidPoseError
from ._joints import JOINT_NAMES
from ._mjcf import hand_spec
from ._shape import HandShape

__all__ = ["BVH_CHANNELS", "BVH_UNITS", "bvh_text", "write_bvh"]

#: Length units a file may be written in, and the factor from millimetres.
BVH_UNITS: dict[str, float] = {"cm": 0.1, "mm": 1.0, "m": 1e-3}
#: Rotation channels of every joint, in the order written (R = Rz Ry Rx).
BVH_CHANNELS: tuple[str, ...] = ("Zrotation", "Yrotation", "Xrotation")
_ROOT_CHANNELS = ("Xposition", "Yposition", "Zposition", *BVH_CHANNELS)
#: Highest frame rate taken, Hz.
_MAX_RATE_HZ = 100_000.0


def _segments(root) -> list:
    """The bodies of a hand spec's tree, depth first (the order of the file's channels)."""
    out = [root]
    for child in root.children:
        out.extend(_segments(child))
    return out


def _angles(angles) -> np.ndarray:
    """`angles` as a finite (N, 20) float64 array, degrees, refusing anything else."""
    a = np.asarray(angles, dtype=np.float64)
    if a.ndim == 1:
        a = a[None, :]
    if a.ndim != 2 or a.shape[1] != len(JOINT_NAMES) or len(a) == 0:
        raise InvalidPoseError(f"angles must have shape (N, {len(JOINT_NAMES)}) with N >= 1 "
                               f"(degrees, canonical joint order), got shape {a.shape}")
    bad = ~np.isfinite(a)
    if bad.any():
        row, col = np.argwhere(bad)[0]
        raise InvalidPoseError(f"angles must be finite: row {row}, {JOINT_NAMES[col]} is "
                               f"{float(a[row, col])!r} ({int(bad.any(axis=1).sum())} row(s) with "
                               "values that are not numbers)")
    return a


def _local_rotations(body, angles_deg: np.ndarray) -> np.ndarray:
    """Rotation of `body` in its parent's frame for each frame, shape (N, 3, 3).

    The rest orientation, then each joint's rotation about its axis (body frame) in the
    order the body lists them, each about the frame the previous ones left, as MuJoCo
    composes a body's joints.
    """
    from scipy.spatial.transform import Rotation

    n = len(angles_deg)
    r = Rotation.from_matrix(np.broadcast_to(body.rot, (n, 3, 3)))
    for name, axis in body.joints:
        unit = np.asarray(axis, float) / np.linalg.norm(axis)
        q = np.radians(angles_deg[:, JOINT_NAMES.index(name)])
        r = r * Rotation.from_rotvec(unit[None, :] * q[:, None])
    return r.as_matrix()


def _euler_zyx_deg(matrices: np.ndarray) -> np.ndarray:
    """(z, y, x) angles, degrees, with R = Rz(z) Ry(y) Rx(x), of (N, 3, 3) rotations."""
    # closed form (no gimbal lock within the hand's ranges, module docstring)
    y = np.arcsin(np.clip(-matrices[:, 2, 0], -1.0, 1.0))
    z = np.arctan2(matrices[:, 1, 0], matrices[:, 0, 0])
    x = np.arctan2(matrices[:, 2, 1], matrices[:, 2, 2])
    return np.degrees(np.column_stack([z, y, x]))


def bvh_text(angles, *, rate_hz: float, shape: HandShape | None = None, side: str = "right",
             units: str = "cm") -> str:
    """The BVH text of joint angles on the handsynth hand (module docstring).

    Parameters
    ----------
    angles : array_like, shape (N, 20) or (20,)
        Joint angles, degrees, canonical order (:data:`~handsynth.models.JOINT_NAMES`), one
        row per frame at `rate_hz`.
    rate_hz : float, keyword-only
        Frames per second (the file's ``Frame Time`` is its inverse).
    shape : HandShape, keyword-only, optional
        The hand whose skeleton carries the angles (the standard hand by default).
    side : {"right", "left"}, keyword-only
    units : {"cm", "mm", "m"}, keyword-only
        Unit of the offsets (centimetres by default, as most motion files are written).

    Returns
    -------
    str

    Raises
    ------
    InvalidPoseError
        Angles of another shape, or not finite (naming the row and the joint).
    InvalidInputError
        `rate_hz` not a positive finite number up to 100 kHz, `units` or `side` unknown.
    InvalidShapeError
        `shape` not a HandShape.
    """
    a = _angles(angles)
    rate = check_number(rate_hz, "rate_hz", above=0, maximum=_MAX_RATE_HZ)
    if units not in BVH_UNITS:
        raise InvalidInputError(f"units must be one of {', '.join(BVH_UNITS)}, got {units!r}")
    shape = HandShape() if shape is None else shape
    from ..errors import InvalidShapeError

    check_instance(shape, HandShape, name="shape", error=InvalidShapeError)
    check_side(side)
    spec = hand_spec(shape, side=side)
    scale = BVH_UNITS[units]
    out = io.StringIO()
    out.write("HIERARCHY\n")

    def offset(p_mm) -> str:
        v = np.asarray(p_mm, float) * scale + 0.0
        return " ".join(f"{x:.6f}" for x in v)

    def emit(body, depth: int) -> None:
        ind = "\t" * depth
        if body is spec.root:
            out.write(f"ROOT {body.name}\n{{\n\tOFFSET 0.000000 0.000000 0.000000\n"
                      f"\tCHANNELS 6 {' '.join(_ROOT_CHANNELS)}\n")
        else:
            out.write(f"{ind}JOINT {body.name}\n{ind}{{\n{ind}\tOFFSET {offset(body.pos_mm)}\n"
                      f"{ind}\tCHANNELS 3 {' '.join(BVH_CHANNELS)}\n")
        for child in body.children:
            emit(child, depth + 1)
        if not body.children:  # the fingertip: the body's last site
            tip = body.sites[-1][1]
            out.write(f"{ind}\tEnd Site\n{ind}\t{{\n{ind}\t\tOFFSET {offset(tip)}\n{ind}\t}}\n")
        out.write(f"{ind}}}\n")

    emit(spec.root, 0)
    bodies = _segments(spec.root)
    columns = [np.zeros((len(a), 6))]
    columns += [_euler_zyx_deg(_local_rotations(b, a)) for b in bodies[1:]]
    motion = np.round(np.hstack(columns), 6) + 0.0  # + 0.0: no "-0.000000"
    out.write(f"MOTION\nFrames: {len(a)}\nFrame Time: {1.0 / rate:.9f}\n")
    np.savetxt(out, motion, fmt="%.6f", delimiter=" ")
    return out.getvalue()


def write_bvh(path, angles, *, rate_hz: float, shape: HandShape | None = None,
              side: str = "right", units: str = "cm", inputs=()) -> Path:
    """Write joint angles as a BVH file on the handsynth hand, complete or not at all.

    Parameters
    ----------
    path : str or os.PathLike
        The ``.bvh`` file; it appears only when written whole.
    angles, rate_hz, shape, side, units
        As :func:`bvh_text`'s.
    inputs : iterable of path, keyword-only
        Files the angles were read from: `path` may not be one of them.

    Returns
    -------
    Path

    Raises
    ------
    InvalidPoseError, InvalidInputError, InvalidShapeError
        As :func:`bvh_text`.
    OutputError
        `path` cannot be written (naming it and why), or is one of `inputs`.
    """
    text = bvh_text(angles, rate_hz=rate_hz, shape=shape, side=side, units=units)
    with atomic_open(Path(path), "w", what="BVH file", inputs=inputs, newline="\n") as f:
        f.write(text)
    return Path(path)
