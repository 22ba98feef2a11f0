"""Kinematic motions of the IMU hand: calibration rotations, free motion, grasps.

A :class:`Motion` holds joint positions, velocities and accelerations of
:data:`MODEL_JOINTS` on the sample grid, all analytic (no numerical
differentiation): smooth sinusoids under a C2 envelope for oscillations, and
minimum-jerk quintics between postures for reaching and grasping (Flash &
Hogan, "The coordination of arm movements", J. Neurosci. 5:1688-1703, 1985).

Every motion starts with a static stretch (initial attitude from gravity and
compass, seed 003 section 2.4.4: 2 s) and, when asked, a whole-arm rotation
(the common rotation that aligns the compass azimuths, seed 003 section 4.2.5,
Fig. 4.11).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..._checks import check_number, short_repr
from ...errors import InvalidInputError
from ...models import JOINT_LIMITS_DEG, JOINT_NAMES
from ._model import ARM_JOINTS, MODEL_JOINTS

__all__ = [
    "ACC_POSES",
    "CALIBRATION_PLAN",
    "GRASP_POSES",
    "MAX_MOTION_S",
    "Motion",
    "calibration_motion",
    "concat_motions",
    "free_motion",
    "grasp_motion",
    "pose_motion",
    "static_motion",
]

_J = {n: i for i, n in enumerate(MODEL_JOINTS)}

#: The longest motion a generator makes, s (one hour: 360,000 samples at 100 Hz; each sample
#: holds positions, velocities and accelerations of the 29 joints).
MAX_MOTION_S = 3600.0


@dataclass(frozen=True)
class Motion:
    """Joint trajectories of :data:`MODEL_JOINTS` sampled at `rate_hz`.

    Attributes
    ----------
    rate_hz : float
    q, qd, qdd : ndarray, shape (N, 29), float64
        Hinges in deg, deg/s, deg/s^2; the elbow slides in m, m/s, m/s^2.
    label : str
    segments : tuple of (str, int, int)
        Named stretches (label, first sample, end sample), e.g. the static
        start or one joint's calibration rotation.
    """

    rate_hz: float
    q: np.ndarray
    qd: np.ndarray
    qdd: np.ndarray
    label: str = ""
    segments: tuple = ()

    @property
    def n(self) -> int:
        return self.q.shape[0]

    @property
    def t(self) -> np.ndarray:
        """Sample times, s, shape (N,)."""
        return np.arange(self.n) / self.rate_hz


def _grid(duration_s: float, rate_hz: float, name: str = "duration_s") -> np.ndarray:
    """Sample times of a motion of `duration_s` (named `name` in messages) at `rate_hz`."""
    duration_s = check_number(duration_s, name, above=0.0, maximum=MAX_MOTION_S)
    rate_hz = check_number(rate_hz, "rate_hz", minimum=10.0, maximum=1000.0)
    return np.arange(round(duration_s * rate_hz)) / rate_hz


def _check_pose(pose, name: str) -> np.ndarray | None:
    """`pose` as the 29 positions of :data:`MODEL_JOINTS` (None passes); 20 canonical hand
    angles (:func:`handsynth.models.named_pose`) are placed with the arm joints at 0."""
    if pose is None:
        return None
    shapes = (f"an array of shape ({len(MODEL_JOINTS)},) (MODEL_JOINTS) or ({len(JOINT_NAMES)},) "
              f"(canonical hand angles, deg)")
    if isinstance(pose, (str, bytes)):
        raise InvalidInputError(f"{name} must be {shapes}, got {type(pose).__name__} "
                                f"{short_repr(pose)} (a named pose: handsynth.models.named_pose(name))")
    try:
        a = np.asarray(pose, dtype=np.float64)
    except (TypeError, ValueError):
        raise InvalidInputError(f"{name} must be {shapes} of numbers, got {type(pose).__name__} "
                                f"{short_repr(pose)}") from None
    if a.shape == (len(JOINT_NAMES),):
        a = _full_pose(hand_deg=a)
    elif a.shape != (len(MODEL_JOINTS),):
        raise InvalidInputError(f"{name} must be {shapes}, got shape {a.shape}")
    if not np.isfinite(a).all():
        raise InvalidInputError(f"{name} must be finite, got {short_repr(pose)}")
    return a


def _smoothstep(t, t0, t1):
    """C2 quintic ramp 0 -> 1 on [t0, t1] and its first two derivatives."""
    T = t1 - t0
    s = np.clip((t - t0) / T, 0.0, 1.0)
    inside = (t > t0) & (t < t1)
    w = 10 * s**3 - 15 * s**4 + 6 * s**5
    wd = np.where(inside, (30 * s**2 - 60 * s**3 + 30 * s**4) / T, 0.0)
    wdd = np.where(inside, (60 * s - 180 * s**2 + 120 * s**3) / T**2, 0.0)
    return w, wd, wdd


def _envelope(t, t0, t1, ramp):
    """1 on [t0+ramp, t1-ramp], C2 ramps at both ends, 0 outside."""
    a, ad, add = _smoothstep(t, t0, t0 + ramp)
    b, bd, bdd = _smoothstep(t, t1 - ramp, t1)
    return a * (1 - b), ad * (1 - b) - a * bd, add * (1 - b) - 2 * ad * bd - a * bdd


def _base(n: int, pose=None):
    q = np.zeros((n, len(MODEL_JOINTS)))
    if pose is not None:
        q[:] = pose
    return q, np.zeros_like(q), np.zeros_like(q)


def _full_pose(hand_deg=None, arm=None) -> np.ndarray:
    p = np.zeros(len(MODEL_JOINTS))
    if hand_deg is not None:
        p[len(ARM_JOINTS):] = np.asarray(hand_deg, float)
    for k, v in (arm or {}).items():
        p[_J[k]] = v
    return p


def static_motion(duration_s: float = 2.0, *, rate_hz: float = 100.0, pose=None) -> Motion:
    """Hold `pose` (shape (29,) or (20,), default zeros) still for `duration_s`.

    Parameters
    ----------
    duration_s : float
        Length, s (finite, > 0, at most :data:`MAX_MOTION_S`); ``round(duration_s *
        rate_hz)`` samples.
    rate_hz : float, keyword-only
        Sampling rate, Hz, in [10, 1000].
    pose : array_like, shape (29,) or (20,), keyword-only, optional
        Positions of :data:`MODEL_JOINTS`: hinges in deg, the elbow slides in
        m; or the 20 canonical hand angles in deg (a
        :func:`handsynth.models.named_pose`), the arm joints then at 0; None
        for all zeros.

    Returns
    -------
    Motion
        Zero velocities and accelerations; labelled ``"static"`` with one
        segment ``("static", 0, N)``.

    Raises
    ------
    InvalidInputError
        `duration_s` not a finite number > 0 and <= :data:`MAX_MOTION_S`, `rate_hz` outside
        [10, 1000], or `pose` not a finite array of shape (29,) or (20,) (a pose name is
        refused: give ``named_pose(name)``).
    """
    t = _grid(duration_s, rate_hz)
    q, qd, qdd = _base(t.size, _check_pose(pose, "pose"))
    return Motion(rate_hz, q, qd, qdd, "static", (("static", 0, t.size),))


def _oscillate(t, q, qd, qdd, joint, amp, freq, t0, t1, ramp=0.4, phase=0.0):
    w, wd, wdd = _envelope(t, t0, t1, ramp)
    om = 2 * np.pi * freq
    arg = om * (t - t0) + phase
    s, sd, sdd = np.sin(arg), om * np.cos(arg), -om**2 * np.sin(arg)
    j = _J[joint]
    q[:, j] += amp * w * s
    qd[:, j] += amp * (wd * s + w * sd)
    qdd[:, j] += amp * (wdd * s + 2 * wd * sd + w * sdd)


#: Joint rotations for the sensor-to-joint vectors, seed 003 Table 3.5: each
#: entry is (label, joints rotated, amplitude deg, frequency Hz).  Two-axis
#: joints rotate about each axis; one-axis joints (PIP, DIP, IP, MCP of the
#: thumb) are paired with the proximal two-axis joint's other axis (Fig. 3.3).
CALIBRATION_PLAN: tuple[tuple[str, tuple[str, ...], float, float], ...] = (
    ("elbow_flex", ("elbow_flex",), 25.0, 0.8),
    ("humeral_rot", ("humeral_rot",), 25.0, 0.8),
    ("wrist_flex", ("wrist_flex",), 30.0, 1.0),
    ("wrist_dev", ("wrist_dev",), 15.0, 1.0),
    ("ulnar_cm_flex", ("ulnar_cm_flex",), 10.0, 1.2),
    ("thumb_cmc_flex", ("thumb_cmc_flex",), 20.0, 1.2),
    ("thumb_cmc_abd", ("thumb_cmc_abd",), 20.0, 1.2),
    ("thumb_mcp_flex", ("thumb_mcp_flex",), 25.0, 1.4),
    ("thumb_ip_flex", ("thumb_ip_flex",), 30.0, 1.4),
    *(
        item
        for f in ("index", "middle", "ring", "little")
        for item in (
            (f"{f}_mcp_flex", (f"{f}_mcp_flex",), 35.0, 1.2),
            (f"{f}_mcp_abd", (f"{f}_mcp_abd",), 12.0, 1.2),
            (f"{f}_pip_flex", (f"{f}_pip_flex",), 35.0, 1.4),
            (f"{f}_dip_flex", (f"{f}_dip_flex",), 30.0, 1.4),
        )
    ),
)

# centre of each calibration oscillation: mid-range so that +/- amplitude is legal
_CAL_CENTRE = {"elbow_flex": 30.0, "thumb_cmc_abd": 30.0, "thumb_cmc_flex": 10.0,
               "ulnar_cm_flex": 10.0, "thumb_mcp_flex": 25.0, "thumb_ip_flex": 30.0,
               **{f"{f}_{j}": c for f in ("index", "middle", "ring", "little")
                  for j, c in (("mcp_flex", 40.0), ("pip_flex", 40.0), ("dip_flex", 35.0))}}


#: Arm postures (elbow_flex, forearm_rot, wrist_flex), deg, held still for the
#: accelerometer calibration (multi-position fit, :mod:`._acccal`): elbow
#: flexion and wrist flexion turn every segment about the hand's x axis,
#: forearm rotation about its y axis, so gravity takes 13 directions in every
#: sensor frame, 14 with the static start.
ACC_POSES: tuple[tuple[float, float, float], ...] = (
    (30.0, 80.0, 0.0), (30.0, -80.0, 0.0), (120.0, 0.0, 0.0), (120.0, 80.0, 0.0),
    (120.0, -80.0, 0.0), (30.0, 0.0, 65.0), (30.0, 0.0, -60.0), (120.0, 0.0, -60.0),
    (30.0, 80.0, 60.0), (30.0, -80.0, -55.0), (-5.0, 80.0, 0.0), (-5.0, -80.0, 0.0),
    (120.0, 60.0, 60.0),
)


def _pose_sequence(rest, poses, rate_hz, *, move_s=1.0, hold_s=1.5) -> list[Motion]:
    pieces = []
    cur = rest.copy()
    arm = (_J["elbow_flex"], _J["forearm_rot"], _J["wrist_flex"])
    targets = []
    for pose in poses:
        p = rest.copy()
        p[list(arm)] = pose
        targets.append(p)
    targets.append(rest.copy())
    for k, p in enumerate(targets):
        last = k == len(targets) - 1
        t = _grid(move_s + (0.5 if last else hold_s), rate_hz, "length of an acc_pose move")
        q, qd, qdd = _base(t.size, cur)
        for j in arm:
            if p[j] != cur[j]:
                _minjerk_add(t, q, qd, qdd, j, p[j] - cur[j], 0.0, move_s)
        a = int(round(move_s * rate_hz))
        segs = () if last else ((f"acc_pose_{k}", a, t.size),)
        pieces.append(Motion(rate_hz, q, qd, qdd, "acc_poses", segs))
        cur = p
    return pieces


def calibration_motion(*, rate_hz: float = 100.0, cycles: float = 5.0, static_s: float = 2.0,
                       plan=CALIBRATION_PLAN, rest_pose=None, acc_poses: bool = False
                       ) -> Motion:
    """Static start, then each joint of `plan` rotated alone, the others still.

    Each rotation starts with 0.5 s still at the rest pose, then is
    ``amp * sin(2 pi f t)`` about a mid-range centre, so that
    the angular velocity passes zero at the turning points where the angular
    acceleration is largest (the samples eqs. 3.2-3.4 use, Fig. 3.6).

    Parameters
    ----------
    rate_hz, cycles, static_s : float, keyword-only
    plan : sequence of (label, joints, amp_deg, freq_hz), keyword-only
    rest_pose : (29,) float, keyword-only
        Posture between rotations; by default every joint at its oscillation
        centre's neighbour zero except the elbow at 30 deg.  20 canonical hand
        angles (deg) place the arm joints at 0, as in :func:`static_motion`.
    acc_poses : bool, keyword-only
        After the static start, hold the arm still in the postures of
        :data:`ACC_POSES` (1 s move, 1.5 s hold each, labelled
        ``acc_pose_<k>``) for the accelerometer calibration, then return to
        the rest pose.

    Returns
    -------
    Motion
        ``segments`` names each rotation by its label.

    Raises
    ------
    InvalidInputError
        `rest_pose` not a finite array of shape (29,) or (20,); `static_s` not in
        (0, :data:`MAX_MOTION_S`]; `rate_hz` outside [10, 1000].
    """
    checked = _check_pose(rest_pose, "rest_pose")
    rest = _full_pose(arm={"elbow_flex": _CAL_CENTRE["elbow_flex"]}) if checked is None else checked
    pieces = [static_motion(static_s, rate_hz=rate_hz, pose=rest)]
    if acc_poses:
        pieces += _pose_sequence(rest, ACC_POSES, rate_hz)
    hold = 0.5  # still at the rest pose at the start of every rotation
    for label, joints, amp, freq in plan:
        dur = hold + cycles / freq + 1.0
        t = _grid(dur, rate_hz, f"length of the {label!r} rotation")
        q, qd, qdd = _base(t.size, rest)
        for j in joints:
            c = _CAL_CENTRE.get(j, rest[_J[j]])
            # move to the centre and back with min-jerk, oscillate in between
            if c != rest[_J[j]]:
                _minjerk_add(t, q, qd, qdd, _J[j], c - rest[_J[j]], hold, hold + 0.5)
                _minjerk_add(t, q, qd, qdd, _J[j], rest[_J[j]] - c, dur - 0.5, dur)
            _oscillate(t, q, qd, qdd, j, amp, freq, hold + 0.5, dur - 0.5, ramp=1.0 / freq)
        pieces.append(Motion(rate_hz, q, qd, qdd, label, ((label, 0, t.size),)))
    return concat_motions(pieces, label="calibration")


def _minjerk_add(t, q, qd, qdd, j, delta, t0, t1):
    w, wd, wdd = _smoothstep(t, t0, t1)
    q[:, j] += delta * w
    qd[:, j] += delta * wd
    qdd[:, j] += delta * wdd


def concat_motions(motions, *, label: str = "") -> Motion:
    """Join motions end to end (same rate; each must start where the last ended).

    Parameters
    ----------
    motions : iterable of Motion
        At least one, all at the same ``rate_hz``.  That each starts where the
        last ended is the caller's to ensure: it is not checked.
    label : str, keyword-only
        Label of the result.

    Returns
    -------
    Motion
        The samples one after another; every motion's ``segments`` kept, their
        sample indices shifted to the joined grid.

    Raises
    ------
    InvalidInputError
        Motions of different rates.
    """
    motions = list(motions)
    rate = motions[0].rate_hz
    segs: list[tuple[str, int, int]] = []
    off = 0
    for m in motions:
        if m.rate_hz != rate:
            raise InvalidInputError(f"cannot join motions at {rate} Hz and {m.rate_hz} Hz")
        segs.extend((s, a + off, b + off) for s, a, b in m.segments)
        off += m.n
    return Motion(rate, np.concatenate([m.q for m in motions]),
                  np.concatenate([m.qd for m in motions]),
                  np.concatenate([m.qdd for m in motions]), label, tuple(segs))


# interior ranges used by free motion (deg): centre and amplitude per joint
def _free_ranges():
    lim = JOINT_LIMITS_DEG
    centre = {n: 0.5 * (lo + hi) for n, (lo, hi) in zip(JOINT_NAMES, lim)}
    amp = {n: 0.35 * (hi - lo) for n, (lo, hi) in zip(JOINT_NAMES, lim)}
    for f in ("index", "middle", "ring", "little"):
        centre[f"{f}_mcp_abd"], amp[f"{f}_mcp_abd"] = 0.0, 8.0
    centre.update(wrist_flex=0.0, wrist_dev=-5.0, ulnar_cm_flex=8.0, elbow_flex=35.0,
                  humeral_rot=0.0, forearm_rot=0.0)
    amp.update(wrist_flex=25.0, wrist_dev=10.0, ulnar_cm_flex=6.0, elbow_flex=20.0,
               humeral_rot=20.0, forearm_rot=30.0)
    return centre, amp


def free_motion(duration_s: float = 30.0, *, rate_hz: float = 100.0, seed: int = 0,
                elbow: str = "fixed", speed: float = 1.0, static_s: float = 2.0,
                align_rotation: bool = True, elbow_amp_m: float = 0.08) -> Motion:
    """Free finger, wrist and elbow motion: sums of sinusoids per joint.

    Each joint moves as a sum of three sinusoids with random frequencies
    (0.15-1.2 Hz times `speed`), phases and a random share of an interior
    amplitude, under a C2 envelope after the static start.

    Parameters
    ----------
    duration_s : float
        Total length including the static start and the alignment rotation.
    rate_hz : float, keyword-only
    seed : int, keyword-only
    elbow : {"fixed", "moving"}, keyword-only
        "fixed": the elbow centre stays put (it may still flex and rotate);
        "moving": it also translates up to `elbow_amp_m` on each axis.
    speed : float, keyword-only
        Frequency scale (2 doubles every angular velocity).
    static_s : float, keyword-only
    align_rotation : bool, keyword-only
        Insert a 2 s elbow-flexion oscillation (25 deg, 0.5 Hz) after the
        static start: the common rotation of seed 003 section 4.2.5, turning
        every sensor of the forearm and hand together.
    """
    if elbow not in ("fixed", "moving"):
        raise InvalidInputError(f"elbow must be 'fixed' or 'moving', got {elbow!r}")
    if not (0.05 <= speed <= 5.0):
        raise InvalidInputError(f"speed must be in [0.05, 5], got {speed!r}")
    t = _grid(duration_s, rate_hz)
    rng = np.random.default_rng(seed)
    centre, amp = _free_ranges()
    rest = _full_pose(arm={"elbow_flex": centre["elbow_flex"]})
    q, qd, qdd = _base(t.size, rest)
    start = static_s
    segs: list[tuple[str, int, int]] = [("static", 0, int(static_s * rate_hz))]
    if align_rotation:
        _oscillate(t, q, qd, qdd, "elbow_flex", 25.0, 0.5, static_s, static_s + 2.0, ramp=0.5)
        segs.append(("align", int(static_s * rate_hz), int((static_s + 2) * rate_hz)))
        start += 2.0
    if duration_s - start < 2.0:
        raise InvalidInputError(f"duration_s={duration_s} leaves no time for motion")
    # move from the rest pose to each joint's centre, then oscillate about it
    joints = [*ARM_JOINTS[3:], *JOINT_NAMES]
    for name in joints:
        j = _J[name]
        delta = centre[name] - rest[j]
        if delta:
            _minjerk_add(t, q, qd, qdd, j, delta, start, start + 1.0)
        for _ in range(3):
            f = rng.uniform(0.15, 1.2) * speed
            a = amp[name] * rng.uniform(0.15, 0.33)
            _oscillate(t, q, qd, qdd, name, a, f, start + 0.5, t[-1] + 1.0 / rate_hz,
                       ramp=0.8, phase=rng.uniform(0, 2 * np.pi))
    if elbow == "moving":
        for name in ("elbow_x", "elbow_y", "elbow_z"):
            for _ in range(2):
                f = rng.uniform(0.2, 0.8) * speed
                _oscillate(t, q, qd, qdd, name, elbow_amp_m * rng.uniform(0.2, 0.5), f,
                           start + 0.5, t[-1] + 1.0 / rate_hz, ramp=0.8,
                           phase=rng.uniform(0, 2 * np.pi))
    _clip_limits(q)
    segs.append(("motion", int(start * rate_hz), t.size))
    return Motion(rate_hz, q, qd, qdd, f"free_{elbow}", tuple(segs))


def _clip_limits(q: np.ndarray) -> None:
    lim = np.array([[-1.0, 1.0]] * 3 + [[-90, 90], [-10, 140], [-90, 90], [-70, 80], [-30, 20],
                                       [-5, 25]] + JOINT_LIMITS_DEG.tolist())
    bad = (q < lim[:, 0] - 1e-9) | (q > lim[:, 1] + 1e-9)
    if bad.any():
        j = int(np.nonzero(bad.any(axis=0))[0][0])
        raise InvalidInputError(
            f"motion leaves the range of joint {MODEL_JOINTS[j]!r} "
            f"({q[:, j].min():.1f}..{q[:, j].max():.1f} deg, limits {lim[j][0]:g}..{lim[j][1]:g})")


def _pose(thumb, index, middle, ring, little) -> np.ndarray:
    return np.array([*thumb, *index, *middle, *ring, *little], dtype=np.float64)


#: Grasp postures of Cutkosky's taxonomy that the simulated hand can form
#: (M. R. Cutkosky, IEEE Trans. Robot. Autom. 5(3):269-279, 1989; seed 003
#: Fig. 5.12), canonical joint order, degrees.  Hand-tuned on the standard hand.
GRASP_POSES: dict[str, np.ndarray] = {
    "open": np.zeros(len(JOINT_NAMES)),
    "power_sphere": _pose((25, 45, 20, 20), (40, 5, 40, 25), (42, 0, 42, 25), (45, -5, 42, 25),
                          (48, -10, 40, 25)),
    "medium_wrap": _pose((30, 40, 30, 25), (65, 0, 60, 35), (68, 0, 62, 35), (70, 0, 62, 35),
                         (72, 0, 60, 35)),
    "lateral_pinch": _pose((5, 10, 10, 20), (70, 0, 75, 45), (80, 0, 85, 50), (85, 0, 85, 50),
                           (85, 0, 85, 50)),
    "precision_tripod": _pose((36, 30, 10, 15), (45, 0, 40, 25), (45, 0, 40, 25), (20, 0, 20, 10),
                              (15, 0, 20, 10)),
    "tip_pinch": _pose((36, 24, 4, 9), (46, 0, 41, 27), (15, 0, 20, 13), (15, 0, 20, 13),
                       (15, 0, 20, 13)),
}
for _p in GRASP_POSES.values():
    _p.setflags(write=False)


def grasp_motion(grasps=("power_sphere", "medium_wrap", "lateral_pinch", "tip_pinch"), *,
                 rate_hz: float = 100.0, hold_s: float = 2.0, move_s: float = 1.0,
                 static_s: float = 2.0, elbow: str = "fixed", seed: int = 0,
                 align_rotation: bool = True) -> Motion:
    """Open hand, then each grasp in turn: reach it (min-jerk), hold, release.

    ``segments`` names every hold ``grasp:<name>`` for classification tests.
    With ``elbow="moving"`` the arm sways (its own sway, below).

    Parameters
    ----------
    grasps : sequence of str
        Keys of :data:`GRASP_POSES`, formed in this order, each from and back
        to the open hand.
    rate_hz : float, keyword-only
        Sampling rate, Hz, in [10, 1000].
    hold_s : float, keyword-only
        Time each grasp is held, s.
    move_s : float, keyword-only
        Duration of each reach and each release, s.
    static_s : float, keyword-only
        Still start, s (segment ``"static"``).
    elbow : {"fixed", "moving"}, keyword-only
        ``"moving"``: the elbow centre sways (one sinusoid of 0.04 m on each
        axis) and the wrist flexion and humeral rotation oscillate (10 deg);
        ``"fixed"`` keeps the arm still.
    seed : int, keyword-only
        Seed of the sway's frequencies and phases (used only with
        ``elbow="moving"``).
    align_rotation : bool, keyword-only
        Insert a 2 s elbow-flexion oscillation after the static start
        (segment ``"align"``), the common rotation of the azimuth alignment.

    Returns
    -------
    Motion
        Labelled ``"grasps"``; hinges in deg, elbow slides in m, elbow flexion
        held at 35 deg; ``static_s + 2 (with align_rotation) +
        len(grasps) * (2 * move_s + hold_s) + 0.5`` s long.

    Raises
    ------
    InvalidInputError
        An unknown grasp or `elbow`; `rate_hz` outside [10, 1000]; a motion
        that leaves a joint's range.
    """
    for g in grasps:
        if g not in GRASP_POSES:
            raise InvalidInputError(f"unknown grasp {g!r}; expected one of {', '.join(GRASP_POSES)}")
    return pose_motion([GRASP_POSES[g] for g in grasps], names=[f"grasp:{g}" for g in grasps],
                       rate_hz=rate_hz, hold_s=hold_s, move_s=move_s, static_s=static_s,
                       elbow=elbow, seed=seed, align_rotation=align_rotation, label="grasps")


def pose_motion(poses, *, names=None, rate_hz: float = 100.0, hold_s: float = 2.0,
                move_s: float = 1.0, static_s: float = 2.0, elbow: str = "fixed", seed: int = 0,
                align_rotation: bool = True, label: str = "poses") -> Motion:
    """Open hand, then each pose in turn: reach it (min-jerk), hold, release.

    :func:`grasp_motion` with poses of any source (another system's test poses, a
    recording's key poses).

    Parameters
    ----------
    poses : array_like, shape (K, 20)
        Hand poses, canonical joint order, degrees; each joint is held within its range.
    names : sequence of str, keyword-only, optional
        The hold segments' names (``pose:<k>`` by default).
    rate_hz, hold_s, move_s, static_s, elbow, seed, align_rotation
        As :func:`grasp_motion`'s.
    label : str, keyword-only
        The motion's label.

    Returns
    -------
    Motion
        ``static_s + 2 (with align_rotation) + K * (2 * move_s + hold_s) + 0.5`` s long.

    Raises
    ------
    InvalidInputError
        `poses` not a finite (K, 20) array with K >= 1, `names` not one per pose,
        `elbow` unknown, `rate_hz` outside [10, 1000], a motion longer than
        :data:`MAX_MOTION_S`.
    """
    if elbow not in ("fixed", "moving"):
        raise InvalidInputError(f"elbow must be 'fixed' or 'moving', got {elbow!r}")
    p = np.asarray(poses, dtype=np.float64)
    if p.ndim != 2 or p.shape[1] != len(JOINT_NAMES) or len(p) == 0 or not np.isfinite(p).all():
        raise InvalidInputError(f"poses must be a finite array of shape (K, {len(JOINT_NAMES)}) "
                                f"with K >= 1, degrees, got shape {p.shape}")
    names = [f"pose:{k}" for k in range(len(p))] if names is None else list(names)
    if len(names) != len(p):
        raise InvalidInputError(f"names must name each of the {len(p)} poses, got {len(names)}")
    lead = static_s + (2.0 if align_rotation else 0.0)
    dur = lead + len(p) * (2 * move_s + hold_s) + 0.5
    t = _grid(dur, rate_hz, f"length of the {label} motion")
    rest = _full_pose(arm={"elbow_flex": 35.0})
    q, qd, qdd = _base(t.size, rest)
    segs: list[tuple[str, int, int]] = [("static", 0, int(static_s * rate_hz))]
    if align_rotation:
        _oscillate(t, q, qd, qdd, "elbow_flex", 25.0, 0.5, static_s, static_s + 2.0, ramp=0.5)
        segs.append(("align", int(static_s * rate_hz), int(lead * rate_hz)))
    t0 = lead
    off = len(ARM_JOINTS)
    lo, hi = JOINT_LIMITS_DEG[:, 0], JOINT_LIMITS_DEG[:, 1]
    for name, pose in zip(names, np.clip(p, lo, hi)):
        for k in range(len(JOINT_NAMES)):
            if pose[k]:
                _minjerk_add(t, q, qd, qdd, off + k, pose[k], t0, t0 + move_s)
                _minjerk_add(t, q, qd, qdd, off + k, -pose[k], t0 + move_s + hold_s,
                             t0 + 2 * move_s + hold_s)
        segs.append((name, int((t0 + move_s) * rate_hz), int((t0 + move_s + hold_s) * rate_hz)))
        t0 += 2 * move_s + hold_s
    if elbow == "moving":
        rng = np.random.default_rng(seed)
        for j in ("elbow_x", "elbow_y", "elbow_z", "wrist_flex", "humeral_rot"):
            a = 0.04 if j.startswith("elbow_") else 10.0
            _oscillate(t, q, qd, qdd, j, a, rng.uniform(0.2, 0.6), lead, t[-1] + 1 / rate_hz,
                       ramp=0.8, phase=rng.uniform(0, 2 * np.pi))
    _clip_limits(q)
    return Motion(rate_hz, q, qd, qdd, label, tuple(segs))
