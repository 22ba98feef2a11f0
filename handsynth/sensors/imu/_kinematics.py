"""Link frames, joint angles, fingertip positions and grasp classes (seed 003 ch. 5).

Link frame (eqs. 5.1-5.2): x along the flexion-extension axis of the link's
proximal joint, taken from the sensor's own gyro during that joint's
calibration rotation, signed so that extension is positive (the thesis'
"伸展側方向正"; for a sensor on the back of the segment, x cross V points out
of the back); z = x cross V / |x cross V| with V the link vector; y = z
cross x.  L_R_S has those axes as rows.

Joint angle (eqs. 5.4-5.5): the rotation from the proximal to the distal
link frame, L(j+1)_R_Lj, decomposed as Euler angles in the order z, y, x
(the distal link turned about z, then y, then x): phi about x is
extension (minus flexion), psi about z is abduction.  In canonical names:
``<f>_mcp_flex = -phi``, ``<f>_mcp_abd = psi`` (right hand; the sign is
flipped for the left), ``pip/dip/ip/thumb mcp flex = -phi``.  The thumb CMC
has oblique axes that the z-y-x decomposition does not separate into the
model's ``thumb_cmc_flex``/``thumb_cmc_abd`` (its Euler angles are returned
separately).  Beyond the thesis, :func:`thumb_cmc_model` learns the two CMC
axes from the calibration's two CMC rotations (the metacarpal's gyro, as
eq. 5.1 does for the flexion axes) and :func:`joint_angles` reads the CMC
angles as the rotation vector of the metacarpal relative to its static pose,
resolved on those two axes (least squares).  Angles are measured from the
calibration's static pose (the anatomical zero).

Fingertips (eq. 3.12): the sum of the link vectors, each turned by its
sensor's attitude, from the elbow.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial.transform import Rotation

from ..._checks import check_number, check_side
from ...errors import EstimationError, InvalidInputError
from ...models import BVH_BONE_STARTS, JOINT_LIMITS_DEG, JOINT_NAMES
from ._layout import CHAINS, FLEX_JOINT
from ._quat import check_quats, mat_to_quat, quat_to_mat
from ._recording import ImuRecording
from ._vectors import ChainModel, _segment

__all__ = [
    "JOINT_LINKS",
    "ThumbCmcModel",
    "angles_beyond_range",
    "bone_lengths_mm",
    "classify_grasp",
    "fingertip_positions",
    "hand_attitude",
    "joint_angles",
    "link_frames",
    "thumb_cmc_model",
    "truth_hand_attitude",
    "truth_link_frames",
    "zero_offsets",
]

_F4 = ("index", "middle", "ring", "little")

#: canonical joint (or joint pair) -> (proximal link sensor, distal link sensor)
JOINT_LINKS = {
    "thumb_cmc": ("hand_radial", "thumb_metacarpal"),
    "thumb_mcp": ("thumb_metacarpal", "thumb_proximal"),
    "thumb_ip": ("thumb_proximal", "thumb_distal"),
    **{f"{f}_mcp": ("hand_ulnar" if f in ("ring", "little") else "hand_radial", f"{f}_proximal")
       for f in _F4},
    **{f"{f}_pip": (f"{f}_proximal", f"{f}_middle") for f in _F4},
    **{f"{f}_dip": (f"{f}_middle", f"{f}_distal") for f in _F4},
}

# the calibration rotation whose axis is each frame's x: the proximal joint's
# flexion (eq. 5.1), except the ring/little side of the hand, which takes the
# wrist's like the index/middle side so that both hand parts share the
# wrist flexion axis the thesis chose for the hand (section 5.2.1)
_FRAME_ROTATION = {**FLEX_JOINT, "hand_ulnar": "wrist_flex"}

#: Height above its joint's flexion axis (the part of the sensor's vector from its joint
#: across the link, m) from which that vector, not the sensor's own z axis, tells the back
#: of the segment from the palm side.  Phalanx sensors sit 9-15 mm above their joints in the
#: simulated hand; the vector of ``hand_ulnar`` from its joint is estimated least well (its
#: height read 18-27 mm on four simulated devices, but -4 mm on one, whose link frame then
#: came out turned over: ring and little MCP flexions about -170 deg at the zero pose).
_HEIGHT_DECIDES_M = 0.008
#: Largest angle any joint may read at the calibration's static start (the anatomical
#: zero), deg: the offsets that link-vector and axis errors leave are a few degrees (at most
#: 17 on eight simulated devices); a half-turn means a link frame turned over.
_MAX_ZERO_OFFSET_DEG = 45.0

# the link whose vector gives each sensor's frame its y direction
_FRAME_LINK = {
    "hand_radial": ("wrist", "middle_mcp"),
    "hand_ulnar": ("ulnar_cm", "ring_mcp"),
}


def _frame_vector(model: ChainModel, sensor: str) -> np.ndarray:
    if sensor in _FRAME_LINK:
        a, b = _FRAME_LINK[sensor]
        return model.links[(sensor, a, b)]
    return model.link(sensor)[2]


def _frame(x, v) -> np.ndarray:
    """Link frame rows (x, y, z) from the flexion axis x and link vector v (eq. 5.2)."""
    z = np.cross(x, v)
    nz = np.linalg.norm(z)
    if nz < 1e-9:
        raise EstimationError("the flexion axis is parallel to the link vector")
    z /= nz
    y = np.cross(z, x)
    return np.stack([x, y, z])                                              # eq. 5.2


def _rotation_axis(cal: ImuRecording, sensor: str, label: str,
                   hold_s: float) -> tuple[np.ndarray, np.ndarray]:
    """Principal direction (3,) of `sensor`'s angular velocity in the rotation `label`
    (eq. 5.1, all samples), and that angular velocity less the still start's, (N, 3)."""
    a, b = _segment(cal.labelled(), label)
    k = cal.index(sensor)
    hold = max(3, int(hold_s * cal.rate_hz))
    w = cal.gyr[k, a:b] - cal.gyr[k, a:a + hold].mean(axis=0)
    _, _, vt = np.linalg.svd(w, full_matrices=False)
    return vt[0], w


def link_frames(cal: ImuRecording, model: ChainModel, *, hold_s: float = 0.5) -> dict:
    """L_R_S of every link sensor from the calibration rotations (eqs. 5.1-5.2).

    Parameters
    ----------
    cal : ImuRecording
        The calibration recording, with the labelled rotation of each
        sensor's frame axis (its proximal joint's flexion; the wrist's for
        ``hand_ulnar``).
    model : ChainModel
        The link model (:func:`chain_model`): a frame is made for every sensor
        of its ``own``, its link vector giving the frame's y direction.
    hold_s : float, keyword-only
        Still time at the start of every rotation, s, whose mean gyro is
        subtracted.

    Returns
    -------
    dict
        sensor -> (3, 3) rotation from sensor frame to link frame.

    Raises
    ------
    InvalidInputError
        A rotation the recording has no labelled stretch for.
    RecordingError
        A sensor of `model` missing from `cal`.
    EstimationError
        A flexion axis parallel to its link vector.
    """
    out = {}
    for s in model.own:
        x, _ = _rotation_axis(cal, s, _FRAME_ROTATION[s], hold_s)
        v = _frame_vector(model, s)
        # extension positive: the frame's z (x cross v) points to the back of the segment,
        # where the sensor sits above the joint (9-15 mm in the simulated hand). Judged by
        # the sensor's own vector from its joint where that vector stands clearly off the
        # link, so that a sensor mounted upside down (z toward the palm) gets the same
        # frame (by its z axis its flexion read 360 deg less the true angle: index PIP 301
        # for 59 deg); by the sensor's z axis, mounted on the back, where it does not.
        z = np.cross(x, v)
        height = float(z @ model.own[s]) / float(np.linalg.norm(z) or 1.0)
        if (height if abs(height) >= _HEIGHT_DECIDES_M else z[2]) < 0:
            x = -x
        out[s] = _frame(x, v)
    return out


@dataclass(frozen=True)
class ThumbCmcModel:
    """The thumb CMC's two axes and the metacarpal's static pose (beyond the thesis).

    Attributes
    ----------
    axes : ndarray, shape (2, 3)
        Unit flexion and abduction axes in the metacarpal's link frame at
        the static pose, signed so that the calibration's move toward
        mid-range (flexion and palmar abduction) is positive.
    rest : ndarray, shape (3, 3)
        Hand (radial) link frame to metacarpal link frame at the static pose.
    """

    axes: np.ndarray
    rest: np.ndarray

    def angles(self, relative: np.ndarray) -> np.ndarray:
        """``thumb_cmc_flex`` and ``thumb_cmc_abd`` (N, 2), degrees, from L_hand_R_L_meta (N, 3, 3)."""
        d = np.einsum("ji,njk->nik", self.rest, relative)
        r = Rotation.from_matrix(d).as_rotvec(degrees=True)                # (N, 3)
        sol, *_ = np.linalg.lstsq(self.axes.T, r.T, rcond=None)
        return sol.T


def thumb_cmc_model(cal: ImuRecording, frames: dict, *, static=None,
                    hold_s: float = 0.5) -> ThumbCmcModel:
    """Learn the thumb CMC's axes from the calibration's ``thumb_cmc_flex``/``_abd`` rotations.

    Each axis is the principal direction of the metacarpal's gyro during that
    rotation (the hand still), turned into the metacarpal's link frame; its
    sign makes the mean angle of the rotation positive: the calibration moves
    the joint toward mid-range (flexion, palmar abduction) before it
    oscillates (:func:`calibration_motion`).  The static pose comes from the
    attitudes of the static start, as :func:`zero_offsets` takes them.

    Parameters
    ----------
    cal : ImuRecording
        The calibration recording, with the ``thumb_cmc_flex`` and
        ``thumb_cmc_abd`` rotations labelled and the ``hand_radial`` and
        ``thumb_metacarpal`` sensors.
    frames : dict
        sensor -> (3, 3) link frame, from :func:`link_frames`.
    static : StaticStart, keyword-only, optional
        The static start and common rotation; None takes them from the
        recording's ``"static"`` and ``"elbow_flex"`` stretches.
    hold_s : float, keyword-only
        Still time at the start of each CMC rotation, s, whose mean gyro is
        subtracted.

    Returns
    -------
    ThumbCmcModel

    Raises
    ------
    InvalidInputError
        A labelled stretch missing.
    RecordingError
        A sensor missing from `cal`.
    EstimationError
        From the azimuth alignment (:func:`azimuth_correction`).
    """
    from ._attitude import initial_attitude
    from ._vectors import _calibration_static

    axes = []
    for label in ("thumb_cmc_flex", "thumb_cmc_abd"):
        x, w = _rotation_axis(cal, "thumb_metacarpal", label, hold_s)
        if np.mean(np.cumsum(w @ x)) < 0:                                    # toward mid-range
            x = -x
        axes.append(frames["thumb_metacarpal"] @ x)
    q0 = initial_attitude(cal, static or _calibration_static(cal))
    rest = _relative(quat_to_mat(q0[:, None]), cal.sensors, frames, "hand_radial",
                     "thumb_metacarpal")[0]
    return ThumbCmcModel(np.stack(axes), rest)


def truth_link_frames(rec: ImuRecording, model: ChainModel, hand) -> dict:
    """Link frames from the model's true flexion axes (for reference).

    Parameters
    ----------
    rec : ImuRecording
        A simulated recording; only its truth's joint count is used (and its
        truth required).
    model : ChainModel
        A frame is made for every sensor of its ``own``; its link vectors
        give the frames' y directions.
    hand : ImuHand
        The MuJoCo hand (with its sensor placement) the recording was
        simulated on; it is left at the zero pose, where the axes are read.

    Returns
    -------
    dict
        sensor -> (3, 3) rotation from sensor frame to link frame.

    Raises
    ------
    InvalidInputError
        `rec` has no truth.
    EstimationError
        A flexion axis parallel to its link vector.
    """
    import mujoco

    out = {}
    if rec.truth is None:
        raise InvalidInputError("truth_link_frames needs a simulated recording")
    hand.set_state(np.zeros(len(rec.truth.angles[0])))
    d = hand.data
    for s in model.own:
        j = hand.model.joint(_FRAME_ROTATION[s]).id
        axis_world = d.xaxis[j].copy()
        site = hand.model.site(f"imu_{s}").id
        r = d.site_xmat[site].reshape(3, 3)
        x = -(r.T @ axis_world)                 # model axes are flexion-positive
        if np.dot(np.cross(x, _frame_vector(model, s)), [0.0, 0.0, 1.0]) < 0:
            x = -x
        out[s] = _frame(x, _frame_vector(model, s))
    del mujoco
    return out


def _euler_zyx(r):
    """phi (x), theta (y), psi (z) of R = Rz(psi) Ry(theta) Rx(phi), radians (eqs. 2.9-2.11)."""
    theta = -np.arcsin(np.clip(r[..., 2, 0], -1.0, 1.0))
    phi = np.arctan2(r[..., 2, 1], r[..., 2, 2])
    psi = np.arctan2(r[..., 1, 0], r[..., 0, 0])
    return phi, theta, psi


def bone_lengths_mm(chains: dict) -> dict[str, float]:
    """The hand's bone lengths as the link model measures them, mm (a BVH skeleton's).

    Each bone of :data:`~handsynth.models.BVH_BONES` runs from its proximal joint centre
    (the wrist for the thumb's CMC and each finger's MCP) to the point it is named by; its
    length is the distance of the two points of eq. 3.12's chain, median over the samples
    (only the ring and little fingers' MCPs, two links from the wrist across the hand's
    ulnar CM joint, change with the pose; every other bone is one link vector's length).

    Parameters
    ----------
    chains : dict
        As :func:`fingertip_positions` returns it (or ``ImuCalibration.track``'s
        ``"chains"``): its ``"<finger>_joints"`` entries, (N, L, 3) metres, are read.

    Returns
    -------
    dict
        bone name -> length, mm, for the 20 bones, as
        :func:`~handsynth.models.bvh_text` takes them (``bone_lengths_mm``).

    Raises
    ------
    InvalidInputError
        A finger's joints missing from `chains`, or of another shape than its chain's.
    """
    where = {}
    for f, chain in CHAINS.items():
        joints = chains.get(f"{f}_joints") if isinstance(chains, dict) else None
        if joints is None or np.ndim(joints) != 3 or np.shape(joints)[1:] != (len(chain), 3):
            raise InvalidInputError(f"chains must hold '{f}_joints' of shape (N, {len(chain)}, 3), "
                                    "as fingertip_positions returns it")
        where.update({b: np.asarray(joints)[:, i] for i, (_, _, b) in enumerate(chain)})
    return {bone: float(np.median(np.linalg.norm(where[bone] - where[start], axis=1)) * 1e3)
            for bone, start in BVH_BONE_STARTS.items()}


def _world_link(rot, sensors, frames, sensor):
    """Rotation G_R_L from `sensor`'s link frame to the world, (N, 3, 3), from the sensors'
    rotation matrices `rot` (S, N, 3, 3) (:func:`quat_to_mat` of their quaternions)."""
    return rot[sensors.index(sensor)] @ np.asarray(frames[sensor], float).T


def _relative(rot, sensors, frames, prox, dist):
    """Rotation Lj_R_L(j+1) from the proximal to the distal link frame (eq. 5.4); `rot` as
    :func:`_world_link`'s."""
    rp = _world_link(rot, sensors, frames, prox)                             # G_R_Lj
    rd = _world_link(rot, sensors, frames, dist)
    return np.einsum("nji,njk->nik", rp, rd)                                 # Lj_R_L(j+1), eq. 5.4


def joint_angles(quats, sensors, frames: dict, *, side: str = "right",
                 zero: np.ndarray | None = None,
                 cmc: ThumbCmcModel | None = None) -> tuple[np.ndarray, dict]:
    """Joint angles in canonical order from sensor attitudes (eqs. 5.4-5.5).

    Parameters
    ----------
    quats : ndarray, shape (S, N, 4)
    sensors : sequence of str, length S
    frames : dict
        From :func:`link_frames`.
    side : {"right", "left"}, keyword-only
    zero : ndarray, shape (20,), keyword-only
        Angles of the anatomical zero pose as this function measures them
        (subtracted); see :func:`zero_offsets`.
    cmc : ThumbCmcModel, keyword-only
        The thumb CMC's axes (:func:`thumb_cmc_model`); without it the
        thumb CMC entries are NaN.

    Returns
    -------
    angles : ndarray, shape (N, 20), degrees
        Canonical :data:`JOINT_NAMES`.
    extra : dict
        ``"thumb_cmc_euler"``: (N, 3) phi, theta, psi in degrees.

    Raises
    ------
    InvalidInputError
        `quats` not unit quaternions of shape (S, N, 4) (see
        :func:`check_quats`); a sensor of :data:`JOINT_LINKS` missing from
        `sensors` or `frames`; `side` not "right" or "left"; `zero` not of
        shape (20,).
    """
    sensors = tuple(sensors)
    quats = check_quats(quats, sensors)
    check_side(side)
    if zero is not None:
        zero = np.asarray(zero, dtype=float)
        if zero.shape != (len(JOINT_NAMES),):
            raise InvalidInputError(f"zero must have shape ({len(JOINT_NAMES)},) (one angle per "
                                    f"joint of JOINT_NAMES), got {zero.shape}")
    for joint, pair in JOINT_LINKS.items():
        for s in pair:
            if s not in sensors:
                raise InvalidInputError(f"joint angles need sensor {s!r} (joint {joint}) in "
                                        f"sensors; given {', '.join(sensors)}")
            if s not in frames:
                raise InvalidInputError(f"frames has no link frame of sensor {s!r} (joint "
                                        f"{joint}); see link_frames")
    n = quats.shape[1]
    out = np.full((n, len(JOINT_NAMES)), np.nan)
    sign = 1.0 if side == "right" else -1.0
    extra = {}
    rot = quat_to_mat(quats)
    for joint, (prox, dist) in JOINT_LINKS.items():
        rel = _relative(rot, sensors, frames, prox, dist)
        phi, theta, psi = (np.degrees(a) for a in _euler_zyx(rel))
        if joint == "thumb_cmc":
            extra["thumb_cmc_euler"] = np.stack([phi, theta, psi], axis=1)
            if cmc is not None:
                out[:, :2] = cmc.angles(rel)
            continue
        out[:, JOINT_NAMES.index(f"{joint}_flex")] = -phi
        if joint.endswith("_mcp") and not joint.startswith("thumb"):
            out[:, JOINT_NAMES.index(f"{joint}_abd")] = sign * psi
    if zero is not None:
        out -= np.nan_to_num(zero)
    return out, extra


def hand_attitude(quats, sensors, frames: dict) -> np.ndarray:
    """The hand frame's attitude in the world, from the hand sensor's.

    The link frame of ``hand_radial`` (:func:`link_frames`) takes its x axis from the
    wrist's flexion and its y axis from the link from the wrist to the middle finger's MCP
    joint: the axes of the hand frame (:mod:`handsynth.models`: +y toward the middle
    finger's MCP, +z out of the back of the hand), so the sensor's attitude turned by its
    link frame is the hand's: built from the simulation's true axes it is the palm's to
    1e-6 (a test); from the calibration's, the hand's attitude read 0.38-1.01 deg RMSE on six
    held-out draws (``python scripts/study_imu_bvh.py``; :func:`truth_hand_attitude`).

    Parameters
    ----------
    quats : ndarray, shape (S, N, 4)
        Sensor-to-world unit quaternions (w, x, y, z).
    sensors : sequence of str, length S
        Names of the rows of `quats`, ``hand_radial`` among them.
    frames : dict
        From :func:`link_frames`, with ``hand_radial``'s.

    Returns
    -------
    ndarray, shape (N, 4)
        Hand-to-world unit quaternions (w, x, y, z).

    Raises
    ------
    InvalidInputError
        `quats` not unit quaternions of shape (S, N, 4); ``hand_radial`` missing from
        `sensors` or `frames`.
    """
    sensors = tuple(sensors)
    quats = check_quats(quats, sensors)
    if "hand_radial" not in sensors or "hand_radial" not in frames:
        raise InvalidInputError("the hand's attitude needs sensor 'hand_radial' in sensors and "
                                "its link frame in frames (see link_frames)")
    return mat_to_quat(_world_link(quat_to_mat(quats), sensors, frames, "hand_radial"))


def truth_hand_attitude(rec: ImuRecording, hand) -> np.ndarray:
    """The hand frame's true attitude in each sample of a simulated recording (for reference).

    The rigid fit (Kabsch) of the hand model's palm points (wrist, index and middle MCP,
    thumb CMC, all on the palm) onto where the simulation put them.

    Parameters
    ----------
    rec : ImuRecording
        A simulated recording (its truth's keypoints are used).
    hand : ImuHand
        The hand the recording was simulated with (its shape and side).

    Returns
    -------
    ndarray, shape (N, 3, 3)
        Hand-to-world rotations.

    Raises
    ------
    InvalidInputError
        A recording without truth.
    """
    from ...models import KEYPOINT_SITES, HandModel
    from ._layout import POINTS

    if rec.truth is None:
        raise InvalidInputError("the true hand attitude needs a simulated recording with truth")
    names = ("wrist", "index_mcp", "middle_mcp", "thumb_cmc")
    model = HandModel(hand.shape, side=hand.side, forearm=False)
    model.set_pose(np.zeros(len(JOINT_NAMES)))
    a = model.keypoints()[[KEYPOINT_SITES.index(n) for n in names]]
    a = a - a.mean(axis=0)
    out = np.empty((rec.n, 3, 3))
    for i, pts in enumerate(rec.truth.keypoints[:, [POINTS.index(n) for n in names]]):
        u, _, vt = np.linalg.svd((pts - pts.mean(axis=0)).T @ a)
        out[i] = u @ np.diag([1.0, 1.0, np.linalg.det(u @ vt)]) @ vt
    return out


def zero_offsets(cal: ImuRecording, frames: dict, *, side: str = "right",
                 static=None) -> np.ndarray:
    """Joint angles measured on the calibration's static start (the anatomical zero).

    The static start's attitudes (eqs. 2.9-2.11 with the azimuth alignment)
    give the angles this method reads for the zero pose; subtracting them
    removes the constant offsets that link-vector and axis errors leave
    (an addition to the thesis, which reports the raw Euler angles).

    Parameters
    ----------
    cal : ImuRecording
        The calibration recording.
    frames : dict
        sensor -> (3, 3) link frame, from :func:`link_frames`.
    side : {"right", "left"}, keyword-only
        As :func:`joint_angles` (the sign of MCP abduction).
    static : StaticStart, keyword-only, optional
        The static start and common rotation; None takes them from the
        recording's ``"static"`` and ``"elbow_flex"`` stretches.

    Returns
    -------
    ndarray, shape (20,), degrees (0 for the thumb CMC).
        Canonical order; any NaN is written as 0.

    Raises
    ------
    InvalidInputError
        `side` not ``"right"`` or ``"left"``; a stretch missing; a sensor or
        frame :func:`joint_angles` needs missing.
    EstimationError
        From the azimuth alignment (:func:`azimuth_correction`); a joint
        reading more than 45 deg at the static start (link frames half a
        turn apart).
    """
    from ._attitude import initial_attitude
    from ._vectors import _calibration_static

    check_side(side)
    q0 = initial_attitude(cal, static or _calibration_static(cal))
    a, _ = joint_angles(q0[:, None], cal.sensors, frames, side=side)
    zero = np.nan_to_num(a[0])
    far = np.flatnonzero(np.abs(zero) > _MAX_ZERO_OFFSET_DEG)
    if far.size:
        joint = JOINT_NAMES[far[0]]
        pair = JOINT_LINKS[joint.rsplit("_", 1)[0]]
        raise EstimationError(
            f"at the calibration's static start {joint} reads {zero[far[0]]:.1f} deg, not about 0 "
            f"(the hand should be at the anatomical zero pose): the link frames of {pair[0]} and "
            f"{pair[1]} disagree by about half a turn; check that hand and fingers were still "
            f"and flat during the static start, and the labels of the calibration rotations")
    return zero


def angles_beyond_range(angles, *, margin_deg: float = 30.0, min_share: float = 0.05) -> str | None:
    """Say which sensor a hand's impossible joint angles point to, or None.

    A sensor turned on its segment after the calibration (clipped back the other way
    round, or a recording whose columns of two sensors are swapped) leaves every later
    sample's attitudes plausible on their own, but the joints it spans read far beyond
    what a hand can do: measured on the held-out simulated configuration, a middle
    phalanx's sensor turned half a turn about its z axis read the index PIP at -66 deg
    (its own range -5 to 100), about its x axis PIP and DIP near +-180 deg, the
    hand's radial sensor turned about z read the index and middle MCP abductions
    near +-180 deg, while untouched sensors stayed within 0.6 deg of
    :data:`~handsynth.models.JOINT_LIMITS_DEG` (six draws, tuning and held-out
    configurations, free motions with the elbow fixed and moving, and grasps).

    Parameters
    ----------
    angles : ndarray, shape (N, 20), degrees
        Canonical joint angles (:func:`joint_angles`); NaN entries are ignored.
    margin_deg : float, keyword-only
        How far beyond a joint's range (:data:`~handsynth.models.JOINT_LIMITS_DEG`,
        the AAOS ranges and hyperextension) an angle must be to count: the
        default 30 deg leaves room for hypermobile joints and estimation error.
    min_share : float, keyword-only
        Share of the samples, in (0, 1], in which a joint must count.

    Returns
    -------
    str or None
        One sentence naming each such joint (share of samples, worst angle, its
        range) and the sensor(s) they share, most likely the one that moved; None
        when every joint stays within range.

    Raises
    ------
    InvalidInputError
        `angles` not of shape (N, 20), `margin_deg` not a number >= 0, `min_share`
        not in (0, 1].
    """
    angles = np.asarray(angles, dtype=float)
    if angles.ndim != 2 or angles.shape[1] != len(JOINT_NAMES):
        raise InvalidInputError(f"angles must have shape (N, {len(JOINT_NAMES)}) (canonical joint "
                                f"angles, deg), got {angles.shape}")
    margin_deg = check_number(margin_deg, "margin_deg", minimum=0)
    min_share = check_number(min_share, "min_share", above=0, maximum=1)
    if angles.shape[0] == 0:
        return None
    lo, hi = JOINT_LIMITS_DEG[:, 0], JOINT_LIMITS_DEG[:, 1]
    with np.errstate(invalid="ignore"):
        beyond = (angles < lo - margin_deg) | (angles > hi + margin_deg)
    share = beyond.mean(axis=0)
    flagged = [j for j in range(len(JOINT_NAMES)) if share[j] >= min_share]
    if not flagged:
        return None
    parts = []
    for j in flagged:
        a = angles[beyond[:, j], j]
        worst = a[np.argmax(np.maximum(lo[j] - a, a - hi[j]))]
        parts.append(f"{JOINT_NAMES[j]} in {100 * share[j]:.0f} % of the samples ({worst:.0f} deg; "
                     f"range {lo[j]:g} to {hi[j]:g})")
    # each joint (a flexion and abduction of one joint count once) votes for its two sensors
    joints = list(dict.fromkeys(JOINT_NAMES[j].rsplit("_", 1)[0] for j in flagged))
    counts: dict[str, int] = {}
    for joint in joints:
        for s in JOINT_LINKS[joint]:
            counts[s] = counts.get(s, 0) + 1
    top = max(counts.values())
    suspects = [s for s, c in counts.items() if c == top]
    if len(suspects) == 1:
        who = f"sensor {suspects[0]} (a sensor of {top} of those {len(joints)} joints)"
    else:
        who = "sensor " + ", ".join(suspects[:-1]) + f" or {suspects[-1]}"
    return (f"{len(flagged)} joint angle{'s' if len(flagged) > 1 else ''} read more than "
            f"{margin_deg:g} deg beyond the hand's range of motion: {'; '.join(parts)}. Most "
            f"likely {who} turned or moved on its segment since the calibration, or its columns "
            "are another sensor's: put it back as it was when calibrated, or calibrate again")


def fingertip_positions(quats, sensors, model: ChainModel) -> dict:
    """Fingertip positions from the elbow by chaining link vectors (eq. 3.12).

    Parameters
    ----------
    quats : ndarray, shape (S, N, 4)
        Sensor-to-world unit quaternions (w, x, y, z).
    sensors : sequence of str, length S
        Names of the rows of `quats`; every sensor of :data:`CHAINS`.
    model : ChainModel
        Its link vectors (metres, sensor frame) are summed.

    Returns
    -------
    dict
        finger -> (N, 3) metres, world frame, relative to the elbow centre;
        also ``"<finger>_joints"`` -> (N, L, 3) the chain's joint positions.

    Raises
    ------
    InvalidInputError
        `quats` not unit quaternions of shape (S, N, 4) (see
        :func:`check_quats`); a chain's sensor missing from `sensors`.
    """
    sensors = tuple(sensors)
    quats = check_quats(quats, sensors)
    out = {}
    rot = quat_to_mat(quats)
    for f, chain in CHAINS.items():
        pos = np.zeros((quats.shape[1], 3))
        joints = []
        for s, a, b in chain:
            if s not in sensors:
                raise InvalidInputError(f"fingertip of {f} needs sensor {s!r}")
            v = model.links[(s, a, b)]
            pos = pos + np.einsum("nij,j->ni", rot[sensors.index(s)], v)
            joints.append(pos.copy())
        out[f] = pos
        out[f"{f}_joints"] = np.stack(joints, axis=1)
    return out


def classify_grasp(angles, grasps: dict) -> list[str]:
    """Nearest grasp posture (Cutkosky classes) for each row of canonical angles.

    Parameters
    ----------
    angles : ndarray, shape (N, 20), degrees (NaN entries ignored)
    grasps : dict
        name -> (20,) posture, e.g. :data:`GRASP_POSES`.
    """
    names = list(grasps)
    ref = np.stack([grasps[g] for g in names])
    a = np.asarray(angles, float)
    ok = np.isfinite(a)
    d = np.nansum(np.where(ok[:, None], (a[:, None] - ref[None]) ** 2, 0.0), axis=-1)
    return [names[i] for i in np.argmin(d, axis=1)]
