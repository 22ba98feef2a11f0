"""Readers of real recordings: Polhemus PiMgr / Liberty text exports.

PiMgr (Polhemus' Liberty manager, the patent's recording software, para.
0097) and the Liberty's ASCII output write one line per sensor per frame:
whitespace- or comma-separated numbers, typically ``station x y z azimuth
elevation roll`` with positions in inches or centimetres and Euler angles in
degrees, or a quaternion ``w x y z`` when so configured.  Column layout,
units and angle convention differ between set-ups, so every one is an
argument here.  Polhemus' azimuth, elevation, roll are rotations about the
transmitter's z, then the new y, then the new x: intrinsic ``"ZYX"``.
"""

from __future__ import annotations

import os
import re
import warnings
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

from ...errors import InvalidInputError, RecordingError
from ._recording import Recording

__all__ = ["DEFAULT_COLUMNS", "read_polhemus", "read_recording"]

#: Default column layout: station number, position, Euler angles.
DEFAULT_COLUMNS = ("sensor", "x", "y", "z", "a1", "a2", "a3")
_UNITS_M = {"m": 1.0, "cm": 1e-2, "mm": 1e-3, "in": 0.0254}
_NUMBER = re.compile(r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?|nan|NaN|NAN")


def _parse_lines(path: Path, n_cols: int) -> tuple[np.ndarray, np.ndarray]:
    """Numeric rows of a text file and their 1-based line numbers."""
    rows, lines = [], []
    try:
        text = path.read_text(encoding="utf-8", errors="replace")
    except OSError as exc:
        raise RecordingError(f"cannot read {str(path)!r}: {exc.strerror or exc}") from None
    bad = []
    for no, line in enumerate(text.splitlines(), start=1):
        s = line.strip()
        if not s or s[0] in "#%;":  # comments
            continue
        fields = [f for f in re.split(r"[,\s]+", s) if f]
        if not _NUMBER.fullmatch(fields[0]) and fields[0][0].isalpha():
            continue  # a header line such as "Sensor X Y Z Az El Ro"
        if not all(_NUMBER.fullmatch(f) for f in fields):
            bad.append(no)
            continue
        if len(fields) < n_cols:
            bad.append(no)
            continue
        rows.append([float(f) for f in fields[:n_cols]])
        lines.append(no)
    if not rows:
        raise RecordingError(
            f"{str(path)!r}: no data line with {n_cols} numeric columns found"
            + (f" (first unparseable line: {bad[0]})" if bad else "")
        )
    if bad:
        frac = len(bad) / (len(bad) + len(rows))
        if frac > 0.05:
            raise RecordingError(
                f"{str(path)!r}: {len(bad)} of {len(bad) + len(rows)} data lines cannot "
                f"be parsed with {n_cols} numeric columns (first: line {bad[0]})"
            )
        warnings.warn(
            f"{path.name}: skipped {len(bad)} unparseable lines (first: line {bad[0]})",
            stacklevel=3,
        )
    return np.asarray(rows, dtype=np.float64), np.asarray(lines)


#: Slack on the Euler-angle ranges, degrees (a tracker may print 180.00 or 90.004).
_EULER_SLACK_DEG = 0.01


def _check_euler_range(a: np.ndarray, lines: np.ndarray, finite: np.ndarray, order: str,
                       path: Path, names: tuple[str, ...], suffix: str) -> None:
    """Refuse Euler angles outside their ranges: first and last in [-180, 180] deg, the
    middle one in [-90, 90] deg (Tait-Bryan orders such as Polhemus' azimuth, elevation,
    roll) or [0, 180] deg (proper Euler orders such as ZXZ).  Out-of-range values mean
    another column layout or unit, not an orientation."""
    tait_bryan = len(set(order.upper())) == 3
    lo_mid, hi_mid = (-90.0, 90.0) if tait_bryan else (0.0, 180.0)
    bounds = ((-180.0, 180.0), (lo_mid, hi_mid), (-180.0, 180.0))
    for j, (lo, hi) in enumerate(bounds):
        col = a[finite, j]
        bad = np.flatnonzero((col < lo - _EULER_SLACK_DEG) | (col > hi + _EULER_SLACK_DEG))
        if bad.size:
            k = int(bad[0])
            raise RecordingError(
                f"{path.name} line {int(lines[finite][k])}: Euler angle {names[j] + suffix} is "
                f"{col[k]:g} deg, outside [{lo:g}, {hi:g}] for order {order!r}; are the columns, "
                "the angle format and the units right?")


def read_polhemus(
    path: str | os.PathLike,
    *,
    columns: tuple[str, ...] | None = None,
    units: str = "cm",
    angles: str = "euler",
    euler_order: str = "ZYX",
    sensors: tuple[int, int] = (1, 2),
    rate_hz: float = 240.0,
    labels: tuple[str, str] = ("upper", "lower"),
    joint: str = "joint",
    on_invalid: str = "raise",
) -> Recording:
    """Read a PiMgr / Liberty text export of two sensors.

    Parameters
    ----------
    path : path-like
    columns : tuple of str, optional
        Name of each leading column; extra columns are ignored.  Default
        :data:`DEFAULT_COLUMNS`, or ``("sensor", "x", "y", "z", "qw", "qx",
        "qy", "qz")`` with ``angles="quaternion"``.  Required:
        ``"x", "y", "z"`` and either ``"a1", "a2", "a3"`` (Euler angles in
        degrees, applied in `euler_order`) or ``"qw", "qx", "qy", "qz"``.
        ``"sensor"`` (station number) marks a one-sensor-per-line file;
        ``"frame"`` (frame counter) and ``"time"`` (seconds) are optional.
        Without ``"sensor"``, each line holds both sensors and the names
        carry a suffix: ``"x1", ..., "a31", "x2", ...``.
    units : {"cm", "in", "mm", "m"}
        Unit of the positions (PiMgr default: inches or cm, as configured).
    angles : {"euler", "quaternion"}
    euler_order : str
        SciPy Euler sequence; ``"ZYX"`` (intrinsic) is Polhemus' azimuth,
        elevation, roll.
    sensors : (int, int)
        Station numbers of the upper and lower sensor.
    rate_hz : float
        Sampling rate used to build times when there is no ``"time"`` column
        (frame counter times ``1 / rate_hz`` when there is a ``"frame"``).
    labels, joint : see :class:`Recording`.
    on_invalid : {"raise", "drop"}
        What to do with frames that have NaN values or miss one of the two
        sensors: raise :class:`RecordingError` naming them, or drop them with
        a warning naming how many and which.

    Returns
    -------
    Recording

    Raises
    ------
    RecordingError
        Unreadable or unparseable file, missing sensors, NaN or missing rows
        (with ``on_invalid="raise"``), matrices that are not rotations.
    InvalidInputError
        Bad arguments.
    """
    path = Path(path)
    if units not in _UNITS_M:
        raise InvalidInputError(f"units: expected one of {sorted(_UNITS_M)}, got {units!r}")
    if angles not in ("euler", "quaternion"):
        raise InvalidInputError(f"angles: expected 'euler' or 'quaternion', got {angles!r}")
    if on_invalid not in ("raise", "drop"):
        raise InvalidInputError(f"on_invalid: expected 'raise' or 'drop', got {on_invalid!r}")
    if not (np.isfinite(rate_hz) and rate_hz > 0):
        raise InvalidInputError(f"rate_hz must be > 0, got {rate_hz!r}")
    if columns is None:
        columns = DEFAULT_COLUMNS if angles == "euler" else (
            "sensor", "x", "y", "z", "qw", "qx", "qy", "qz")
    columns = tuple(columns)
    if len(set(columns)) != len(columns):
        raise InvalidInputError(f"columns: duplicate names in {columns!r}")
    ang = ("a1", "a2", "a3") if angles == "euler" else ("qw", "qx", "qy", "qz")
    long_format = "sensor" in columns
    per_sensor = ("x", "y", "z", *ang)
    need = per_sensor if long_format else tuple(
        f"{c}{k}" for k in (1, 2) for c in per_sensor
    )
    missing = [c for c in need if c not in columns]
    if missing:
        raise InvalidInputError(
            f"columns: {missing} missing for angles={angles!r} in {columns!r}"
        )
    data, line_no = _parse_lines(path, len(columns))
    col = {c: i for i, c in enumerate(columns)}

    def pose(rows: np.ndarray, lines: np.ndarray, suffix: str = "") -> tuple[np.ndarray, np.ndarray]:
        pos = rows[:, [col[c + suffix] for c in ("x", "y", "z")]] * _UNITS_M[units]
        a = rows[:, [col[c + suffix] for c in ang]]
        finite = np.isfinite(a).all(axis=1)
        rot = np.full((rows.shape[0], 3, 3), np.nan)
        if angles == "euler":
            _check_euler_range(a, lines, finite, euler_order, path, ang, suffix)
            rot[finite] = Rotation.from_euler(euler_order, a[finite], degrees=True).as_matrix()
        else:
            q = a[finite]
            norm = np.linalg.norm(q, axis=1)
            if np.any(np.abs(norm - 1) > 1e-2):
                i = int(np.flatnonzero(np.abs(norm - 1) > 1e-2)[0])
                raise RecordingError(
                    f"{path.name}: quaternion with norm {norm[i]:.4f} != 1 at line "
                    f"{lines[finite][i]}; is the angle format really 'quaternion'?"
                )
            rot[finite] = Rotation.from_quat(q[:, [1, 2, 3, 0]]).as_matrix()
        return pos, rot

    if long_format:
        station = data[:, col["sensor"]]
        unknown = sorted(set(station[np.isfinite(station)].astype(int)) - set(sensors))
        if unknown:
            warnings.warn(f"{path.name}: ignoring stations {unknown}", stacklevel=2)
        if "frame" in col:
            frame_id = data[:, col["frame"]]
        else:  # consecutive lines of the first sensor start a new frame
            frame_id = np.cumsum(station == sensors[0]).astype(np.float64)
        frames = np.unique(frame_id[np.isin(station, sensors)])
        n = frames.size
        positions = np.full((n, 2, 3), np.nan)
        rotations = np.full((n, 2, 3, 3), np.nan)
        times = frames / rate_hz if "frame" in col else np.arange(n) / rate_hz
        for s, st in enumerate(sensors):
            rows = station == st
            if not rows.any():
                raise RecordingError(f"{path.name}: no line of sensor (station) {st}")
            k = np.searchsorted(frames, frame_id[rows])
            p, r = pose(data[rows], line_no[rows])
            positions[k, s], rotations[k, s] = p, r
            if "time" in col and s == 0:
                times = np.full(n, np.nan)
                times[k] = data[rows, col["time"]]
    else:
        n = data.shape[0]
        positions = np.empty((n, 2, 3))
        rotations = np.empty((n, 2, 3, 3))
        for s, k in enumerate(("1", "2")):
            positions[:, s], rotations[:, s] = pose(data, line_no, k)
        if "time" in col:
            times = data[:, col["time"]]
        elif "frame" in col:
            times = data[:, col["frame"]] / rate_hz
        else:
            times = np.arange(n) / rate_hz

    bad = ~(
        np.isfinite(positions).all(axis=(1, 2))
        & np.isfinite(rotations).all(axis=(1, 2, 3))
        & np.isfinite(times)
    )
    if bad.any():
        where = np.flatnonzero(bad)
        msg = (
            f"{path.name}: {where.size} of {n} frames have NaN values or miss a "
            f"sensor's line (frames {where[:8].tolist()}{' ...' if where.size > 8 else ''})"
        )
        if on_invalid == "raise":
            raise RecordingError(msg + "; pass on_invalid='drop' to skip them")
        warnings.warn(msg + "; dropped", stacklevel=2)
        keep = ~bad
        times, positions, rotations = times[keep], positions[keep], rotations[keep]
    return Recording(
        times=times,
        positions=positions,
        rotations=rotations,
        labels=labels,
        joint=joint,
        metadata={
            "source": str(path),
            "format": "polhemus-text",
            "units": units,
            "angles": angles,
            "euler_order": euler_order,
            "columns": list(columns),
            "sensors": list(sensors),
            "dropped_frames": int(bad.sum()),
        },
    )


def read_recording(path: str | os.PathLike, **kwargs) -> Recording:
    """Read a recording, choosing the reader by file name.

    ``.h5`` / ``.hdf5`` files go to :func:`~handsynth.sensors.load_recording`
    (no options), anything else to :func:`read_polhemus` with `kwargs`.
    """
    from ._hdf5 import load_recording

    if Path(path).suffix.lower() in (".h5", ".hdf5"):
        if kwargs:
            raise InvalidInputError(
                f"options {sorted(kwargs)} apply to text exports, not HDF5 {str(path)!r}"
            )
        return load_recording(path)
    return read_polhemus(path, **kwargs)
