"""MJCF generation for the parametric hand (hand and scene in separate documents).

The model follows MuJoCo Menagerie conventions: nested default classes per
segment, one naming pattern (``<finger>_<segment>`` for bodies, the canonical
joint names of :data:`JOINT_NAMES` for joints, ``<finger>_<joint>`` for
joint-centre sites), keyframes for the standard poses, and the hand in one
document that the scene includes.

Naming
------
bodies
    ``forearm``, ``palm``, ``thumb_metacarpal``, ``thumb_proximal``,
    ``thumb_distal``, ``<f>_proximal``, ``<f>_middle``, ``<f>_distal``.
sites (the 21 keypoints)
    ``wrist``, ``thumb_cmc``, ``thumb_mcp``, ``thumb_ip``, ``thumb_tip``,
    ``<f>_mcp``, ``<f>_pip``, ``<f>_dip``, ``<f>_tip``.
geom groups
    1 hand, 2 forearm stub.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .._checks import check_instance, check_side
from ._anthropometry import (
    DEPTH_TO_BREADTH,
    FINGER_BREADTH_MM,
    HAND_BREADTH_MM,
    HAND_LENGTH_MM,
    PALM_THICKNESS_MM,
    SEGMENT_COEFFICIENTS,
    standard_layout_mm,
)
from ._geometry import forearm_vertices, palm_vertices, phalanx_vertices
from ._joints import FINGERS, JOINT_LIMITS_DEG, JOINT_NAMES
from ._pose import NAMED_POSES
from ._shape import HandShape

__all__ = ["KEYPOINT_SITES", "SEGMENT_BODIES", "HandSpec", "hand_mjcf", "hand_spec"]

#: Sites of the 21 keypoints in output order: wrist, then base to tip per
#: finger, thumb first.
KEYPOINT_SITES: tuple[str, ...] = (
    "wrist",
    "thumb_cmc", "thumb_mcp", "thumb_ip", "thumb_tip",
    *(f"{f}_{j}" for f in FINGERS[1:] for j in ("mcp", "pip", "dip", "tip")),
)

SEGMENT_BODIES: dict[str, tuple[str, ...]] = {
    "thumb": ("thumb_metacarpal", "thumb_proximal", "thumb_distal"),
    **{f: (f"{f}_proximal", f"{f}_middle", f"{f}_distal") for f in FINGERS[1:]},
}

# Rest orientation of the thumb metacarpal (right hand): turned 40 deg from
# the hand axis toward the radial side, 12 deg below the palm plane and
# pronated 50 deg about its own axis, the relaxed open-hand posture
# (Kapandji 2007, "the hand": the thumb column lies about 40 deg from the
# index in the palm plane at rest).
THUMB_YAW_DEG = 40.0
THUMB_PITCH_DEG = 12.0
_THUMB_PRONATION_DEG = -50.0
_FOREARM_LENGTH_MM = 90.0
_MIRROR = np.diag([-1.0, 1.0, 1.0])


def _rot(axis: str, deg: float) -> np.ndarray:
    c, s = np.cos(np.radians(deg)), np.sin(np.radians(deg))
    i = "xyz".index(axis)
    j, k = (i + 1) % 3, (i + 2) % 3  # cyclic, so that the rotation is right-handed
    r = np.eye(3)
    r[j, j], r[j, k], r[k, j], r[k, k] = c, -s, s, c
    return r


@dataclass
class _Body:
    name: str
    pos_mm: np.ndarray                      # in parent frame
    rot: np.ndarray                         # rest orientation in parent frame
    mesh: np.ndarray                        # vertices, mm, body frame
    cls: str                                # default class of the segment
    joints: list[tuple[str, np.ndarray]] = field(default_factory=list)  # (name, axis in body frame)
    sites: list[tuple[str, np.ndarray]] = field(default_factory=list)
    children: list[_Body] = field(default_factory=list)


@dataclass(frozen=True)
class HandSpec:
    """Everything the MJCF is made from, for one shape and side.

    Attributes
    ----------
    shape : HandShape
    side : {"right", "left"}
    root : _Body
        The palm body with the whole tree below it.
    forearm : ndarray, shape (M, 3)
        Forearm stub vertices, mm.
    """

    shape: HandShape
    side: str
    root: _Body
    forearm: np.ndarray


def hand_spec(shape: HandShape, *, side: str = "right") -> HandSpec:
    """Build the segment tree of a hand of `shape` (see :class:`HandShape`).

    Parameters
    ----------
    shape : HandShape
        Scale factors of the standard hand.
    side : {"right", "left"}, keyword-only
        The left hand is the right one mirrored in the y-z plane (x -> -x),
        joint senses kept.

    Returns
    -------
    HandSpec
        Positions, meshes and the forearm stub in mm.

    Raises
    ------
    InvalidShapeError
        `shape` not a :class:`HandShape`, or `side` neither ``"right"`` nor
        ``"left"``.
    """
    from ..errors import InvalidShapeError

    check_instance(shape, HandShape, name="shape", error=InvalidShapeError)
    check_side(side, error=InvalidShapeError)
    lay = standard_layout_mm()
    hl = HAND_LENGTH_MM
    flex_axis = np.array([-1.0, 0.0, 0.0])  # +angle turns +y toward -z (palm)
    abd_axis = np.array([0.0, 0.0, 1.0])    # +angle turns +y toward -x (thumb side)

    mcp_scaled = {f: c * np.array([shape.palm, 1.0, 1.0]) for f, c in lay.mcp.items()}
    palm = _Body(
        "palm", np.zeros(3), np.eye(3),
        palm_vertices(lay.mcp, {f: FINGER_BREADTH_MM[f][0] * 1.05 for f in lay.mcp},
                      thickness_mm=PALM_THICKNESS_MM, wrist_halfwidth_mm=0.31 * HAND_BREADTH_MM,
                      x_scale=shape.palm),
        "palm", sites=[("wrist", np.zeros(3))],
    )

    def chain(base_pos: np.ndarray, base_rot: np.ndarray, lengths: list[float],
              breadths: list[float], joint_names: list[list[str]],
              axes: list[list[np.ndarray]], site_names: list[str], bodies: tuple[str, ...],
              classes: list[str]) -> None:
        """Append a digit of ``len(bodies)`` segments to the palm, base first."""
        parent = palm
        for k, body_name in enumerate(bodies):
            tip = k == len(bodies) - 1
            b = _Body(
                body_name,
                base_pos if k == 0 else np.array([0.0, lengths[k - 1], 0.0]),
                base_rot if k == 0 else np.eye(3),
                phalanx_vertices(lengths[k], breadths[k], breadths[k + 1],
                                 depth_ratio=DEPTH_TO_BREADTH, tip=tip),
                classes[k],
                joints=list(zip(joint_names[k], axes[k])),
                sites=[(site_names[k], np.zeros(3))],
            )
            if tip:
                b.sites.append((site_names[k + 1], np.array([0.0, lengths[k], 0.0])))
            parent.children.append(b)
            parent = b

    for f in FINGERS[1:]:
        c = SEGMENT_COEFFICIENTS[f]
        lengths = [hl * ci * shape.length for ci in c[1:]]
        b_prox, b_dist = (b * shape.width for b in FINGER_BREADTH_MM[f])
        breadths = [1.05 * b_prox, b_prox, b_dist, 0.85 * b_dist]
        chain(
            mcp_scaled[f], _rot("z", lay.finger_yaw_deg[f]), lengths, breadths,
            [[f"{f}_mcp_abd", f"{f}_mcp_flex"], [f"{f}_pip_flex"], [f"{f}_dip_flex"]],
            [[abd_axis, flex_axis], [flex_axis], [flex_axis]],
            [f"{f}_mcp", f"{f}_pip", f"{f}_dip", f"{f}_tip"],
            SEGMENT_BODIES[f], ["proximal", "middle", "distal"],
        )

    # thumb: metacarpal (CMC, 2 DOF), proximal (MCP), distal (IP)
    c = SEGMENT_COEFFICIENTS["thumb"]
    cmc = lay.thumb_cmc * np.array([shape.palm, shape.thumb, 1.0])
    rest = _rot("z", THUMB_YAW_DEG) @ _rot("x", -THUMB_PITCH_DEG) @ _rot("y", _THUMB_PRONATION_DEG)
    d = rest[:, 1]
    cmc_flex = np.array([0.0, 0.0, -1.0])          # across the palm toward the little finger
    cmc_abd = np.cross(d, [0.0, 0.0, -1.0])        # away from the palm plane, palmar
    cmc_abd /= np.linalg.norm(cmc_abd)
    b_mcp, b_ip = (b * shape.width for b in FINGER_BREADTH_MM["thumb"])
    lengths = [hl * c[0], hl * c[1] * shape.length, hl * c[2] * shape.length]
    chain(
        cmc, rest, lengths, [1.25 * b_mcp, b_mcp, b_ip, 0.85 * b_ip],
        [["thumb_cmc_flex", "thumb_cmc_abd"], ["thumb_mcp_flex"], ["thumb_ip_flex"]],
        [[rest.T @ cmc_flex, rest.T @ cmc_abd], [flex_axis], [flex_axis]],
        ["thumb_cmc", "thumb_mcp", "thumb_ip", "thumb_tip"],
        SEGMENT_BODIES["thumb"], ["thumb_metacarpal", "proximal", "distal"],
    )
    forearm = forearm_vertices(length_mm=_FOREARM_LENGTH_MM, halfwidth_mm=0.33 * HAND_BREADTH_MM,
                               halfdepth_mm=0.45 * PALM_THICKNESS_MM)
    spec = HandSpec(shape, side, palm, forearm)
    if side == "left":
        _mirror(palm)
        spec = HandSpec(shape, side, palm, forearm @ _MIRROR)
    return spec


def _mirror(body: _Body) -> None:
    """Reflect a body tree in the y-z plane (x -> -x), keeping joint senses.

    Positions and vertices map by M = diag(-1, 1, 1), rotations by M R M, and
    joint axes, being pseudovectors, by -M a so that a positive angle is the
    same anatomical motion on both hands.
    """
    body.pos_mm = _MIRROR @ body.pos_mm
    body.rot = _MIRROR @ body.rot @ _MIRROR
    body.mesh = body.mesh @ _MIRROR
    body.joints = [(n, -(_MIRROR @ a)) for n, a in body.joints]
    body.sites = [(n, _MIRROR @ p) for n, p in body.sites]
    for ch in body.children:
        _mirror(ch)


def _fmt(values, scale: float = 1.0, *, digits: int = 9) -> str:
    # Round-off below 1e-12 (e.g. 3e-18 from a rotation on another numpy
    # build) is written as 0 so the committed MJCF is the same on every
    # machine; ``+ 0.0`` turns -0.0 into 0.
    v = np.ravel(values) * scale
    v = np.where(np.abs(v) < 1e-12, 0.0, v) + 0.0
    return " ".join(f"{x:.{digits}g}" for x in v)


def _quat(rot: np.ndarray) -> str:
    import mujoco

    q = np.empty(4)
    mujoco.mju_mat2Quat(q, np.ascontiguousarray(rot, dtype=np.float64).ravel())
    return _fmt(q)


def hand_mjcf(shape: HandShape | None = None, *, side: str = "right",
              forearm: bool = True, silhouette: bool = False) -> str:
    """MJCF document of the hand alone (no lights, no camera).

    Parameters
    ----------
    shape : HandShape, optional
        Hand shape; the standard hand by default.
    side : {"right", "left"}, keyword-only
        The left hand is the mirror image (x -> -x) of the right.
    forearm : bool, keyword-only
        Include the distal forearm stub (geom group 2) that the device camera
        sees behind the wrist.
    silhouette : bool, keyword-only
        Use a flat, unlit white material (for mask rendering).

    Returns
    -------
    str
        A complete ``<mujoco>`` document, lengths in metres, angles in degrees.
    """
    spec = hand_spec(HandShape() if shape is None else shape, side=side)
    lim = {n: JOINT_LIMITS_DEG[i] for i, n in enumerate(JOINT_NAMES)}
    meshes: list[str] = []
    lines: list[str] = []

    def emit(b: _Body, depth: int) -> None:
        ind = "  " * depth
        attrs = f'name="{b.name}"'
        if b is not spec.root:
            attrs += f' pos="{_fmt(b.pos_mm, 1e-3)}"'
        if not np.allclose(b.rot, np.eye(3)):
            attrs += f' quat="{_quat(b.rot)}"'
        cls = "" if b.name == "palm" else f' childclass="{b.cls}"'
        lines.append(f"{ind}<body {attrs}{cls}>")
        for jn, axis in b.joints:
            lo, hi = lim[jn]
            lines.append(f'{ind}  <joint name="{jn}" axis="{_fmt(axis)}" range="{lo:g} {hi:g}"/>')
        meshes.append(f'    <mesh name="{b.name}" vertex="{_fmt(b.mesh, 1e-3)}"/>')
        lines.append(f'{ind}  <geom name="{b.name}" mesh="{b.name}"/>')
        for sn, p in b.sites:
            lines.append(f'{ind}  <site name="{sn}" pos="{_fmt(p, 1e-3)}"/>')
        for ch in b.children:
            emit(ch, depth + 1)
        lines.append(f"{ind}</body>")

    emit(spec.root, 2)
    if forearm:
        meshes.append(f'    <mesh name="forearm" vertex="{_fmt(spec.forearm, 1e-3)}"/>')
        lines.insert(0, '    <body name="forearm" childclass="hand"><geom class="forearm" '
                        'name="forearm" mesh="forearm"/></body>')
    order = [JOINT_NAMES.index(n) for n in _joint_order(spec.root)]
    keys = "\n".join(
        f'    <key name="{n}" qpos="{_fmt(np.radians(p[order]), digits=12)}"/>'
        for n, p in NAMED_POSES.items()
    )
    skin = ('rgba="1 1 1 1" emission="1" specular="0" shininess="0"' if silhouette
            else 'rgba="0.87 0.70 0.60 1" specular="0.15" shininess="0.3"')
    return f"""<mujoco model="handsynth_{side}_hand">
  <!-- Generated by handsynth.models.hand_mjcf for {spec.shape.name}; do not edit. -->
  <compiler angle="degree" autolimits="true"/>
  <default>
    <default class="hand">
      <geom type="mesh" material="skin" contype="0" conaffinity="0" group="1"/>
      <joint type="hinge" damping="0.05" armature="0.001"/>
      <site size="0.002" rgba="0.9 0.1 0.1 1" group="4"/>
      <default class="palm"/>
      <default class="forearm"><geom group="2"/></default>
      <default class="thumb_metacarpal"/>
      <default class="proximal"/>
      <default class="middle"/>
      <default class="distal"/>
    </default>
  </default>
  <asset>
    <material name="skin" {skin}/>
{chr(10).join(meshes)}
  </asset>
  <worldbody>
{lines[0] if forearm else ""}
    <frame childclass="hand">
{chr(10).join(lines[1:] if forearm else lines)}
    </frame>
  </worldbody>
  <keyframe>
{keys}
  </keyframe>
</mujoco>
"""


def _joint_order(root: _Body) -> tuple[str, ...]:
    """Joint names of a segment tree in MuJoCo's qpos order (bodies depth-first)."""
    out: list[str] = [n for n, _ in root.joints]
    for ch in root.children:
        out.extend(_joint_order(ch))
    return tuple(out)
