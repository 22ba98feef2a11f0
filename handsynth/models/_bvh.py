"""Joint angles as a BVH motion file: the handsynth hand's skeleton, posed frame by frame.

BVH (Biovision Hierarchy) is the motion format of animation and motion-capture tools.  The
skeleton is the handsynth hand of one shape and side
(:func:`~handsynth.models.hand_spec`):

* the root ``palm`` at the wrist joint centre, in the hand frame (+y toward the middle
  finger's MCP joint, +z out of the back of the hand); its six channels are zero in every
  frame, so the file's frame is the hand frame, unless the hand's place and attitude in
  a world frame are given (``root_position_mm``, ``root_quat``: an IMU recording's);
* one joint per segment (``thumb_metacarpal``, ``thumb_proximal``, ``thumb_distal``,
  ``<finger>_proximal``, ``<finger>_middle``, ``<finger>_distal``) whose ``OFFSET`` is its
  joint centre in its parent's frame, and an ``End Site`` at each fingertip.

Each of those 20 offsets is a bone, named by the point at its end (:data:`BVH_BONES`: the
thumb's CMC, MCP, IP and tip, each finger's MCP, PIP, DIP and tip, as the model's keypoints
are named).  ``bone_lengths_mm`` sets any of them to another hand's length (an IMU
calibration's, :func:`~handsynth.sensors.imu.bone_lengths_mm`), each along the handsynth
hand's own direction.

A segment's rotation is its rest orientation followed by its joints' rotations about their
axes, composed as MuJoCo composes the hand model's (so the joint centres of the file are the
model's keypoints, which a test checks).  It is written as the channels ``Zrotation
Yrotation Xrotation`` (R = Rz Ry Rx, intrinsic, degrees): over every joint's range the
middle angle of this order stays within 49 deg (the thumb's metacarpal), where the other
five orders reach 57-90 deg, so no pose is near gimbal lock.  Each channel is unwrapped
over the frames (no jump of 360 deg between two frames, which animation tools would
interpolate as a turn).
"""

from __future__ import annotations

import io
from pathlib import Path

import numpy as np

from .._checks import check_instance, check_number, check_side
from .._io import atomic_open
from ..errors import InvalidInputError, InvalidPoseError, InvalidShapeError
from ._joints import JOINT_NAMES
from ._mjcf import hand_spec
from ._shape import HandShape

__all__ = ["BVH_BONES", "BVH_BONE_STARTS", "BVH_CHANNELS", "BVH_UNITS", "bvh_text", "write_bvh"]

#: Length units a file may be written in, and the factor from millimetres.
BVH_UNITS: dict[str, float] = {"cm": 0.1, "mm": 1.0, "m": 1e-3}
#: Rotation channels of every joint, in the order written (R = Rz Ry Rx).
BVH_CHANNELS: tuple[str, ...] = ("Zrotation", "Yrotation", "Xrotation")
_ROOT_CHANNELS = ("Xposition", "Yposition", "Zposition", *BVH_CHANNELS)
#: The skeleton's bones, each named by the point at its end (its proximal end is the joint
#: centre before it, the wrist for the thumb's CMC and each finger's MCP), in file order.
BVH_BONES: tuple[str, ...] = (
    "thumb_cmc", "thumb_mcp", "thumb_ip", "thumb_tip",
    *(f"{f}_{p}" for f in ("index", "middle", "ring", "little") for p in ("mcp", "pip", "dip", "tip")),
)
#: Each bone of :data:`BVH_BONES` -> the point it starts at (keypoint names).
BVH_BONE_STARTS: dict[str, str] = {
    bone: "wrist" if bone in ("thumb_cmc", *(f"{f}_mcp" for f in ("index", "middle", "ring", "little")))
    else BVH_BONES[BVH_BONES.index(bone) - 1]
    for bone in BVH_BONES
}
#: Longest bone taken, mm.
_MAX_BONE_MM = 500.0
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
    """(z, y, x) angles, degrees, with R = Rz(z) Ry(y) Rx(x), of (N, 3, 3) rotations, each
    unwrapped over the N frames."""
    import warnings

    from scipy.spatial.transform import Rotation

    with warnings.catch_warnings():  # gimbal lock (a root turned so): one of many triples
        warnings.simplefilter("ignore", UserWarning)
        zyx = Rotation.from_matrix(matrices).as_euler("ZYX", degrees=True)
    return np.unwrap(zyx, period=360.0, axis=0)


def _root_motion(n: int, root_quat, root_position_mm, scale: float) -> np.ndarray:
    """The root's six channels for `n` frames: zero, or the given place and attitude."""
    out = np.zeros((n, 6))
    if root_position_mm is not None:
        p = np.asarray(root_position_mm, dtype=np.float64)
        if p.shape != (n, 3) or not np.isfinite(p).all():
            raise InvalidInputError(f"root_position_mm must be finite, of shape ({n}, 3) (one "
                                    f"place per frame), got shape {p.shape}")
        out[:, :3] = p * scale
    if root_quat is not None:
        q = np.asarray(root_quat, dtype=np.float64)
        norm = np.linalg.norm(q, axis=-1) if q.ndim == 2 else None
        if (q.shape != (n, 4) or norm is None or not np.isfinite(q).all()
                or not (norm > 0.5).all()):
            raise InvalidInputError(f"root_quat must be finite unit quaternions (w, x, y, z) "
                                    f"of shape ({n}, 4), one per frame, got shape {q.shape}")
        from scipy.spatial.transform import Rotation

        turn = Rotation.from_quat(q[:, [1, 2, 3, 0]] / norm[:, None])
        out[:, 3:] = _continuous(_euler_zyx_deg(turn.as_matrix()))
    return out


def _bone_lengths(lengths) -> dict[str, float]:
    """`lengths` as a dict of bone name -> length, mm, refusing unknown bones and bad lengths."""
    if lengths is None:
        return {}
    if not hasattr(lengths, "items"):
        raise InvalidInputError(f"bone_lengths_mm must be a mapping of bone name -> length in mm, "
                                f"got {type(lengths).__name__}")
    out = {}
    for name, value in lengths.items():
        if name not in BVH_BONES:
            raise InvalidInputError(f"bone_lengths_mm: unknown bone {name!r}; bones are "
                                    f"{', '.join(BVH_BONES)}")
        out[name] = check_number(value, f"bone_lengths_mm[{name!r}]", above=0,
                                 maximum=_MAX_BONE_MM)
    return out


def _continuous(zyx: np.ndarray) -> np.ndarray:
    """Each frame's (z, y, x) angles, deg, as the one of the two triples of its rotation,
    (z, y, x) and (z + 180, 180 - y, x + 180), each to within whole turns, nearest the frame
    before's: a root that turns freely passes y = +-90 deg, where the triple of the range
    [-90, 90] jumps by 180 deg in z and x."""
    out = np.array(zyx, dtype=np.float64)
    for i in range(1, len(out)):
        prev = out[i - 1]
        best = None
        z, y, x = out[i]
        for cand in (np.array([z, y, x]), np.array([z + 180.0, 180.0 - y, x + 180.0])):
            near = cand + 360.0 * np.round((prev - cand) / 360.0)
            if best is None or np.abs(near - prev).sum() < np.abs(best - prev).sum():
                best = near
        out[i] = best
    return out


def bvh_text(angles, *, rate_hz: float, shape: HandShape | None = None, side: str = "right",
             units: str = "cm", root_quat=None, root_position_mm=None,
             bone_lengths_mm=None) -> str:
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
    root_quat : array_like, shape (N, 4), keyword-only, optional
        The hand frame's attitude in a world frame in each frame (hand-to-world unit
        quaternions, w, x, y, z); the root's rotation channels.  Zero by default.
    root_position_mm : array_like, shape (N, 3), keyword-only, optional
        The wrist joint centre's place in that world frame, mm; the root's position
        channels.  Zero by default.
    bone_lengths_mm : mapping of str to float, keyword-only, optional
        Lengths of any of the bones (:data:`BVH_BONES`), mm, each along the direction the
        handsynth hand of `shape` gives it; the others keep that hand's.

    Returns
    -------
    str

    Raises
    ------
    InvalidPoseError
        Angles of another shape, or not finite (naming the row and the joint).
    InvalidInputError
        `rate_hz` not a positive finite number up to 100 kHz, `units` or `side` unknown,
        `root_quat` or `root_position_mm` of another shape or not finite; a bone of
        `bone_lengths_mm` unknown, or its length not a finite number in (0, 500] mm.
    InvalidShapeError
        `shape` not a HandShape.
    """
    a = _angles(angles)
    lengths = _bone_lengths(bone_lengths_mm)
    rate = check_number(rate_hz, "rate_hz", above=0, maximum=_MAX_RATE_HZ)
    if units not in BVH_UNITS:
        raise InvalidInputError(f"units must be one of {', '.join(BVH_UNITS)}, got {units!r}")
    shape = HandShape() if shape is None else shape
    check_instance(shape, HandShape, name="shape", error=InvalidShapeError)
    check_side(side)
    spec = hand_spec(shape, side=side)
    scale = BVH_UNITS[units]
    out = io.StringIO()
    out.write("HIERARCHY\n")

    def offset(p_mm, bone: str) -> str:
        v = np.asarray(p_mm, float)
        if bone in lengths:
            v = v * (lengths[bone] / np.linalg.norm(v))
        return " ".join(f"{x:.6f}" for x in v * scale + 0.0)

    def emit(body, depth: int) -> None:
        ind = "\t" * depth
        if body is spec.root:
            out.write(f"ROOT {body.name}\n{{\n\tOFFSET 0.000000 0.000000 0.000000\n"
                      f"\tCHANNELS 6 {' '.join(_ROOT_CHANNELS)}\n")
        else:
            bone = offset(body.pos_mm, body.sites[0][0])
            out.write(f"{ind}JOINT {body.name}\n{ind}{{\n{ind}\tOFFSET {bone}\n"
                      f"{ind}\tCHANNELS 3 {' '.join(BVH_CHANNELS)}\n")
        for child in body.children:
            emit(child, depth + 1)
        if not body.children:  # the fingertip: the body's last site
            name, tip = body.sites[-1]
            out.write(f"{ind}\tEnd Site\n{ind}\t{{\n{ind}\t\tOFFSET {offset(tip, name)}\n"
                      f"{ind}\t}}\n")
        out.write(f"{ind}}}\n")

    emit(spec.root, 0)
    bodies = _segments(spec.root)
    columns = [_root_motion(len(a), root_quat, root_position_mm, scale)]
    columns += [_euler_zyx_deg(_local_rotations(b, a)) for b in bodies[1:]]
    motion = np.round(np.hstack(columns), 6) + 0.0  # + 0.0: no "-0.000000"
    out.write(f"MOTION\nFrames: {len(a)}\nFrame Time: {1.0 / rate:.9f}\n")
    np.savetxt(out, motion, fmt="%.6f", delimiter=" ")
    return out.getvalue()


def write_bvh(path, angles, *, rate_hz: float, shape: HandShape | None = None,
              side: str = "right", units: str = "cm", root_quat=None, root_position_mm=None,
              bone_lengths_mm=None, inputs=()) -> Path:
    """Write joint angles as a BVH file on the handsynth hand, complete or not at all.

    Parameters
    ----------
    path : str or os.PathLike
        The ``.bvh`` file; it appears only when written whole.
    angles, rate_hz, shape, side, units, root_quat, root_position_mm, bone_lengths_mm
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
    text = bvh_text(angles, rate_hz=rate_hz, shape=shape, side=side, units=units,
                    root_quat=root_quat, root_position_mm=root_position_mm,
                    bone_lengths_mm=bone_lengths_mm)
    with atomic_open(Path(path), "w", what="BVH file", inputs=inputs, newline="\n") as f:
        f.write(text)
    return Path(path)
