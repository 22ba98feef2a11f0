"""Readers of real recordings: Polhemus PiMgr and Liberty text exports.

Two families of files reach users (PiMgr, Polhemus' Liberty manager, is the
patent's recording software, para. 0097):

* **PiMgr CSV** with a header, one line per sample holding both sensors::

      Time,w1,x1,y1,z1,w2,x2,y2,z2,loc1_x,loc1_y,loc1_z,loc2_x,loc2_y,loc2_z

  ``w, x, y, z`` are the sensor's quaternion (scalar first), ``loc`` its
  position.  Times are Unix seconds or seconds from the start; PiMgr writes
  rows faster than the tracker samples, so a sample can appear on two rows
  (identical pose values): such duplicates are dropped and counted.
* **Liberty ASCII** (the tracker's own output, also what PiMgr saves as
  text): one line per station and frame, ``station [frame] x y z`` then
  Euler angles ``azimuth elevation roll`` (degrees) or a quaternion
  ``w x y z``.  The frame-counter column is optional; it is recognised by
  the number of columns together with an integer counter that never
  decreases, and the layout found is recorded, never guessed silently
  (eight columns that are neither a unit quaternion nor a counter are an
  error).  A frame is two consecutive lines of the two stations, in the
  order the file writes them (station 1 then 2, or 2 then 1, whichever
  order forms the most frames; not the order `sensors` names them in), or,
  with a counter, both lines of one counter value: a station line without
  its partner -- a lost line -- drops that half frame, it is never merged
  into a neighbour.  A counter that restarts (takes written into one file)
  keeps one take (``take``, the first by default) with a warning naming the
  line, as a time column does.
  Cells may be quoted (``"Time","w1",...``).

Polhemus' azimuth, elevation, roll are rotations about the transmitter's
``z``, then the new ``y``, then the new ``x``: intrinsic ``"ZYX"``.

Decimal commas (``12,5`` with ``;`` or whitespace between fields) are read
and recorded.  A number with an underscore (``1_000``, which Python's
``float`` reads but no exporter writes) is refused, naming the line and the
cell; so is a number no tracker writes (beyond 1e100 in any column, a position
beyond 1e5 in the file's unit, a time beyond 1e13, a frame counter beyond 1e12),
naming the line, the column and the value, and a header that names a column the
reader uses twice.  A file that ends without a line end was cut off while being written
(the last line may stop mid-number, ``12.3`` of ``12.345``): its last line is
left out with a warning naming it.  Position units are checked against a
finger joint: two sensors on adjacent phalanges are 10-90 mm apart
(receivers 9.6 mm wide, para. 0094; phalanges up to about 50 mm, Buchholz et
al. 1992); with ``units="auto"`` the unit that puts the median spacing
nearest 28 mm is used, and an explicit unit that puts it outside that range
is warned about when another unit would not.  Centimetres and inches (2.54 apart) both fit
many spacings: when they do and the spacing chosen is outside 22.4-35 mm, the
guess is warned about (a cm file with sensors 15 mm apart reads as inches).  Glitches -- a sensor position
more than `glitch_mm` from the median of its five-frame neighbourhood, which
smooth finger motion never is -- are dropped, counted and named (a file where
half the frames or more would be glitches is refused instead: glitches are
isolated, and so many point to positions read in the wrong unit); so are
dropouts (a sensor at exactly ``(0, 0, 0)``, however many frames in a row)
and frozen stretches (one sensor's position and angles repeated bit for bit
over five or more frames while the other sensor moves: the repeats are
dropped, the stretch's first frame, the real sample that was repeated, is
kept; a sensor frozen throughout is left to the estimators, which refuse
it).  Euler angles all within +-pi are warned about as radians.  A time
column that is constant is refused; one that restarts (takes written into
one file) keeps one take (``take``, the first by default) with a warning naming
the line; one that
advances by seconds per sample is warned about as milliseconds.  A time
column gives the sample times; `rate_hz` gives them only without one.
"""

from __future__ import annotations

import dataclasses
import inspect
import os
import re
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy.ndimage import median_filter
from scipy.spatial.transform import Rotation

from ..._checks import check_path
from ..._csv import read_text
from ...errors import InvalidInputError, RecordingError
from ._checks import check_integer, check_number
from ._recording import Recording

__all__ = ["DEFAULT_COLUMNS", "read_polhemus", "read_recording"]

#: Highest sampling rate taken: trackers sample at up to about 1 kHz (Polhemus Viper 960 Hz).
_MAX_RATE_HZ = 100_000.0
#: Column layout of Liberty ASCII without frame counter (Euler angles).
DEFAULT_COLUMNS = ("sensor", "x", "y", "z", "a1", "a2", "a3")
_UNITS_M = {"cm": 1e-2, "in": 0.0254, "mm": 1e-3, "m": 1.0}
_NUMBER = re.compile(r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?|[-+]?(?:nan|NaN|NAN|inf|Inf)")
_COMMA_NUMBER = re.compile(r"[-+]?\d+,\d+(?:[eE][-+]?\d+)?")
_SPACING_MM = (10.0, 90.0)  # plausible distance of two sensors across a finger joint
_TYPICAL_SPACING_MM = 28.0
#: A spacing within this factor of the typical one decides between cm and inches.
_UNIT_DECIDES = 1.25
_BINARY_MAGIC = {
    b"PK\x03\x04": "a zip archive (an .npz file?)",
    b"\x93NUMPY": "a NumPy .npy file",
    b"\x89HDF": "an HDF5 file (give it the .h5 suffix)",
}


@dataclass
class _Table:
    """Parsed numeric rows of a text export."""

    rows: np.ndarray  # (m, k) float64
    lines: np.ndarray  # (m,) 1-based line numbers
    header: tuple[str, ...] | None
    decimal_comma: bool
    skipped: list[int]  # unparseable line numbers
    cut_line: int | None = None  # last line left out: the file ends without a line end


def _read_text(path: Path) -> str:
    text = read_text(path, what="a Polhemus text export", signatures=_BINARY_MAGIC)
    if not text.strip():
        raise RecordingError(f"{str(path)!r} is empty")
    return text


def _split(line: str, sep: str, decimal_comma: bool) -> list[str]:
    if sep == "ws":
        fields = line.split()
    else:
        fields = [f.strip() for f in line.split(sep)]
    # quoted cells ("Time","w1",... or "0.0125"): the quotes are not part of the value
    fields = [f[1:-1].strip() if len(f) >= 2 and f[0] == f[-1] and f[0] in "\"'" else f
              for f in fields]
    if decimal_comma:
        fields = [f.replace(",", ".") for f in fields]
    return fields


def _tokenise(path: Path) -> _Table:
    """Numeric rows of a text export, the header names and the separator."""
    text = _read_text(path)
    physical = text.splitlines()
    content = []
    for no, line in enumerate(physical, start=1):
        s = line.strip()
        if s and s[0] not in "#%":
            content.append((no, s))
    if not content:
        raise RecordingError(f"{str(path)!r} has no data lines (only blanks or comments)")
    cut_line = None
    if text[-1] not in "\r\n" and len(content) > 1 and content[-1][0] == len(physical):
        # a recording cut off while being written: the last line may stop mid-number
        # (``12.3`` of ``12.345``), which reads as a wrong value, not as an error
        cut_line = content.pop()[0]
        warnings.warn(
            f"{path}, line {cut_line}: the file ends without a line end, as a recording cut "
            f"off while being written does; line {cut_line} was left out", stacklevel=3)
    sample = [s for _, s in content[:200]]
    # separator and decimal mark
    if sum(";" in s for s in sample) > len(sample) // 2:
        sep, dec = ";", any(_COMMA_NUMBER.search(s) for s in sample)
    elif any("," in s for s in sample):
        ws_tokens = [t for s in sample for t in s.split()]
        dec = (
            len(ws_tokens) > 0
            and any(_COMMA_NUMBER.fullmatch(t) for t in ws_tokens)
            and all(_NUMBER.fullmatch(t) or _COMMA_NUMBER.fullmatch(t) for t in ws_tokens
                    if not t[0].isalpha())
            and all(len(s.split()) >= 4 for s in sample if not s[0].isalpha())
        )
        sep = "ws" if dec else ","
    else:
        sep, dec = "ws", False
    header = None
    rows, lines, skipped = [], [], []
    for no, s in content:
        fields = _split(s, sep, dec)
        if not any(fields):
            skipped.append(no)
            continue
        for j, f in enumerate(fields):
            if "_" in f and _NUMBER.fullmatch(f.replace("_", "")):
                cell = _split(s, sep, False)[j]  # as the file writes it
                raise RecordingError(f"{path}, line {no}: {cell!r} is not a number as "
                                     f"recordings write them (an underscore)")
        if all(_NUMBER.fullmatch(f) for f in fields if f) and all(fields):
            rows.append([float(f) for f in fields])
            lines.append(no)
        elif not rows and header is None and any(f[:1].isalpha() for f in fields if f):
            header = tuple(f.strip().strip('"').lower() for f in fields)
        else:
            skipped.append(no)
    if not rows:
        raise RecordingError(
            f"{str(path)!r}: no data line of numbers found"
            + (f" (first unparseable line: {skipped[0]})" if skipped else "")
        )
    counts = np.array([len(r) for r in rows])
    values, freq = np.unique(counts, return_counts=True)
    k = int(values[np.argmax(freq)])
    odd = counts != k
    if odd.any():
        skipped.extend(int(n) for n in np.asarray(lines)[odd])
        rows = [r for r, o in zip(rows, odd) if not o]
        lines = [n for n, o in zip(lines, odd) if not o]
    skipped.sort()
    total = len(rows) + len(skipped)
    if skipped and len(skipped) > 0.05 * total:
        raise RecordingError(
            f"{str(path)!r}: {len(skipped)} of {total} lines cannot be read as the "
            f"{k} numeric fields most lines have (mixed field counts or text; first: "
            f"line {skipped[0]})"
        )
    table = _Table(np.asarray(rows, dtype=np.float64), np.asarray(lines), header, dec, skipped,
                   cut_line)
    _refuse_huge(table, path, np.ones(k, dtype=bool), _MAX_ABS_VALUE,
                 "no tracker export writes a number this large")
    return table


def _column_name(table: _Table, j: int) -> str:
    """The header's name of column `j` (0-based), or its number."""
    if table.header is not None and len(table.header) == table.rows.shape[1]:
        return f"column {table.header[j]!r}"
    return f"column {j + 1}"


def _refuse_huge(table: _Table, path: Path, columns: np.ndarray, limit: float, why: str) -> None:
    """Refuse the first cell of `columns` (a boolean mask of the table's columns) whose
    magnitude exceeds `limit`, naming the line, the column and the value.

    Such a cell is a damaged line, never a measurement; left in, it would overflow in
    the arithmetic that follows (``1e300`` squared) or pass for a glitch or a restart.
    NaN and infinity are not judged here (they make invalid frames, dropped and counted).
    """
    if table.rows.size == 0 or not columns.any():
        return
    with np.errstate(invalid="ignore"):
        big = np.isfinite(table.rows) & (np.abs(table.rows) > limit) & columns[None, :]
    if big.any():
        i, j = (int(v) for v in np.argwhere(big)[0])
        raise RecordingError(
            f"{path}, line {int(table.lines[i])}, {_column_name(table, j)}: value "
            f"{table.rows[i, j]:g} is beyond {limit:g} in magnitude ({why}); a damaged line?")


#: Largest magnitude of any number in a text export: beyond it the file is damaged.
_MAX_ABS_VALUE = 1e100
#: Largest magnitude of a position in the file's unit: 100 m in millimetres, 1 km in
#: centimetres; a tracker's range is a few metres.
_MAX_ABS_POSITION = 1e5
#: Largest time stamp: Unix time in milliseconds is about 1.7e12.
_MAX_ABS_TIME = 1e13
#: Largest frame counter: 130 years at 240 Hz.
_MAX_COUNTER = 1e12


def _check_magnitudes(table: _Table, lay: _Layout, path: Path) -> None:
    """Refuse a position, time or frame counter beyond what a tracker can write."""
    k = table.rows.shape[1]
    pos = np.zeros(k, dtype=bool)
    pos[[j for p in lay.pos for j in p]] = True
    _refuse_huge(table, path, pos, _MAX_ABS_POSITION,
                 "a position 100 m away in millimetres, farther in any other unit")
    for col, limit, what in ((lay.time, _MAX_ABS_TIME, "a time stamp"),
                             (lay.frame, _MAX_COUNTER, "a frame counter")):
        if col is not None:
            mask = np.zeros(k, dtype=bool)
            mask[col] = True
            _refuse_huge(table, path, mask, limit, f"not {what}")


# --------------------------------------------------------------------------
# layouts


@dataclass
class _Layout:
    """Where the fields of one line are."""

    kind: str  # "station" (one sensor per line) or "wide" (both sensors per line)
    description: str
    time: int | None = None
    frame: int | None = None
    station: int | None = None
    pos: tuple[list[int], ...] = ()  # per sensor (wide) or one entry (station)
    ang: tuple[list[int], ...] = ()
    angles: str = "euler"


def _is_counter(col: np.ndarray, station: np.ndarray) -> bool:
    if not np.all(np.isfinite(col)) or not np.all(col == np.round(col)) or np.any(col < 0):
        return False
    for st in np.unique(station):
        c = col[station == st]
        if c.size > 1 and (np.any(np.diff(c) < 0) or not np.any(np.diff(c) > 0)):
            return False
    return True


def _counter_restart(col: np.ndarray, station: np.ndarray | None) -> int | None:
    """Row where a frame counter restarts (two takes in one file), or None.

    The column must be an integer counter (see `_is_counter`) up to that row,
    and the row's value lower than the previous one of its station: a counter
    never goes back within one take.
    """
    if station is None:
        station = np.zeros(col.shape[0])
    if not np.all(np.isfinite(col)) or not np.all(col == np.round(col)) or np.any(col < 0):
        return None
    first = None
    for st in np.unique(station):
        idx = np.flatnonzero(station == st)
        back = np.flatnonzero(np.diff(col[idx]) < 0)
        if back.size and (first is None or idx[back[0] + 1] < first):
            first = int(idx[back[0] + 1])
    if first is None or not _is_counter(col[:first], station[:first]):
        return None
    return first


def _counter_restarts(col: np.ndarray, station: np.ndarray | None) -> list[int]:
    """Every row where a frame counter restarts (:func:`_counter_restart`, take after take)."""
    starts: list[int] = []
    while True:
        off = starts[-1] if starts else 0
        i = _counter_restart(col[off:], None if station is None else station[off:])
        if i is None or i == 0:
            return starts
        starts.append(off + i)


def _select_take(path: Path, column: str, starts: list[int], lines: np.ndarray,
                 jump: tuple[float, float], take: int, notes: dict, stacklevel: int) -> slice:
    """The rows of take `take` (1 = the first) of a file whose `column` restarts at the rows
    `starts` (first from ``jump[0]`` to ``jump[1]``), with a warning that says which take is
    used and how many rows are dropped.

    Raises
    ------
    RecordingError
        The file holds fewer takes than `take`.
    """
    n = len(lines)
    bounds = [0, *starts, n]
    takes = len(bounds) - 1
    if take > takes:
        raise RecordingError(
            f"{path.name}: take={take}, but the {column} restarts {takes - 1} time(s) (at line(s) "
            f"{[int(lines[i]) for i in starts][:5]}): the file holds {takes} takes")
    rows = slice(bounds[take - 1], bounds[take])
    i = starts[0]
    first = (f"only the rows before line {int(lines[i])} are used" if take == 1 else
             f"take {take} is used (lines {int(lines[rows.start])}-{int(lines[rows.stop - 1])})")
    warnings.warn(
        f"{path.name} line {int(lines[i])}: the {column} restarts ({jump[0]:g} -> "
        f"{jump[1]:g}): {'two' if takes == 2 else takes} takes in one file? {first} "
        f"({n - (rows.stop - rows.start)} rows of the other take{'s' if takes > 2 else ''} "
        f"dropped; take=N, --take N, reads another)", stacklevel=stacklevel + 1)
    notes["restart_line"] = int(lines[i])
    notes["rows_after_restart"] = n - i
    notes["takes"] = takes
    notes["take"] = take
    return rows


def _unit_quaternions(q: np.ndarray) -> bool:
    norm = np.linalg.norm(q, axis=1)
    ok = np.isfinite(norm)
    return bool(ok.any() and np.mean(np.abs(norm[ok] - 1) < 2e-2) > 0.99)


def _detect_station_layout(t: _Table, path: Path) -> _Layout:
    rows = t.rows
    k = rows.shape[1]
    station = rows[:, 0]
    if not (np.all(station == np.round(station)) and np.all((station >= 0) & (station <= 32))):
        raise RecordingError(
            f"{path.name}: the first column is not a station number (values "
            f"{np.unique(station)[:4].tolist()}...) and there is no header naming the "
            f"columns; expected Liberty ASCII 'station [frame] x y z az el ro' or a PiMgr "
            f"CSV with a header"
        )
    if k == 7:
        return _Layout("station", "Liberty ASCII: station x y z azimuth elevation roll",
                       station=0, pos=([1, 2, 3],), ang=([4, 5, 6],))
    counter = k in (8, 9) and _is_counter(rows[:, 1], station)
    # a counter that restarts (two takes in one file) is a counter too: the reader keeps
    # the first take
    restarts = k in (8, 9) and not counter and _counter_restart(rows[:, 1], station) is not None
    if k == 8:
        quat = _unit_quaternions(rows[:, 4:8])
        if quat and not counter:
            return _Layout("station", "Liberty ASCII: station x y z qw qx qy qz", station=0,
                           pos=([1, 2, 3],), ang=([4, 5, 6, 7],), angles="quaternion")
        if (counter or restarts) and not quat:
            return _Layout("station", "Liberty ASCII: station frame x y z azimuth elevation roll",
                           station=0, frame=1, pos=([2, 3, 4],), ang=([5, 6, 7],))
        raise RecordingError(
            f"{path.name}: 8 columns that are "
            + ("both a frame counter + Euler angles and a unit quaternion"
               if quat else "neither a frame counter (column 2) nor a unit quaternion "
               "(columns 5-8)")
            + "; give the layout with columns=(...)"
        )
    if k == 9:
        if _unit_quaternions(rows[:, 5:9]) and (counter or restarts):
            return _Layout("station", "Liberty ASCII: station frame x y z qw qx qy qz",
                           station=0, frame=1, pos=([2, 3, 4],), ang=([5, 6, 7, 8],),
                           angles="quaternion")
        raise RecordingError(
            f"{path.name}: 9 columns but not 'station frame x y z qw qx qy qz' (no "
            f"increasing integer counter in column 2 or no unit quaternion in columns 6-9)"
        )
    raise RecordingError(
        f"{path.name}: {k} numeric columns and no header: not a Liberty ASCII layout "
        f"(7 to 9 columns: station [frame] x y z and 3 Euler angles or a quaternion)"
    )


def _header_layout(header: tuple[str, ...], k: int, path: Path) -> _Layout:
    if len(header) != k:
        raise RecordingError(
            f"{path.name}: the header names {len(header)} columns but the data lines have {k}"
        )
    idx = {h: i for i, h in enumerate(header)}

    def find(*names: str) -> int | None:
        """Column of the first of `names` in the header; a name it gives twice is refused."""
        name = next((n for n in names if n in idx), None)
        if name is None:
            return None
        where = [i + 1 for i, h in enumerate(header) if h == name]
        if len(where) > 1:
            raise RecordingError(
                f"{path.name}: the header names column {name!r} {len(where)} times (columns "
                f"{', '.join(map(str, where))}); which one holds the data is unknown")
        return idx[name]

    pos, ang = [], []
    for s in ("1", "2"):
        p = [find(f"loc{s}_{c}", f"pos{s}_{c}", f"{c}{s}_pos") for c in "xyz"]
        q = [find(f"{c}{s}", f"q{c}{s}") for c in "wxyz"]
        e = [find(f"{c}{s}") for c in ("az", "el", "ro")]
        if any(i is None for i in p):
            raise RecordingError(
                f"{path.name}: header {','.join(header)!r} has no position columns "
                f"loc{s}_x, loc{s}_y, loc{s}_z for sensor {s}"
            )
        if all(i is not None for i in q):
            ang.append([int(i) for i in q if i is not None])
        elif all(i is not None for i in e):
            ang.append([int(i) for i in e if i is not None])
        else:
            raise RecordingError(
                f"{path.name}: header has no orientation of sensor {s} (w{s},x{s},y{s},z{s} "
                f"or az{s},el{s},ro{s})"
            )
        pos.append([int(i) for i in p if i is not None])
    angles = "quaternion" if len(ang[0]) == 4 else "euler"
    return _Layout("wide", f"PiMgr CSV with header ({angles})", time=find("time", "t"),
                   frame=find("frame", "count"), pos=tuple(pos), ang=tuple(ang), angles=angles)


def _explicit_layout(columns: tuple[str, ...], angles: str, k: int, path: Path) -> _Layout:
    """The old ``columns=`` interface: names of the leading columns."""
    if len(set(columns)) != len(columns):
        raise InvalidInputError(f"columns: duplicate names in {columns!r}")
    if k < len(columns):
        raise RecordingError(
            f"{path.name}: lines have {k} fields, columns= names {len(columns)}"
        )
    ang = ("a1", "a2", "a3") if angles == "euler" else ("qw", "qx", "qy", "qz")
    col = {c: i for i, c in enumerate(columns)}
    long_format = "sensor" in columns
    per = ("x", "y", "z", *ang)
    need = per if long_format else tuple(f"{c}{s}" for s in (1, 2) for c in per)
    missing = [c for c in need if c not in col]
    if missing:
        raise InvalidInputError(f"columns: {missing} missing for angles={angles!r} in {columns!r}")
    if long_format:
        return _Layout("station", f"columns={list(columns)}", time=col.get("time"),
                       frame=col.get("frame"), station=col["sensor"],
                       pos=([col[c] for c in "xyz"],), ang=([col[c] for c in ang],),
                       angles=angles)
    return _Layout("wide", f"columns={list(columns)}", time=col.get("time"),
                   frame=col.get("frame"),
                   pos=tuple([col[f"{c}{s}"] for c in "xyz"] for s in (1, 2)),
                   ang=tuple([col[f"{c}{s}"] for c in ang] for s in (1, 2)), angles=angles)


# --------------------------------------------------------------------------
# assembling frames


def _rotations(a: np.ndarray, angles: str, euler_order: str) -> tuple[np.ndarray, int]:
    """Matrices of Euler angles (deg) or quaternions (w first); NaN rows stay NaN.

    Returns the matrices and the number of quaternion sign flips between
    consecutive rows (harmless: ``q`` and ``-q`` are one rotation).
    """
    rot = np.full(a.shape[:1] + (3, 3), np.nan)
    finite = np.isfinite(a).all(axis=1)
    flips = 0
    if angles == "euler":
        rot[finite] = Rotation.from_euler(euler_order, a[finite], degrees=True).as_matrix()
        return rot, 0
    q = a[finite]
    norm = np.linalg.norm(q, axis=1)
    good = np.abs(norm - 1) < 2e-2
    if q.shape[0] > 1:
        flips = int(np.sum(np.einsum("ij,ij->i", q[1:], q[:-1]) < 0))
    idx = np.flatnonzero(finite)
    ok = idx[good]
    rot[ok] = Rotation.from_quat(q[good][:, [1, 2, 3, 0]]).as_matrix()
    return rot, flips


def _pair_stations(station: np.ndarray, frame: np.ndarray | None,
                   sensors: tuple[int, int]) -> tuple[np.ndarray, np.ndarray, np.ndarray, int, int]:
    """Rows of the upper and lower sensor that form complete frames.

    Returns row indices (upper, lower), the frame key of each (counter or
    ordinal of the upper line), the number of half frames dropped and of
    duplicated lines dropped.
    """
    a, b = sensors
    if frame is not None:
        keys: dict[float, list[int | None]] = {}
        dups = 0
        for i, (st, fr) in enumerate(zip(station, frame)):
            if st not in (a, b):
                continue
            slot = keys.setdefault(float(fr), [None, None])
            j = 0 if st == a else 1
            if slot[j] is None:
                slot[j] = i
            else:
                dups += 1
        full = sorted((k, v) for k, v in keys.items() if v[0] is not None and v[1] is not None)
        half = len(keys) - len(full)
        up = np.array([v[0] for _, v in full], dtype=np.int64)
        lo = np.array([v[1] for _, v in full], dtype=np.int64)
        return up, lo, np.array([k for k, _ in full], dtype=np.float64), half, dups
    sel = np.flatnonzero(np.isin(station, sensors))
    st = station[sel]
    # A frame is two consecutive lines of the two stations in the file's own order (which
    # need not be the order `sensors` names them in): the order that forms the most complete
    # frames, the first line's station first on a tie.  A line without its partner in that
    # order is a half frame, never paired with a neighbouring frame's line.
    orders = [(a, b), (b, a)] if st.size == 0 or st[0] == a else [(b, a), (a, b)]
    best: tuple[list[int], list[int], list[float], int] | None = None
    for first, second in orders:
        up_l, lo_l, key = [], [], []
        half = 0
        i = 0
        ordinal = 0  # frames started so far, complete or not: the frame's time slot
        while i < sel.size:
            if st[i] == first and i + 1 < sel.size and st[i + 1] == second:
                u, v = (sel[i], sel[i + 1]) if first == a else (sel[i + 1], sel[i])
                up_l.append(int(u))
                lo_l.append(int(v))
                key.append(float(ordinal))
                i += 2
            else:
                half += 1
                i += 1
            ordinal += 1
        if best is None or len(up_l) > len(best[0]):
            best = (up_l, lo_l, key, half)
    assert best is not None
    up_l, lo_l, key, half = best
    return (np.array(up_l, dtype=np.int64), np.array(lo_l, dtype=np.int64),
            np.array(key, dtype=np.float64), half, 0)


def _choose_units(positions_file: np.ndarray, units: str,
                  path: Path) -> tuple[str, str, str | None]:
    """Unit of the file's positions, a note on how it was chosen and a warning to give once
    the file is known to hold enough frames (None: none), that centimetres and inches both
    fit and the spacing does not decide."""
    spacing = np.linalg.norm(positions_file[:, 1] - positions_file[:, 0], axis=1)
    spacing = spacing[np.isfinite(spacing)]
    if spacing.size == 0:
        return (units if units != "auto" else "cm"), "no finite positions", None
    med = float(np.median(spacing))
    in_mm = {u: med * f * 1e3 for u, f in _UNITS_M.items()}
    plausible = [u for u, v in in_mm.items() if _SPACING_MM[0] <= v <= _SPACING_MM[1]]
    if units == "auto":
        best = min(in_mm, key=lambda u: abs(np.log(max(in_mm[u], 1e-12) / _TYPICAL_SPACING_MM)))
        note = f"auto: sensor spacing {in_mm[best]:.1f} mm"
        if best not in plausible:
            warnings.warn(
                f"{path.name}: no unit gives a plausible spacing of two sensors across a "
                f"finger joint ({_SPACING_MM[0]:g}-{_SPACING_MM[1]:g} mm); using {best!r} "
                f"({in_mm[best]:.3g} mm); pass units= if that is wrong", stacklevel=4)
        elif len(plausible) > 1:
            others = [u for u in plausible if u != best]
            note += f"; {', '.join(others)} also plausible"
            # centimetres and inches differ by 2.54, less than the 9x of the plausible
            # spacings: a spacing of 10-35 mm in cm is 25-90 mm in inches. Nothing else in
            # the data tells them apart (a centre scales with the positions), and the
            # spacing nearer 28 mm is the wrong unit for sensors closer than 17.6 mm in a
            # cm file or farther than 44.6 mm in an inch file: the centre 2.54x off. A
            # spacing outside 22.4-35 mm (28 mm within a factor 1.25) is too far from the
            # typical one to decide by it, and is warned about.
            if abs(np.log(in_mm[best] / _TYPICAL_SPACING_MM)) > np.log(_UNIT_DECIDES):
                return best, note, (
                    f"{path.name}: the unit is ambiguous: in {best!r} the two sensors are "
                    f"{in_mm[best]:.3g} mm apart, in "
                    + " or ".join(f"{u!r} {in_mm[u]:.3g} mm" for u in others)
                    + f", {'both' if len(others) == 1 else 'all'} plausible across a finger "
                    f"joint; using {best!r} (nearer the typical {_TYPICAL_SPACING_MM:g} mm); "
                    f"pass units= (--units) if that is wrong")
        return best, note, None
    if units not in plausible:
        others = [u for u in plausible if u != units]
        if others:
            warnings.warn(
                f"{path.name}: in {units!r} the two sensors are {in_mm[units]:.3g} mm apart, "
                f"implausible across a finger joint; the data look like "
                f"{' or '.join(repr(u) for u in others)} ({in_mm[others[0]]:.3g} mm)",
                stacklevel=4)
    return units, f"given: sensor spacing {in_mm[units]:.1f} mm", None


#: Largest fraction of frames taken as glitches.  A five-frame median finds
#: isolated jumps; when half the frames or more are off their neighbours, the
#: positions scatter more than a finger moves (a file in millimetres read as
#: centimetres: Liberty-level noise of 0.76 mm becomes 7.6 mm per axis, and 77 %
#: of the frames exceed 10 mm), and dropping them would leave a fraction of the
#: recording, still in the wrong unit.
_MAX_GLITCH_FRACTION = 0.5


def _glitches(positions: np.ndarray, glitch_mm: float) -> np.ndarray:
    """Frames where a sensor is farther than `glitch_mm` from its 5-frame median."""
    if positions.shape[0] < 5:
        return np.zeros(positions.shape[0], dtype=bool)
    med = median_filter(positions, size=(5, 1, 1), mode="nearest")
    dev = np.linalg.norm(positions - med, axis=2).max(axis=1) * 1e3
    return dev > glitch_mm


#: Shortest run of bit-identical samples of one sensor (while the other moves) taken
#: as a frozen sensor: a tracker at 0.1 mm and 0.01 deg resolution never repeats a moving
#: finger's pose for this many frames.
_FROZEN_RUN = 5


def _frozen_runs(pos_file: np.ndarray, ang: list[np.ndarray], dropout: np.ndarray) -> np.ndarray:
    """Frames inside a run of at least `_FROZEN_RUN` bit-identical samples of one sensor
    while the other sensor's samples change, less the run's first frame: that is the
    sample the tracker measured and then repeated, the last real one before the stretch.
    A run over the whole file is left to the estimators (a sensor frozen throughout:
    nothing moved)."""
    n = pos_file.shape[0]
    frozen = np.zeros(n, dtype=bool)
    if n < _FROZEN_RUN:
        return frozen
    samples = [np.concatenate([pos_file[:, s], ang[s]], axis=1) for s in (0, 1)]
    for s in (0, 1):
        mine, other = samples[s], samples[1 - s]
        same = np.all(mine[1:] == mine[:-1], axis=1) & ~dropout[1:] & ~dropout[:-1]
        start = 0
        while start < n - 1:
            if not same[start]:
                start += 1
                continue
            stop = start
            while stop < n - 1 and same[stop]:
                stop += 1
            # frames start..stop (inclusive) hold one sample
            length = stop - start + 1
            moves = np.any(other[start + 1:stop + 1] != other[start:stop])
            if length >= _FROZEN_RUN and length < n and moves:
                frozen[start + 1:stop + 1] = True  # frame `start` is the real sample
            start = stop + 1
    return frozen


def _check_times(
    pos_file: np.ndarray, ang: list[np.ndarray], times: np.ndarray, line_no: np.ndarray,
    notes: dict, path: Path, take: int,
) -> tuple[np.ndarray, list[np.ndarray], np.ndarray, np.ndarray]:
    """Times of a file with a time column from 0; rows whose time does not advance
    dropped; a constant column refused; a restart (two takes pasted together) and a time
    that looks like milliseconds warned about."""
    fin = np.isfinite(times)
    if not fin.any():
        raise RecordingError(
            f"{path.name}: the time column holds no number on any of its {times.size} rows "
            f"(first: line {int(line_no[0])} reads {times[0]:g}); is it the time column of "
            f"this export?")
    if fin.sum() > 1 and np.ptp(times[fin]) == 0:
        raise RecordingError(
            f"{path.name}: the time column is {times[fin][0]:g} on all {int(fin.sum())} rows: "
            f"it gives no sample times (is it the time column of this export?)")
    # a restart: the time jumps back by much more than a sample interval
    steps = np.diff(times)
    forward = steps[np.isfinite(steps) & (steps > 0)]
    dt = float(np.median(forward)) if forward.size else 0.0
    back = np.flatnonzero(np.isfinite(steps) & (steps < -10 * dt)) if dt > 0 else np.array([], int)
    if back.size:
        i = int(back[0]) + 1
        k = _select_take(path, "time", [int(b) + 1 for b in back], line_no,
                         (times[i - 1], times[i]), take, notes, stacklevel=3)
        pos_file, ang, times, line_no = pos_file[k], [a[k] for a in ang], times[k], line_no[k]
    origin = float(np.nanmin(times))
    times = times - origin
    # rows re-written with a time that does not advance
    ok = np.ones(times.size, dtype=bool)
    last = -np.inf
    for i, tt in enumerate(times):
        if np.isfinite(tt) and tt <= last:
            ok[i] = False
        elif np.isfinite(tt):
            last = tt
    if not ok.all() and (~ok).sum() >= 0.5 * ok.size:
        i = int(np.flatnonzero(~ok)[0])
        raise RecordingError(
            f"{path.name}: the time column goes back or stands still on {int((~ok).sum())} of "
            f"{ok.size} rows (first: line {int(line_no[i])}, {float(times[i] + origin)!r} after "
            f"{float(times[i - 1] + origin)!r}); are the rows in time order, and is it the time column?")
    if not ok.all():
        notes["non_increasing_times"] = int((~ok).sum())
        pos_file, ang, times, line_no = pos_file[ok], [a[ok] for a in ang], times[ok], line_no[ok]
    steps = np.diff(times[np.isfinite(times)])
    if steps.size:
        rate = 1.0 / float(np.median(steps))
        if rate < 2.0 and 20.0 <= rate * 1e3 <= 10000.0:
            warnings.warn(
                f"{path.name}: the time column advances by {1 / rate:.4g} per sample, "
                f"{rate:.3g} Hz if it is seconds: it looks like milliseconds "
                f"({rate * 1e3:.4g} Hz); the times are read as seconds", stacklevel=3)
            notes["time_looks_like_ms"] = True
    return pos_file, ang, times, line_no


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


#: A recording whose Euler angles all lie within +-pi (plus this slack) looks like radians.
_RADIAN_SLACK = 1e-3


def _check_radians(ang: list[np.ndarray], path: Path) -> None:
    """Warn when every Euler angle of both sensors lies within +-pi: radians, not degrees.

    A finger flexed by tens of degrees never keeps all three angles of both sensors
    within 3.14 deg for a whole recording.
    """
    values = np.concatenate([a[np.isfinite(a).all(axis=1)].ravel() for a in ang])
    if values.size >= 30 and np.abs(values).max() <= np.pi + _RADIAN_SLACK:
        warnings.warn(
            f"{path.name}: every Euler angle is within +-pi ({np.abs(values).max():.3g} at "
            f"most): the angles look like radians, but they are read as degrees; convert "
            f"them to degrees", stacklevel=3)


def _wide_order(sensors, path: Path) -> tuple[int, int]:
    """Which of a one-line-per-sample file's sensors (columns suffixed 1 and 2) is upper, lower."""
    if sensors is None:
        return (0, 1)
    pair = (int(sensors[0]), int(sensors[1]))
    if sorted(pair) != [1, 2]:
        raise InvalidInputError(f"{path.name}: holds sensors 1 and 2 (columns suffixed 1 and 2), "
                                f"not {pair[0]} and {pair[1]}: give sensors (1, 2) or (2, 1)")
    return (pair[0] - 1, pair[1] - 1)


def read_polhemus(
    path: str | os.PathLike,
    *,
    columns: tuple[str, ...] | None = None,
    units: str = "auto",
    angles: str | None = None,
    euler_order: str = "ZYX",
    sensors: tuple[int, int] | None = None,
    rate_hz: float = 240.0,
    labels: tuple[str, str] = ("upper", "lower"),
    joint: str = "joint",
    on_invalid: str = "drop",
    glitch_mm: float = 10.0,
    take: int = 1,
) -> Recording:
    """Read a PiMgr CSV or Liberty ASCII export of two sensors.

    The layout is detected (see the module docstring) unless `columns` is
    given; what was found is in ``recording.metadata`` (``format``,
    ``layout``, ``units``, ``units_note``, counts of ``duplicates``,
    ``half_frames``, ``glitch_frames``, ``dropout_frames``,
    ``frozen_frames``, ``invalid_frames``, ``skipped_lines``,
    ``quaternion_sign_flips``, ``decimal_comma``, ``times_from`` (``"time
    column"``, ``"frame counter and rate_hz"`` or ``"rate_hz"``);
    ``restart_line``, ``rows_after_restart``, ``takes`` and ``take`` (a time
    column or frame counter that restarts), ``cut_off_line`` (the last line, left out of a
    file that ends without a line end) and ``time_looks_like_ms`` when
    found).

    Parameters
    ----------
    path : path-like
    columns : tuple of str, optional
        Explicit names of the leading columns (old interface): ``"x", "y",
        "z"`` and ``"a1", "a2", "a3"`` (Euler, degrees) or ``"qw", "qx",
        "qy", "qz"``, plus ``"sensor"`` for one sensor per line, or the same
        names suffixed ``1``/``2`` for both sensors per line; ``"frame"``
        and ``"time"`` optional.
    units : {"auto", "cm", "in", "mm", "m"}
        Unit of the positions; ``"auto"`` judges it by the sensor spacing.
    angles : {"euler", "quaternion"}, optional
        Orientation columns: required meaning with `columns`; otherwise
        detected, and a file whose layout has the other kind is refused.
    euler_order : str
        SciPy Euler sequence; ``"ZYX"`` (intrinsic) is Polhemus' azimuth,
        elevation, roll.
    sensors : (int, int), optional
        Station numbers of the upper and lower sensor; default: the two
        stations in the file (lowest first), or 1 and 2 when there are more.
        A file with both sensors on one line (PiMgr) takes (1, 2) or (2, 1):
        its columns suffixed 1 and 2.
    rate_hz : float
        Sampling rate used for times when the file has none (frame counter
        times ``1 / rate_hz`` when there is a counter); a time column is
        used instead of it (``metadata["times_from"]`` says which).  At most
        100 kHz.
    labels, joint : see :class:`Recording`.
    on_invalid : {"drop", "raise"}
        Frames with NaN values, half frames (lost lines), glitches,
        dropouts and frozen stretches:
        drop them with a warning that counts them, or raise
        :class:`RecordingError` naming them.
    glitch_mm : float
        Glitch threshold (see module docstring), millimetres.  When half the
        frames or more would be glitches the file is refused: the positions
        are not in the unit used (or `glitch_mm` is far too small).
    take : int
        Which take to read, 1 (the first, default) or later, of a file whose
        time column or frame counter restarts (several takes written into one
        file); the others are dropped with a warning that says so.

    Returns
    -------
    Recording

    Raises
    ------
    RecordingError
        Unreadable, empty, binary or unparseable file, unknown layout,
        missing sensors, invalid frames with ``on_invalid="raise"``, fewer
        than 10 usable frames (the message says what was dropped), half the
        frames or more glitches, matrices that are not rotations, fewer takes
        than `take`.
    InvalidInputError
        Bad arguments.
    """
    path = check_path(path, "path")
    if units != "auto" and units not in _UNITS_M:
        raise InvalidInputError(
            f"units: expected 'auto' or one of {sorted(_UNITS_M)}, got {units!r}")
    if not (isinstance(euler_order, str) and re.fullmatch(r"[xyz]{3}|[XYZ]{3}", euler_order)
            and euler_order[0] != euler_order[1] != euler_order[2]):
        raise InvalidInputError(f"euler_order: expected three axes of 'xyz' (extrinsic) or 'XYZ' "
                                f"(intrinsic), no axis twice in a row, as 'ZYX', got {euler_order!r}")
    if angles is not None and angles not in ("euler", "quaternion"):
        raise InvalidInputError(f"angles: expected 'euler' or 'quaternion', got {angles!r}")
    if on_invalid not in ("raise", "drop"):
        raise InvalidInputError(f"on_invalid: expected 'drop' or 'raise', got {on_invalid!r}")
    check_number(rate_hz, "rate_hz", above=0.0, maximum=_MAX_RATE_HZ)
    check_number(glitch_mm, "glitch_mm", above=0.0)
    take = check_integer(take, "take", minimum=1)
    if sensors is not None and (len(sensors) != 2 or sensors[0] == sensors[1]):
        raise InvalidInputError(f"sensors: expected two different station numbers, got {sensors!r}")

    t = _tokenise(path)
    k = t.rows.shape[1]
    if columns is not None:
        lay = _explicit_layout(tuple(columns), angles or "euler", k, path)
    elif t.header is not None and any(h.startswith(("loc", "pos")) for h in t.header):
        lay = _header_layout(t.header, k, path)
    else:
        lay = _detect_station_layout(t, path)
    _check_magnitudes(t, lay, path)
    if angles is not None and lay.angles != angles:
        raise RecordingError(
            f"{path.name}: the layout found is {lay.description!r}, whose orientation is "
            f"{lay.angles!r}, not angles={angles!r}")
    notes: dict = {"skipped_lines": len(t.skipped)}
    if t.cut_line is not None:
        notes["cut_off_line"] = t.cut_line
    if lay.frame is not None:
        col = t.rows[:, lay.frame]
        stations = t.rows[:, lay.station] if lay.station is not None else None
        starts = _counter_restarts(col, stations)
        if starts:
            i = starts[0]
            # the value before the restart is the last one of the restarting row's station
            prev = col[:i][stations[:i] == stations[i]] if stations is not None else col[:i]
            k = _select_take(path, "frame counter", starts, t.lines, (prev[-1], col[i]), take,
                             notes, stacklevel=2)
            t = dataclasses.replace(t, rows=t.rows[k], lines=t.lines[k])
    rows = t.rows
    # where the sample times come from: `rate_hz` is used only without a time column
    notes["times_from"] = ("time column" if lay.time is not None else
                           "frame counter and rate_hz" if lay.frame is not None else "rate_hz")
    if t.skipped:
        warnings.warn(f"{path.name}: skipped {len(t.skipped)} unreadable lines (first: line "
                      f"{t.skipped[0]})", stacklevel=2)

    if lay.kind == "station":
        assert lay.station is not None
        station = rows[:, lay.station]
        present = sorted(int(s) for s in np.unique(station[np.isfinite(station)]))
        if sensors is None:
            if len(present) < 2:
                raise RecordingError(
                    f"{path.name}: only station {present} in the file; two sensors are needed")
            first, second = (1, 2) if len(present) > 2 and {1, 2} <= set(present) else present[:2]
            pair: tuple[int, int] = (first, second)
        else:
            pair = (int(sensors[0]), int(sensors[1]))
        missing_st = [s for s in pair if s not in present]
        if missing_st:
            raise RecordingError(f"{path.name}: no line of sensor (station) {missing_st[0]} "
                                 f"(stations present: {present})")
        extra = sorted(set(present) - set(pair))
        if extra:
            warnings.warn(f"{path.name}: ignoring stations {extra}", stacklevel=2)
        frame_col = rows[:, lay.frame] if lay.frame is not None else None
        up, lo, key, half, dups = _pair_stations(station, frame_col, pair)
        if up.size == 0:
            raise RecordingError(f"{path.name}: no complete frame of stations {pair}")
        sel = [up, lo]
        pos_file = np.stack([rows[s][:, lay.pos[0]] for s in sel], axis=1)
        ang = [rows[s][:, lay.ang[0]] for s in sel]
        ang_lines = [t.lines[s] for s in sel]
        if lay.angles == "euler":  # before any frame is dropped: the line numbers are the file's
            for a, lines in zip(ang, ang_lines):
                _check_euler_range(a, lines, np.isfinite(a).all(axis=1), euler_order, path,
                                   ("a1", "a2", "a3"), "")
            _check_radians(ang, path)
        if lay.time is not None:
            times = rows[up, lay.time]
        else:  # frame counter or frame ordinal
            times = (key - key[0]) / rate_hz
        line_no = t.lines[up]
        notes["half_frames"] = half
        notes["duplicates"] = dups
    else:
        order = _wide_order(sensors, path)
        pos_file = np.stack([rows[:, lay.pos[k]] for k in order], axis=1)
        ang = [rows[:, lay.ang[k]] for k in order]
        line_no = t.lines
        ang_lines = [t.lines, t.lines]
        if lay.angles == "euler":  # before any frame is dropped: the line numbers are the file's
            for a, lines in zip(ang, ang_lines):
                _check_euler_range(a, lines, np.isfinite(a).all(axis=1), euler_order, path,
                                   ("a1", "a2", "a3"), "")
            _check_radians(ang, path)
        # duplicated rows: the same sample written again
        pose = np.concatenate([pos_file.reshape(len(rows), -1), *ang], axis=1)
        same = np.zeros(len(rows), dtype=bool)
        same[1:] = np.all(pose[1:] == pose[:-1], axis=1)
        if lay.time is not None:
            times = rows[:, lay.time]
        elif lay.frame is not None:
            times = rows[:, lay.frame] / rate_hz
        else:
            times = np.arange(len(rows)) / rate_hz
        keep = ~same
        notes["duplicates"] = int(same.sum())
        pos_file, ang, times, line_no = (pos_file[keep], [a[keep] for a in ang], times[keep],
                                         line_no[keep])
        notes["half_frames"] = 0
        if lay.time is not None and np.isfinite(times).any() and np.nanmin(times) > 1e8:
            notes["time_origin_unix_s"] = float(np.nanmin(times))
        pair = (order[0] + 1, order[1] + 1)
    if lay.time is not None and times.size:
        pos_file, ang, times, line_no = _check_times(pos_file, ang, times, line_no, notes, path,
                                                     1 if "takes" in notes else take)
    if take > 1 and "takes" not in notes:
        raise RecordingError(f"{path.name}: take={take}, but the file holds one take (neither "
                             f"a time column nor a frame counter restarts)")

    # a tracker's dropout: a sensor reported at exactly (0, 0, 0)
    dropout = np.any(np.all(pos_file == 0, axis=2), axis=1)
    frozen = _frozen_runs(pos_file, ang, dropout)
    unit, unit_note, unit_warning = _choose_units(pos_file[~dropout], units, path)
    positions = pos_file * _UNITS_M[unit]
    rots, flips = zip(*(_rotations(a, lay.angles, euler_order) for a in ang))
    rotations = np.stack(rots, axis=1)
    n = positions.shape[0]
    invalid = ~(np.isfinite(positions).all(axis=(1, 2)) & np.isfinite(rotations).all(axis=(1, 2, 3))
                & np.isfinite(times))
    if lay.angles == "quaternion":
        for s, a in enumerate(ang):
            norm = np.linalg.norm(a, axis=1)
            badq = np.isfinite(norm) & (np.abs(norm - 1) >= 2e-2)
            if badq.sum() > 0.05 * n:
                i = int(np.flatnonzero(badq)[0])
                raise RecordingError(
                    f"{path.name}: {int(badq.sum())} quaternions of sensor {s + 1} have a norm "
                    f"far from 1 (first: {norm[i]:.4f} at line {line_no[i]}); are these columns "
                    f"really a quaternion?")
    glitch = np.zeros(n, dtype=bool)
    fin = ~(invalid | dropout | frozen)
    if fin.sum() >= 5:
        glitch[np.flatnonzero(fin)] = _glitches(positions[fin], glitch_mm)
    if fin.sum() >= 5 and glitch.sum() >= _MAX_GLITCH_FRACTION * fin.sum():
        raise RecordingError(
            f"{path.name}: {int(glitch.sum())} of {int(fin.sum())} frames have a position > "
            f"{glitch_mm:g} mm off its neighbours, too many to be glitches (isolated jumps): "
            f"the positions scatter more than a finger moves; are the units right "
            f"(units={unit!r}, {unit_note})? If they are, pass a larger glitch_mm")
    notes["invalid_frames"] = int(invalid.sum())
    notes["glitch_frames"] = int(glitch.sum())
    notes["dropout_frames"] = int(dropout.sum())
    notes["frozen_frames"] = int(frozen.sum())
    notes["quaternion_sign_flips"] = int(sum(flips))
    problems = []
    if notes["half_frames"]:
        problems.append(f"{notes['half_frames']} half frames (a station line without its "
                        f"partner: lost lines)")
    if invalid.any():
        w = np.flatnonzero(invalid)
        problems.append(f"{w.size} frames with NaN values or unusable angles (lines "
                        f"{line_no[w[:5]].tolist()}{' ...' if w.size > 5 else ''})")
    if dropout.any():
        w = np.flatnonzero(dropout)
        problems.append(f"{w.size} dropout frames (a sensor at exactly (0, 0, 0): the tracker "
                        f"lost it; lines {line_no[w[:5]].tolist()}{' ...' if w.size > 5 else ''})")
    if frozen.any():
        w = np.flatnonzero(frozen)
        problems.append(f"{w.size} frozen frames (one sensor's position and angles repeated "
                        f"bit for bit over {_FROZEN_RUN} or more frames while the other moves; "
                        f"lines {line_no[w[:5]].tolist()}{' ...' if w.size > 5 else ''})")
    if glitch.any():
        w = np.flatnonzero(glitch)
        problems.append(f"{w.size} glitch frames (a position > {glitch_mm:g} mm off its "
                        f"neighbours; lines {line_no[w[:5]].tolist()}"
                        f"{' ...' if w.size > 5 else ''})")
    keep = ~(invalid | glitch | dropout | frozen)
    msg = f"{path.name}: " + "; ".join(problems)
    if problems and on_invalid == "raise":
        raise RecordingError(msg + " (on_invalid='drop' drops them)")
    if keep.sum() < 10:  # the reasons go with the refusal, not in a warning before it
        if notes["duplicates"]:
            problems.append(f"{notes['duplicates']} duplicated rows dropped before (the same "
                            "sample written again)")
        if notes.get("non_increasing_times"):
            problems.append(f"{notes['non_increasing_times']} rows dropped before whose time "
                            "does not advance")
        raise RecordingError(f"{path.name}: only {int(keep.sum())} usable frames of {n}"
                             + (f" ({'; '.join(problems)})" if problems else ""))
    if unit_warning is not None:  # after the refusals: they say what is wrong themselves
        warnings.warn(unit_warning, stacklevel=2)
    if problems:
        warnings.warn(msg + "; dropped", stacklevel=2)
    if notes["duplicates"]:
        warnings.warn(f"{path.name}: dropped {notes['duplicates']} duplicated rows", stacklevel=2)
    times, positions, rotations = times[keep], positions[keep], rotations[keep]
    return Recording(
        times=times,
        positions=positions,
        rotations=rotations,
        labels=labels,
        joint=joint,
        metadata={
            "source": str(path),
            "format": "pimgr-csv" if lay.kind == "wide" and columns is None else "liberty-ascii"
            if columns is None else "polhemus-text",
            "layout": lay.description,
            "units": unit,
            "units_note": unit_note,
            "angles": lay.angles,
            "euler_order": euler_order,
            "sensors": list(pair),
            "decimal_comma": bool(t.decimal_comma),
            "dropped_frames": int((~keep).sum()) + int(notes["half_frames"]),
            **notes,
        },
    )


def read_recording(path: str | os.PathLike, **kwargs) -> Recording:
    """Read a recording, choosing the reader by file name.

    ``.h5`` / ``.hdf5`` files go to :func:`~handsynth.sensors.load_recording`
    (no options), anything else to :func:`read_polhemus` with `kwargs`.

    Parameters
    ----------
    path : str or os.PathLike
        The suffix, in any case, chooses the reader.
    **kwargs
        Keyword options of :func:`read_polhemus` (``units``, ``sensors``,
        ``rate_hz``, ...); none for an HDF5 file.

    Returns
    -------
    Recording

    Raises
    ------
    InvalidInputError
        `path` not a str or path-like, or an empty name; options given for an
        HDF5 file; an option :func:`read_polhemus` does not take (named, with
        the ones it takes); bad option values of :func:`read_polhemus`.
    RecordingError
        As :func:`~handsynth.sensors.load_recording` or :func:`read_polhemus`.
    """
    from ._hdf5 import SUFFIXES, load_recording

    path = check_path(path, "path")
    if path.suffix.lower() in SUFFIXES:
        if kwargs:
            raise InvalidInputError(
                f"options {sorted(kwargs)} apply to text exports, not HDF5 {str(path)!r}"
            )
        return load_recording(path)
    unknown = sorted(set(kwargs) - set(_POLHEMUS_OPTIONS))
    if unknown:
        raise InvalidInputError(f"read_recording() got unknown options {unknown}; the options of a "
                                f"text export are {', '.join(_POLHEMUS_OPTIONS)}")
    return read_polhemus(path, **kwargs)


#: Keyword options of :func:`read_polhemus`, which :func:`read_recording` forwards.
_POLHEMUS_OPTIONS: tuple[str, ...] = tuple(
    n for n, p in inspect.signature(read_polhemus).parameters.items() if p.kind is p.KEYWORD_ONLY)
