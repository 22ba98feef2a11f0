"""Sensor-to-joint-centre vectors and link vectors from rotations (seed 003 ch. 3).

For a rotation about a fixed centre, the accelerometer minus gravity is the
rotational acceleration (eq. 3.7)

    a_r = dw x P + w x (w x P)          (eq. 3.1 without the Coriolis term)

where P is the vector from the centre to the sensor (sensor frame).  At the
turning points of an oscillation (w ~ 0) only the tangential term is left,
perpendicular to P; two rotations about different axes give P's direction
as the cross product of their accelerations (eq. 3.2), its sign from the
construction of Fig. 3.2 (P . (a_r x dw) > 0), and its length as the slope
of |a_r| against sqrt(|dw|^2 - (u . dw)^2) (eqs. 3.3-3.4, 3.8, least
squares).  Every pair of turning points gives one direction; they are
averaged with the weights of eq. 3.9 (inverse deviation from the fitted
line, inverse RMSE of the predicted rotational acceleration over the whole
rotation) as in eq. 3.10.  One-axis joints pair their rotation with a
non-parallel rotation of the proximal two-axis joint for the direction and
use their own rotation alone for the length (Fig. 3.3).

Skin (an addition to the thesis): a sensor whose segment's proximal joint is
the one rotating slides and tilts with that joint's angle, so eq. 3.10 gives
its vector at the oscillation's mid-angle, not at the static pose.  With
``static_pose=True`` the vector is estimated from the turning points nearer
to and farther from the static pose separately and extrapolated linearly to
the static pose's angle.

Hinge centres (an addition to the thesis): a one-axis joint's rotation fixes
the distance of its centre from the sensor across its axis but not where
along the axis the centre lies, and eq. 3.2 with the second rotation of
another joint leaves that component biased (on the exact mounting of the
tuning configuration, 5-8 mm for the thumb's MCP and IP, 18-27 mm for the
ring/little carpometacarpal hinge).  Each sensor then names a slightly
different point on the axis, and a link measured by two sensors does not
close.  With ``hinge_plane=True`` every sensor takes the point of the axis
nearest the centre of the joint whose rotation eq. 3.2 pairs it with (the
wrist for the carpometacarpal hinge, the thumb CMC for the thumb's MCP and
IP, the finger's MCP for its PIP and DIP), estimated from the same sensor;
a fingertip sensor, which sits over the tip, takes the point nearest itself.

Link vectors (eq. 3.6, 3.11): the link from J1 to J2 measured by sensor S1 is
R_S1^T R_S2 (S2 P^J1 - S2 P^J2), S2 being the next link's sensor (the
temporary fingertip sensor for the distal phalanges, minus its height above
the tip, the thesis' "offset").

The hand's ulnar side (an addition to the thesis): the ring and little fingers' MCPs
are two links from the wrist, across the carpometacarpal hinge, whose centre each link
takes from another sensor (eq. 3.6: the ulnar hand sensor's view for the first link,
the proximal phalanx's for the second).  The hinge's small rotation (10 deg in
:data:`~handsynth.sensors.imu.CALIBRATION_PLAN`) sets that centre's distance from the
sensor by accelerations of a few hundredths of m/s^2, so with uncorrected sensors
(accelerometer scale and axes off by a few per cent) the two views of it parted by about
20 mm across the axis and the two links did not close: ring and little fingertips 18-32
mm from the truth where the other fingers' were 4-7 mm (standard hand, no skin motion, no
static poses).  The proximal phalanx's sensor sees the wrist and its own MCP through the
wrist's and MCP's large two-axis rotations; with its vector to the wrist in the vectors
(``calibrate_vectors`` adds it where ``hinge_plane``), the second link is that view of
wrist-to-MCP less the first link, so the two links close on it and the hinge's centre only
says how the hinge turns them.

Baseline: the least-squares joint position of Seel, Schauer & Raisch,
"Joint axis and position estimation from inertial measurement data by
exploiting kinematic constraints", IEEE CCA 2012: for two sensors on either
side of a joint, find o1, o2 minimising sum_t (|a1 + G1 o1| - |a2 + G2 o2|)^2,
G o = w x (w x o) + dw x o, o from sensor to joint, by Levenberg-Marquardt
from a starting guess; it needs no orientation.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from itertools import pairwise
from types import MappingProxyType

import numpy as np
from scipy.signal import savgol_filter

from ...errors import EstimationError, InvalidInputError
from ._attitude import StaticStart, initial_attitude
from ._layout import CHAINS, FLEX_JOINT, LINKS
from ._model import GRAVITY_MPS2
from ._quat import quat_to_mat
from ._recording import ImuRecording

__all__ = [
    "ROTATIONS",
    "ChainModel",
    "VectorEstimate",
    "calibrate_vectors",
    "chain_model",
    "link_vectors",
    "rotation_vector",
    "seel_joint_positions",
    "smoothed_motion",
    "truth_chain_model",
]

_FINGERS4 = ("index", "middle", "ring", "little")
#: The links across the hand's ulnar hinge -> the sensor that closes them on the wrist.
_ACROSS_HINGE = MappingProxyType({
    ("hand_ulnar", "ulnar_cm", f"{f}_mcp"): f"{f}_proximal" for f in ("ring", "little")})
#: The vectors that close them (not sensor-to-joint vectors of the sensor's own segment).
CLOSING_VECTORS = frozenset((sensor, "wrist") for sensor in _ACROSS_HINGE.values())

#: point -> (rotations giving the direction, rotations giving the length),
#: the calibration segments of :func:`calibration_motion` (seed 003 Table 3.5).
ROTATIONS = MappingProxyType({
    "elbow": (("elbow_flex", "humeral_rot"), ("elbow_flex", "humeral_rot")),
    "wrist": (("wrist_flex", "wrist_dev"), ("wrist_flex", "wrist_dev")),
    "ulnar_cm": (("ulnar_cm_flex", "wrist_dev"), ("ulnar_cm_flex",)),
    "thumb_cmc": (("thumb_cmc_flex", "thumb_cmc_abd"), ("thumb_cmc_flex", "thumb_cmc_abd")),
    "thumb_mcp": (("thumb_mcp_flex", "thumb_cmc_abd"), ("thumb_mcp_flex",)),
    "thumb_ip": (("thumb_ip_flex", "thumb_cmc_abd"), ("thumb_ip_flex",)),
    **{f"{f}_mcp": ((f"{f}_mcp_flex", f"{f}_mcp_abd"), (f"{f}_mcp_flex", f"{f}_mcp_abd"))
       for f in _FINGERS4},
    **{f"{f}_{j}": ((f"{f}_{j}_flex", f"{f}_mcp_abd"), (f"{f}_{j}_flex",))
       for f in _FINGERS4 for j in ("pip", "dip")},
})


@dataclass(frozen=True)
class VectorEstimate:
    """One sensor-to-centre vector.

    Attributes
    ----------
    vector : ndarray, shape (3,)
        From the centre to the sensor, sensor frame, metres (eq. 3.5).
    pairs : int
        Turning-point pairs that gave a direction (N1 N2 of eq. 3.10).
    r2 : float
        Coefficient of determination of the length fit (eq. 3.8, Fig. 3.7).
    axis : ndarray, shape (3,), or None
        For a one-axis joint, its axis in the sensor frame (the main axis of the
        gyro over the joint's own rotation, unit); None for a two-axis joint.
    """

    vector: np.ndarray
    pairs: int
    r2: float
    axis: np.ndarray | None = None


def _segment(rec_segments, label):
    for name, a, b in rec_segments:
        if name == label:
            return a, b
    have = ", ".join(name for name, _, _ in rec_segments) or "none"
    raise InvalidInputError(f"the calibration recording has no labelled stretch {label!r} "
                            f"(its labels: {have}; a label misspelled in the segments file?)")


def _turning_points(gyr, dgyr, *, frac_w=0.25, frac_dw=0.5):
    w = np.linalg.norm(gyr, axis=-1)
    dw = np.linalg.norm(dgyr, axis=-1)
    i = np.arange(1, w.size - 1)
    w_ref, dw_ref = np.percentile(w, 95), np.percentile(dw, 95)
    loc = (w[i] <= w[i - 1]) & (w[i] <= w[i + 1]) & (w[i] < frac_w * w_ref) \
        & (dw[i] > frac_dw * dw_ref)
    return i[loc]


#: Samples a labelled rotation needs at least: the shortest Savitzky-Golay window of its
#: gyro (:func:`_smoothing_windows`; more samples at rates above 100 Hz).
_MIN_ROTATION_SAMPLES = 5
#: Spans of the Savitzky-Golay fits (quadratic) of the gyro and its derivative and of the
#: accelerometer, s: 5 samples each at 100 Hz.  Fixed in time, not in samples: 7 gyro samples
#: at 1,000 Hz differentiated ten times as much noise per second as at 100 Hz (the
#: datasheet noise's s.d. per sample grows with the square root of the rate) and took the
#: held-out elbow vectors 25-36 mm from the truth.  The gyro's 50 ms was chosen on the
#: tuning configuration at 100 Hz against the 70 ms (7 samples) used before and 90 ms:
#: sensor-to-joint vectors 0.70-0.85 mm median against 0.77-0.93 and 0.83-1.06 on four
#: draws (a 30-ms accelerometer span: 1.06-1.17 mm).
_GYRO_SPAN_S, _ACC_SPAN_S = 0.05, 0.05


def _smoothing_windows(rate_hz: float) -> tuple[int, int]:
    """Odd Savitzky-Golay windows (gyro, accelerometer), samples, for `rate_hz`.

    ``(5, 5)`` at 100 Hz and below, growing with the rate above it so that each covers
    :data:`_GYRO_SPAN_S` and :data:`_ACC_SPAN_S`.
    """
    def odd(n: float) -> int:
        return max(_MIN_ROTATION_SAMPLES, int(round(n)) // 2 * 2 + 1)

    return odd(_GYRO_SPAN_S * rate_hz), odd(_ACC_SPAN_S * rate_hz)


def _min_rotation_samples(rate_hz: float) -> int:
    """Samples a labelled rotation needs at least at `rate_hz` (its gyro's smoothing window)."""
    return _smoothing_windows(rate_hz)[0]


def _rotation_data(rec: ImuRecording, k: int, a: int, b: int, hold: int):
    """gyro, angular acceleration and rotational acceleration (eq. 3.7) of sensor k on a:b."""
    dt = 1.0 / rec.rate_hz
    wg, wa = _smoothing_windows(rec.rate_hz)
    gyr = rec.gyr[k, a:b] - rec.gyr[k, a:a + hold].mean(axis=0)
    gyr_s = savgol_filter(gyr, wg, 2, axis=0)
    dgyr = savgol_filter(gyr, wg, 2, deriv=1, delta=dt, axis=0)
    acc = savgol_filter(rec.acc[k, a:b], wa, 2, axis=0)
    # gravity in the sensor frame: from the still start, carried along by the gyro
    g = rec.acc[k, a:a + hold].mean(axis=0)
    g *= GRAVITY_MPS2 / np.linalg.norm(g)
    gs = np.empty_like(acc)
    from ._filters import integrate_gyro

    q = integrate_gyro(np.array([[1.0, 0, 0, 0]]), gyr[None], rec.rate_hz)[0]
    r = quat_to_mat(q)                                  # S(0) <- S(t)
    gs[:] = np.einsum("nji,j->ni", r, g)
    return gyr_s, dgyr, acc - gs                        # eq. 3.7


def _direction_and_length(data: dict, pts: dict, dir_rot, len_rot) -> tuple[np.ndarray, int, float]:
    """Eqs. 3.2-3.10 on the turning points `pts` (label -> sample indices)."""
    a1 = data[dir_rot[0]][2][pts[dir_rot[0]]]
    a2 = data[dir_rot[1]][2][pts[dir_rot[1]]]
    dw1 = data[dir_rot[0]][1][pts[dir_rot[0]]]
    u = np.cross(a1[:, None], a2[None]).reshape(-1, 3)                    # eq. 3.2
    norm = np.linalg.norm(u, axis=-1)
    keep = norm > 1e-3 * norm.max()
    u = u[keep] / norm[keep, None]
    # sign (Fig. 3.2): P . (a_r x dw) > 0 for the first rotation's samples
    ref = np.cross(a1, dw1).mean(axis=0)
    u *= np.sign(u @ ref)[:, None]
    # length (eqs. 3.3-3.4, 3.8): |a_r| = |P| sqrt(|dw|^2 - (u . dw)^2), per u_i
    a_len = np.concatenate([data[lab][2][pts[lab]] for lab in len_rot])
    dw_len = np.concatenate([data[lab][1][pts[lab]] for lab in len_rot])
    y = np.linalg.norm(a_len, axis=-1)
    x = np.sqrt(np.maximum(np.sum(dw_len**2, -1)[None] - (u @ dw_len.T) ** 2, 0.0))  # (U, M)
    length = float(np.sum(x * y) / np.sum(x * x))
    d = np.sqrt(np.mean((y - length * x) ** 2, axis=1)) + 1e-9          # deviation from the line
    w1 = 1.0 / d                                                        # eq. 3.9
    # w2: RMSE of eq. 3.1 (first two terms) over each direction rotation
    w2 = np.zeros(len(u))
    for lab in dir_rot:
        gyr_s, dgyr, a_r = data[lab]
        p = length * u                                                  # (U, 3)
        pred = np.cross(dgyr[None], p[:, None]) + np.cross(
            gyr_s[None], np.cross(gyr_s[None], p[:, None]))
        w2 += np.sum(np.mean((pred - a_r[None]) ** 2, axis=1), axis=1)
    w2 = 1.0 / np.sqrt(w2)
    w = w1 * w2
    u_mean = np.sum(w[:, None] * u, axis=0) / np.sum(w)                 # eq. 3.10
    u_mean /= np.linalg.norm(u_mean)
    x_all = np.sqrt(np.maximum(np.sum(dw_len**2, -1) - (dw_len @ u_mean) ** 2, 0))
    length = float(np.sum(x_all * y) / np.sum(x_all * x_all))
    res = y - length * x_all
    r2 = 1.0 - float(np.sum(res**2) / max(np.sum((y - y.mean()) ** 2), 1e-12))
    return length * u_mean, int(len(u)), r2                             # eq. 3.5


def _main_axis(gyr_s: np.ndarray) -> np.ndarray:
    """Unit axis about which the smoothed gyro (N, 3) turns most (its first principal direction)."""
    return np.linalg.svd(gyr_s, full_matrices=False)[2][0]


def _turned_angle(gyr_s: np.ndarray, rate_hz: float) -> np.ndarray:
    """Angle turned since the still start about the rotation's main axis, rad."""
    return np.cumsum(gyr_s @ _main_axis(gyr_s)) / rate_hz


def rotation_vector(rec: ImuRecording, sensor: str, point: str, *, hold_s: float = 0.5,
                    static_pose: bool = True) -> VectorEstimate:
    """Vector from `point` (a joint centre) to `sensor` from calibration rotations.

    Parameters
    ----------
    rec : ImuRecording
        A recording of :func:`calibration_motion` (its truth's ``segments``
        locate the rotations; recordings from elsewhere pass the same names).
    sensor : str
    point : str
        A key of :data:`ROTATIONS`.
    hold_s : float, keyword-only
        Still time at the start of every rotation (gravity and gyro bias).
    static_pose : bool, keyword-only
        For a sensor whose own segment's flexion is the rotation (its skin
        moves with the angle), estimate the vector twice, from the turning
        points nearer to and farther from the static pose, and extrapolate
        linearly to the static pose's angle (an addition to the thesis; the
        skin moves the sensor, so eq. 3.10 alone gives the vector at the
        oscillation's mid-angle).  False: eqs. 3.2-3.10 alone.

    Returns
    -------
    VectorEstimate
    """
    if point not in ROTATIONS:
        raise InvalidInputError(f"no calibration rotations for {point!r}; expected one of "
                                f"{', '.join(ROTATIONS)}")
    segments = rec.labelled()
    k = rec.index(sensor)
    hold = max(3, int(hold_s * rec.rate_hz))
    dir_rot, len_rot = ROTATIONS[point]
    data = {}
    for lab in dir_rot:
        a, b = _segment(segments, lab)
        if b - a < _min_rotation_samples(rec.rate_hz):
            raise EstimationError(
                f"rotation {lab!r} spans {b - a} samples ({(b - a) / rec.rate_hz:.3g} s); at least "
                f"{_min_rotation_samples(rec.rate_hz)} are needed, and turning points need seconds (rotate "
                "longer, or check its span in the segments)")
        data[lab] = _rotation_data(rec, k, a, b, hold)
    pts = {lab: _turning_points(data[lab][0], data[lab][1]) for lab in dir_rot}
    for lab, idx in pts.items():
        if idx.size < 2:
            raise EstimationError(f"sensor {sensor!r}: rotation {lab!r} has {idx.size} usable "
                                  "turning points (need >= 2; rotate faster or longer)")
    vector, pairs, r2 = _direction_and_length(data, pts, dir_rot, len_rot)
    flex = len_rot[0]
    if static_pose and FLEX_JOINT.get(sensor) == flex and pts[flex].size >= 4:
        phi = _turned_angle(data[flex][0], rec.rate_hz)[pts[flex]]
        near = np.abs(phi) <= np.median(np.abs(phi))
        ends = []
        for part in (near, ~near):
            sub = dict(pts, **{flex: pts[flex][part]})
            ends.append((_direction_and_length(data, sub, dir_rot, len_rot)[0],
                         float(phi[part].mean())))
        (p_near, a_near), (p_far, a_far) = ends
        if abs(a_far - a_near) > np.radians(10.0):
            vector = p_near - a_near / (a_far - a_near) * (p_far - p_near)
    axis = _main_axis(data[len_rot[0]][0]) if len(len_rot) == 1 else None
    return VectorEstimate(vector, pairs, r2, axis)


def _child(sensor: str, dist: str) -> str:
    """Sensor of the link that starts at `dist` after `sensor`'s link."""
    for chain in CHAINS.values():
        for (s1, _, d1), nxt in pairwise(chain):
            if s1 == sensor and d1 == dist:
                return nxt[0]
    # the distal phalanx: its fingertip sensor
    return dist  # e.g. "index_tip" is also the tip sensor's name


def calibrate_vectors(rec: ImuRecording, *, hold_s: float = 0.5, static_pose: bool = True,
                      hinge_plane: bool = True) -> dict:
    """Every vector the link model and the EKF need, from a calibration recording.

    `hold_s` and `static_pose` as :func:`rotation_vector`.

    Parameters
    ----------
    rec : ImuRecording
        A calibration recording with every sensor of :data:`LINKS` and the
        fingertip sensors, and the labelled rotations of :data:`ROTATIONS`.
    hold_s : float, keyword-only
        Still time at the start of every rotation, s (gravity and gyro bias).
    static_pose : bool, keyword-only
        Extrapolate the vectors of sensors whose skin moves with the rotation
        to the static pose (see :func:`rotation_vector`).
    hinge_plane : bool, keyword-only
        Place each one-axis joint's centre, which its rotation leaves free
        along its axis, at the point of the axis nearest the centre of the
        joint eq. 3.2 pairs it with, as seen by the same sensor (a fingertip
        sensor: nearest itself), so that every sensor names the same point
        (an addition to the thesis, see the module's notes).  False: eq.
        3.2's direction as it falls (the thesis).

    Returns
    -------
    dict
        ``(sensor, point) -> VectorEstimate`` for each link's own sensor to
        its proximal point and the next link's sensor to both ends; where
        `hinge_plane`, also the ring and little fingers' proximal phalanx
        sensors to the wrist (the links across the hand's ulnar hinge close
        on them, see the module's notes).

    Raises
    ------
    InvalidInputError
        A rotation the recording has no labelled stretch for.
    RecordingError
        A sensor missing from the recording.
    EstimationError
        A rotation with fewer than 2 usable turning points.
    """
    out = {}
    for s1, j1, j2 in LINKS:
        s2 = _child(s1, j2)
        wanted = [(s1, j1), (s2, j1)]
        if not j2.endswith("_tip"):
            wanted.append((s2, j2))
        else:
            wanted.append((s1, j1))
        for s, p in wanted:
            if (s, p) not in out:
                out[(s, p)] = rotation_vector(rec, s, p, hold_s=hold_s, static_pose=static_pose)
    # the distal sensors' and tip sensors' own DIP/IP vectors
    for chain in CHAINS.values():
        _, j_prox, tip = chain[-1]
        out.setdefault((tip, j_prox), rotation_vector(rec, tip, j_prox, hold_s=hold_s,
                                                      static_pose=static_pose))
    if hinge_plane:
        # the ulnar fingers' view of the wrist (the module's notes); first, so that the
        # hinge plane of their carpometacarpal vectors, paired with the wrist, reads it
        for sensor, point in sorted(CLOSING_VECTORS):
            out[(sensor, point)] = rotation_vector(rec, sensor, point, hold_s=hold_s,
                                                   static_pose=static_pose)
        out = _hinge_plane(rec, out, hold_s=hold_s, static_pose=static_pose)
    return out


def _paired_joint(point: str) -> str | None:
    """The joint whose rotation eq. 3.2 pairs with one-axis `point`'s own; None for two-axis points."""
    dir_rot, len_rot = ROTATIONS[point]
    if len(len_rot) > 1:
        return None
    return dir_rot[1].rsplit("_", 1)[0]     # "index_mcp_abd" -> "index_mcp", "wrist_dev" -> "wrist"


def _hinge_plane(rec: ImuRecording, vectors: dict, *, hold_s: float, static_pose: bool) -> dict:
    """`vectors` with every one-axis joint's centre moved along its axis to the point nearest
    the paired joint's centre (fingertip sensors: nearest the sensor), see the module's notes.

    A sensor whose own view of the paired joint cannot be estimated (too few turning
    points) keeps eq. 3.2's vector."""
    out = dict(vectors)
    refs = dict(vectors)    # and the paired joints' vectors computed here, once each
    for (sensor, point), est in vectors.items():
        ref = _paired_joint(point)
        if ref is None or est.axis is None:
            continue
        if sensor.endswith("_tip"):
            along = 0.0
        else:
            if (sensor, ref) not in refs:
                try:
                    refs[(sensor, ref)] = rotation_vector(rec, sensor, ref, hold_s=hold_s,
                                                          static_pose=static_pose)
                except EstimationError:     # too few turning points seen from here:
                    refs[(sensor, ref)] = None  # keep eq. 3.2's answer for this sensor
            if refs[(sensor, ref)] is None:
                continue
            along = float(refs[(sensor, ref)].vector @ est.axis)
        v, n = est.vector, est.axis
        out[(sensor, point)] = replace(est, vector=v + (along - float(v @ n)) * n)
    return out


def link_vectors(rec: ImuRecording, vectors: dict, *, static: StaticStart | None = None,
                 tip_offset_m: float = 0.004) -> dict:
    """Link vectors in their own sensor's frame, eq. 3.6 / 3.11.

    Parameters
    ----------
    rec : ImuRecording
        The calibration recording (its static start gives the relative
        rotations R_S1^T R_S2, eqs. 2.7, 2.9, 2.11 with the azimuth alignment
        of section 4.2.5 on its first rotation).
    vectors : dict
        ``(sensor, point) -> (3,)`` or VectorEstimate.
    tip_offset_m : float, keyword-only
        Height of the fingertip sensors above the fingertip point.

    Returns
    -------
    dict
        ``(sensor, proximal point, distal point) -> (3,)`` metres.
    """
    _check_vector_keys(vectors)
    vec = {k: (v.vector if isinstance(v, VectorEstimate) else np.asarray(v, float))
           for k, v in vectors.items()}
    if static is None:
        static = _calibration_static(rec)
    r = quat_to_mat(initial_attitude(rec, static))
    out = {}
    for s1, j1, j2 in LINKS:
        s2 = _child(s1, j2)
        r12 = r[rec.index(s1)].T @ r[rec.index(s2)]
        if j2.endswith("_tip"):
            tip = vec[(s2, j1)] - np.array([0.0, 0.0, tip_offset_m])
            out[(s1, j1, j2)] = r12 @ tip
        else:
            out[(s1, j1, j2)] = r12 @ (vec[(s2, j1)] - vec[(s2, j2)])     # eq. 3.6
    for link, s2 in _ACROSS_HINGE.items():  # closed on the wrist (the module's notes)
        if (s2, "wrist") not in vec:
            continue
        s1, _, mcp = link
        first = next(k for k in LINKS if k[0] == "hand_radial" and k[2] == link[1])
        to_s1 = r[rec.index(s1)].T
        wrist_to_mcp = to_s1 @ r[rec.index(s2)] @ (vec[(s2, "wrist")] - vec[(s2, mcp)])
        out[link] = wrist_to_mcp - to_s1 @ r[rec.index(first[0])] @ out[first]
    return out


def _needed_vector_keys() -> list[tuple[str, str]]:
    """The (sensor, joint) vectors that the link model of :data:`LINKS` reads, in order."""
    keys: dict[tuple[str, str], None] = {}
    for s1, j1, j2 in LINKS:
        s2 = _child(s1, j2)
        keys[(s1, j1)] = None
        keys[(s2, j1)] = None
        if not j2.endswith("_tip"):
            keys[(s2, j2)] = None
    return list(keys)


def _check_vector_keys(vectors) -> None:
    """Refuse `vectors` without every key the link model reads, naming the first missing."""
    if not isinstance(vectors, dict):
        raise InvalidInputError(f"vectors must be a dict of (sensor, joint) -> vector, as "
                                f"calibrate_vectors returns, got {type(vectors).__name__}")
    needed = _needed_vector_keys()
    missing = [f"{s}->{j}" for s, j in needed if (s, j) not in vectors]
    if missing:
        raise InvalidInputError(f"vectors lacks {len(missing)} of the {len(needed)} sensor-to-joint "
                                f"vectors the link model needs: {', '.join(missing[:4])}"
                                + (", ..." if len(missing) > 4 else "")
                                + " (keys are (sensor, joint) pairs, as calibrate_vectors returns)")


def _calibration_static(rec: ImuRecording) -> StaticStart:
    segs = rec.labelled()
    static_end = _segment(segs, "static")[1] / rec.rate_hz
    a, b = _segment(segs, "elbow_flex")
    return StaticStart(static_s=static_end, align_start_s=a / rec.rate_hz,
                       align_end_s=b / rec.rate_hz)


@dataclass(frozen=True)
class ChainModel:
    """Link model of the system: vectors every chain estimator needs.

    Attributes
    ----------
    own : dict
        sensor -> (3,) vector from its link's proximal point to the sensor
        (S P^J of eq. 4.27), sensor frame, metres.
    links : dict
        (sensor, proximal, distal) -> (3,) link vector (eq. 3.11), sensor frame.
    """

    own: dict
    links: dict

    def link(self, sensor: str) -> tuple[str, str, np.ndarray]:
        for (s, a, b), v in self.links.items():
            if s == sensor:
                return a, b, v
        raise InvalidInputError(f"no link measured by sensor {sensor!r}")


def chain_model(rec: ImuRecording, vectors: dict | None = None, **kw) -> ChainModel:
    """The link model from a calibration recording (eqs. 3.2-3.11).

    Parameters
    ----------
    rec : ImuRecording
        The calibration recording; its static start gives the relative
        rotations of :func:`link_vectors`.
    vectors : dict, optional
        ``(sensor, point) -> (3,)`` vector (metres, sensor frame) or
        :class:`VectorEstimate`, as :func:`calibrate_vectors` returns; None
        computes them with :func:`calibrate_vectors`'s defaults.
    **kw
        Passed to :func:`link_vectors` (``static``, ``tip_offset_m``).

    Returns
    -------
    ChainModel
        Vectors in metres.

    Raises
    ------
    InvalidInputError
        `vectors` lacks a link's own sensor-to-proximal-point vector (a
        missing next-link vector raises ``KeyError`` in :func:`link_vectors`);
        without ``static``, a recording without the ``"static"`` and
        ``"elbow_flex"`` stretches; as :func:`calibrate_vectors`.
    RecordingError, EstimationError
        As :func:`calibrate_vectors` when `vectors` is None; the azimuth
        alignment of the static start (:func:`azimuth_correction`) may raise
        EstimationError too.
    """
    vectors = vectors if vectors is not None else calibrate_vectors(rec)
    _check_vector_keys(vectors)
    own = {}
    for s1, j1, _ in LINKS:
        v = vectors[(s1, j1)]
        own[s1] = v.vector if isinstance(v, VectorEstimate) else np.asarray(v, float)
    return ChainModel(own, link_vectors(rec, vectors, **kw))


def truth_chain_model(rec: ImuRecording) -> ChainModel:
    """The exact link model of a simulated recording (for tests and as a reference).

    Parameters
    ----------
    rec : ImuRecording
        A simulated recording: its truth's ``joint_vectors`` (zero pose,
        nominal mounting) give every vector.

    Returns
    -------
    ChainModel
        Vectors in metres, each sensor's frame.

    Raises
    ------
    InvalidInputError
        `rec` has no truth.
    """
    if rec.truth is None:
        raise InvalidInputError("truth_chain_model needs a simulated recording")
    jv = rec.truth.joint_vectors
    own = {s1: jv[(s1, j1)] for s1, j1, _ in LINKS}
    links = {(s1, j1, j2): jv[(s1, j1)] - jv[(s1, j2)] for s1, j1, j2 in LINKS}
    return ChainModel(own, links)


def seel_joint_positions(rec: ImuRecording, s1: str, s2: str, *, iterations: int = 30,
                         start: int = 0, stop: int | None = None,
                         init=None) -> tuple[np.ndarray, np.ndarray]:
    """Least-squares joint position between two sensors (Seel et al. 2012).

    Parameters
    ----------
    rec : ImuRecording
    s1, s2 : str
        Sensors on the proximal and distal segments of the joint.
    iterations : int, keyword-only
        Gauss-Newton steps.
    start, stop : int, keyword-only
        Samples used.
    init : (6,) float, keyword-only
        Starting o1, o2 (metres); 1 cm below both sensors by default.

    Returns
    -------
    o1, o2 : ndarray, shape (3,)
        The joint centre in each sensor's frame (sensor -> joint, i.e. -P).
    """
    stop = rec.n if stop is None else stop
    g1, d1, a1 = smoothed_motion(rec, rec.index(s1), start, stop)
    g2, d2, a2 = smoothed_motion(rec, rec.index(s2), start, stop)

    def gamma(g, d):
        # K with K o = w x (w x o) + dw x o
        wx = _skew(g)
        return wx @ wx + _skew(d)

    k1m, k2m = gamma(g1, d1), gamma(g2, d2)
    x = np.r_[0.0, 0.0, -0.01, 0.0, 0.0, -0.01] if init is None else np.asarray(init, float)

    def residual(x):
        # the joint centre's specific force seen from either sensor: a + G o
        e1 = a1 + np.einsum("nij,j->ni", k1m, x[:3])
        e2 = a2 + np.einsum("nij,j->ni", k2m, x[3:])
        n1 = np.linalg.norm(e1, axis=-1) + 1e-12
        n2 = np.linalg.norm(e2, axis=-1) + 1e-12
        return n1 - n2, e1 / n1[:, None], e2 / n2[:, None]

    lam = 1e-3
    r, u1, u2 = residual(x)
    cost = float(r @ r)
    for _ in range(iterations):
        jac = np.concatenate([np.einsum("ni,nij->nj", u1, k1m),
                              -np.einsum("ni,nij->nj", u2, k2m)], axis=1)
        jtj = jac.T @ jac
        # Levenberg-Marquardt; the damping also keeps the position along a
        # hinge axis (not observable) near the start
        step = np.linalg.solve(jtj + lam * (np.diag(np.diag(jtj)) + 1e-9 * np.eye(6)), -jac.T @ r)
        r2, v1, v2 = residual(x + step)
        c2 = float(r2 @ r2)
        if c2 < cost:
            x, r, u1, u2, cost = x + step, r2, v1, v2, c2
            lam = max(lam / 3, 1e-7)
            if np.linalg.norm(step) < 1e-7:
                break
        else:
            lam *= 10
            if lam > 1e8:
                break
    # a hinge leaves the position along its axis free (both o shift along
    # it); as Seel et al., move the solution along such weakly determined
    # directions to the point closest to the sensors
    jac = np.concatenate([np.einsum("ni,nij->nj", u1, k1m),
                          -np.einsum("ni,nij->nj", u2, k2m)], axis=1)
    ev, vec = np.linalg.eigh(jac.T @ jac)
    null = vec[:, ev < 1e-3 * ev.max()]
    x = x - null @ (null.T @ x)
    return x[:3], x[3:]


def smoothed_motion(rec: ImuRecording, k: int, start: int = 0,
                    stop: int | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Sensor `k`'s angular rate, its derivative and its specific force, smoothed.

    Quadratic Savitzky-Golay filters over a fixed time (:func:`_smoothing_windows`), as
    eqs. 3.1-3.10 read them.

    Returns
    -------
    w : ndarray, shape (N, 3), rad/s
    dw : ndarray, shape (N, 3), rad/s^2
    a : ndarray, shape (N, 3), m/s^2
        Samples `start` to `stop` of the recording.
    """
    stop = rec.n if stop is None else stop
    wg, wa = _smoothing_windows(rec.rate_hz)
    gyr = rec.gyr[k, start:stop]
    return (savgol_filter(gyr, wg, 2, axis=0),
            savgol_filter(gyr, wg, 2, deriv=1, delta=1.0 / rec.rate_hz, axis=0),
            savgol_filter(rec.acc[k, start:stop], wa, 2, axis=0))


def _skew(v):
    z = np.zeros(v.shape[:-1])
    x, y, w = v[..., 0], v[..., 1], v[..., 2]
    return np.stack([np.stack([z, -w, y], -1), np.stack([w, z, -x], -1),
                     np.stack([-y, x, z], -1)], -2)
