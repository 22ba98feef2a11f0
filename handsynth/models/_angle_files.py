"""Files of joint angles, one row per frame, read back (to write them in another format).

Three commands write the 20 joint angles under their canonical names
(:data:`~handsynth.models.JOINT_NAMES`, degrees): ``handsynth estimate --out`` (CSV or JSON
Lines, times in ``timestamp_s``; a frame with no hand in view has no angles),
``handsynth imu track --angles-out`` and ``handsynth glove apply`` (CSV, ``time_s``; a
``sample`` count where the readings had no time).  :func:`read_angle_table` reads any of them,
and any CSV or JSON Lines file with those 20 columns.
"""

from __future__ import annotations

import json
import math
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .._checks import check_number
from .._csv import column_index, read_rows, read_text
from ..errors import RecordingError
from ._joints import JOINT_NAMES

__all__ = ["TIME_COLUMNS", "AngleTable", "read_angle_table"]

#: Columns read as each row's time, seconds, in order of preference.
TIME_COLUMNS: tuple[str, ...] = ("time_s", "timestamp_s")
#: Largest angle magnitude read, deg (two turns: beyond it a cell is not an angle).
_MAX_ABS_DEG = 720.0
_MAX_RATE_HZ = 100_000.0


@dataclass(frozen=True)
class AngleTable:
    """Joint angles read from a file, one row per frame.

    Attributes
    ----------
    path : Path
    angles_deg : ndarray, shape (N, 20), float64
        Degrees, canonical order; NaN in a row that has no angles (a frame with no hand).
    times_s : ndarray, shape (N,), or None
        Each row's time (the file's ``time_s`` or ``timestamp_s``), strictly increasing;
        None where the file has no time column.
    lines : ndarray, shape (N,), int
        Each row's line in the file (1 = the first line).
    """

    path: Path
    angles_deg: np.ndarray
    times_s: np.ndarray | None
    lines: np.ndarray

    def resampled(self, rate_hz: float | None = None) -> tuple[np.ndarray, float]:
        """The angles at a constant frame rate, rows without angles filled.

        With a time column the angles are interpolated linearly, joint by joint, at
        `rate_hz` from the first row's time to the last (by default at the rows' median
        rate, so evenly spaced rows are kept as they are); without one each row is a frame
        at `rate_hz`.  A row without angles takes them from the rows either side
        (interpolated; the nearest row's at the ends), with a warning counting such rows.

        Parameters
        ----------
        rate_hz : float, optional
            Frames per second; needed where the file has no time column.

        Returns
        -------
        angles : ndarray, shape (M, 20), float64
            Degrees, every value finite.
        rate_hz : float

        Raises
        ------
        RecordingError
            No row has angles; no time column and no `rate_hz`; `rate_hz` not a positive
            finite number up to 100 kHz.
        """
        a, t = self.angles_deg, self.times_s
        whole = np.isfinite(a).all(axis=1)
        if not whole.any():
            raise RecordingError(f"{self.path}: no row has all 20 joint angles (every frame "
                                 "without a hand?)")
        if rate_hz is not None:
            rate = float(check_number(rate_hz, "rate_hz", above=0, maximum=_MAX_RATE_HZ,
                                      error=RecordingError))
        elif t is None:
            raise RecordingError(f"{self.path}: no time column ({' or '.join(TIME_COLUMNS)}): "
                                 "give the frame rate")
        else:
            # to 4 digits: times written to the microsecond put 30 Hz at 30.0003
            rate = float(f"{1.0 / float(np.median(np.diff(t))):.4g}") if len(t) > 1 else 1.0
        missing = int((~whole).sum())
        if missing:
            first = int(self.lines[np.flatnonzero(~whole)[0]])
            warnings.warn(f"{self.path}: {missing} of {len(a)} rows have no angles (first at "
                          f"line {first}); their frames take the angles of the rows either side",
                          stacklevel=2)
        if t is None:
            x = np.arange(len(a), dtype=float)
            x_new = x
        else:
            x = t
            count = int(math.floor((t[-1] - t[0]) * rate + 1e-6)) + 1
            x_new = t[0] + np.arange(count) / rate
        out = np.column_stack([np.interp(x_new, x[whole], a[whole, j])
                               for j in range(a.shape[1])])
        return out, rate


def _number(cell, path, line: int, column: str) -> float:
    """A cell as an angle or time: empty, null and NaN read as NaN; other text refused."""
    if cell is None or (isinstance(cell, str) and cell.strip().lower() in ("", "nan", "null")):
        return math.nan
    if isinstance(cell, bool):
        raise RecordingError(f"{path}, line {line}, {column}: {cell!r} is not a number")
    try:
        v = float(cell)
    except (TypeError, ValueError):
        raise RecordingError(f"{path}, line {line}, {column}: {cell!r} is not a number") from None
    if not math.isnan(v) and not abs(v) <= (_MAX_ABS_DEG if column in JOINT_NAMES else 1e13):
        raise RecordingError(f"{path}, line {line}, {column}: {cell!r} is not "
                             + ("an angle in degrees (beyond 720)" if column in JOINT_NAMES
                                else "a time in seconds"))
    return v


def _jsonl_rows(path: Path) -> tuple[list[dict], list[int]]:
    text = read_text(path, what="JSON Lines of joint angles")
    rows, lines = [], []
    for no, line in enumerate(text.splitlines(), start=1):
        if not line.strip():
            continue
        try:
            row = json.loads(line)
        except json.JSONDecodeError as exc:
            raise RecordingError(f"{path}, line {no}: not JSON ({exc.msg})") from None
        if not isinstance(row, dict):
            raise RecordingError(f"{path}, line {no}: a JSON {type(row).__name__}, expected an "
                                 "object of joint angles")
        rows.append(row)
        lines.append(no)
    return rows, lines


def read_angle_table(path) -> AngleTable:
    """Read joint angles from a CSV or JSON Lines file (module docstring).

    Parameters
    ----------
    path : str or os.PathLike
        A ``.jsonl`` or ``.ndjson`` file is read as JSON Lines, anything else as delimited
        text with a header.

    Returns
    -------
    AngleTable

    Raises
    ------
    RecordingError
        No such file, binary content, no rows, a joint column missing (naming them), a cell
        that is not a number or an angle beyond 720 deg (naming line, column and value), a
        time that does not advance (naming the line).
    """
    path = Path(path)
    if not path.is_file():
        raise RecordingError(f"cannot read joint angles {str(path)!r}: no such file")
    cells: list[list]
    if path.suffix.lower() in (".jsonl", ".ndjson"):
        records, lines = _jsonl_rows(path)
        names = list(dict.fromkeys(k for r in records for k in r))
        cells = [[r.get(n) for n in names] for r in records]
    else:
        content = read_rows(path, what="joint-angle table")
        if not content.rows:
            raise RecordingError(f"{path}: no rows")
        names = content.rows[0]
        column_index(names, path=path, line=content.lines[0])
        cells = list(content.rows[1:])
        lines = content.lines[1:]
        for row, no in zip(cells, lines):
            if len(row) != len(names):
                raise RecordingError(f"{path}, line {no}: {len(row)} cells, the header has "
                                     f"{len(names)}")
    missing = [n for n in JOINT_NAMES if n not in names]
    if missing:
        shown = ", ".join(missing[:4]) + (f" and {len(missing) - 4} more" if len(missing) > 4
                                          else "")
        raise RecordingError(f"{path}: no column {shown}; expected the 20 joint angles "
                             f"({JOINT_NAMES[0]} .. {JOINT_NAMES[-1]}, degrees) as handsynth "
                             "writes them")
    if not cells:
        raise RecordingError(f"{path}: a header and no rows")
    col = {n: i for i, n in enumerate(names)}
    angles = np.array([[_number(row[col[n]], path, no, n) for n in JOINT_NAMES]
                       for row, no in zip(cells, lines)])
    times = None
    time_name = next((n for n in TIME_COLUMNS if n in col), None)
    if time_name is not None:
        times = np.array([_number(row[col[time_name]], path, no, time_name)
                          for row, no in zip(cells, lines)])
        bad = np.flatnonzero(~np.isfinite(times))
        if bad.size:
            raise RecordingError(f"{path}, line {lines[bad[0]]}: no {time_name}")
        back = np.flatnonzero(np.diff(times) <= 0)
        if back.size:
            i = back[0] + 1
            raise RecordingError(f"{path}, line {lines[i]}: {time_name} {times[i]:g} does not "
                                 f"come after the row before's {times[i - 1]:g}")
    return AngleTable(path, angles, times, np.asarray(lines, dtype=int))
