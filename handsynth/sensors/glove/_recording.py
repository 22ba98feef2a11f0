"""A glove recording: sensor readings, optional reference angles, labels; CSV I/O.

CSV layout (one header line, comma-separated, one row per sample)::

    time_s,motion,trial,sensor_thumb,...,sensor_little[,thumb_cmc_flex,...,little_dip_flex]

The joint columns use the canonical names of :data:`handsynth.models.JOINT_NAMES`
and are optional (a recording to be estimated has none).  ``motion`` may be
empty where unknown, ``trial`` is an integer.  Empty or ``nan`` sensor cells
are read as NaN (a dropped sample), and the estimators flag them.
"""

from __future__ import annotations

import csv
import re
import warnings
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..._checks import check_path, short_repr
from ..._csv import column_index, names_by_meaning, read_rows, reads_as_number
from ..._io import atomic_open
from ...errors import InvalidInputError, RecordingError
from ...models import JOINT_NAMES
from ._models import GloveWarning
from ._motions import MOTIONS
from ._sensors import GLOVE_KINDS, SENSOR_NAMES

#: Labels of the open-hand and fist holds of a range calibration (column ``motion``).
RANGE_LABELS = ("range_open", "range_fist")
#: Labels read whatever their case, with spaces or dashes for ``_`` (``STANDARD`` is
#: ``standard``, ``Range Open`` is ``range_open``): the motions and holds handsynth knows.
_KNOWN_LABELS = {name.lower(): name for name in (*MOTIONS, *RANGE_LABELS)}

__all__ = ["GloveRecording", "read_glove_csv", "write_angles_csv", "write_glove_csv"]

#: A glove's own name for a finger's sensor, any case, spaces, dots or dashes for ``_``:
#: ``Thumb``, ``index sensor``, ``Bend_Middle``, ``pinky``.
_LOOSE_SENSOR = re.compile(r"(?:(?:sensor|bend|flex)_)?(?P<finger>thumb|index|middle|ring|little|"
                           r"pinky|pinkie)(?:_(?:sensor|bend|flex))?")


#: A time column in seconds as loggers name it: ``Time (s)``, ``time [s]``, ``Time_S``.
_LOOSE_TIME_S = re.compile(r"(?:time|timestamp)(?:_[(\[]?|[(\[])s[)\]]?")


#: A time column in milliseconds: ``time_ms``, ``Time (ms)``, ``timestamp [ms]``.
_LOOSE_TIME_MS = re.compile(r"(?:time|timestamp)(?:_[(\[]?|[(\[])ms[)\]]?")


def _time_ms_column(header: list[str]) -> int | None:
    """Index of the one column of `header` that names a time in milliseconds, or None."""
    found = [i for i, h in enumerate(header)
             if _LOOSE_TIME_MS.fullmatch(re.sub(r"[ .-]+", "_", h.strip().lower()))]
    return found[0] if len(found) == 1 else None


def _meaning(name: str, *, time_given: bool) -> str | None:
    """The canonical name a glove export's column name means: a finger's sensor
    (:data:`SENSOR_NAMES`), or ``time_s`` when the file has no ``time_s`` column."""
    loose = re.sub(r"[ .-]+", "_", name.strip().lower())
    if _LOOSE_TIME_S.fullmatch(loose):
        return None if time_given else "time_s"
    m = _LOOSE_SENSOR.fullmatch(loose)
    if not m:
        return None
    finger = "little" if m["finger"] in ("pinky", "pinkie") else m["finger"]
    return f"sensor_{finger}"


@dataclass(frozen=True, eq=False)
class GloveRecording:
    """Readings of a five-sensor glove with optional reference joint angles.

    Parameters
    ----------
    sensors : ndarray, shape (N, 5), float64, counts
        Raw readings thumb to little finger (:data:`SENSOR_NAMES`); NaN marks
        a missing sample.
    angles : ndarray, shape (N, 20), float64, deg, or None
        Reference joint angles (canonical order), e.g. from a 22-sensor glove
        worn under it; None when unknown.
    motion : ndarray, shape (N,), str
        Motion name per sample, "" where unknown.
    trial : ndarray, shape (N,), int64
        Trial number per sample; a (motion, trial) pair is one trial.
    time_s : ndarray, shape (N,), float64, s
    kind : str
        Glove design, one of :data:`GLOVE_KINDS`, or "" when unknown.
    truth : ndarray, shape (N, 20), float64, deg, or None
        Noise-free joint angles of a simulated recording (``angles`` then
        carries the reference glove's error); None for real data.
    adc_max : float
        Full scale of the readings (a reading at 0 or `adc_max` is saturated; one
        below 0 or above `adc_max` is out of the converter's range).
    meta : dict
        Free-form notes (not written to CSV).
    lines : ndarray, shape (N,), int64, or None
        Line of each sample in the file it was read from (1 = the header line),
        so that messages name rows as the file numbers them; None for data not
        read from a file.

    Raises
    ------
    RecordingError
        Shapes that do not match (the message names the field and shape).
    """

    sensors: np.ndarray
    angles: np.ndarray | None = None
    # None means "unknown" and becomes an array in __post_init__
    motion: np.ndarray = None  # type: ignore[assignment]
    trial: np.ndarray = None  # type: ignore[assignment]
    time_s: np.ndarray = None  # type: ignore[assignment]
    kind: str = ""
    truth: np.ndarray | None = None
    adc_max: float = 4095.0
    meta: dict = field(default_factory=dict)
    lines: np.ndarray | None = None

    def __post_init__(self) -> None:
        try:
            s = np.asarray(self.sensors, dtype=np.float64)
        except (TypeError, ValueError):
            raise RecordingError(f"sensors must be an (N, 5) array of readings, got "
                                 f"{type(self.sensors).__name__} {short_repr(self.sensors)}") from None
        if s.ndim != 2 or s.shape[1] != 5:
            raise RecordingError(f"sensors must have shape (N, 5), got {s.shape}")
        n = s.shape[0]
        object.__setattr__(self, "sensors", s)
        for name in ("angles", "truth"):
            a = getattr(self, name)
            if a is not None:
                try:
                    a = np.asarray(a, dtype=np.float64)
                except (TypeError, ValueError):
                    raise RecordingError(f"{name} must be an ({n}, 20) array of angles, got "
                                         f"{type(a).__name__} {short_repr(a)}") from None
                if a.shape != (n, len(JOINT_NAMES)):
                    raise RecordingError(f"{name} must have shape ({n}, 20), got {a.shape}")
                object.__setattr__(self, name, a)
        motion = np.full(n, "", dtype=object) if self.motion is None \
            else np.asarray(self.motion, dtype=object)
        trial = np.zeros(n, dtype=np.int64) if self.trial is None \
            else np.asarray(self.trial, dtype=np.int64)
        time_s = np.arange(n, dtype=np.float64) if self.time_s is None \
            else np.asarray(self.time_s, dtype=np.float64)
        for name, arr in (("motion", motion), ("trial", trial), ("time_s", time_s)):
            if arr.shape != (n,):
                raise RecordingError(f"{name} must have shape ({n},), got {arr.shape}")
        object.__setattr__(self, "motion", motion)
        object.__setattr__(self, "trial", trial)
        object.__setattr__(self, "time_s", time_s)
        if self.kind not in ("", *GLOVE_KINDS):
            raise RecordingError(f"kind must be one of {', '.join(GLOVE_KINDS)} or '', "
                                 f"got {self.kind!r}")
        _check_adc_max(self.adc_max)
        if self.lines is not None:
            lines = np.asarray(self.lines, dtype=np.int64)
            if lines.shape != (n,):
                raise RecordingError(f"lines must have shape ({n},), got {lines.shape}")
            object.__setattr__(self, "lines", lines)

    @property
    def n_samples(self) -> int:
        return self.sensors.shape[0]

    def select(self, mask) -> GloveRecording:
        """The samples where boolean `mask` (shape (N,)) is true."""
        m = np.asarray(mask, dtype=bool)
        return GloveRecording(
            sensors=self.sensors[m],
            angles=None if self.angles is None else self.angles[m],
            motion=self.motion[m], trial=self.trial[m], time_s=self.time_s[m],
            kind=self.kind, truth=None if self.truth is None else self.truth[m],
            adc_max=self.adc_max, meta=dict(self.meta),
            lines=None if self.lines is None else self.lines[m])

    def trials(self) -> list[tuple[str, int]]:
        """The (motion, trial) pairs in order of first appearance."""
        seen = dict.fromkeys(zip(self.motion.tolist(), self.trial.tolist()))
        return list(seen)

    def phase(self) -> np.ndarray:
        """Time within each trial scaled to [0, 1], shape (N,), float64."""
        out = np.zeros(self.n_samples)
        for m, t in self.trials():
            idx = np.flatnonzero((self.motion == m) & (self.trial == t))
            ts = self.time_s[idx]
            span = ts.max() - ts.min()
            out[idx] = (ts - ts.min()) / span if span > 0 else 0.0
        return out

    @staticmethod
    def concatenate(recs) -> GloveRecording:
        """Join recordings end to end (their kinds must agree)."""
        recs = list(recs)
        kinds = {r.kind for r in recs} - {""}
        if len(kinds) > 1:
            raise RecordingError(f"cannot join recordings of glove kinds {sorted(kinds)}")

        def cat(name):
            vals = [getattr(r, name) for r in recs]
            return None if any(v is None for v in vals) else np.concatenate(vals)

        return GloveRecording(
            sensors=cat("sensors"), angles=cat("angles"), motion=cat("motion"),
            trial=cat("trial"), time_s=cat("time_s"), kind=kinds.pop() if kinds else "",
            truth=cat("truth"), adc_max=max(r.adc_max for r in recs))


def _atomic_write(path, write) -> Path:
    with atomic_open(path, "w", what="glove CSV", newline="") as f:
        write(f)
    return Path(path)


def write_glove_csv(path, rec: GloveRecording, *, with_angles: bool = True) -> Path:
    """Write `rec` as CSV (layout in the module docstring), atomically.

    The file appears complete or not at all.  Reference `angles` are written
    when present and `with_angles` is true; the simulator's noise-free truth
    is never written.

    Parameters
    ----------
    path : str or os.PathLike
        Written whole or not at all.
    rec : GloveRecording
        Its ``time_s`` (s, 6 decimals), ``motion``, ``trial`` and ``sensors``
        (counts, 4 decimals) are written; its ``kind``, ``adc_max`` and
        ``meta`` are not.
    with_angles : bool, keyword-only
        Write the reference ``angles`` (deg, 4 decimals) as the joint columns
        when `rec` has them.

    Returns
    -------
    pathlib.Path
        `path`.

    Raises
    ------
    OutputError
        The file cannot be written.
    """
    angles = rec.angles if with_angles else None
    header = ["time_s", "motion", "trial", *SENSOR_NAMES]
    if angles is not None:
        header += list(JOINT_NAMES)

    def write(f):
        w = csv.writer(f)
        w.writerow(header)
        for i in range(rec.n_samples):
            row = [f"{rec.time_s[i]:.6f}", rec.motion[i], int(rec.trial[i])]
            row += [_fmt(v) for v in rec.sensors[i]]
            if angles is not None:
                row += [_fmt(v) for v in angles[i]]
            w.writerow(row)

    return _atomic_write(path, write)


def write_angles_csv(path, angles: np.ndarray, *, time_s: np.ndarray | None = None) -> Path:
    """Write estimated joint angles in degrees with canonical column names.

    Parameters
    ----------
    path : str or Path
        Written whole or not at all.
    angles : array_like, shape (N, 20), deg
        NaN where a row could not be estimated (written ``nan``).
    time_s : array_like, shape (N,), s, keyword-only, optional
        The first column, ``time_s``; without it the first column is
        ``sample``, the row's index (not a time).

    Returns
    -------
    pathlib.Path

    Raises
    ------
    InvalidInputError
        `angles` not (N, 20) numbers or with an infinite value; `time_s` not
        N finite numbers.
    """
    try:
        angles = np.asarray(angles, dtype=np.float64)
        t = None if time_s is None else np.asarray(time_s, dtype=np.float64)
    except (TypeError, ValueError):
        raise InvalidInputError("angles and time_s must be arrays of numbers") from None
    if angles.ndim != 2 or angles.shape[1] != len(JOINT_NAMES):
        raise InvalidInputError(f"angles must have shape (N, {len(JOINT_NAMES)}), got {angles.shape}")
    if np.isinf(angles).any():
        raise InvalidInputError("angles must not hold infinite values (NaN marks a row not estimated)")
    n = angles.shape[0]
    if t is not None and (t.shape != (n,) or not np.isfinite(t).all()):
        raise InvalidInputError(f"time_s must be {n} finite numbers (one per row of angles), got "
                                f"shape {t.shape}" + ("" if t.shape != (n,) else " with NaN or inf"))

    def write(f):
        w = csv.writer(f)
        w.writerow(["time_s" if t is not None else "sample", *JOINT_NAMES])
        for i in range(n):
            first = f"{t[i]:.6f}" if t is not None else str(i)
            w.writerow([first, *(_fmt(v) for v in angles[i])])

    return _atomic_write(path, write)


def _fmt(v: float) -> str:
    return "nan" if not np.isfinite(v) else f"{v:.4f}"


def glove_columns(header: list[str], *, path, line: int) -> tuple[list[str], dict[str, int],
                                                                  int | None]:
    """A glove CSV's header read: its names (a glove's own read by their meaning, with a
    warning), the column of each name, and the column of a time in milliseconds (None
    where the header has ``time_s`` or no such column; warned of when read).

    Raises
    ------
    RecordingError
        A header of numbers (no header), a missing sensor column, a name given twice.
    """
    first = header
    if not any(c in header for c in SENSOR_NAMES):  # a glove's own names, read by meaning
        given = "time_s" in header
        header, renamed = names_by_meaning(header, lambda h: _meaning(h, time_given=given),
                                           path=path)
        if renamed:
            shown = ", ".join(f"{name!r} as {canon}" for name, canon in renamed)
            warnings.warn(f"{path}: {len(renamed)} columns read by their meaning "
                          f"({shown})", GloveWarning, stacklevel=3)
    missing = [c for c in SENSOR_NAMES if c not in header]
    if missing and sum(reads_as_number(c) for c in first) >= len(SENSOR_NAMES):
        raise RecordingError(f"{path}, line {line}: the first line holds numbers, "
                             "not column names; a glove CSV starts with a header line naming "
                             f"its columns ({', '.join(('time_s', 'motion', 'trial', *SENSOR_NAMES))})")
    if missing:
        raise RecordingError(f"{path}: missing sensor column(s) {', '.join(missing)}; "
                             f"header is {', '.join(header)}")
    col = column_index(header, path=path, line=line)
    ms_col = None if "time_s" in col else _time_ms_column(header)
    if ms_col is not None:
        warnings.warn(f"{path}: column {header[ms_col]!r} read as time_s (milliseconds / 1000)",
                      GloveWarning, stacklevel=3)
    return header, col, ms_col


def read_glove_csv(path, *, kind: str = "", adc_max: float = 4095.0) -> GloveRecording:
    """Read a glove CSV written by :func:`write_glove_csv` or by hand.

    Parameters
    ----------
    path : str or Path
        Sensor columns ``sensor_thumb`` .. ``sensor_little``; a file with none
        of them is read by what its names mean, with a warning listing them:
        a finger's name, any case, alone or with ``sensor``, ``bend`` or
        ``flex`` (``Thumb``, ``index sensor``, ``Bend-Middle``; ``pinky``
        for the little finger), and ``Time (s)`` or the like as ``time_s``.
    kind : str, keyword-only
        Glove design to record in the result ("" if unknown).
    adc_max : float, keyword-only
        Full scale of the readings, counts.

    Returns
    -------
    GloveRecording
        With ``angles`` when all 20 joint columns are present, and ``lines``,
        each row's line in the file (for messages).  A time column in
        milliseconds (``time_ms``, ``Time (ms)``) is read as ``time_s`` / 1000
        with a warning when the file has no ``time_s``; a file with neither
        gets ``time_s`` = the row index and ``meta["time_column"]`` False.

    Raises
    ------
    RecordingError
        No such file, no header (a first line of numbers is named as such), a
        missing sensor column, two columns that
        name one finger's sensor, some but not all
        joint columns, a row of the wrong length, or a cell that is not a
        number, is infinite or beyond any reading or angle; the message names
        the file, line and column.
    InvalidInputError
        `path` not a str or path-like (None, a number, an open file), or an empty name.
    """
    path = check_path(path, "path")
    _check_adc_max(adc_max)  # before reading the file
    content = read_rows(path, what="glove CSV")
    rows = content.rows
    if not rows:
        raise RecordingError(f"{path}: empty file, expected a header line")
    header, col, ms_col = glove_columns(rows[0], path=path, line=content.lines[0])
    joints = [c for c in JOINT_NAMES if c in header]
    if joints and len(joints) != len(JOINT_NAMES):
        absent = [c for c in JOINT_NAMES if c not in header]
        raise RecordingError(f"{path}: joint columns are incomplete, missing "
                             f"{', '.join(absent)}")
    body = rows[1:]
    if not body:
        raise RecordingError(f"{path}: no data rows after the header")
    n = len(body)
    sensors = np.empty((n, 5))
    angles = np.empty((n, len(JOINT_NAMES))) if joints else None
    motion = np.full(n, "", dtype=object)
    trial = np.zeros(n, dtype=np.int64)
    time_s = np.arange(n, dtype=np.float64)
    for i, (r, line) in enumerate(zip(body, content.lines[1:])):
        while len(r) > len(header) and r[-1] == "":  # a logger's delimiter after each row
            r = r[:-1]
        if len(r) != len(header):
            raise RecordingError(f"{path}, line {line}: {len(r)} fields, header has "
                                 f"{len(header)}")
        for k, name in enumerate(SENSOR_NAMES):
            sensors[i, k] = _num(r[col[name]], path, line, name, allow_empty=True,
                                 bound=_MAX_READING)
        if angles is not None:
            for k, name in enumerate(JOINT_NAMES):
                angles[i, k] = _num(r[col[name]], path, line, name, allow_empty=True,
                                    bound=_MAX_ANGLE_DEG)
        if "time_s" in col:
            time_s[i] = _num(r[col["time_s"]], path, line, "time_s", finite=True)
        elif ms_col is not None:
            time_s[i] = _num(r[ms_col], path, line, header[ms_col], finite=True) / 1000.0
        if "motion" in col:
            label = r[col["motion"]].strip()
            motion[i] = _KNOWN_LABELS.get(re.sub(r"[ -]+", "_", label.lower()), label)
        if "trial" in col:
            v = _num(r[col["trial"]], path, line, "trial", finite=True)
            if v != int(v) or abs(v) >= 2**31:
                raise RecordingError(f"{path}, line {line}: trial must be an integer, "
                                     f"got {r[col['trial']]!r}")
            trial[i] = int(v)
    if angles is not None:
        _check_degrees(angles, path)
    timed = "time_s" in col or ms_col is not None
    _check_trials(time_s, motion, trial, content.lines[1:], path, has_time=timed)
    return GloveRecording(sensors=sensors, angles=angles, motion=motion, trial=trial,
                          time_s=time_s, kind=kind, adc_max=adc_max,
                          meta={"time_column": timed},
                          lines=np.asarray(content.lines[1:], dtype=np.int64))


def _check_trials(time_s, motion, trial, lines, path, *, has_time: bool) -> None:
    """Refuse a trial given in two stretches or whose time goes back.

    A trial is one stretch of rows (:meth:`GloveRecording.phase` places its
    samples by their time within it).  Repeats of a motion written under one
    trial number would be mixed into one trial of nonsense and fail later with
    a message about something else.
    """
    last: dict[tuple[str, int], tuple[float, int]] = {}
    prev_key = None
    for t, m, k, line in zip(time_s.tolist(), motion.tolist(), trial.tolist(), lines):
        key = (m, k)
        seen = last.get(key)
        if seen is not None and key != prev_key:
            raise RecordingError(
                f"{path}, line {line}: motion {m!r}, trial {k} starts again after other rows "
                f"(it stopped at line {seen[1]}): two trials under one number? give each "
                "trial its own number in the 'trial' column")
        if seen is not None and has_time and t < seen[0]:
            raise RecordingError(
                f"{path}, line {line}: time_s goes back from {seen[0]:g} s (line {seen[1]}) to "
                f"{t:g} s within motion {m!r}, trial {k}: two trials under one number? "
                "give each trial its own number in the 'trial' column")
        last[key] = (t, line)
        prev_key = key



def _check_adc_max(adc_max) -> None:
    if isinstance(adc_max, bool) or not isinstance(adc_max, (int, float)) \
            or not 0 < adc_max < np.inf:
        raise RecordingError(f"adc_max (--adc-max), the full scale of the readings, must be a "
                             f"positive number of counts, got {adc_max!r}")


#: Largest |reading| (counts) and |joint angle| (deg) a glove file can hold: beyond, a cell
#: is corrupt, and the regressions would overflow into a calibration of infinities.
_MAX_READING = 1e9
_MAX_ANGLE_DEG = 720.0


def _num(cell: str, path, line: int, name: str, *, allow_empty: bool = False,
         finite: bool = False, bound: float = np.inf) -> float:
    s = cell.strip()
    if s == "" and allow_empty:
        return float("nan")
    try:
        v = float(s)
    except ValueError:
        raise RecordingError(f"{path}, line {line}: {name} is {cell!r}, not a number") from None
    if np.isinf(v) or (finite and np.isnan(v)):
        raise RecordingError(f"{path}, line {line}: {name} is {cell!r}, not a finite number")
    if abs(v) > bound:
        raise RecordingError(f"{path}, line {line}: {name} is {cell!r}, beyond any "
                             f"{'reading' if name in SENSOR_NAMES else 'joint angle'} "
                             f"(|value| <= {bound:g})")
    return v


#: Reference angles that all lie within this many degrees are read as radians: a
#: calibration recording flexes the fingers far beyond 3.3 deg (its motions close the hand).
_RADIANS_SPAN_DEG = 3.3


def _check_degrees(angles: np.ndarray, path) -> None:
    """Refuse reference angles that look like radians (the columns are degrees)."""
    finite = angles[np.isfinite(angles)]
    if finite.size and np.abs(finite).max() <= _RADIANS_SPAN_DEG and np.ptp(finite) > 0:
        raise RecordingError(
            f"{path}: every joint angle lies within +-{np.abs(finite).max():.2f}; the joint "
            "columns are degrees and a calibration recording flexes the fingers much further: "
            "are they in radians? (multiply by 180/pi)")
