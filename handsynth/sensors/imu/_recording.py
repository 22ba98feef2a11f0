"""IMU recordings: the data container, input checks and the CSV reader/writer.

A recording holds S sensors sampled together at one rate: accelerometer in
m/s^2 (specific force, +g upward at rest), gyro in rad/s, magnetometer in
microtesla, each shaped (S, N, 3).  :func:`check_recording` finds what makes
a recording unusable or suspicious (NaN, gaps in the time stamps, samples lost by
the logger, saturated channels, wrong units, magnetic disturbances) and either raises
:class:`~handsynth.errors.RecordingError` naming the sensor, channel and
sample, or returns the warnings it found.
"""

from __future__ import annotations

import dataclasses
import math
import re
import warnings as _warnings
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..._checks import check_instance, check_number, check_path, is_number
from ..._csv import column_index, names_by_meaning, read_number_table, read_rows, read_text, reads_as_number
from ..._io import atomic_open
from ...errors import InvalidInputError, RecordingError
from ._axes import (
    REVERSED,
    SIGNED_PERMUTATIONS,
    axes_label,
    gyro_axes_errors,
    mag_axes_errors,
    moving_mean,
    parse_axes,
)
from ._model import GRAVITY_MPS2
from ._motion import CALIBRATION_PLAN

__all__ = [
    "UNITS",
    "ImuRecording",
    "ImuTruth",
    "check_recording",
    "read_imu_csv",
    "sample_times",
    "with_axes",
    "write_imu_csv",
]

#: Accepted units per channel and their factor to SI (m/s^2, rad/s, uT).
UNITS = {
    "acc": {"m/s2": 1.0, "g": GRAVITY_MPS2, "mg": GRAVITY_MPS2 * 1e-3},
    "gyr": {"rad/s": 1.0, "deg/s": np.pi / 180.0},
    "mag": {"uT": 1.0, "mT": 1e3, "G": 100.0, "nT": 1e-3},
}


@dataclass(frozen=True)
class ImuTruth:
    """Ground truth of a simulated recording (world frame, metres).

    Attributes
    ----------
    quat : ndarray, shape (S, N, 4)
        Nominal sensor-to-world rotation (w, x, y, z): the segment's rotation
        times the sensor's mounting (skin motion not included).
    sensor_pos : ndarray, shape (S, N, 3)
        Where each sensor actually is.
    keypoints : ndarray, shape (N, 23, 3)
        The elbow, wrist and ulnar CM centres, the joint centres and the fingertips, in
        :data:`~handsynth.sensors.imu.POINTS` order.
    elbow : ndarray, shape (N, 3)
        Elbow joint centre.
    angles : ndarray, shape (N, 29)
        Joint angles of :data:`MODEL_JOINTS` (deg; slides m).
    joint_vectors : dict
        ``(sensor, point) -> (3,)`` vector from each point of :data:`POINTS`
        to the sensor in the sensor frame at the zero pose, nominal
        mounting, metres (meaningful for points on the sensor's own chain).
    segments : tuple
        The motion's named stretches.
    """

    quat: np.ndarray
    sensor_pos: np.ndarray
    keypoints: np.ndarray
    elbow: np.ndarray
    angles: np.ndarray
    joint_vectors: dict = field(default_factory=dict)
    segments: tuple = ()


@dataclass(frozen=True)
class ImuRecording:
    """Synchronous samples of S IMUs.

    Attributes
    ----------
    rate_hz : float
    sensors : tuple of str, length S
    acc : ndarray, shape (S, N, 3), m/s^2
    gyr : ndarray, shape (S, N, 3), rad/s
    mag : ndarray, shape (S, N, 3), uT, or None
        None: 6-axis sensors (accelerometer and gyro only, no magnetometer);
        the sensors' headings then come from the common rotation
        (:func:`initial_attitude`), and the estimators that need a compass
        refuse the recording.
    truth : ImuTruth or None
    segments : tuple of (str, int, int)
        Labelled stretches (label, first sample, end sample), e.g. the
        calibration rotations of a real recording; a simulation's are in
        its truth.
    start_s : float
        Time of the first sample, s, as the recording's time column gave it
        (0 for a simulation and a file without one): sample ``i`` is at
        ``start_s + i / rate_hz``.  Outputs are stamped in these times.
    filled : ndarray of bool, shape (S, N), or None
        Samples that were not read but filled in (:func:`bridge_lost` sets
        it); Filter 4 lets those sensors' attitudes loosen meanwhile, so that
        the readings after the gap pull them back.  None: every sample read.
    reported : frozenset of str or None
        The warnings :func:`check_recording` has returned for this object;
        None before it was checked (when made, and for a copy made with
        :func:`dataclasses.replace`).  Not a field to give: an estimator run
        on a recording already checked does not repeat them.
    """

    rate_hz: float
    sensors: tuple
    acc: np.ndarray
    gyr: np.ndarray
    mag: np.ndarray | None
    truth: ImuTruth | None = None
    segments: tuple = ()
    start_s: float = 0.0
    filled: np.ndarray | None = None
    reported: frozenset | None = field(default=None, init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        """Check what is cheap to check and store the arrays as float64, C order.

        Raises
        ------
        RecordingError
            A rate that is not a finite number > 0 (up to 100 kHz); sensor
            names that are not strings or that repeat; `acc`, `gyr` or `mag`
            that are not numbers of shape (S, N, 3) with S = len(sensors),
            or whose N differ.  The content (NaN, units, saturation, the
            static start) is checked by :func:`check_recording`, which every
            estimator's ``run`` applies.
        """
        object.__setattr__(self, "rate_hz", check_rate(self.rate_hz))
        object.__setattr__(self, "start_s", check_number(self.start_s, "start_s",
                                                         error=RecordingError))
        sensors = self.sensors
        if isinstance(sensors, str) or not all(isinstance(x, str) for x in sensors):
            raise RecordingError(f"sensors must be a sequence of sensor names (str), got "
                                 f"{sensors!r}")
        sensors = tuple(sensors)
        object.__setattr__(self, "sensors", sensors)
        check_unique_names(sensors)
        s = len(sensors)
        for name in ("acc", "gyr", "mag"):
            value = getattr(self, name)
            if name == "mag" and value is None:
                continue
            try:
                a = np.ascontiguousarray(value, dtype=np.float64)
            except (TypeError, ValueError):
                raise RecordingError(f"{name} must be an array of numbers of shape (S, N, 3) "
                                     f"with S = len(sensors) = {s}, got "
                                     f"{type(value).__name__}") from None
            if a.ndim != 3 or a.shape[0] != s or a.shape[2] != 3:
                hint = ""
                if a.ndim == 2 and a.shape[-1] == 3:
                    hint = " (one sensor's (N, 3) samples? give them as a[None])"
                elif a.ndim == 3 and a.shape[0] == s and a.shape[1] == 3:
                    hint = " (axes last: (S, 3, N) given? use a.transpose(0, 2, 1))"
                raise RecordingError(f"{name} has shape {a.shape}, expected (S, N, 3) with "
                                     f"S = len(sensors) = {s}{hint}")
            object.__setattr__(self, name, a)
        if self.filled is not None:
            f = np.asarray(self.filled)
            if f.dtype != bool or f.shape != self.gyr.shape[:2]:
                raise RecordingError(f"filled must be booleans of shape (S, N) = "
                                     f"{self.gyr.shape[:2]}, got {f.dtype} of shape {f.shape}")
            object.__setattr__(self, "filled", np.ascontiguousarray(f))
        mag_shape = self.gyr.shape if self.mag is None else self.mag.shape
        if not self.acc.shape[1] == self.gyr.shape[1] == mag_shape[1]:
            raise RecordingError(f"acc, gyr and mag must have as many samples, got shapes "
                                 f"{self.acc.shape}, {self.gyr.shape} and {mag_shape}")

    @property
    def has_mag(self) -> bool:
        """Whether the sensors read a magnetometer (False: 6-axis sensors)."""
        return self.mag is not None

    def labelled(self) -> tuple:
        """The labelled stretches: `segments`, else the truth's, else ()."""
        if self.segments:
            return self.segments
        return self.truth.segments if self.truth is not None else ()

    @property
    def n(self) -> int:
        return self.acc.shape[1]

    @property
    def duration_s(self) -> float:
        return self.n / self.rate_hz

    def index(self, sensor: str) -> int:
        try:
            return self.sensors.index(sensor)
        except ValueError:
            raise RecordingError(
                f"no sensor {sensor!r} in the recording; it has {', '.join(self.sensors)}"
            ) from None

    def subset(self, sensors) -> ImuRecording:
        """The recording of `sensors` only (truth dropped)."""
        idx = [self.index(s) for s in sensors]
        return ImuRecording(self.rate_hz, tuple(sensors), self.acc[idx], self.gyr[idx],
                            None if self.mag is None else self.mag[idx], start_s=self.start_s,
                            filled=None if self.filled is None else self.filled[idx])

    def slice(self, start: int, stop: int) -> ImuRecording:
        """Samples ``start:stop`` (truth dropped)."""
        first = range(self.n)[start:stop].start if self.n else 0
        return ImuRecording(self.rate_hz, self.sensors, self.acc[:, start:stop],
                            self.gyr[:, start:stop],
                            None if self.mag is None else self.mag[:, start:stop],
                            start_s=self.start_s + first / self.rate_hz,
                            filled=None if self.filled is None else self.filled[:, start:stop])


def check_recording(rec: ImuRecording, *, acc_full_scale: float = 16 * GRAVITY_MPS2,
                    gyr_full_scale: float = np.radians(2000.0), static_s: float = 1.0,
                    source: str = "recording", sensor_calibration=None,
                    axes: bool = True) -> list[str]:
    """Check a recording; raise on unusable data, return warnings otherwise.

    Parameters
    ----------
    rec : ImuRecording
    acc_full_scale, gyr_full_scale : float, keyword-only
        The sensors' full-scale ranges (m/s^2, rad/s); the defaults are the
        widest common ones (16 g, 2000 deg/s).
    static_s : float, keyword-only
        Length of the still start, s (``--static``).
    source : str, keyword-only
        The file, for messages.
    sensor_calibration : SensorCalibration, keyword-only, optional
        The sensors' calibration (:func:`~handsynth.sensors.imu.fit_sensor_calibration`):
        the magnetometers' field strength is judged on the readings it corrects, so that a
        magnetometer's own hard and soft iron, which it removes, are not called a
        disturbance (on the held-out configuration's calibration recording 13 of 25
        sensors were, none of them near a magnet).  The other checks read `rec` as given.
    axes : bool, keyword-only
        Judge whether the gyro's and the magnetometer's axes are the accelerometer's
        (False: a stretch too short to tell, such as a static start and one common
        rotation, whose single axis of turning leaves the others unseen).

    Raises
    ------
    RecordingError
        `sensor_calibration` no :class:`SensorCalibration`;
        `acc_full_scale` or `gyr_full_scale` not a finite number > 0, a
        `static_s` or rate that is not one; non-finite samples; shapes that
        disagree; fewer than 2 samples; samples lost by the logger
        (:func:`~handsynth.sensors.imu.lost_stretches`): a sensor's
        accelerometer and gyro repeating a reading bit for bit for 0.1 s or
        more while it turns or another sensor's readings change, or reading
        exactly 0 on all six axes; a channel pinned at full
        scale, or at its own extreme value beyond 1.5 g or 2 rad/s (the flat
        top of a sensor with a smaller range), for 5 or more consecutive
        samples (saturation); values beyond the full scale by far (wrong
        units); a static start whose accelerometer magnitude is not about
        1 g (wrong acceleration units), whose gyro reads more than 0.5 rad/s
        while the accelerometer is still (deg/s given as rad/s) or whose
        accelerometer moves (the start is not still); a magnetometer that
        reads zero field (dead), or a value beyond 10,000 uT (no magnetometer's
        range: a damaged sample or the wrong units); a gyro that reads exactly 0
        on every axis in every sample of 10 or more (dead), or that turns less
        than half the angle its accelerometer's gravity direction tilts (rad/s
        given as deg/s); a median field strength outside 10-200 uT
        (magnetometer units).

    Returns
    -------
    list of str
        Warnings: a magnetometer whose field strength departs more than 15 %
        from the recording's median (a magnetic disturbance), with the time; a gyro
        far noisier at rest than its accelerometer moves (deg/s given as rad/s with
        the bias taken off); magnetometer axes that are not the accelerometer's
        (:func:`_check_mag_axes`).
    """
    check_instance(rec, ImuRecording, name=f"{source}: rec", error=RecordingError)
    if sensor_calibration is not None:
        from ._sensorcal import SensorCalibration  # it reads this module

        check_instance(sensor_calibration, SensorCalibration, name="sensor_calibration",
                       error=RecordingError)
    rate = check_rate(rec.rate_hz, source=source)
    static_s = check_static(static_s, source=source)
    for arg, value in (("acc_full_scale", acc_full_scale), ("gyr_full_scale", gyr_full_scale)):
        if not (is_number(value) and math.isfinite(value) and value > 0):
            raise RecordingError(f"{arg} must be a finite number > 0 (the sensors' full scale), "
                                 f"got {value!r}")
    s = len(rec.sensors)
    for name in ("acc", "gyr", "mag"):  # shapes and names were checked when `rec` was made
        a = getattr(rec, name)
        if a is None or math.isfinite(float(np.sum(a))):  # the quick test; a finite sum needs finite values
            continue
        bad = ~np.isfinite(a)
        if bad.any():
            k, i, j = np.argwhere(bad)[0]
            raise RecordingError(
                f"{source}: sensor {rec.sensors[k]!r} {name} axis {'xyz'[j]} is not finite "
                f"at sample {i} ({bad.sum()} such values); fill the gap in from the other "
                "sensors' readings (--bridge-lost; library: bridge_lost) or cut it first")
    if rec.n < 2:
        raise RecordingError(f"{source}: needs at least 2 samples, got {rec.n}")
    from ._lost import MAX_BRIDGE_S, lost_stretches  # _lost reads ImuRecording from here

    lost = lost_stretches(rec)
    if lost:
        h = max(lost, key=lambda x: x.duration_s)
        more = f" ({len(lost)} such stretches, this the longest)" if len(lost) > 1 else ""
        how = ("the last one repeated by the logger (a wireless link's dropout?)"
               if h.kind == "held" else "written as zeros by the logger")
        remedy = (f"cut the recording there (longer than the {MAX_BRIDGE_S:g} s bridged by "
                  "default; --bridge-lost --bridge-max SECONDS fills it in, further off)"
                  if h.duration_s > MAX_BRIDGE_S else
                  "fill them in from the other sensors' readings (--bridge-lost; library: "
                  "bridge_lost) or cut the recording there")
        raise RecordingError(f"{source}: {h.describe()}{more}: samples lost and {how}, which "
                             f"no working sensor reads; {remedy}")
    for name, fs, unit, floor, hint in (
            ("acc", acc_full_scale, "m/s^2", 1.5 * GRAVITY_MPS2,
             "acceleration in mg or cm/s^2 read as m/s^2? (acc units 'mg': --acc-units mg)"),
            ("gyr", gyr_full_scale, "rad/s", 2.0,
             "deg/s given as rad/s? (gyro units 'deg/s': --gyr-units deg/s)")):
        a = getattr(rec, name)
        absa = np.abs(a)
        peak = _per_axis(np.max, absa)  # (S, 3)
        k, j = np.unravel_index(int(np.argmax(peak)), peak.shape)
        if peak[k, j] > 1.5 * fs:
            i = int(np.argmax(np.abs(a[k, :, j])))
            raise RecordingError(
                f"{source}: sensor {rec.sensors[k]!r} {name} axis {'xyz'[j]} reads "
                f"{a[k, i, j]:.4g} {unit} at sample {i}, {peak[k, j] / fs:.3g} times the full "
                f"scale {fs:.4g} {unit}: no sensor of that range reads that; {hint}, or a "
                f"wider full scale (--acc-range, --gyr-range)")
        pinned = absa >= 0.999 * fs
        # a flat top: the channel's own extreme value held (a sensor of a smaller range);
        # only a channel at its top in 5 or more samples can hold it for 5
        top = absa >= np.maximum(peak[:, None, :], floor) * (1 - 1e-9)
        run = _longest_run(pinned)
        if (_per_axis(np.count_nonzero, top) >= 5).any():
            run = max(run, _longest_run(top & _held(a)))
        if run[0] >= 5:
            k, j, i = run[1:]
            raise RecordingError(
                f"{source}: sensor {rec.sensors[k]!r} {name} axis {'xyz'[j]} is saturated "
                f"(|value| {abs(a[k, i, j]):.4g} {unit} held at the full scale) for {run[0]} "
                f"samples from sample {i}")
    if rec.mag is not None:
        _check_mag_range(rec, source)
    # a gyro at exactly 0 while its own accelerometer's readings change: the accelerometer
    # shows the sensor alive (noise or motion), the gyro is dead.  A noise-free simulation
    # of a still hand reads 0 and a constant gravity, and is left alone.
    dead_gyr = [rec.sensors[k] for k in range(s)
                if not rec.gyr[k].any() and np.ptp(rec.acc[k], axis=0).max() > 0]
    if dead_gyr and rec.n >= 10:
        raise RecordingError(
            f"{source}: the gyro of sensor(s) {', '.join(map(repr, dead_gyr))} reads exactly 0 on "
            f"every axis in all {rec.n} samples while the accelerometer's readings change, which "
            "a working gyro never does (its noise alone moves it): dead or unconnected; leave "
            "that sensor out of the recording")
    n0 = max(2, min(rec.n, int(static_s * rate)))
    w0 = np.linalg.norm(rec.gyr[:, :n0], axis=-1).mean(axis=1)
    acc_spread = np.linalg.norm(rec.acc[:, :n0].std(axis=1), axis=-1)
    for k, w in enumerate(w0):
        if w > 0.5 and acc_spread[k] > 0.5:
            raise RecordingError(
                f"{source}: sensor {rec.sensors[k]!r} is not still during the static start "
                f"(first {static_s:g} s): the gyro reads {w:.3g} rad/s and the accelerometer "
                f"varies by {acc_spread[k]:.3g} m/s^2; start the recording at rest or "
                "shorten the static start (--static)")
    gmag = np.linalg.norm(rec.acc[:, :n0].mean(axis=1), axis=-1)
    for k, g in enumerate(gmag):
        if not (0.7 * GRAVITY_MPS2 < g < 1.3 * GRAVITY_MPS2):
            hint = " (given in g? use acc units 'g', --acc-units g)" if 0.7 < g < 1.3 else ""
            raise RecordingError(
                f"{source}: sensor {rec.sensors[k]!r} reads {g:.4g} m/s^2 over the static start, "
                f"not about 9.81 m/s^2{hint}; check the accelerometer units or the static start")
    for k, w in enumerate(w0):
        if w > 0.5:
            raise RecordingError(
                f"{source}: sensor {rec.sensors[k]!r} gyro reads {w:.3g} rad/s during the static "
                f"start while its accelerometer is still; deg/s given as rad/s? (use gyro units "
                f"'deg/s', --gyr-units deg/s)")
    _check_gyro_turns(rec, n0, source)
    warnings, gyro_off = _check_gyro_axes(rec, n0) if axes else ([], frozenset())
    # deg/s read as rad/s where the gyro's bias is small (a logger that takes it off): the
    # mean stays under 0.5 "rad/s", but the gyro's noise at rest is 57 times too large
    # (0.18 "rad/s" in the simulated start against 0.003) while the accelerometer, which
    # a real tremor would move, stays still
    gyr_spread = np.linalg.norm(rec.gyr[:, :n0].std(axis=1), axis=-1)
    noisy = [k for k in range(s) if gyr_spread[k] > _GYR_REST_SPREAD
             and gyr_spread[k] > acc_spread[k] * _GYR_PER_ACC_SPREAD]
    if noisy and n0 >= 10:
        k = max(noisy, key=lambda i: gyr_spread[i])
        warnings.append(
            f"the gyro of {len(noisy)} sensor(s) ({', '.join(rec.sensors[i] for i in noisy[:4])}"
            f"{', ...' if len(noisy) > 4 else ''}) varies by up to {gyr_spread[k]:.3g} rad/s "
            f"RMS during the static start (first {static_s:g} s) while its accelerometer varies "
            f"by {acc_spread[k]:.3g} m/s^2: {gyr_spread[k] / np.radians(0.1):.3g} times a MEMS "
            "gyro's noise at rest (about 0.1 deg/s); deg/s given as rad/s? (gyro units "
            "'deg/s', --gyr-units deg/s)")
    if rec.mag is not None:
        strength = None if sensor_calibration is None else _corrected_mag(rec, sensor_calibration)
        warnings.extend(_check_mag_field(rec, source, n0=n0, gyro_off=gyro_off,
                                         corrected_ut=strength, axes=axes))
    # what was reported for this object, so that an estimator's run does not repeat it
    object.__setattr__(rec, "reported", (rec.reported or frozenset()) | frozenset(warnings))
    return warnings


def _check_mag_range(rec: ImuRecording, source: str) -> None:
    """Refuse a magnetometer reading beyond any magnetometer's full scale."""
    assert rec.mag is not None
    peak = _per_axis(np.max, np.abs(rec.mag))
    k, j = np.unravel_index(int(np.argmax(peak)), peak.shape)
    if peak[k, j] > _MAG_FULL_SCALE_UT:
        i = int(np.argmax(np.abs(rec.mag[k, :, j])))
        raise RecordingError(
            f"{source}: sensor {rec.sensors[k]!r} mag axis {'xyz'[j]} reads {rec.mag[k, i, j]:.4g} "
            f"uT at sample {i}, beyond any magnetometer's full scale ({_MAG_FULL_SCALE_UT:g} uT; "
            "the Earth's field is 25-65 uT): a damaged sample, or the magnetometer units "
            "(--mag-units)")


def _corrected_mag(rec: ImuRecording, sensor_calibration) -> np.ndarray:
    """`rec`'s magnetometer readings, those of the sensors `sensor_calibration` holds
    corrected by it, (S, N, 3) uT in `rec`'s sensors' order."""
    assert rec.mag is not None
    known = [s for s in rec.sensors if s in sensor_calibration.sensors]
    mag = np.array(rec.mag, dtype=np.float64)
    if known:
        fixed = sensor_calibration.apply(rec.subset(known), gyro=False).mag
        for i, name in enumerate(known):
            mag[rec.index(name)] = fixed[i]
    return mag


def _check_mag_field(rec: ImuRecording, source: str, *, n0: int, gyro_off: frozenset[str],
                     corrected_ut: np.ndarray | None = None, axes: bool = True) -> list[str]:
    """Refuse dead magnetometers and a field of the wrong units; warn about disturbances and
    magnetometer axes that are not the gyro's (of the sensors not in `gyro_off`).  The
    disturbances are judged on `corrected_ut` where given (the readings corrected by the
    sensor calibration, in `rec`'s sensors' order)."""
    assert rec.mag is not None
    s, rate = len(rec.sensors), rec.rate_hz
    warnings: list[str] = []
    field_norm = np.sqrt(np.einsum("snk,snk->sn", rec.mag, rec.mag))
    per_sensor = np.median(field_norm, axis=1)
    if np.all(per_sensor <= 0):
        raise RecordingError(f"{source}: the magnetometers read zero field")
    dead = [rec.sensors[k] for k in range(s) if per_sensor[k] < 0.05 * per_sensor.max()]
    if dead:
        raise RecordingError(
            f"{source}: the magnetometer of sensor(s) {', '.join(map(repr, dead))} reads "
            f"(almost) zero field ({per_sensor.min():.3g} uT against {per_sensor.max():.3g} uT); "
            "dead or unconnected: leave that sensor out of the recording")
    med = np.median(field_norm)
    if not _EARTH_FIELD_UT[0] <= med <= _EARTH_FIELD_UT[1]:
        raise RecordingError(
            f"{source}: the magnetometers read a median field of {med:.4g} uT; the Earth's is "
            f"25-65 uT (indoors {_EARTH_FIELD_UT[0]:g}-{_EARTH_FIELD_UT[1]:g} taken as "
            "possible): check the magnetometer units (--mag-units)")
    if axes:
        warnings.extend(_check_mag_axes(rec, n0, gyro_off))
    if corrected_ut is not None:
        field_norm = np.sqrt(np.einsum("snk,snk->sn", corrected_ut, corrected_ut))
        med = np.median(field_norm)
    dev = np.abs(field_norm / med - 1.0) > 0.15
    for k in range(s):
        if dev[k].any():
            i = np.nonzero(dev[k])[0]
            warnings.append(
                f"sensor {rec.sensors[k]!r}: magnetic field strength departs >15 % from "
                f"{med:.1f} uT during {i.size / rate:.2f} s from t={i[0] / rate:.2f} s "
                "(magnetic disturbance)")
    return warnings


#: Smallest tilt, deg, of a sensor's gravity direction over a recording that the gyro check
#: judges, and the smallest ratio of the angle the gyro turns (the sum of its magnitude,
#: never less than the rotation) to that tilt: 3.0 or more in the simulated recordings,
#: 0.14 or less with rad/s read as deg/s (57 times too small).
_TILT_CHECKED_DEG = 20.0
_MIN_TURN_PER_TILT = 0.5


def _check_gyro_turns(rec: ImuRecording, n0: int, source: str) -> None:
    """Refuse a gyro that turns far less than the accelerometer says its sensor tilts.

    The accelerometer averaged over 0.5 s gives the gravity direction where the sensor
    moves little (its magnitude within 20 % of 1 g); the largest angle between that and
    the static start's is the least the sensor turned.  A gyro whose magnitude summed over
    the recording is less than half that angle reads too small a unit: rad/s given as
    deg/s (``--gyr-units deg/s`` on a file in rad/s).
    """
    w = max(1, min(rec.n, int(0.5 * rec.rate_hz)))
    if rec.n < 2 * w:
        return
    lp = moving_mean(rec.acc, w)
    g0 = rec.acc[:, :n0].mean(axis=1)
    norm = np.linalg.norm(lp, axis=-1)
    quasi = np.abs(norm - GRAVITY_MPS2) < 0.2 * GRAVITY_MPS2
    cos = np.einsum("snk,sk->sn", lp, g0) / (norm * np.linalg.norm(g0, axis=-1)[:, None] + 1e-300)
    tilt = np.degrees(np.arccos(np.clip(np.where(quasi, cos, 1.0), -1.0, 1.0))).max(axis=1)
    turned = np.degrees(np.linalg.norm(rec.gyr, axis=-1).sum(axis=1) / rec.rate_hz)
    for k in range(len(rec.sensors)):
        if tilt[k] > _TILT_CHECKED_DEG and turned[k] < _MIN_TURN_PER_TILT * tilt[k]:
            raise RecordingError(
                f"{source}: sensor {rec.sensors[k]!r} tilts by {tilt[k]:.3g} deg (its "
                f"accelerometer's gravity direction) but its gyro turns {turned[k]:.3g} deg in "
                "all: the gyro reads far too little; rad/s given as deg/s? (gyro units "
                "'rad/s': --gyr-units rad/s)")


#: A gyro varying by more than this, rad/s RMS over the static start (summed over its axes),
#: and by more than this many rad/s per m/s^2 of its accelerometer's variation, is warned
#: about as deg/s read as rad/s: the simulated MPU-9250 varies by 0.002-0.01 rad/s at
#: 60-1000 Hz (0.14-0.55 in the wrong unit) with its accelerometer at 0.04-0.16 m/s^2;
#: a hand's tremor that turns a sensor by 0.05 rad/s moves its accelerometer by more.
_GYR_REST_SPREAD = 0.05
_GYR_PER_ACC_SPREAD = 1.0

#: A gyro is named when its axes as read carry gravity's direction this many times farther
#: off (RMS angle) than another signed permutation of them does
#: (:func:`~handsynth.sensors.imu._axes.gyro_axes_errors`); pooled over the sensors of a
#: recording of `_POOLED_SENSORS` or more judged sensors, `_POOLED_RATIO` (the same
#: permutation for all, as a logger's convention is).  Measured (``python
#: scripts/study_imu_axes.py``): axes as read 0.07-1.52 on BROAD's single sensors (over 1.0
#: only on its translations and the trials with a magnet beside the sensor, which tell
#: little), 1.53 at most per sensor and 0.95 pooled on 21 simulated recordings; one axis
#: with the other sign pooled 1.68 or more, two axes exchanged 2.87 or more.
_AXES_RATIO = 2.0
_POOLED_RATIO = 1.5
_POOLED_SENSORS = 5
#: ... and only where the directions read move at least this many times farther (RMS angle
#: from each window's first) than the best reading leaves them off: a recording of
#: translations, where the accelerometer reads the hand's accelerations more than gravity,
#: has its directions move about as far as any reading of the axes misses them (BROAD's
#: translations and magnet trials 0.94-1.43), a turning one farther (as read 1.45-3.97 on
#: BROAD's other trials, 1.54-2.76 simulated; the gyro's y reversed 1.87-31.8 and 3.07-7.12).
_MOVES_RATIO = 1.5
#: Fewest directions compared (0.02-s steps) for a sensor to be judged.
_AXES_MIN_COUNT = 20


def _outside_rotations(rec: ImuRecording) -> np.ndarray | None:
    """Samples outside the calibration rotations labelled in `rec` (None: none labelled).

    A calibration rotation oscillates one joint at about 1 Hz, and its tangential
    acceleration swings the accelerometer's direction against the turn: on the held-out
    configuration's calibration recordings without static poses the gyros read with one
    axis reversed carried gravity's direction 1.33-1.54 times closer than as read (a false
    alarm at the 1.5 pooled), with static poses 0.31-0.34.
    """
    rotations = {label for label, *_ in CALIBRATION_PLAN}
    spans = [(a, b) for label, a, b in rec.labelled() if label in rotations]
    if not spans:
        return None
    keep = np.ones(rec.n, bool)
    for a, b in spans:
        keep[a:b] = False
    return keep


def _check_gyro_axes(rec: ImuRecording, n0: int) -> tuple[list[str], frozenset[str]]:
    """Warn about gyros whose axes are not their accelerometer's (a logger's convention).

    Returns the warnings and the sensors whose gyros they name (every sensor where the
    warning is pooled)."""
    sq_err, count, sq_fixed = gyro_axes_errors(rec.acc, rec.gyr, rec.rate_hz, static_n=n0,
                                               keep=_outside_rotations(rec))
    judged = count >= _AXES_MIN_COUNT
    if not judged.any():
        return [], frozenset()
    rms = np.sqrt(sq_err[judged] / count[judged, None])
    best = 1 + np.argmin(rms[:, 1:], axis=1)
    best_rms = np.maximum(rms[np.arange(len(best)), best], 1e-12)
    ratio = np.where(np.sqrt(sq_fixed[judged] / count[judged]) >= _MOVES_RATIO * best_rms,
                     rms[:, 0] / best_rms, 0.0)  # 0: the directions hardly move, not judged
    names = [s for s, j in zip(rec.sensors, judged) if j]
    pooled = np.sqrt(sq_err[judged].sum(axis=0) / count[judged].sum())
    p_best = 1 + int(np.argmin(pooled[1:]))
    p_ratio = pooled[0] / max(pooled[p_best], 1e-12)
    moves = np.sqrt(sq_fixed[judged].sum() / count[judged].sum()) >= _MOVES_RATIO * pooled[p_best]
    if len(names) >= _POOLED_SENSORS and p_ratio >= _POOLED_RATIO and moves:
        label = axes_label(*SIGNED_PERMUTATIONS[p_best])
        return [f"the gyros carry gravity's direction as their accelerometers read it only with "
                f"their axes read as ({label}): {p_ratio:.3g} times closer than as read, pooled "
                f"over {len(names)} sensors; does the logger write the gyros' axes otherwise "
                f"than the accelerometers'? Read them so (--gyr-axes {label.replace(' ', '')}; "
                "library: with_axes), or every attitude and angle will be wrong"
                ], frozenset(rec.sensors)
    off = [(n, b, r) for n, b, r in zip(names, best, ratio) if r >= _AXES_RATIO]
    found = [f"{n} ({axes_label(*SIGNED_PERMUTATIONS[b])}, {r:.3g} times closer)" for n, b, r in off]
    if not found:
        return [], frozenset()
    return [f"the gyro of {len(found)} sensor(s) carries gravity's direction as its "
            f"accelerometer reads it only with its axes read otherwise: {', '.join(found[:4])}"
            f"{', ...' if len(found) > 4 else ''}; are its axes not the accelerometer's? Turn "
            "its gyro's columns into the accelerometer's axes first (--gyr-axes turns every "
            "sensor's), or every attitude and angle will be wrong"
            ], frozenset(n for n, _, _ in off)


#: A magnetometer is named when its axes as read let the gyro carry its field's direction
#: this many times farther off (RMS angle) than another signed permutation of them does
#: (:func:`~handsynth.sensors.imu._axes.mag_axes_errors`; the reverse of every axis cannot
#: be told and is not counted).  Measured (``python scripts/study_imu_axes.py``): axes as
#: read 0.03-1.25 on BROAD's sensors (the highest with a magnet fixed 1 cm from the sensor,
#: a field that hardly turns with it), 0.63 at most on 21 simulated recordings; the
#: AK8963's axes (y, x, -z) 3.03 or more on BROAD but with that magnet (1.59), 4.59 or
#: more simulated.
_MAG_AXES_RATIO = 2.0


def _check_mag_axes(rec: ImuRecording, n0: int, gyro_off: frozenset[str]) -> list[str]:
    """Warn about magnetometers whose axes are not their gyro's (and accelerometer's).

    The gyro, integrated over 2-s windows, carries the Earth's field as the magnetometer
    reads it (:func:`~handsynth.sensors.imu._axes.mag_axes_errors`); read in the wrong axes
    (an MPU-9250's AK8963: x and y swapped, z reversed) it does not.  A sensor is named when
    another reading of its axes carries the field 2 times closer than the axes as read, and 2
    times closer than a field that stays put in the sensor; sensors whose gyro is itself
    warned about (`gyro_off`) are not judged.
    """
    assert rec.mag is not None
    sq_err, count, sq_fixed = mag_axes_errors(rec.gyr, rec.mag, rec.rate_hz, static_n=n0)
    others = [j for j in range(len(SIGNED_PERMUTATIONS)) if j not in (0, REVERSED)]
    found, labels = [], set()
    for k, name in enumerate(rec.sensors):
        if count[k] < _AXES_MIN_COUNT or name in gyro_off:
            continue
        rms = np.sqrt(sq_err[k] / count[k])
        best = others[int(np.argmin(rms[others]))]
        # and the field must turn with the gyro under that reading better than it stays put
        # (a magnet fixed to the sensor, a stuck magnetometer: no reading of its axes holds)
        fixed = np.sqrt(sq_fixed[k] / count[k])
        if rms[0] >= _MAG_AXES_RATIO * rms[best] and fixed >= _MAG_AXES_RATIO * rms[best]:
            label = axes_label(*SIGNED_PERMUTATIONS[best])
            labels.add(label)
            found.append(f"{name} ({label})")
    if not found:
        return []
    how = (f"Read them so (--mag-axes {labels.pop().replace(' ', '')}; library: with_axes)"
           if len(labels) == 1 else "Turn its columns into the accelerometer's axes first")
    return [f"the magnetometer of {len(found)} sensor(s) turns with its gyro only with its axes "
            f"read otherwise: {', '.join(found[:4])}{', ...' if len(found) > 4 else ''} of the "
            "accelerometer's; its axes are not the accelerometer's (the MPU-9250's AK8963 reads "
            f"(y, x, -z))? {how}, or its headings will be wrong"]


#: Largest magnetometer reading taken, uT: above the widest full scale of MEMS
#: magnetometers (the MPU-9250's AK8963: 4912 uT; others 800-1600 uT), with a margin.
_MAG_FULL_SCALE_UT = 10_000.0


def _per_axis(reduce, a: np.ndarray) -> np.ndarray:
    """`reduce` over the samples of (S, N, 3) `a`, one axis at a time (faster than axis=1)."""
    return np.stack([reduce(a[:, :, j], axis=1) for j in range(3)], axis=-1)


def _held(a: np.ndarray) -> np.ndarray:
    """True where a sample equals the one before or after it (a value held), shape of `a`."""
    same = a[:, 1:] == a[:, :-1]
    out = np.zeros(a.shape, bool)
    out[:, 1:] |= same
    out[:, :-1] |= same
    return out


def _longest_run(mask: np.ndarray):
    best = (0, 0, 0, 0)
    if not mask.any():
        return best
    s, _, _ = mask.shape
    for k in range(s):
        for j in range(3):
            m = mask[k, :, j]
            if not m.any():
                continue
            d = np.diff(np.r_[0, m.astype(np.int8), 0])
            starts, ends = np.nonzero(d == 1)[0], np.nonzero(d == -1)[0]
            lengths = ends - starts
            i = int(np.argmax(lengths))
            if lengths[i] > best[0]:
                best = (int(lengths[i]), k, j, int(starts[i]))
    return best


_AXES = "xyz"
#: Characters a sensor name may not hold in a CSV file (field separators the reader
#: recognises, quotes, line breaks).
_NOT_IN_NAMES = ",;\t\"'\n\r"


#: Median field strength a recording's magnetometers may read, uT: the Earth's field is
#: 25-65 uT (NOAA World Magnetic Model), and indoors steel bends it by tens of percent; a
#: median outside these is a unit error (nT, mT or gauss read as uT).
_EARTH_FIELD_UT = (10.0, 200.0)
#: Highest sampling rate taken for an IMU's, Hz (MEMS IMUs sample at up to a few kHz).
_MAX_RATE_HZ = 100_000.0
#: A ``time_ms`` column stepping faster than this holds seconds: it is above the fastest
#: output of an MPU-9250-class gyroscope (32 kHz, its low-pass filter bypassed), and a
#: 100-Hz recording in seconds under ``time_ms`` steps at 100 kHz.
_MS_COLUMN_MAX_HZ = 32_000.0


def check_unique_names(sensors, *, error: type[InvalidInputError] = RecordingError) -> None:
    """Refuse sensor names given more than once (whose data would be which?).

    Raises
    ------
    InvalidInputError
        (`error`) naming the names that repeat.
    """
    names = tuple(sensors)
    twice = sorted({x for x in names if names.count(x) > 1})
    if twice:
        raise error(f"sensor name(s) {', '.join(map(repr, twice))} given more than once; every "
                    "sensor needs its own name")


def check_rate(rate_hz, *, source: str = "recording") -> float:
    """`rate_hz` as a float, refusing a rate that is not a finite number > 0.

    Ints, floats and NumPy integer or floating scalars are numbers; a bool or
    a text (``"100"``) is not, although ``float()`` would take it.

    Raises
    ------
    RecordingError
        `rate_hz` is not a number, not finite, or not positive.
    """
    if not is_number(rate_hz):
        raise RecordingError(f"{source}: sampling rate rate_hz (--rate) is {rate_hz!r}, "
                             "not a number")
    try:
        rate = float(rate_hz)
    except OverflowError:  # an int too large for a float
        rate = math.inf
    if not (math.isfinite(rate) and 0 < rate <= _MAX_RATE_HZ):
        raise RecordingError(f"{source}: sampling rate rate_hz (--rate) must be a finite number "
                             f"> 0 Hz and at most {_MAX_RATE_HZ:g} Hz, got {rate_hz!r}")
    return rate


def check_static(static_s, *, source: str = "recording") -> float:
    """`static_s` as a float, refusing a length that is not a finite number > 0.

    A bool or a text (``"2"``) is not a number, although ``float()`` would take it.
    """
    try:
        value = float(static_s) if is_number(static_s) else math.nan
    except OverflowError:  # an int too large for a float
        value = math.inf
    if not (math.isfinite(value) and value > 0):
        raise RecordingError(f"{source}: the static start static_s (--static) must be a finite "
                             f"number of seconds > 0, got {static_s!r}")
    return value


def write_imu_csv(rec: ImuRecording, path) -> None:
    """Write `rec` as CSV (``time_s``, then ``<sensor>_<acc|gyr|mag>_<x|y|z>``, SI/uT).

    The file is written to a temporary name and renamed, so a crash never
    leaves a half-written file under `path`.

    Parameters
    ----------
    rec : ImuRecording
        Its samples are written (``time_s`` = ``start_s`` + sample index /
        ``rate_hz``, s, to the microsecond;
        acc m/s^2, gyr rad/s, mag uT (none for 6-axis sensors); 9 significant digits)
        and its rate in the
        comment line (``rate_hz``, 6 significant digits); its truth,
        ``segments`` and ``filled`` are not written.
    path : str or os.PathLike
        The file written.

    Raises
    ------
    RecordingError
        `rec` is not an :class:`ImuRecording`, or a sensor name that
        :func:`read_imu_csv` could not read back (empty, with a field
        separator, quote, line break or surrounding space).  Names that
        repeat and rates that are not finite numbers > 0 are refused when
        the recording is made.
    OutputError
        The file cannot be written.
    """
    check_instance(rec, ImuRecording, name="rec", error=RecordingError)
    for s in rec.sensors:
        if not s or s != s.strip() or any(c in s for c in _NOT_IN_NAMES):
            raise RecordingError(
                f"sensor name {s!r} cannot be written as a CSV column: a name must be "
                "non-empty, without surrounding space and without ',', ';', tab, quotes or "
                "line breaks")
    path = Path(path)
    channels = ("acc", "gyr") if rec.mag is None else ("acc", "gyr", "mag")
    cols = ["time_s"] + [f"{s}_{c}_{a}" for s in rec.sensors for c in channels for a in _AXES]
    data = [sample_times(rec)]
    for k in range(len(rec.sensors)):
        for c in channels:
            data.extend(getattr(rec, c)[k].T)
    table = np.column_stack(data)
    with atomic_open(path, "w", what="IMU recording", newline="") as f:
        f.write(f"# handsynth imu recording; acc m/s2, gyr rad/s, mag uT; rate_hz={rec.rate_hz:g}\n")
        f.write(",".join(cols) + "\n")
        np.savetxt(f, table, delimiter=",", fmt=["%.6f"] + ["%.9g"] * (table.shape[1] - 1))


#: A channel column as loggers and spreadsheets name it: a sensor, a channel and an axis
#: (``Hand1 AccX``, ``hand1.gyro.y``, ``S3_Magnetometer_Z``), read when no column has the
#: names :func:`write_imu_csv` writes.
_LOOSE_CHANNEL = re.compile(
    r"(?P<sensor>.*?[^ ._-])[ ._-]*(?P<channel>accelerometer|accel|acc|gyroscope|gyro|gyr|"
    r"magnetometer|magn|mag)[ ._-]*(?P<axis>[xyz])", re.IGNORECASE)
_LOOSE_TIME = re.compile(r"(?:time|timestamp)(?:[ ._-]+[(\[]?|[(\[])(?P<unit>s|ms)[)\]]?",
                         re.IGNORECASE)
_CHANNEL = {"accelerometer": "acc", "accel": "acc", "acc": "acc", "gyroscope": "gyr",
            "gyro": "gyr", "gyr": "gyr", "magnetometer": "mag", "magn": "mag", "mag": "mag"}


def _meaning(name: str) -> str | None:
    """The canonical name a column name means (:data:`_LOOSE_CHANNEL`, :data:`_LOOSE_TIME`)."""
    m = _LOOSE_CHANNEL.fullmatch(name)
    if m:
        sensor = re.sub(r"[ .-]+", "_", m["sensor"])
        return f"{sensor}_{_CHANNEL[m['channel'].lower()]}_{m['axis'].lower()}"
    t = _LOOSE_TIME.fullmatch(name)
    return f"time_{t['unit'].lower()}" if t else None



def _check_header(header, path, line) -> None:
    """Refuse a first line of numbers: the header is missing (its numbers would be read as
    column names, and the first repeated value named as a column that stands twice)."""
    names = [h for h in header if h]
    if names and all(reads_as_number(h) for h in names):
        raise RecordingError(
            f"{path}, line {line}: the first line holds numbers ({', '.join(names[:3])}, ...), "
            "not column names: the header (time_s, <sensor>_acc_x .. <sensor>_mag_z) is missing")


def _columns(header, col, path) -> tuple[dict[str, int], list[str], str | None, list[str],
                                         list[tuple[str, str]]]:
    """The columns by name, the sensors, the time column (or None), the columns to read,
    by name, and the columns read by their meaning (:data:`_LOOSE_CHANNEL`)."""
    renamed: list[tuple[str, str]] = []
    if not any(h.endswith("_acc_x") for h in header):
        header, renamed = names_by_meaning(header, _meaning, path=path)
        col = column_index(header, path=path)
    sensors = list(dict.fromkeys(h[: -len("_acc_x")] for h in header if h.endswith("_acc_x")))
    if not sensors:
        raise RecordingError(f"{path}: no '<sensor>_acc_x' column found (nor a column named "
                             f"like 'hand1 AccX' or 'hand1.accel.x')")
    mags = [f"{s}_mag_{a}" for s in sensors for a in _AXES]
    six_axis = not any(name in col for name in mags)  # accelerometer and gyro only
    channels = [f"{s}_{c}_{a}" for s in sensors for c in (("acc", "gyr") if six_axis else
                                                          ("acc", "gyr", "mag")) for a in _AXES]
    missing = [name for name in channels if name not in col]
    if missing and all(name.rsplit("_", 2)[-2] == "mag" for name in missing):
        without = list(dict.fromkeys(name.rsplit("_", 2)[0] for name in missing))
        raise RecordingError(
            f"{path}: no magnetometer column for sensor(s) {', '.join(without[:4])}"
            f"{', ...' if len(without) > 4 else ''} (such as {missing[0]}) while other sensors "
            "have them: give every sensor's magnetometer, or none (a 6-axis recording)")
    if missing:
        raise RecordingError(f"{path}: missing column(s) {', '.join(missing[:6])}")
    time_name = "time_s" if "time_s" in col else "time_ms" if "time_ms" in col else None
    return col, sensors, time_name, ([time_name] if time_name else []) + channels, renamed


def _read_any_csv(path: Path) -> tuple:
    """Any delimited text a spreadsheet or logger writes (:func:`read_rows`), checked.

    Returns
    -------
    col : dict
        Column of each name of the header.
    sensors : list of str
    time_name : str or None
    needed : list of str
        The columns read, in the order of `table`'s.
    lines : list of int
        Line of each row of `table` in the file.
    table : ndarray, shape (N, len(needed)), float64
    cell : callable
        ``cell(i, j)``: the text of row `i`, column `j`, for messages.
    renamed : list of (str, str)
        Columns read by their meaning: (name in the file, name read as).
    """
    content = read_rows(path, what="IMU recording")
    if len(content.rows) < 3:
        raise RecordingError(f"{path}: needs a header and at least 2 rows, got "
                             f"{len(content.rows)} lines")
    header = content.rows[0]
    _check_header(header, path, content.lines[0])
    col = column_index(header, path=path, line=content.lines[0])
    for row, line in zip(content.rows[1:], content.lines[1:]):
        if len(row) != len(header):
            raise RecordingError(f"{path}, line {line}: {len(row)} values but "
                                 f"{len(header)} columns")
    col, sensors, time_name, needed, renamed = _columns(header, col, path)
    idx = [col[name] for name in needed]
    # an empty sensor cell is a sample lost (NaN: check_recording names it, bridge_lost fills
    # it); an empty time cell stays an error
    data = {i for name, i in zip(needed, idx) if name != time_name}
    try:
        table = np.array([[row[i] if (i not in data or row[i].strip()) else "nan" for i in idx]
                          for row in content.rows[1:]], dtype=np.float64)
    except ValueError:  # find the cell to name
        for row, line in zip(content.rows[1:], content.lines[1:]):
            for name, i in zip(needed, idx):
                try:
                    float(row[i])
                except ValueError:
                    raise RecordingError(f"{path}, line {line}: {name} is {row[i]!r}, "
                                         "not a number") from None
        raise
    rows = content.rows
    return col, sensors, time_name, needed, content.lines[1:], table, \
        lambda i, j: rows[1 + i][j], renamed


def _read_plain_csv(path: Path) -> tuple | None:
    """A plain comma-separated file read straight into floats
    (:func:`handsynth._csv.read_number_table`), else None: :func:`_read_any_csv`
    reads every other file, and names what is wrong with one.

    Returns
    -------
    tuple or None
        As :func:`_read_any_csv`.
    """
    picked: dict = {}

    def usecols(header, line):
        _check_header(header, path, line)
        col = column_index(header, path=path, line=line)
        col, sensors, time_name, needed, renamed = _columns(header, col, path)
        picked.update(col=col, sensors=sensors, time_name=time_name, needed=needed,
                      renamed=renamed)
        return [col[name] for name in needed]

    got = read_number_table(path, what="IMU recording", usecols=usecols)
    if got is None or len(got.lines) < 2:
        return None

    def cell(i, j):
        line = read_text(path, what="CSV text (IMU recording)").splitlines()[got.lines[i] - 1]
        return line.split(",")[j].strip()

    return (picked["col"], picked["sensors"], picked["time_name"], picked["needed"], got.lines,
            got.table, cell, picked["renamed"])


def with_axes(rec: ImuRecording, *, gyr: str | None = None, mag: str | None = None) -> ImuRecording:
    """`rec` with its gyros' or magnetometers' axes read otherwise (a logger's convention).

    Parameters
    ----------
    rec : ImuRecording
    gyr, mag : str, optional, keyword-only
        The axes of the accelerometer that the file's gyro (magnetometer) columns x, y,
        z hold, as the axes warnings of :func:`check_recording` name them: ``"y,x,-z"``
        (an MPU-9250's AK8963 magnetometer) makes the gyro (magnetometer) reading
        ``(y, x, -z)`` of each sample (:func:`parse_axes`).
        None leaves the channel as it is.

    Returns
    -------
    ImuRecording
        A new recording (truth dropped: it belongs to the readings as simulated).

    Raises
    ------
    InvalidInputError
        `rec` not an ImuRecording; axes that do not name x, y and z once each; `mag` for
        a recording without magnetometers.
    """
    check_instance(rec, ImuRecording, name="rec")
    changes = {}
    for name, text in (("gyr", gyr), ("mag", mag)):
        if text is None:
            continue
        a = getattr(rec, name)
        if a is None:
            raise InvalidInputError(f"{name} axes given ({text!r}) for a recording without "
                                    "magnetometers")
        perm, signs = parse_axes(text, name=f"{name} axes")
        changes[name] = a[..., list(perm)] * signs
    return dataclasses.replace(rec, truth=None, **changes) if changes else rec


def check_units(**units: str) -> None:
    """Refuse a unit of a channel (``acc=``, ``gyr=``, ``mag=``) that :data:`UNITS` lacks."""
    for ch, u in units.items():
        if u not in UNITS[ch]:
            raise RecordingError(f"unknown {ch} units {u!r}; expected one of {', '.join(UNITS[ch])}")


def read_imu_csv(path, *, acc_units: str = "m/s2", gyr_units: str = "rad/s",
                 mag_units: str = "uT", rate_hz: float | None = None,
                 max_gap: float = 1.5) -> ImuRecording:
    """Read a CSV recording with per-sensor columns.

    Columns: ``time_s`` (or ``time_ms``) and, for every sensor,
    ``<sensor>_acc_x`` .. ``<sensor>_mag_z``; a file with no magnetometer
    column at all is a recording of 6-axis sensors (``mag`` None); other columns (a note, a
    date) are ignored; lines starting with ``#`` are
    comments.  A file with none of these names is read by what its names
    mean, with a warning listing them: a sensor, a channel (``acc``,
    ``accel``, ``accelerometer``, ``gyr``, ``gyro``, ``gyroscope``, ``mag``,
    ``magn``, ``magnetometer``, any case) and an axis, with or without
    spaces, dots, dashes or underscores between them (``Hand1 AccX``,
    ``hand1.gyro.y`` read as ``Hand1_acc_x``, ``hand1_gyr_y``), and
    ``Time (s)``, ``timestamp_ms`` and the like as the time column.
    Sensors are taken in the order of their first column.
    Spreadsheet exports are read as they come (``;`` or tab between the
    fields, decimal commas, quoted cells, a byte-order mark;
    :func:`handsynth._csv.read_rows`).

    The sampling rate is the mean over the span of the time stamps
    ((last - first) / (N - 1)), so rounded or jittered stamps give the
    right rate.

    Parameters
    ----------
    path : path-like
    acc_units, gyr_units, mag_units : str, keyword-only
        One of :data:`UNITS` for each channel.
    rate_hz : float, optional, keyword-only
        Sampling rate (``--rate``); by default from the time column.  A rate
        that differs from the time column's by more than 2 % is warned about.
    max_gap : float, keyword-only
        Largest allowed step between time stamps, in mean sample periods
        (widened by the stamps' own jitter); a larger step means missing
        samples and raises.

    Raises
    ------
    RecordingError
        Missing file or columns (magnetometer columns for some sensors but
        not others), a column named twice, non-numeric cells,
        time stamps that go back, repeat (unless coarser than the sampling period:
        integer milliseconds at 1024 Hz) or leave a gap, a time column whose rate is
        not an IMU's (0.5 Hz - 100 kHz: milliseconds under ``time_s``?),
        a rate that is not a finite number > 0, unknown units (see
        :func:`check_recording` for the content checks, which the caller
        runs).
    InvalidInputError
        `path` not a str or path-like (None, a number, an open file), or an empty
        name; `max_gap` not a finite number > 0 (NaN would turn the gap check off).
    """
    path = check_path(path, "path")
    max_gap = check_number(max_gap, "max_gap", above=0.0)
    check_units(acc=acc_units, gyr=gyr_units, mag=mag_units)
    if rate_hz is not None:
        rate_hz = check_rate(rate_hz, source=str(path))
    if not path.is_file():
        raise RecordingError(f"{path}: no such file")
    # a plain comma-separated file (what write_imu_csv and most loggers write) is parsed
    # straight into floats; anything else, and every file with an error in it, goes through
    # read_rows, which names the error (a recording's rows as strings take ~10x its size)
    parsed = _read_plain_csv(path)
    if parsed is None:
        parsed = _read_any_csv(path)
    col, sensors, time_name, needed, lines, table, cell, renamed = parsed
    if renamed:
        shown = ", ".join(f"{name!r} as {canon}" for name, canon in renamed[:4])
        _warnings.warn(f"{path}: {len(renamed)} columns read by their meaning ({shown}"
                       f"{', ...' if len(renamed) > 4 else ''}); check the sensors' names and "
                       f"order: {', '.join(sensors)}", stacklevel=2)
    pos = {name: i for i, name in enumerate(needed)}
    if time_name is not None:
        t = table[:, pos[time_name]] * (1.0 if time_name == "time_s" else 1e-3)
        bad = np.nonzero(~np.isfinite(t))[0]
        if bad.size:
            i = int(bad[0])
            raise RecordingError(f"{path}, line {lines[i]}: {time_name} is "
                                 f"{cell(i, col[time_name])!r}, not a number")
        dt = np.diff(t)
        step = (t[-1] - t[0]) / (t.size - 1)
        # stamps coarser than the sampling period (integer milliseconds at 1024 Hz) repeat
        # where two samples fall in one tick: equal stamps are refused only where the
        # smallest step between stamps is not longer than the mean step
        positive = dt[dt > 0]
        quantised = positive.size > 0 and positive.min() > 1.01 * step
        back = np.nonzero(dt < 0 if quantised else dt <= 0)[0]
        if back.size:
            i = int(back[0])
            raise RecordingError(
                f"{path}, line {lines[i + 1]}: time stamps do not increase ({time_name} "
                f"{cell(i + 1, col[time_name])} after "
                f"{cell(i, col[time_name])} on line {lines[i]})")
        jitter = 1.4826 * np.median(np.abs(dt - np.median(dt)))
        limit = max(max_gap * step, step + 6.0 * jitter)
        gaps = np.nonzero(dt > limit)[0]
        if gaps.size:
            i = int(gaps[0])
            # the mean step counts the gaps (one damaged stamp of 1e300 s makes it 1e297 s):
            # the stamps' usual step is their median one
            usual = float(np.median(dt)) if np.median(dt) > 0 else step
            raise RecordingError(
                f"{path}, line {lines[i + 1]}: {gaps.size} gap(s) in the time stamps, the first "
                f"{dt[i]:.4g} s long after t={t[i]:.4g} s (the stamps step {usual:.4g} s "
                f"elsewhere): missing samples, or a damaged stamp ({time_name} "
                f"{cell(i + 1, col[time_name])})")
        file_rate = 1.0 / step
        seconds_as_ms = time_name == "time_ms" and file_rate > _MS_COLUMN_MAX_HZ
        if seconds_as_ms or not 0.5 <= file_rate <= _MAX_RATE_HZ:
            hint = (" (milliseconds under time_s? name the column time_ms)"
                    if time_name == "time_s" and file_rate < 0.5 else
                    " (seconds under time_ms? name the column time_s)" if seconds_as_ms else "")
            if rate_hz is None:
                raise RecordingError(
                    f"{path}: the {time_name} column steps {step:.4g} s on average, "
                    f"{file_rate:.4g} Hz: not an IMU sampling rate{hint}; fix the time column "
                    "or give the rate (--rate)")
        if rate_hz is not None and abs(rate_hz / file_rate - 1.0) > 0.02:
            _warnings.warn(f"{path}: the rate given, {rate_hz:g} Hz (--rate), contradicts the "
                           f"{time_name} column's {file_rate:.4g} Hz; using {rate_hz:g} Hz",
                           stacklevel=2)
        rate = file_rate if rate_hz is None else rate_hz
    elif rate_hz is None:
        raise RecordingError(f"{path}: no time_s/time_ms column; pass rate_hz (--rate)")
    else:
        rate = rate_hz

    def block(ch, units):
        f = UNITS[ch][units]
        return np.stack([np.column_stack([table[:, pos[f"{s}_{ch}_{a}"]] for a in _AXES])
                         for s in sensors]) * f

    six_axis = not any(name.endswith("_mag_x") for name in needed)
    return ImuRecording(float(rate), tuple(sensors), block("acc", acc_units),
                        block("gyr", gyr_units), None if six_axis else block("mag", mag_units),
                        start_s=float(t[0]) if time_name is not None else 0.0)


def sample_times(rec: ImuRecording) -> np.ndarray:
    """The time of each sample of `rec`, s: ``start_s + i / rate_hz`` (shape (N,), float64)."""
    return rec.start_s + np.arange(rec.n) / rec.rate_hz
