"""Evaluation on simulated data: the thesis' tables against trivial baselines.

Two simulator configurations:

- ``tuning``: the standard hand, datasheet noise (:data:`MPU9250_DATASHEET`),
  sensors exactly where :class:`ImuPlacement` puts them, no skin motion.
  The filters' options were chosen on this one.
- ``heldout``: another hand (longer, narrower), other noise figures
  (:data:`EVAL_NOISE`, with a magnet near the hand from 14 to 19 s), every
  sensor tilted (5 deg s.d. per axis) and shifted (2 mm s.d.) on its segment,
  and skin motion (:class:`SkinMotion`).  Nothing was tuned on it.

Every recording of one configuration is made with the same physical
sensors (``device_seed``): their scale/cross-axis errors, turn-on biases and
magnetometer hard and soft iron are fixed, so the accelerometer, gyro and
magnetometer calibration fitted on the calibration recording is applied to
every trial (``sensor_calibration=False`` leaves the trials uncorrected).

Each trial is a free motion of 15 or 30 s with the elbow fixed or moving
(as the thesis' section 4.4); orientation RMSE is per segment over the
motion (after the static start and the alignment rotation).  Beside every
filter stand two trivial answers: ``constant`` (the initial attitude held)
and ``raw`` (gyro integration).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from dataclasses import dataclass, field
from functools import partial
from typing import Any

import numpy as np

from ...errors import InvalidInputError
from ...models import JOINT_NAMES, HandShape
from ._calibration import ImuCalibration, calibrate
from ._ekf import FILTER4B, ChainEKF, ChainEKFOptions
from ._filters import (
    AhrsEKFEstimator,
    ConstantEstimator,
    Filter1,
    MadgwickEstimator,
    MahonyEstimator,
    RawIntegration,
    VQFEstimator,
)
from ._gated import GatedFilter
from ._kinematics import classify_grasp, fingertip_positions, joint_angles
from ._layout import CHAINS, LINKS, POINTS
from ._model import SENSOR_NAMES, ImuHand, ImuPlacement
from ._motion import GRASP_POSES, calibration_motion, free_motion, grasp_motion, static_motion
from ._noise import EVAL_NOISE, MPU9250_DATASHEET, ImuNoise
from ._quat import angle_deg, heading_inclination_deg, heading_rad, qexp, qmul
from ._recording import ImuRecording, ImuTruth, check_recording
from ._sensorcal import SensorCalibration
from ._simulate import SkinMotion, simulate_imu
from ._vectors import CLOSING_VECTORS, link_vectors, seel_joint_positions, truth_chain_model

__all__ = ["COMPASS_FILTERS", "FILTERS", "HELDOUT", "TUNING", "SimConfig", "evaluate", "evaluate_trial",
           "make_filter"]

#: Names of the orientation estimators that :func:`evaluate` can run.
FILTERS: tuple[str, ...] = ("constant", "raw", "filter1", "filter4", "filter4b", "gated", "vqf",
                            "vqf_online", "madgwick", "mahony", "ahrs_ekf")
#: Those of :data:`FILTERS` that observe the compass, and so refuse 6-axis sensors.
COMPASS_FILTERS: tuple[str, ...] = ("filter1", "madgwick", "mahony", "ahrs_ekf")


@dataclass(frozen=True)
class SimConfig:
    """One simulator configuration (frozen).

    Parameters
    ----------
    label : str
    shape : HandShape
    noise : ImuNoise
    tilt_sd_deg, offset_sd_mm : float
        Random mounting errors of every sensor on its segment.
    skin : SkinMotion or None
    seed : int
    """

    label: str
    shape: HandShape = field(default_factory=HandShape)
    noise: ImuNoise = MPU9250_DATASHEET
    tilt_sd_deg: float = 0.0
    offset_sd_mm: float = 0.0
    skin: SkinMotion | None = None
    seed: int = 0

    def placement(self) -> ImuPlacement:
        rng = np.random.default_rng(self.seed + 1000)
        tilts = {s: tuple(rng.normal(0, self.tilt_sd_deg, 3)) for s in SENSOR_NAMES} \
            if self.tilt_sd_deg else {}
        offs = {s: tuple(rng.normal(0, self.offset_sd_mm, 3) * np.array([1, 1, 0.3]))
                for s in SENSOR_NAMES} if self.offset_sd_mm else {}
        return ImuPlacement(tilts_deg=tilts, offsets_mm=offs)

    def describe(self) -> dict:
        return {"label": self.label, "hand_shape": self.shape.name, "noise": self.noise.label,
                "tilt_sd_deg": self.tilt_sd_deg, "offset_sd_mm": self.offset_sd_mm,
                "skin_motion": None if self.skin is None else dataclasses.asdict(self.skin),
                "magnetic_disturbances": [dataclasses.asdict(d) for d in self.noise.disturbances],
                "seed": self.seed}


TUNING = SimConfig("tuning")
HELDOUT = SimConfig("heldout", HandShape(length=1.08, width=0.93, palm=0.95), EVAL_NOISE,
                    tilt_sd_deg=5.0, offset_sd_mm=2.0, skin=SkinMotion(2.0, 4.0), seed=1)


def make_filter(name: str, model=None):
    """An estimator by name (``filter4`` needs the link model).

    Parameters
    ----------
    name : str
        One of :data:`FILTERS`.
    model : ChainModel, optional
        The link model (:func:`chain_model`), needed by ``"filter4"`` and
        ``"filter4b"``; ignored by the others.

    Returns
    -------
    OrientationEstimator
        A new estimator with its default options (``"filter4b"``:
        :data:`FILTER4B`; ``"vqf_online"``: :class:`VQFEstimator` with
        ``online=True``).

    Raises
    ------
    InvalidInputError
        An unknown `name`; ``"filter4"`` or ``"filter4b"`` without `model`, or
        with one that is no :class:`ChainModel`.
    """
    table: dict[str, Callable[[], Any]] = {
        "constant": ConstantEstimator, "raw": RawIntegration, "filter1": Filter1,
        "gated": GatedFilter, "vqf": VQFEstimator,
        "vqf_online": partial(VQFEstimator, online=True, name="vqf_online"),
        "madgwick": MadgwickEstimator, "mahony": MahonyEstimator, "ahrs_ekf": AhrsEKFEstimator}
    chain = {"filter4": ChainEKFOptions(), "filter4b": FILTER4B}  # need the link model
    if name in chain:
        if model is None:
            raise InvalidInputError(f"{name} needs a link model (calibration)")
        return ChainEKF(model, options=chain[name], name=name)
    if name not in table:
        raise InvalidInputError(f"unknown filter {name!r}; expected one of {', '.join(FILTERS)}")
    return table[name]()


def _rmse(x, axis=None):
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # all-NaN columns (thumb CMC) stay NaN
        m = np.sqrt(np.nanmean(np.square(x), axis=axis))
    return float(m) if axis is None else m


def _truth(rec: ImuRecording) -> ImuTruth:
    if rec.truth is None:
        raise InvalidInputError("evaluation needs simulated recordings with truth")
    return rec.truth


def _vector_errors(est: dict, truth: dict) -> dict:
    err = {f"{s}<-{p}": float(np.linalg.norm(np.asarray(v) - truth[(s, p)]) * 1e3)
           for (s, p), v in est.items()}
    vals = np.array(list(err.values()))
    return {"median_mm": float(np.median(vals)), "mean_mm": float(vals.mean()),
            "max_mm": float(vals.max()), "n": int(vals.size), "per_vector_mm": err}


def _device_seed(config: SimConfig) -> int:
    return config.seed + 900


def _calibration_recording(config: SimConfig, placement: ImuPlacement | None = None, *,
                           acc_poses: bool = True) -> ImuRecording:
    """The configuration's calibration recording as the eval simulates it: its hand with the
    fingertip sensors, its noise without the magnet, its skin motion and physical sensors
    (``device_seed``); with the static poses, or without them (the thesis' protocol)."""
    hand = ImuHand(config.shape, placement=config.placement() if placement is None else placement,
                   tip_sensors=True)
    quiet = dataclasses.replace(config.noise, disturbances=())
    return simulate_imu(calibration_motion(acc_poses=acc_poses), hand=hand, noise=quiet,
                        skin=config.skin, seed=config.seed + 7, device_seed=_device_seed(config))


def _calibrate(config: SimConfig, placement: ImuPlacement, *, six_axis: bool = False):
    cal = _calibration_recording(config, placement)
    if six_axis:  # the same sensors' accelerometers and gyros only
        cal = dataclasses.replace(cal, mag=None)
    # accelerometer, gyro and magnetometer corrections from the static poses, kept in
    # the calibration for the later recordings of the same sensors
    calib = calibrate(cal)
    sensor_cal = calib.sensor_calibration
    if sensor_cal is None:
        raise InvalidInputError("the calibration recording has no static poses")
    return sensor_cal.apply(cal), calib, sensor_cal


def _vector_report(cal, model, config: SimConfig, placement, lsq_rec) -> dict:
    from ._vectors import calibrate_vectors

    truth = _truth(cal).joint_vectors
    vec = calibrate_vectors(cal)
    thesis_vec = calibrate_vectors(cal, hinge_plane=False)

    def own(vectors: dict) -> dict:
        """Each sensor's to its own segment's joints (not the ulnar fingers' views of the
        wrist, which only close the links across the hand's hinge)."""
        return {k: v.vector for k, v in vectors.items()
                if not k[0].endswith("_tip") and k not in CLOSING_VECTORS}

    rot, plain = own(vec), own(calibrate_vectors(cal, static_pose=False))
    thesis = own(thesis_vec)
    # baseline 1: the standard hand with sensors where they should be
    std = simulate_imu(static_motion(0.1), hand=ImuHand(tip_sensors=True), noise=None)
    std_vec = _truth(std).joint_vectors
    nominal = {k: std_vec[k] for k in rot}
    zero_vec = {k: np.zeros(3) for k in rot}
    # baseline 2: least squares (Seel et al. 2012) on a free motion, per joint
    lsq: dict = {}
    for s1, _, j2 in LINKS:
        child = next((lk[0] for lk in LINKS if lk[1] == j2), None)
        if child is None:
            continue
        # started from the standard hand's vectors, as a user would
        init = np.r_[-std_vec[(s1, j2)], -std_vec[(child, j2)]]
        o1, o2 = seel_joint_positions(lsq_rec, s1, child, start=int(4 * lsq_rec.rate_hz),
                                      init=init)
        if (s1, j2) in truth:
            lsq.setdefault((s1, j2), -o1)
        lsq.setdefault((child, j2), -o2)
    rot_common = {k: rot[k] for k in lsq if k in rot}
    truth_links = truth_chain_model(cal).links
    link_err = {f"{s}:{a}->{b}": float(np.linalg.norm(v - truth_links[(s, a, b)]) * 1e3)
                for (s, a, b), v in model.links.items()}
    lv = np.array(list(link_err.values()))
    lt = np.array([np.linalg.norm(v - truth_links[k]) * 1e3
                   for k, v in link_vectors(cal, thesis_vec).items()])
    return {
        "rotation_method": _vector_errors(rot, truth),
        "rotation_method_eq310_only": _vector_errors(plain, truth),
        "rotation_method_without_hinge_plane": _vector_errors(thesis, truth),
        "rotation_method_on_lsq_pairs": _vector_errors(rot_common, truth),
        "least_squares_seel": _vector_errors(lsq, truth),
        "baseline_standard_hand": _vector_errors(nominal, truth),
        "baseline_zero_vector": _vector_errors(zero_vec, truth),
        "link_vectors_mm": {"median_mm": float(np.median(lv)), "max_mm": float(lv.max()),
                            "per_link_mm": link_err},
        "link_vectors_without_hinge_plane_mm": {"median_mm": float(np.median(lt)),
                                                "max_mm": float(lt.max())},
    }


def _trial(rec, filters, calib: ImuCalibration, series: dict | None = None, *,
           plate_fusion: bool = True) -> dict:
    truth = _truth(rec)
    motion_start = next((b for s, _, b in truth.segments if s == "align"), 0)
    sl = slice(motion_start, None)
    out: dict = {"orientation_rmse_deg": {}, "heading_rmse_deg": {}, "inclination_rmse_deg": {},
                 "joint_rmse_deg": {}, "fingertip_rmse_mm": {}, "fingertip_from_wrist_rmse_mm": {}}
    kp = truth.keypoints
    true_angles = truth.angles[:, 9:]
    check_recording(rec)  # the configuration's magnet is on purpose: no filter warns of it
    for name in filters:
        q = calib.fuse(make_filter(name, calib.model).run(rec), rec.sensors,
                       plate_fusion=plate_fusion)
        if rec.mag is None:
            q = _common_heading(q, truth.quat)
        err = angle_deg(q[:, sl], truth.quat[:, sl])
        head, incl = heading_inclination_deg(q[:, sl], truth.quat[:, sl])
        if series is not None:
            series.setdefault("t", np.arange(rec.n)[sl] / rec.rate_hz)
            series.setdefault("error", {})[name] = err.mean(axis=0)
        out["orientation_rmse_deg"][name] = dict(zip(rec.sensors, _rmse(err, axis=1).tolist()))
        out["heading_rmse_deg"][name] = float(_rmse(head))
        out["inclination_rmse_deg"][name] = float(_rmse(incl))
        ang, _ = joint_angles(q, rec.sensors, calib.frames, zero=calib.zero, cmc=calib.cmc)
        je = _rmse(ang[sl] - true_angles[sl], axis=0)
        out["joint_rmse_deg"][name] = {n: float(v) for n, v in zip(JOINT_NAMES, je)
                                       if np.isfinite(v)}
        tips = fingertip_positions(q, rec.sensors, calib.model)
        fe, fw = {}, {}
        for f, chain in CHAINS.items():
            true = kp[:, POINTS.index(f"{f}_tip")] - kp[:, POINTS.index("elbow")]
            fe[f] = float(_rmse(np.linalg.norm(tips[f][sl] - true[sl], axis=-1)) * 1e3)
            wrist_est = tips[f"{f}_joints"][:, 0]
            true_w = true - (kp[:, POINTS.index("wrist")] - kp[:, POINTS.index("elbow")])
            fw[f] = float(_rmse(np.linalg.norm((tips[f] - wrist_est)[sl] - true_w[sl], axis=-1)) * 1e3)
            del chain
        out["fingertip_rmse_mm"][name] = fe
        if series is not None:
            i = int(np.argmax(np.abs(true_angles[:, JOINT_NAMES.index("index_pip_flex")])))
            series.setdefault("chains", {})[name] = {
                f: np.vstack([np.zeros(3), tips[f"{f}_joints"][i]]) for f in CHAINS}
            true_chain = {}
            for f, links in CHAINS.items():
                pts = [kp[i, POINTS.index(a)] for _, a, _ in links] + [kp[i, POINTS.index(f"{f}_tip")]]
                true_chain[f] = np.array(pts) - kp[i, POINTS.index("elbow")]
            series["chains"]["truth"] = true_chain
            series["chain_time_s"] = i / rec.rate_hz
        out["fingertip_from_wrist_rmse_mm"][name] = fw
    return out


def _common_heading(q: np.ndarray, q_true: np.ndarray) -> np.ndarray:
    """`q` (S, N, 4) turned about the vertical by one angle, the circular mean over the
    sensors of their heading error at the first sample.

    Without magnetometers the hand's heading in the world is unobservable: the estimate's
    world x axis is the common rotation's direction, not north.  One angle for every
    sensor and the whole recording, fixed at its first sample, takes that out and leaves
    the sensors' headings relative to one another and their drift in the errors.
    """
    psi = heading_rad(q_true[:, 0], q[:, 0])  # each sensor's heading error at the start
    mean = float(np.angle(np.exp(1j * psi).mean()))
    return qmul(qexp(np.array([0.0, 0.0, mean])), q)


def _grasp_report(config, placement, filters, calib: ImuCalibration,
                  sensor_cal: SensorCalibration | None, plate_fusion: bool = True, *,
                  six_axis: bool = False) -> dict:
    hand = ImuHand(config.shape, placement=placement)
    rec = simulate_imu(grasp_motion(), hand=hand, noise=config.noise, skin=config.skin,
                       seed=config.seed + 31, device_seed=_device_seed(config))
    if six_axis:
        rec = dataclasses.replace(rec, mag=None)
    if sensor_cal is not None:
        rec = sensor_cal.apply(rec)
    classes = {g: p for g, p in GRASP_POSES.items() if g != "open"}
    truth = _truth(rec)
    holds = [(s.split(":", 1)[1], a, b) for s, a, b in truth.segments if s.startswith("grasp:")]
    out: dict = {"classes": list(classes), "accuracy": {}}
    check_recording(rec)  # the configuration's magnet is on purpose: no filter warns of it
    for name in filters:
        q = calib.fuse(make_filter(name, calib.model).run(rec), rec.sensors,
                       plate_fusion=plate_fusion)
        ang, _ = joint_angles(q, rec.sensors, calib.frames, zero=calib.zero, cmc=calib.cmc)
        hits = [classify_grasp(ang[a:b].mean(axis=0, keepdims=True), classes)[0] == g
                for g, a, b in holds]
        out["accuracy"][name] = float(np.mean(hits))
    truth_hits = [classify_grasp(truth.angles[a:b, 9:].mean(axis=0, keepdims=True),
                                 classes)[0] == g for g, a, b in holds]
    out["accuracy"]["true_angles"] = float(np.mean(truth_hits))
    out["baseline_majority"] = 1.0 / len(classes)
    return out


def free_trials(config: SimConfig, hand: ImuHand, *, durations=(15.0, 30.0),
                elbows=("fixed", "moving"), speed: float = 1.0):
    """The free-motion recordings of :func:`evaluate`, uncorrected.

    Yields
    ------
    duration_s : float
    elbow : str
    recording : ImuRecording
        Made with the configuration's noise, skin motion and physical
        sensors (``device_seed``), one seed per duration and elbow.
    """
    for k, dur in enumerate(durations):
        for m, elbow in enumerate(elbows):
            seed = config.seed * 100 + 10 * k + m
            yield float(dur), elbow, simulate_imu(
                free_motion(float(dur), seed=seed, elbow=elbow, speed=speed), hand=hand,
                noise=config.noise, skin=config.skin, seed=seed + 50,
                device_seed=_device_seed(config))


def _check_filters(filters) -> None:
    """Refuse a filter name not in :data:`FILTERS`, naming it."""
    for f in filters:
        if f not in FILTERS:
            raise InvalidInputError(f"unknown filter {f!r}; expected one of {', '.join(FILTERS)}")


def evaluate(config: SimConfig = HELDOUT, *, durations=(15.0, 30.0), elbows=("fixed", "moving"),
             filters=FILTERS, grasps: bool = True, speed: float = 1.0,
             sensor_calibration: bool = True, plate_fusion: bool = True,
             series: dict | None = None, six_axis: bool = False) -> dict:
    """Run the evaluation and return a JSON-ready dict.

    Parameters
    ----------
    config : SimConfig
    durations : sequence of float, keyword-only
        Trial lengths, s (>= 6).
    elbows : sequence of {"fixed", "moving"}, keyword-only
    filters : sequence of str, keyword-only
        Names from :data:`FILTERS`.
    grasps : bool, keyword-only
        Also classify the grasps of :func:`grasp_motion`.
    speed : float, keyword-only
        Frequency scale of the free motions.
    sensor_calibration : bool, keyword-only
        Apply the accelerometer/gyro/magnetometer calibration to every trial (it is
        always applied to the calibration recording itself).
    plate_fusion : bool, keyword-only
        Fuse the forearm plate's three attitudes into one after every filter
        (:func:`fuse_plate`); False keeps each forearm sensor's own.
    series : dict, keyword-only
        Filled with the last trial's error time series and a stick-figure
        instant (for :mod:`._plot`).
    six_axis : bool, keyword-only
        Read every recording, the calibration's too, without its magnetometers
        (6-axis sensors); the orientation errors are then taken after one turn
        about the vertical per recording (the hand's heading is unobservable
        without a compass).  The filters of :data:`COMPASS_FILTERS` refuse it.

    Raises
    ------
    InvalidInputError
        An unknown filter; with `six_axis`, a filter that needs the compass.
    """
    _check_filters(filters)
    compass = [f for f in filters if f in COMPASS_FILTERS]
    if six_axis and compass:
        raise InvalidInputError(f"filter(s) {', '.join(compass)} observe the compass, which "
                                "6-axis sensors lack; leave them out")
    placement = config.placement()
    cal, calib, sensor_cal = _calibrate(config, placement, six_axis=six_axis)
    hand = ImuHand(config.shape, placement=placement)
    trials = []
    lsq_rec = None
    runs = list(free_trials(config, hand, durations=durations, elbows=elbows, speed=speed))
    for i, (dur, elbow, rec) in enumerate(runs):
        if six_axis:
            rec = dataclasses.replace(rec, mag=None)
        if sensor_calibration:
            rec = sensor_cal.apply(rec)     # keeps the truth
        lsq_rec = lsq_rec or rec
        t = _trial(rec, filters, calib, series if i == len(runs) - 1 else None,
                   plate_fusion=plate_fusion)
        t.update(duration_s=dur, elbow=elbow)
        trials.append(t)
    report = {"config": {**config.describe(), "sensor_calibration_applied": sensor_calibration,
                         "plate_fusion": plate_fusion, "six_axis": six_axis},
              "filters": list(filters),
              "vectors": _vector_report(cal, calib.model, config, placement, lsq_rec),
              "trials": trials, "summary": _summary(trials, filters)}
    if grasps:
        report["grasps"] = _grasp_report(config, placement, filters, calib,
                                         sensor_cal if sensor_calibration else None, plate_fusion,
                                         six_axis=six_axis)
    return report


def evaluate_trial(rec: ImuRecording, calib: ImuCalibration, *, filters=("filter4",),
                   plate_fusion: bool = True) -> dict:
    """Errors of the filters on one simulated recording, summarised as :func:`evaluate` does.

    Parameters
    ----------
    rec : ImuRecording
        A simulated recording (with its truth and an ``align`` stretch), already
        sensor-corrected if that is wanted (``calib.sensor_calibration.apply(rec)``).
    calib : ImuCalibration
        Its calibration (link model, link frames, zero pose).
    filters : sequence of str, keyword-only
        Names from :data:`FILTERS`.
    plate_fusion : bool, keyword-only
        As :func:`evaluate`.

    Returns
    -------
    dict
        filter -> ``orientation_mean_deg``, ``orientation_worst_segment_deg``,
        ``orientation_distal_mean_deg``, ``segments_over_2deg``,
        ``joint_angle_mean_rmse_deg``, ``fingertip_mean_rmse_mm``,
        ``fingertip_from_wrist_mean_rmse_mm`` (from the end of the ``align`` stretch on).

    Raises
    ------
    InvalidInputError
        An unknown filter; `rec` without its truth.
    """
    _check_filters(filters)
    if rec.truth is None:
        raise InvalidInputError("evaluate_trial needs a simulated recording (one with its truth)")
    return _summary([_trial(rec, filters, calib, plate_fusion=plate_fusion)], filters)


_DISTAL = tuple(f"{f}_distal" for f in CHAINS)


def _summary(trials, filters) -> dict:
    out = {}
    for name in filters:
        per = np.array([[t["orientation_rmse_deg"][name][s] for s in SENSOR_NAMES] for t in trials])
        distal = [SENSOR_NAMES.index(s) for s in _DISTAL]
        joint = [np.mean(list(t["joint_rmse_deg"][name].values())) for t in trials]
        tips = [np.mean(list(t["fingertip_rmse_mm"][name].values())) for t in trials]
        tips_w = [np.mean(list(t["fingertip_from_wrist_rmse_mm"][name].values())) for t in trials]
        out[name] = {
            "orientation_mean_deg": float(per.mean()),
            "orientation_worst_segment_deg": float(per.max()),
            "orientation_distal_mean_deg": float(per[:, distal].mean()),
            "segments_over_2deg": int((per.max(axis=0) > 2.0).sum()),
            "joint_angle_mean_rmse_deg": float(np.mean(joint)),
            "fingertip_mean_rmse_mm": float(np.mean(tips)),
            "fingertip_from_wrist_mean_rmse_mm": float(np.mean(tips_w)),
        }
    return out
