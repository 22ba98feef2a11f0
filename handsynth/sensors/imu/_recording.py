"""IMU recordings: the data container, input checks and the CSV reader/writer.

A recording holds S sensors sampled together at one rate: accelerometer in
m/s^2 (specific force, +g upward at rest), gyro in rad/s, magnetometer in
microtesla, each shaped (S, N, 3).  :func:`check_recording` finds what makes
a recording unusable or suspicious (NaN, gaps in the time stamps, saturated
channels, wrong units, magnetic disturbances) and either raises
:class:`~handsynth.errors.RecordingError` naming the sensor, channel and
sample, or returns the warnings it found.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..._csv import read_rows
from ..._io import atomic_open
from ...errors import RecordingError
from ._model import GRAVITY_MPS2

__all__ = [
    "UNITS",
    "ImuRecording",
    "ImuTruth",
    "check_recording",
    "read_imu_csv",
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
    keypoints : ndarray, shape (N, 21, 3)
        Wrist, joint centres and fingertips in :data:`KEYPOINT_SITES` order.
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
    mag : ndarray, shape (S, N, 3), uT
    truth : ImuTruth or None
    segments : tuple of (str, int, int)
        Labelled stretches (label, first sample, end sample), e.g. the
        calibration rotations of a real recording; a simulation's are in
        its truth.
    """

    rate_hz: float
    sensors: tuple
    acc: np.ndarray
    gyr: np.ndarray
    mag: np.ndarray
    truth: ImuTruth | None = None
    segments: tuple = ()

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
        return ImuRecording(self.rate_hz, tuple(sensors), self.acc[idx], self.gyr[idx], self.mag[idx])

    def slice(self, start: int, stop: int) -> ImuRecording:
        """Samples ``start:stop`` (truth dropped)."""
        return ImuRecording(self.rate_hz, self.sensors, self.acc[:, start:stop],
                            self.gyr[:, start:stop], self.mag[:, start:stop])


def check_recording(rec: ImuRecording, *, acc_full_scale: float = 16 * GRAVITY_MPS2,
                    gyr_full_scale: float = np.radians(2000.0), static_s: float = 1.0,
                    source: str = "recording") -> list[str]:
    """Check a recording; raise on unusable data, return warnings otherwise.

    Raises
    ------
    RecordingError
        Non-finite samples; shapes that disagree; a channel pinned at full
        scale for 5 or more consecutive samples (saturation); a static start
        whose accelerometer magnitude is not about 1 g (wrong acceleration
        units) or whose gyro reads more than 0.5 rad/s (deg/s given as rad/s).

    Returns
    -------
    list of str
        Warnings: a magnetometer whose field strength departs more than 15 %
        from the recording's median (a magnetic disturbance), with the time.
    """
    s = len(rec.sensors)
    for name in ("acc", "gyr", "mag"):
        a = getattr(rec, name)
        if a.ndim != 3 or a.shape[0] != s or a.shape[2] != 3 or a.shape[1] != rec.acc.shape[1]:
            raise RecordingError(f"{source}: {name} has shape {a.shape}, expected ({s}, N, 3)")
        bad = ~np.isfinite(a)
        if bad.any():
            k, i, j = np.argwhere(bad)[0]
            raise RecordingError(
                f"{source}: sensor {rec.sensors[k]!r} {name} axis {'xyz'[j]} is not finite "
                f"at sample {i} ({bad.sum()} such values); fill or cut the gap first")
    if rec.n < 2:
        raise RecordingError(f"{source}: needs at least 2 samples, got {rec.n}")
    for name, fs in (("acc", acc_full_scale), ("gyr", gyr_full_scale)):
        a = np.abs(getattr(rec, name)) >= 0.999 * fs
        if a.any():
            run = _longest_run(a)
            if run[0] >= 5:
                k, j, i = run[1:]
                raise RecordingError(
                    f"{source}: sensor {rec.sensors[k]!r} {name} axis {'xyz'[j]} is saturated "
                    f"(|value| at full scale {fs:.4g}) for {run[0]} samples from sample {i}")
    n0 = max(2, min(rec.n, int(static_s * rec.rate_hz)))
    gmag = np.linalg.norm(rec.acc[:, :n0].mean(axis=1), axis=-1)
    for k, g in enumerate(gmag):
        if not (0.7 * GRAVITY_MPS2 < g < 1.3 * GRAVITY_MPS2):
            hint = " (given in g? use acc units 'g')" if 0.7 < g < 1.3 else ""
            raise RecordingError(
                f"{source}: sensor {rec.sensors[k]!r} reads {g:.4g} m/s^2 over the static start, "
                f"not about 9.81 m/s^2{hint}; check the accelerometer units or the static start")
    w0 = np.linalg.norm(rec.gyr[:, :n0], axis=-1).mean(axis=1)
    for k, w in enumerate(w0):
        if w > 0.5:
            raise RecordingError(
                f"{source}: sensor {rec.sensors[k]!r} gyro reads {w:.3g} rad/s during the static "
                f"start; deg/s given as rad/s? (use gyro units 'deg/s')")
    warnings: list[str] = []
    field_norm = np.linalg.norm(rec.mag, axis=-1)
    med = np.median(field_norm)
    if med <= 0:
        raise RecordingError(f"{source}: the magnetometers read zero field")
    dev = np.abs(field_norm / med - 1.0) > 0.15
    for k in range(s):
        if dev[k].any():
            i = np.nonzero(dev[k])[0]
            warnings.append(
                f"sensor {rec.sensors[k]!r}: magnetic field strength departs >15 % from "
                f"{med:.1f} uT during {i.size / rec.rate_hz:.2f} s from t={i[0] / rec.rate_hz:.2f} s "
                "(magnetic disturbance)")
    return warnings


def _longest_run(mask: np.ndarray):
    best = (0, 0, 0, 0)
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


def write_imu_csv(rec: ImuRecording, path) -> None:
    """Write `rec` as CSV (``time_s``, then ``<sensor>_<acc|gyr|mag>_<x|y|z>``, SI/uT).

    The file is written to a temporary name and renamed, so a crash never
    leaves a half-written file under `path`.
    """
    path = Path(path)
    cols = ["time_s"] + [f"{s}_{c}_{a}" for s in rec.sensors for c in ("acc", "gyr", "mag")
                         for a in _AXES]
    data = [np.arange(rec.n) / rec.rate_hz]
    for k in range(len(rec.sensors)):
        for arr in (rec.acc, rec.gyr, rec.mag):
            data.extend(arr[k].T)
    table = np.column_stack(data)
    with atomic_open(path, "w", what="IMU recording", newline="") as f:
        f.write(f"# handsynth imu recording; acc m/s2, gyr rad/s, mag uT; rate_hz={rec.rate_hz:g}\n")
        f.write(",".join(cols) + "\n")
        np.savetxt(f, table, delimiter=",", fmt="%.9g")


def read_imu_csv(path, *, acc_units: str = "m/s2", gyr_units: str = "rad/s",
                 mag_units: str = "uT", rate_hz: float | None = None,
                 max_gap: float = 1.5) -> ImuRecording:
    """Read a CSV recording with per-sensor columns.

    Columns: ``time_s`` (or ``time_ms``) and, for every sensor,
    ``<sensor>_acc_x`` .. ``<sensor>_mag_z``; lines starting with ``#`` are
    comments.  Sensors are taken in the order of their first column.
    Spreadsheet exports are read as they come (``;`` or tab between the
    fields, decimal commas, quoted cells, a byte-order mark;
    :func:`handsynth._csv.read_rows`).

    Parameters
    ----------
    path : path-like
    acc_units, gyr_units, mag_units : str, keyword-only
        One of :data:`UNITS` for each channel.
    rate_hz : float, optional, keyword-only
        Sampling rate; by default from the time column.
    max_gap : float, keyword-only
        Largest allowed step between time stamps, in sample periods; a larger
        step means missing samples and raises.

    Raises
    ------
    RecordingError
        Missing file or columns, non-numeric cells, non-increasing or gapped
        time stamps, unknown units, NaN (see :func:`check_recording` for the
        content checks, which the caller runs).
    """
    path = Path(path)
    for ch, u in (("acc", acc_units), ("gyr", gyr_units), ("mag", mag_units)):
        if u not in UNITS[ch]:
            raise RecordingError(f"unknown {ch} units {u!r}; expected one of {', '.join(UNITS[ch])}")
    if not path.is_file():
        raise RecordingError(f"{path}: no such file")
    content = read_rows(path, what="IMU recording")
    if len(content.rows) < 3:
        raise RecordingError(f"{path}: needs a header and at least 2 rows, got "
                             f"{len(content.rows)} lines")
    header = content.rows[0]
    for row, line in zip(content.rows[1:], content.lines[1:]):
        if len(row) != len(header):
            raise RecordingError(f"{path}, line {line}: {len(row)} values but "
                                 f"{len(header)} columns")
    try:
        table = np.array(content.rows[1:], dtype=np.float64)
    except ValueError:  # find the cell to name
        for row, line in zip(content.rows[1:], content.lines[1:]):
            for name, cell in zip(header, row):
                try:
                    float(cell)
                except ValueError:
                    raise RecordingError(f"{path}, line {line}: {name} is {cell!r}, "
                                         "not a number") from None
        raise
    col = {h: i for i, h in enumerate(header)}
    if "time_s" in col:
        t = table[:, col["time_s"]]
    elif "time_ms" in col:
        t = table[:, col["time_ms"]] * 1e-3
    else:
        t = None
    sensors: list[str] = []
    for h in header:
        for suffix in ("_acc_x",):
            if h.endswith(suffix):
                sensors.append(h[: -len(suffix)])
    if not sensors:
        raise RecordingError(f"{path}: no '<sensor>_acc_x' column found")
    missing = [f"{s}_{c}_{a}" for s in sensors for c in ("acc", "gyr", "mag") for a in _AXES
               if f"{s}_{c}_{a}" not in col]
    if missing:
        raise RecordingError(f"{path}: missing column(s) {', '.join(missing[:6])}")
    if t is not None:
        dt = np.diff(t)
        if not np.all(np.isfinite(t)) or np.any(dt <= 0):
            i = int(np.argmax(~(dt > 0))) if np.any(dt <= 0) else 0
            raise RecordingError(f"{path}: time stamps do not increase at row {i + 2}")
        step = np.median(dt)
        gaps = np.nonzero(dt > max_gap * step)[0]
        if gaps.size:
            i = int(gaps[0])
            raise RecordingError(
                f"{path}: {gaps.size} gap(s) in the time stamps, the first {dt[i]:.4g} s long "
                f"after t={t[i]:.4g} s (expected {step:.4g} s): missing samples")
        rate = 1.0 / step if rate_hz is None else rate_hz
    elif rate_hz is None:
        raise RecordingError(f"{path}: no time_s/time_ms column; pass rate_hz")
    else:
        rate = rate_hz

    def block(ch, units):
        f = UNITS[ch][units]
        return np.stack([np.column_stack([table[:, col[f"{s}_{ch}_{a}"]] for a in _AXES])
                         for s in sensors]) * f

    return ImuRecording(float(rate), tuple(sensors), block("acc", acc_units),
                        block("gyr", gyr_units), block("mag", mag_units))
