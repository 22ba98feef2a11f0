"""The calibrated tracker: link model, link frames and zero pose in one file.

:func:`calibrate` runs chapter 3 and section 5.2.1 of seed 003 on a
calibration recording whose stretches are labelled (``static``, and one
rotation per entry of :data:`CALIBRATION_PLAN`); :class:`ImuCalibration`
saves to and loads from JSON, and :meth:`ImuCalibration.track` turns any
recording of the same sensors into attitudes, joint angles and fingertips.
"""

from __future__ import annotations

import json
import warnings
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

import numpy as np

from ..._checks import check_options, check_side, is_number
from ..._io import write_text
from ...errors import EstimationError, InvalidInputError, OutputError, RecordingError
from ._attitude import StaticStart
from ._ekf import ChainEKF, ChainEKFOptions
from ._kinematics import (
    ThumbCmcModel,
    angles_beyond_range,
    fingertip_positions,
    joint_angles,
    link_frames,
    thumb_cmc_model,
    zero_offsets,
)
from ._lags import late_offsets, late_sensors
from ._lags import realign_late as _realign
from ._layout import FLEX_JOINT
from ._model import TIP_SENSORS
from ._plate import PLATE_SENSORS, fuse_plate, plate_rotations
from ._recording import ImuRecording, check_recording
from ._sensorcal import POSE_PREFIX, SensorCalibration, fit_sensor_calibration
from ._swaps import Misplaced, misplaced_sensors, put_back, undo_misplaced
from ._vectors import CLOSING_VECTORS, ChainModel, _min_rotation_samples, calibrate_vectors, chain_model

__all__ = ["ImuCalibration", "calibrate", "check_stretches", "segments_from_seconds"]

# 2: the thumb CMC axes; 3: the accelerometer/gyro calibration; 4: the
# magnetometer calibration; 5: the forearm plate's rotations (older files load
# without them)
_VERSION = 6
#: Static poses (``acc_pose_<k>``) the sensor calibration needs at least.
_MIN_POSES = 8
#: What a calibration without static poses costs (scripts/study_imu_ulnar.py; simulated
#: sensors of the held-out configuration, EVAL_NOISE: scale 2 % and cross-axis 1 % s.d., within
#: the MPU-9250 datasheet's tolerances of 3 % and 2 %).
_UNCORRECTED = ("the accelerometers and gyros are used uncorrected: on simulated sensors "
                "within the MPU-9250 datasheet's tolerances 12 of 18 such calibrations were "
                "refused and the others read fingertips 22-28 mm from the elbow (mean of the "
                "five), against 3-9 mm with the static poses; record them "
                f"(13 still postures after the static start, labelled {POSE_PREFIX}<k>)")
#: Lower quartile of the sensor-to-joint vectors' R^2 (the fit of their lengths, eqs.
#: 3.3-3.4) below which a calibration is said to fit poorly.  Simulated calibrations of
#: :func:`calibration_motion`'s rotations: 0.96-0.97 (tuning configuration) and 0.93-0.94
#: (held-out), three draws each; with every rotation 0.7 times as large 0.89-0.95, half as
#: large 0.82-0.91 (vectors 1.6-3.2 mm median, fingertips from the elbow 6-15 mm against
#: 4-11), 0.3 times 0.05-0.32 (3.2-5.2 mm, 10-24 mm).  Judged only after the sensor
#: calibration (the static poses), which the figures assume.
_MIN_VECTOR_R2_Q25 = 0.88


def _vector_fit_warning(vectors: dict) -> str | None:
    """Say that the calibration's sensor-to-joint vectors fit poorly, or None."""
    r2 = [v.r2 for k, v in vectors.items() if k not in CLOSING_VECTORS]  # as chosen, below
    q25 = float(np.percentile(r2, 25))
    if q25 >= _MIN_VECTOR_R2_Q25:
        return None
    return (f"the sensor-to-joint vectors fit the calibration rotations poorly: a quarter of "
            f"the {len(r2)} have R^2 {q25:.2f} or less (the fit of their lengths, eqs. 3.3-3.4; "
            f"{_MIN_VECTOR_R2_Q25:g} or more in simulated calibrations of the default rotations). "
            "Rotations too small give vectors off by millimetres and fingertips by centimetres "
            "(half the default rotations: fingertips 12-15 mm from the elbow against 8-11): "
            "turn each joint through about +-25-35 deg (abductions +-12) at about 1 Hz, and "
            "calibrate again")


def segments_from_seconds(spans: dict, rate_hz: float, n: int, *, source: str | None = None) -> tuple:
    """``{label: [start_s, end_s]}`` -> ((label, first sample, end sample), ...), checked.

    Parameters
    ----------
    spans : dict
        label -> [start_s, end_s], two finite numbers (not strings).
    rate_hz : float
    n : int
        Samples in the recording.
    source : str, keyword-only, optional
        The segments file, for messages.

    Raises
    ------
    RecordingError
        A span that is not two finite numbers, or that lies outside the recording.

    Warns
    -----
    UserWarning
        Labels that no step of :func:`calibrate` reads (a misspelt rotation).
    """
    where = f"{source}: " if source else ""
    if not isinstance(spans, dict):
        raise RecordingError(f"{where}expected an object of label: [start_s, end_s], "
                             f"got {type(spans).__name__}")
    out = []
    for label, span in spans.items():
        if (not isinstance(span, (list, tuple)) or len(span) != 2
                or not all(is_number(x) for x in span)):
            raise RecordingError(f"{where}segment {label!r} must be [start_s, end_s], two "
                                 f"numbers, got {span!r}")
        a, b = (float(x) for x in span)
        if not (np.isfinite(a) and np.isfinite(b)):
            raise RecordingError(f"{where}segment {label!r} = {span!r}: the times must be finite "
                                 "numbers of seconds")
        i, j = round(a * rate_hz), round(b * rate_hz)
        if not (0 <= i < j <= n):
            raise RecordingError(f"{where}segment {label!r} = [{a}, {b}] s lies outside the "
                                 f"recording (0-{n / rate_hz:.2f} s) or is empty")
        out.append((str(label), i, j))
    known = _calibration_labels()
    unknown = [lab for lab, _, _ in out if lab not in known and not _is_pose_label(lab)]
    if unknown:
        warnings.warn(f"{where}segment(s) {', '.join(map(repr, unknown))} are no stretch the "
                      "calibration reads (calibration_motion's labels, and acc_pose_<k>): "
                      "ignored", UserWarning, stacklevel=2)
    return tuple(out)


@lru_cache(maxsize=1)
def _calibration_labels() -> frozenset:
    """The labels of :func:`calibration_motion`'s stretches, the static poses left out."""
    from ._motion import calibration_motion

    return frozenset(lab for lab, _, _ in calibration_motion(acc_poses=False).segments)


def _is_pose_label(label: str) -> bool:
    return label.startswith(POSE_PREFIX) and label[len(POSE_PREFIX):].isdigit()


#: A calibration rotation turns its joint by tens of degrees (12 deg for an abduction
#: of :func:`calibration_motion`, 15-76 deg otherwise); a still stretch turns no sensor by
#: more than 0.1 deg once the gyro bias of its first half second is taken off.
_MIN_ROTATION_DEG = 3.0
#: Besides each flexion's own segment (:data:`FLEX_JOINT`), the sensors that the other
#: calibration rotations turn: a label on another rotation's stretch leaves them still.
_ALSO_TURNS = {
    "humeral_rot": ("forearm_1", "forearm_2", "forearm_3"),
    "wrist_dev": ("hand_radial", "hand_ulnar"),
    "thumb_cmc_abd": ("thumb_metacarpal",),
    **{f"{f}_mcp_abd": (f"{f}_proximal",) for f in ("index", "middle", "ring", "little")},
}
#: A still stretch (``static``, ``acc_pose_<k>``) moves no gyro by more than this RMS
#: about its mean, deg/s (0.2 deg/s in the simulated still poses; tens in a motion).
_MAX_STILL_RMS_DPS = 5.0
#: Start of a rotation taken as still for its gyro bias, s (as :func:`rotation_vector`).
_BIAS_HOLD_S = 0.5


def _span_text(a: int, b: int, rate_hz: float) -> str:
    return f"samples {a}-{b - 1} ({a / rate_hz:.2f}-{b / rate_hz:.2f} s)"


def check_stretches(rec: ImuRecording, *, source: str | None = None) -> list[str]:
    """Refuse a calibration rotation labelled over a still stretch; warn of a moving pose.

    A rotation (every label of :func:`calibration_motion` but ``static``) must turn at
    least one sensor: the angle turned, the gyro integrated after the bias of the
    stretch's first half second is taken off, must reach 3 deg for some sensor.  A label
    placed over a still stretch would otherwise give link vectors of metres from noise.
    A flexion must also turn the sensors on the segment it moves (:data:`FLEX_JOINT`):
    ``index_pip_flex`` placed over the DIP's rotation, which leaves ``index_middle``
    still, gave an index MCP-PIP link of half a metre.
    A still stretch (``static``, ``acc_pose_<k>``) in which some sensor's gyro moves by
    more than 5 deg/s RMS about its mean is returned as a warning.

    Parameters
    ----------
    rec : ImuRecording
        The calibration recording with its labelled stretches.
    source : str, keyword-only, optional
        The recording's file, for messages.

    Returns
    -------
    list of str
        Warnings (a still stretch that moves), each naming the label and its samples.

    Raises
    ------
    RecordingError
        A rotation in which no sensor turns, or a flexion in which a sensor of the
        segment it moves does not turn, naming the label, its samples and the angles.
    """
    where = f"{source}: " if source else ""
    rotations = _calibration_labels() - {"static"}
    found = []
    for label, a, b in rec.labelled():
        if b - a < 2:
            continue
        gyr = rec.gyr[:, a:b]
        if label in rotations:
            if b - a < _min_rotation_samples(rec.rate_hz):
                continue  # too short to be still or not: refused as such (chain_model)
            hold = max(3, int(_BIAS_HOLD_S * rec.rate_hz))
            # the hold at the start gives the gyro biases; a stretch too short to begin with
            # one is read as it is (the biases turn a sensor a few degrees per second at most)
            bias = gyr[:, :hold].mean(axis=1, keepdims=True) if b - a >= 2 * hold else 0.0
            turned = np.cumsum(gyr - bias, axis=1)
            angle = np.degrees(np.linalg.norm(turned, axis=2).max(axis=1) / rec.rate_hz)
            k = int(np.argmax(angle))
            if not angle[k] >= _MIN_ROTATION_DEG:  # NaN fails too
                raise RecordingError(
                    f"{where}segment {label!r} ({_span_text(a, b, rec.rate_hz)}) is still: no "
                    f"sensor turns more than {angle[k]:.2g} deg in it (the most: "
                    f"{rec.sensors[k]}), and a calibration rotation turns its joint by tens of "
                    f"degrees; is the label on the rotation's stretch?")
            # the sensors on the segment that this rotation moves must turn with it
            own = [i for i, sensor in enumerate(rec.sensors)
                   if FLEX_JOINT.get(sensor) == label or sensor in _ALSO_TURNS.get(label, ())]
            still = [i for i in own if not angle[i] >= _MIN_ROTATION_DEG]
            if still:
                i = still[0]
                raise RecordingError(
                    f"{where}segment {label!r} ({_span_text(a, b, rec.rate_hz)}) does not turn "
                    f"{rec.sensors[i]} ({angle[i]:.2g} deg), the sensor on the segment this "
                    f"rotation moves, while {rec.sensors[k]} turns {angle[k]:.3g} deg: is the "
                    "label on another rotation's stretch?")
        elif label == "static" or _is_pose_label(label):
            rms = np.degrees(np.sqrt(np.mean(np.sum(
                (gyr - gyr.mean(axis=1, keepdims=True)) ** 2, axis=2), axis=1)))
            k = int(np.argmax(rms))
            if rms[k] > _MAX_STILL_RMS_DPS:
                found.append(
                    f"{where}segment {label!r} ({_span_text(a, b, rec.rate_hz)}) should be "
                    f"still, but the gyro of {rec.sensors[k]} moves by {rms[k]:.3g} deg/s RMS in "
                    f"it; is the label on a still stretch?")
    return found


def _non_finite(obj, where: str = "") -> tuple[str, float] | None:
    """The first NaN or infinite number in nested dicts and lists, as (field, value).

    The field is written as a path: ``own_m.index_middle[1]``.
    """
    if isinstance(obj, float):
        return None if np.isfinite(obj) else (where, obj)
    if isinstance(obj, dict):
        items = ((f"{where}.{k}" if where else str(k), v) for k, v in obj.items())
    elif isinstance(obj, (list, tuple)):
        items = ((f"{where}[{i}]", v) for i, v in enumerate(obj))
    else:
        return None
    for name, value in items:
        found = _non_finite(value, name)
        if found is not None:
            return found
    return None


@dataclass(frozen=True)
class ImuCalibration:
    """Link model, link frames and zero-pose angles of one wearer and mounting.

    Attributes
    ----------
    model : ChainModel
    frames : dict
        sensor -> (3, 3) link frame L_R_S.
    zero : ndarray, shape (20,)
    sensors : tuple of str
        The sensors the tracker expects (the link model's).
    cmc : ThumbCmcModel or None
        The thumb CMC's axes; None (files of version 1): CMC angles are NaN.
    sensor_calibration : SensorCalibration or None
        Accelerometer and gyro corrections of the same physical sensors;
        None (no static poses, or files before version 3): readings are
        used as they come.
    plate : dict or None
        The forearm plate's constant rotations (:func:`plate_rotations`):
        sensor -> rotation from its frame to the first plate sensor's.  None
        (files before version 5): every forearm sensor keeps its own
        attitude.
    side : {"right", "left"}
        The hand the sensors are on; its joint angles are measured as that
        hand's (files before version 6: ``"right"``).
    """

    model: ChainModel
    frames: dict
    zero: np.ndarray
    sensors: tuple
    cmc: ThumbCmcModel | None = None
    sensor_calibration: SensorCalibration | None = None
    plate: dict | None = None
    side: str = "right"

    def fuse(self, quats, sensors, *, plate_fusion: bool = True) -> np.ndarray:
        """Attitudes with the forearm plate's sensors fused into one (:func:`fuse_plate`).

        Parameters
        ----------
        quats : ndarray, shape (S, N, 4)
            Any filter's sensor-to-world quaternions.
        sensors : sequence of str, length S
        plate_fusion : bool, keyword-only
            False (or no plate rotations stored) returns `quats` unchanged.
        """
        if not plate_fusion or self.plate is None:
            return quats
        return fuse_plate(quats, sensors, self.plate)

    def correct(self, rec: ImuRecording, *, sensor_calibration: bool = True) -> ImuRecording:
        """The calibrated sensors of `rec`, the sensor calibration applied (if any and asked).

        Raises
        ------
        RecordingError
            `rec` lacks a calibrated sensor.
        """
        missing = [s for s in self.sensors if s not in rec.sensors]
        if missing:
            unknown = [s for s in rec.sensors if s not in self.sensors]
            raise RecordingError(
                f"the recording lacks sensor(s) {', '.join(missing)} of the calibration (columns "
                f"{missing[0]}_acc_x .. {missing[0]}_mag_z)"
                + (f"; it has sensor(s) the calibration does not know: {', '.join(unknown)} "
                   "(named differently?)" if unknown else ""))
        sub = rec.subset(self.sensors)
        if self.sensor_calibration is None or not sensor_calibration:
            return sub
        try:
            return self.sensor_calibration.apply(sub)
        except InvalidInputError as exc:
            raise RecordingError(f"calibration file inconsistent: {exc}") from None

    def track(self, rec: ImuRecording, *, static=None, sensor_calibration: bool = True,
              plate_fusion: bool = True, options: ChainEKFOptions | None = None,
              undo_misplaced: bool = False, realign_late: bool = False) -> dict:
        """Attitudes (Filter 4), joint angles and fingertips of a recording.

        Parameters
        ----------
        rec : ImuRecording
            Raw readings of (at least) the calibrated sensors.
        static : StaticStart, keyword-only
        sensor_calibration : bool, keyword-only
            Apply the stored accelerometer/gyro/magnetometer calibration first (False:
            `rec` is already corrected).
        plate_fusion : bool, keyword-only
            Fuse the forearm plate's three attitudes into one (:meth:`fuse`;
            needs the plate rotations of a version-5 file).
        options : ChainEKFOptions, keyword-only, optional
            Filter 4's options (its defaults, the thesis' filter, if None;
            :data:`~handsynth.sensors.imu.FILTER4B` learns drifting gyro biases).
        undo_misplaced : bool, keyword-only
            Read the sensors that read as exchanged or turned since the calibration
            (:func:`find_misplaced`) as put back, one at a time (:func:`put_back`, after
            the sensor calibration: each sensor's own travels with it), with a warning
            naming what was undone; the checks after the filter are then made of the
            readings as put back.  Off: they are warned of and read as they are.
        realign_late : bool, keyword-only
            Read the streams that read late or early against their neighbours
            (:func:`late_offsets`: the fewest sensors off along each chain of sensors the
            lag check joins) as realigned (:func:`realign_late`), after any put back, with
            a warning naming each and its lag; the check of the streams after the filter is
            then made of the readings as realigned.  Off: they are warned of and read as
            they are.

        Returns
        -------
        dict
            ``quat`` (S, N, 4), ``angles`` (N, 20) degrees, ``tips``
            finger -> (N, 3) metres from the elbow, ``chains`` all of
            :func:`fingertip_positions` (each chain's joints too),
            ``sensor_calibration`` whether a sensor calibration was applied,
            ``undone`` the :class:`Misplaced` put back (empty when nothing was, or
            `undo_misplaced` is off), ``realigned`` sensor -> the lag its stream was read
            earlier by, s (empty likewise).

        Warns
        -----
        UserWarning
            Joint angles far beyond the hand's range of motion in a share of the samples,
            naming the joints and the sensor they point to (:func:`angles_beyond_range`):
            a sensor turned on its segment since the calibration.  Pairs of sensors whose
            joints agree better with the two exchanged (:func:`swapped_sensors`): sensors
            put back on each other's segments, or columns exchanged.  Sensors whose joints
            agree better with the sensor turned back (:func:`turned_sensors`): a sensor put
            back turned on its segment.  Sensors whose streams
            are 15 ms or more out of step with their neighbours' across a finger's hinge
            joint (the thumb's MCP included), on the forearm plate or on the hand
            (:func:`late_sensors`).
        """
        static = check_options(static, StaticStart, name="static")
        options = check_options(options, ChainEKFOptions)
        sub = self.correct(rec, sensor_calibration=sensor_calibration)
        undone = left = Misplaced()
        if undo_misplaced:
            sub, undone, left = put_back(sub, self.model, self.frames)
            how = ""
            if undone.exchanged and self.sensor_calibration is not None and sensor_calibration:
                sub, how = self._columns_or_sensors(rec, sub, undone)
            if undone:
                warnings.warn(f"read as put back: {undone.describe()}{how} (undo_misplaced)",
                              UserWarning, stacklevel=2)
        static_n = int(static.static_s * sub.rate_hz)
        realigned: dict[str, float] = {}
        if realign_late:
            realigned, _ = late_offsets(sub, self.frames, static_n=static_n)
            if realigned:
                sub = _realign(sub, realigned)
                said = "; ".join(f"{s} {abs(lag) * 1e3:.0f} ms {'earlier' if lag > 0 else 'later'}"
                                 for s, lag in realigned.items())
                warnings.warn(f"read realigned: {said} (realign_late)", UserWarning, stacklevel=2)
        if rec.reported is not None:
            # the caller has had check_recording's warnings of `rec`: the filter's run
            # does not repeat them for the corrected copy
            check_recording(sub, static_s=static.static_s)
        applied = sensor_calibration and self.sensor_calibration is not None
        est = ChainEKF(self.model, options=options, static=static)
        out = self.read_attitudes(est.run(sub), sub.sensors, plate_fusion=plate_fusion)
        beyond = angles_beyond_range(out["angles"])
        if beyond is not None:
            warnings.warn(beyond, UserWarning, stacklevel=2)
        # (put back, the last round's reading of what is left stands)
        for misplaced in (left.warnings if undo_misplaced else
                          misplaced_sensors(sub, self.model, self.frames)):
            warnings.warn(misplaced, UserWarning, stacklevel=2)
        late = late_sensors(sub, self.frames, static_n=static_n)
        if late is not None:
            warnings.warn(late, UserWarning, stacklevel=2)
        return {**out, "sensor_calibration": applied, "undone": undone, "realigned": realigned}

    def _columns_or_sensors(self, rec: ImuRecording, sub: ImuRecording,
                            undone: Misplaced) -> tuple[ImuRecording, str]:
        """`sub` (`rec` corrected, then put back as `undone`: sensors put back on each other's
        segments, each read with its own calibration) or `rec`'s pairs exchanged first, then
        corrected (the recording's columns exchanged, not the sensors: each column's
        calibration is another sensor's), whichever's exchanged magnetometers read the
        steadier field strength (the calibration makes each sensor's constant), and the
        words that say which."""
        columns = undo_misplaced(
            self.correct(undo_misplaced(rec, Misplaced(exchanged=undone.exchanged))),
            Misplaced(turned=undone.turned))
        if columns.mag is None or sub.mag is None:   # 6-axis sensors: nothing tells
            return sub, ""
        rows = [sub.index(s) for pair in undone.exchanged for s in pair]
        as_sensors, as_columns = (float(sum(np.std(np.linalg.norm(mag[k], axis=1)) for k in rows))
                                  for mag in (sub.mag, columns.mag))
        if as_columns < as_sensors:
            return columns, (f" (as columns of the recording exchanged, not sensors: their "
                             f"magnetometers read a steadier field so, {as_columns:.1f} against "
                             f"{as_sensors:.1f} uT s.d.)")
        return sub, ""

    def read_attitudes(self, quats, sensors, *, plate_fusion: bool = True) -> dict:
        """Joint angles and fingertips of sensor attitudes (what :meth:`track` returns).

        Parameters
        ----------
        quats : ndarray, shape (S, N, 4)
            Sensor-to-world quaternions of the calibration's sensors.
        sensors : sequence of str, length S
        plate_fusion : bool, keyword-only
            As :meth:`fuse`.

        Returns
        -------
        dict
            ``quat`` (S, N, 4) fused, ``angles`` (N, 20) degrees, ``tips`` finger ->
            (N, 3) metres from the elbow, ``chains`` all of :func:`fingertip_positions`.
        """
        q = self.fuse(quats, sensors, plate_fusion=plate_fusion)
        angles, _ = joint_angles(q, sensors, self.frames, side=self.side, zero=self.zero,
                                 cmc=self.cmc)
        chains = fingertip_positions(q, sensors, self.model)
        tips = {f: v for f, v in chains.items() if not f.endswith("_joints")}
        return {"quat": q, "angles": angles, "tips": tips, "chains": chains}

    def to_dict(self) -> dict:
        return {"format": "handsynth-imu-calibration", "version": _VERSION,
                "side": self.side, "sensors": list(self.sensors),
                "own_m": {s: v.tolist() for s, v in self.model.own.items()},
                "links_m": [[s, a, b, v.tolist()] for (s, a, b), v in self.model.links.items()],
                "frames": {s: v.tolist() for s, v in self.frames.items()},
                "zero_deg": self.zero.tolist(),
                **({} if self.cmc is None else {"thumb_cmc": {
                    "axes": self.cmc.axes.tolist(), "rest": self.cmc.rest.tolist()}}),
                **({} if self.sensor_calibration is None else {
                    "sensor_calibration": self.sensor_calibration.to_dict()}),
                **({} if self.plate is None else {
                    "plate": {s: v.tolist() for s, v in self.plate.items()}})}

    def save(self, path, *, inputs=()) -> Path:
        """Write JSON atomically (never a half-written file under `path`).

        The whole text is made first and written with :func:`handsynth._io.write_text`
        (a temporary file renamed onto `path`); a NaN or infinite value, which JSON cannot
        hold and :meth:`load` would refuse, is refused before anything is written.

        Parameters
        ----------
        path : path-like
        inputs : iterable of path-like, keyword-only
            The run's input files; `path` must be none of them.

        Returns
        -------
        pathlib.Path

        Raises
        ------
        OutputError
            A non-finite value (the field named, e.g. ``own_m.index_middle[1]``), or
            the file cannot be written (see :func:`handsynth._io.write_text`).
        """
        path = Path(path)
        data = self.to_dict()
        bad = _non_finite(data)
        if bad is not None:
            field, value = bad
            raise OutputError(f"cannot write the calibration file {str(path)!r}: field {field} is "
                              f"{value!r}, and the file must hold finite numbers to be read back "
                              "(a calibration that failed?); nothing was written")
        text = json.dumps(data, indent=1, allow_nan=False) + "\n"
        return write_text(path, text, what="calibration file", inputs=inputs)

    @classmethod
    def load(cls, path) -> ImuCalibration:
        path = Path(path)
        try:
            d = json.loads(path.read_text())
        except FileNotFoundError:
            raise RecordingError(f"{path}: no such file") from None
        except (json.JSONDecodeError, UnicodeDecodeError) as exc:
            raise RecordingError(f"{path}: not a calibration JSON file ({exc})") from None
        if not isinstance(d, dict) or d.get("format") != "handsynth-imu-calibration":
            raise RecordingError(f"{path}: not a handsynth IMU calibration file")
        missing = [k for k in ("sensors", "own_m", "links_m", "frames", "zero_deg") if k not in d]
        if missing:
            raise RecordingError(f"{path}: missing field(s) {', '.join(missing)}")
        version = d.get("version", 1)
        if not isinstance(version, int) or isinstance(version, bool) or version < 1:
            raise RecordingError(f"{path}: field version is {version!r}; expected a whole "
                                 f"number from 1 to {_VERSION}")
        if version > _VERSION:
            raise RecordingError(f"{path}: calibration file version {version!r} is newer than "
                                 f"this handsynth reads (<= {_VERSION})")
        for key, kind in (("sensors", list), ("own_m", dict), ("links_m", list),
                          ("frames", dict), ("zero_deg", list)):
            if not isinstance(d[key], kind):
                raise RecordingError(f"{path}: field {key} must be a JSON "
                                     f"{'object' if kind is dict else 'array'}, got {d[key]!r:.60}")
        if not d["sensors"] or not all(isinstance(x, str) for x in d["sensors"]):
            raise RecordingError(f"{path}: field sensors must be a non-empty array of names")
        try:
            model = ChainModel({s: np.array(v, float) for s, v in d["own_m"].items()},
                               {(s, a, b): np.array(v, float) for s, a, b, v in d["links_m"]})
            frames = {s: np.array(v, float).reshape(3, 3) for s, v in d["frames"].items()}
            zero = np.array(d["zero_deg"], float).reshape(20)
            cmc = None
            if "thumb_cmc" in d:
                cmc = ThumbCmcModel(np.array(d["thumb_cmc"]["axes"], float).reshape(2, 3),
                                    np.array(d["thumb_cmc"]["rest"], float).reshape(3, 3))
        except (TypeError, ValueError, KeyError, AttributeError) as exc:
            raise RecordingError(f"{path}: malformed calibration values ({exc})") from None
        numbers = [("own_m", s, v) for s, v in model.own.items()] + [
            ("links_m", f"{s} {a}->{b}", v) for (s, a, b), v in model.links.items()] + [
            ("frames", s, v) for s, v in frames.items()] + [("zero_deg", "", zero)] + (
            [] if cmc is None else [("thumb_cmc", "axes", cmc.axes), ("thumb_cmc", "rest", cmc.rest)])
        for key, item, v in numbers:
            if not np.all(np.isfinite(v)):
                i = int(np.argmax(~np.isfinite(v).reshape(-1)))
                raise RecordingError(f"{path}: field {key}{' ' + item if item else ''} holds "
                                     f"{float(v.reshape(-1)[i])!r} at index {i}; every value must be a "
                                     "finite number")
        skew = [s for s, r in frames.items() if not np.allclose(r.T @ r, np.eye(3), atol=1e-6)
                or np.linalg.det(r) < 0]
        if skew:
            raise RecordingError(f"{path}: field frames holds {len(skew)} matri(x/ces) that are not "
                                 f"rotations ({', '.join(skew[:4])}): a damaged file")
        sensor_cal = None
        if "sensor_calibration" in d:
            try:
                sensor_cal = SensorCalibration.from_dict(d["sensor_calibration"],
                                                         source=f"{path}: sensor_calibration")
            except InvalidInputError as exc:
                raise RecordingError(str(exc)) from None
            lacking = [s for s in d["sensors"] if s not in sensor_cal.sensors]
            if lacking:
                raise RecordingError(f"{path}: sensor_calibration lacks sensor(s) "
                                     f"{', '.join(lacking)}")
        plate = None
        if "plate" in d:
            try:
                plate = {str(s): np.array(v, float).reshape(3, 3) for s, v in d["plate"].items()}
            except (AttributeError, TypeError, ValueError) as exc:
                raise RecordingError(f"{path}: malformed plate rotations ({exc})") from None
            bad = [s for s, r in plate.items() if s not in d["sensors"]
                   or not np.allclose(r.T @ r, np.eye(3), atol=1e-6)]
            if bad:
                raise RecordingError(f"{path}: plate rotation(s) of {', '.join(bad)} are not "
                                     "rotations of calibrated sensors")
        side = d.get("side", "right")
        if side not in ("right", "left"):
            raise RecordingError(f"{path}: field side must be \"right\" or \"left\", got {side!r:.60}")
        return cls(model, frames, zero, tuple(d["sensors"]), cmc, sensor_cal, plate, side)


def calibrate(rec: ImuRecording, *, sensor_calibration: bool | SensorCalibration = True,
              side: str = "right", source: str | None = None,
              hinge_plane: bool = True) -> ImuCalibration:
    """Calibrate from a recording with labelled stretches (see :func:`calibration_motion`).

    Needs the five fingertip sensors of the calibration (:data:`TIP_SENSORS`)
    for the distal link vectors (seed 003 Table 3.5).  When the recording
    has labelled static poses (``acc_pose_<k>``, see
    :func:`fit_sensor_calibration`), the accelerometers and gyros are first
    corrected for scale, cross-axis error and accelerometer bias, and the
    correction is kept in the result (:meth:`ImuCalibration.track` applies
    it to every recording); ``sensor_calibration=False`` skips it, e.g. for
    a recording already corrected.  The forearm plate's constant rotations
    (:func:`plate_rotations`) are stored too when all its sensors are there.

    Parameters
    ----------
    rec : ImuRecording
        The calibration recording: the labelled stretches of
        :func:`calibration_motion` (in ``segments`` or its truth's), the link
        sensors and the fingertip sensors.
    sensor_calibration : bool or SensorCalibration, keyword-only
        Fit and apply :func:`fit_sensor_calibration` when the recording has at
        least 8 stretches labelled ``acc_pose_<k>``; with none it is skipped,
        with 1-7 skipped with a warning.  False skips it always; a
        :class:`SensorCalibration` (fitted on this recording already, as
        ``handsynth imu calibrate`` does to check the recording's magnetometers
        with it) is applied and kept as it is.
    side : {"right", "left"}, keyword-only
        The hand the sensors are on: the zero offsets and every tracked
        joint angle are measured as that hand's (a left hand read as a right
        one has its abductions turned the other way).
    source : str, keyword-only, optional
        The recording's file, named in the messages of :func:`check_stretches`.
    hinge_plane : bool, keyword-only
        As :func:`calibrate_vectors`: each one-axis joint's centre on the plane of
        the joint its direction is paired with (default), or where eq. 3.2 puts
        it (False, the thesis).

    Returns
    -------
    ImuCalibration
        Link model, link frames, zero offsets, thumb CMC model, the sensor
        correction (None when skipped) and the plate rotations (None without
        all of :data:`PLATE_SENSORS`).

    Raises
    ------
    InvalidInputError
        A labelled stretch that a step needs is missing.
    RecordingError
        A sensor that a step needs is missing; a rotation labelled over a still stretch
        (:func:`check_stretches`).
    EstimationError
        A calibration rotation too short, slow or badly shaped to estimate
        from (see :func:`calibrate_vectors`, :func:`link_frames`,
        :func:`azimuth_correction`); link frames half a turn apart at the static
        start (:func:`zero_offsets`; without static poses, saying that uncorrected
        sensors are the likelier cause).

    Warns
    -----
    UserWarning
        No static poses labelled (the readings used uncorrected, with what that cost on
        simulated sensors), or 1-7 (too few for the sensor calibration); a still stretch
        (``static``, ``acc_pose_<k>``) in which a gyro moves (:func:`check_stretches`).
    """
    check_side(side)
    for message in check_stretches(rec, source=source):
        warnings.warn(message, UserWarning, stacklevel=2)
    sensor_cal = None
    poses = sum(name.startswith(POSE_PREFIX) for name, _, _ in rec.labelled())
    if isinstance(sensor_calibration, SensorCalibration):
        sensor_cal, sensor_calibration = sensor_calibration, False
        rec = sensor_cal.apply(rec)
    elif not isinstance(sensor_calibration, bool):
        raise InvalidInputError(f"sensor_calibration must be True, False or a SensorCalibration, "
                                f"got {type(sensor_calibration).__name__}")
    if sensor_calibration and 0 < poses < _MIN_POSES:
        warnings.warn(f"{poses} static pose(s) labelled {POSE_PREFIX}<k>: the accelerometer and gyro "
                      f"calibration needs {_MIN_POSES} or more, so the readings are used "
                      "uncorrected", UserWarning, stacklevel=2)
    if sensor_calibration and poses == 0:
        where = f"{source}: " if source else ""
        warnings.warn(f"{where}no static poses labelled {POSE_PREFIX}<k>: {_UNCORRECTED}",
                      UserWarning, stacklevel=2)
    if sensor_calibration and poses >= _MIN_POSES:
        try:
            sensor_cal = fit_sensor_calibration(rec)
        except EstimationError as exc:
            if source is None:
                raise
            raise EstimationError(f"{source}: {exc}") from None
        rec = sensor_cal.apply(rec)
    tips = [t for t in TIP_SENSORS if t not in rec.sensors]
    if tips:
        where = f"{source}: " if source else ""
        raise RecordingError(
            f"{where}the calibration needs the five temporary fingertip sensors "
            f"({', '.join(TIP_SENSORS)}) for the distal link vectors; missing "
            f"{', '.join(tips)} (the recording has {', '.join(rec.sensors)})")
    vectors = calibrate_vectors(rec, hinge_plane=hinge_plane)
    # judged after the sensor calibration only: the accelerometers' own scale and axis errors
    # lower the fit of the default rotations to 0.68-0.82 without it (three simulated devices)
    fit = _vector_fit_warning(vectors) if sensor_cal is not None else None
    if fit is not None:
        warnings.warn(f"{source}: {fit}" if source else fit, UserWarning, stacklevel=2)
    model = chain_model(rec, vectors)
    frames = link_frames(rec, model)
    try:
        zero = zero_offsets(rec, frames, side=side)
    except EstimationError as exc:
        if sensor_cal is None and sensor_calibration:  # the likelier cause, said first
            exc = EstimationError(f"{exc}; or, more likely here, {_UNCORRECTED}")
        if source is not None:
            exc = EstimationError(f"{source}: {exc}")
        raise exc from None
    plate = plate_rotations(rec) if all(s in rec.sensors for s in PLATE_SENSORS) else None
    return ImuCalibration(model, frames, zero, tuple(model.own), thumb_cmc_model(rec, frames),
                          sensor_cal, plate, side)
