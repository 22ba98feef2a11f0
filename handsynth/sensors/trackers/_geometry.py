"""Where the two phalanges of a joint are: segment frames and lengths.

The simulation needs, for the joint under test, the pose of the *upper*
(proximal) segment in the hand frame with the finger straight, the axis of the
upper segment's own proximal joint (so that it can move too), the flexion axis
of the joint under test and the lengths of both segments.  These come from
the MuJoCo hand (:class:`handsynth.models.HandModel`) when it is available,
or from a fixed table (``source="table"``) otherwise.

Segment frame (both segments): origin at the segment's proximal joint centre,
``+y`` along the bone toward the fingertip, ``+z`` out of the back of the
finger, ``+x = y x z``.  Positive flexion is a rotation about ``-x``.

Table values: phalanx lengths are the hand model's own constants,
:data:`handsynth.models.SEGMENT_COEFFICIENTS` (Buchholz, Armstrong & Goldstein,
"Anthropometric data for describing the kinematics of the human hand",
*Ergonomics* 35(3):261-273 (1992), Table 1: segment length / hand length)
times :data:`handsynth.models.HAND_LENGTH_MM` (187 mm, about the pooled mean
of Gordon et al. 1989), so that the table and the standard hand share one
source.  MCP positions are rough placements in the hand frame (origin at the
wrist, ``+y`` to the middle-finger MCP, ``+z`` dorsal, ``+x = y x z``) and
matter only for where the sensors sit relative to the transmitter.  The hand
is a right hand, as the model's standard hand
(``handsynth.models.HandModel(side="right")``): seen from the back with the
fingers pointing away, the thumb and the index finger are on the left, at
``-x``, and the little finger at ``+x``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ...errors import InvalidInputError
from ...models import HAND_LENGTH_MM, SEGMENT_COEFFICIENTS

__all__ = ["SUPPORTED_JOINTS", "JointGeometry", "joint_geometry"]

_FINGERS = ("index", "middle", "ring", "little")
_HAND_LENGTH_M = HAND_LENGTH_MM / 1000.0
#: Buchholz et al. (1992) Table 1, as :data:`handsynth.models.SEGMENT_COEFFICIENTS`
#: holds it, without the metacarpals (handled as the palm): phalanx length /
#: hand length, proximal, middle, distal (thumb: proximal, distal).
_BUCHHOLZ: dict[str, tuple[float, ...]] = {
    finger: tuple(coefficients[1:]) for finger, coefficients in SEGMENT_COEFFICIENTS.items()
}
#: Lateral MCP positions of a right hand: the index finger at -x, the little finger at +x
#: (the sides of ``HandModel(side="right").keypoints()``).
_MCP_X_M = {"index": -0.022, "middle": 0.0, "ring": 0.019, "little": 0.036}
_MCP_Y_M = {"index": 0.092, "middle": 0.095, "ring": 0.088, "little": 0.078}

#: Joints that can be simulated: ``<finger>_<joint>``.
SUPPORTED_JOINTS: tuple[str, ...] = tuple(
    f"{f}_{j}" for f in _FINGERS for j in ("pip", "dip")
) + ("thumb_ip",)


@dataclass(frozen=True)
class JointGeometry:
    """Geometry of one joint with the finger straight.

    Attributes
    ----------
    joint : str
        ``"index_dip"`` etc.
    upper, lower : str
        Body names of the proximal and distal segment (``"index_middle"``).
    upper_origin : (3,) ndarray of float64
        Proximal joint centre of the upper segment, hand frame, metres.
    upper_rotation : (3, 3) ndarray of float64
        Upper segment frame to hand frame (see module docstring).
    proximal_axis : (3,) ndarray of float64
        Flexion axis of the upper segment's proximal joint, hand frame, unit.
    upper_length, lower_length : float
        Joint-to-joint (or joint-to-tip) lengths in metres.
    source : str
        ``"model"`` (MuJoCo hand) or ``"table"``.
    """

    joint: str
    upper: str
    lower: str
    upper_origin: np.ndarray
    upper_rotation: np.ndarray
    proximal_axis: np.ndarray
    upper_length: float
    lower_length: float
    source: str


def _split(joint: str) -> tuple[str, str, str, str]:
    if joint not in SUPPORTED_JOINTS:
        raise InvalidInputError(
            f"joint: expected one of {', '.join(SUPPORTED_JOINTS)}, got {joint!r}"
        )
    finger, j = joint.split("_")
    if finger == "thumb":
        return finger, "thumb_proximal", "thumb_distal", "thumb_mcp_flex"
    upper, lower, prox = {
        "pip": ("proximal", "middle", "mcp_flex"),
        "dip": ("middle", "distal", "pip_flex"),
    }[j]
    return finger, f"{finger}_{upper}", f"{finger}_{lower}", f"{finger}_{prox}"


def _table(joint: str) -> JointGeometry:
    finger, upper, lower, _ = _split(joint)
    lengths = np.asarray(_BUCHHOLZ[finger]) * _HAND_LENGTH_M
    if finger == "thumb":
        origin = np.array([-0.045, 0.060, 0.0])  # the thumb on the index side, -x
        i_up = 0
    else:
        i_up = 0 if joint.endswith("pip") else 1
        origin = np.array([_MCP_X_M[finger], _MCP_Y_M[finger], 0.0])
        origin = origin + np.array([0.0, lengths[:i_up].sum(), 0.0])
    return JointGeometry(
        joint=joint,
        upper=upper,
        lower=lower,
        upper_origin=origin,
        upper_rotation=np.eye(3),
        proximal_axis=np.array([-1.0, 0.0, 0.0]),
        upper_length=float(lengths[i_up]),
        lower_length=float(lengths[i_up + 1]),
        source="table",
    )


def _from_model(joint: str, hand) -> JointGeometry:
    finger, upper, lower, prox = _split(joint)
    hand.set_pose(np.zeros(20))
    jname = {"pip": "pip_flex", "dip": "dip_flex", "ip": "ip_flex"}[joint.split("_")[1]]
    centre, flex_axis = hand.joint_axis(f"{finger}_{jname}")
    origin, prox_axis = hand.joint_axis(prox)
    kp = np.asarray(hand.keypoints(), dtype=np.float64)
    fi = ("thumb", "index", "middle", "ring", "little").index(finger)
    chain = kp[1 + 4 * fi : 5 + 4 * fi]  # base .. tip of this finger
    centre = np.asarray(centre, dtype=np.float64)
    origin = np.asarray(origin, dtype=np.float64)
    k = int(np.argmin(np.linalg.norm(chain - centre, axis=1)))
    if k + 1 >= len(chain):
        raise InvalidInputError(f"joint {joint!r}: no distal keypoint in the hand model")
    y = centre - origin
    upper_length = float(np.linalg.norm(y))
    lower_length = float(np.linalg.norm(chain[k + 1] - centre))
    y /= upper_length
    x = -np.asarray(flex_axis, dtype=np.float64)
    x -= y * (x @ y)
    x /= np.linalg.norm(x)
    rot = np.column_stack([x, y, np.cross(x, y)])
    return JointGeometry(
        joint=joint,
        upper=upper,
        lower=lower,
        upper_origin=origin,
        upper_rotation=rot,
        proximal_axis=np.asarray(prox_axis, dtype=np.float64),
        upper_length=upper_length,
        lower_length=lower_length,
        source="model",
    )


def joint_geometry(joint: str, *, source: str = "auto", hand=None) -> JointGeometry:
    """Geometry of `joint` from the MuJoCo hand or the anthropometric table.

    Parameters
    ----------
    joint : str
        One of :data:`SUPPORTED_JOINTS`, e.g. ``"index_dip"``.
    source : {"auto", "model", "table"}
        ``"model"`` uses :class:`handsynth.models.HandModel` (standard shape
        unless `hand` is given); ``"table"`` uses Buchholz et al. (1992) Table 1
        as the model holds it (see the module docstring);
        ``"auto"`` uses the model when it can be imported, else the table.
        The choice made is recorded in :attr:`JointGeometry.source`.
    hand : handsynth.models.HandModel, optional
        A hand of a given shape; implies ``source="model"``.

    Returns
    -------
    JointGeometry
    """
    if source not in ("auto", "model", "table"):
        raise InvalidInputError(
            f"source: expected 'auto', 'model' or 'table', got {source!r}"
        )
    _split(joint)
    if hand is not None:
        return _from_model(joint, hand)
    if source == "table":
        return _table(joint)
    try:
        from ...models import HandModel, HandShape
    except ImportError:
        if source == "model":
            raise InvalidInputError(
                "source='model' but handsynth.models.HandModel is not available"
            ) from None
        return _table(joint)
    return _from_model(joint, HandModel(HandShape()))
