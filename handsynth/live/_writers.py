"""Row writers of the live loop: one complete, flushed line per frame (CSV or JSON Lines).

A row file holds only complete lines, whatever happens: rows are written to
the file in whole lines with one system call per flush, and when a write
fails (a full disk) the file is cut back to the last complete line before
the error is raised.  A killed run leaves the lines flushed so far.
"""

from __future__ import annotations

import contextlib
import csv
import io
import json
import math
import os
import sys
from pathlib import Path

import numpy as np

from .._checks import check_integer
from .._io import check_output, os_error_reason
from ..errors import InvalidInputError, OutputError
from ..models import JOINT_NAMES, KEYPOINT_SITES

__all__ = ["CsvRowWriter", "JsonlRowWriter", "live_columns", "open_row_writer"]

#: Fixed leading columns of every row.
BASE_COLUMNS: tuple[str, ...] = ("frame", "timestamp_s", "no_hand", "confidence",
                                 "low_confidence", "moved", "entry")
#: Keypoint columns, metres, hand frame.
KEYPOINT_COLUMNS: tuple[str, ...] = tuple(f"{s}_{a}_m" for s in KEYPOINT_SITES for a in "xyz")
#: True-angle columns (sources that know the truth), degrees.
TRUTH_COLUMNS: tuple[str, ...] = tuple(f"true_{n}" for n in JOINT_NAMES)



def live_columns(*, keypoints: bool = False, truth: bool = False) -> tuple[str, ...]:
    """Column names of the rows :func:`run_live` writes, in order.

    Parameters
    ----------
    keypoints : bool, keyword-only
        Include the 63 keypoint columns (metres).
    truth : bool, keyword-only
        Include the 20 ``true_<joint>`` columns (degrees).
    """
    return (BASE_COLUMNS + tuple(JOINT_NAMES) + (KEYPOINT_COLUMNS if keypoints else ())
            + (TRUTH_COLUMNS if truth else ()))


def _finite_or_none(v: float, digits: int):
    v = float(v)
    return round(v, digits) if math.isfinite(v) else None


def _make_row(index: int, timestamp_s: float, est, *, keypoints: bool,
              truth: np.ndarray | None) -> dict:
    row = {"frame": index, "timestamp_s": round(float(timestamp_s), 6),
           "no_hand": bool(est.no_hand), "confidence": round(float(est.confidence), 6),
           "low_confidence": bool(est.low_confidence),
           "moved": bool(getattr(est, "moved", False)), "entry": int(est.entry)}
    row.update((n, _finite_or_none(v, 4)) for n, v in zip(JOINT_NAMES, est.angles, strict=True))
    if keypoints:
        kp = np.asarray(est.keypoints, dtype=np.float64).reshape(-1)
        row.update((n, _finite_or_none(v, 6)) for n, v in zip(KEYPOINT_COLUMNS, kp, strict=True))
    if truth is not None:
        row.update((n, round(float(v), 4)) for n, v in zip(TRUTH_COLUMNS, truth, strict=True))
    return row


class _RowWriter:
    format = ""

    def __init__(self, target, *, columns=None, flush_every: int = 1, inputs=()) -> None:
        self.flush_every = check_integer(flush_every, "flush_every", minimum=1)
        self.columns = tuple(columns) if columns is not None else live_columns()
        self._fd: int | None = None
        self._stream = None
        self._pending: list[str] = []
        self._complete = 0  # bytes of complete lines in the file
        self._failed = False
        self.path: Path | None  # None when writing to a stream
        if isinstance(target, (str, os.PathLike)) and str(target) != "-":
            # The file is created (or replaced) when the first row comes: a run that fails
            # before it leaves a file of an earlier run as it was, and no header-only file.
            self.path = check_output(target, what="row file", inputs=inputs)
            folder = self.path.parent
            if not os.access(folder, os.W_OK | os.X_OK) or (
                    self.path.exists() and not os.access(self.path, os.W_OK)):
                raise OutputError(f"cannot write rows to {str(self.path)!r}: permission denied")
        else:
            self.path = None
            self._stream = sys.stdout if str(target) == "-" else target
        self.rows = 0
        self._header()
        self._flush()

    def _header(self) -> None:
        pass

    def _line(self, row: dict) -> str:  # pragma: no cover - overridden
        raise NotImplementedError

    def write(self, row: dict) -> None:
        """Write one row as one complete line (flushed every `flush_every` rows).

        Raises
        ------
        InvalidInputError
            `row` has a key that is not one of :attr:`columns`.
        OutputError
            The file cannot take the rows (a full disk); it keeps the
            complete lines written before.
        """
        extra = set(row).difference(self.columns)
        if extra:
            raise InvalidInputError(f"row has columns {sorted(extra)} that this writer "
                                    f"was not opened with")
        self._pending.append(self._line(row))
        self.rows += 1
        if self.rows % self.flush_every == 0:
            self._flush()

    def _flush(self) -> None:
        if self._failed or (not self._pending and self._fd is not None):
            return
        if self._fd is None and self.path is not None:
            if not self.rows:
                return  # the header waits for the first row
            try:
                self._fd = os.open(self.path, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o666)
            except OSError as exc:
                self._failed = True
                raise OutputError(f"cannot write rows to {str(self.path)!r}: "
                                  f"{os_error_reason(exc)}") from None
        data, self._pending = "".join(self._pending), []
        if self._fd is None:
            if self._stream is None:
                return
            try:
                self._stream.write(data)
                self._stream.flush()
            except OSError as exc:
                self._failed = True
                raise OutputError(f"cannot write rows to the output: "
                                  f"{os_error_reason(exc)}") from None
            return
        view = memoryview(data.encode("utf-8"))
        try:
            while view:
                view = view[os.write(self._fd, view):]
        except OSError as exc:
            self._failed = True
            with contextlib.suppress(OSError):  # cut back to the last complete line
                os.ftruncate(self._fd, self._complete)
            raise OutputError(
                f"cannot write rows to {str(self.path)!r}: {os_error_reason(exc)}; it holds "
                "the complete rows written before") from None
        self._complete += len(data.encode("utf-8"))

    def close(self) -> None:
        """Flush, and close the file if this writer opened it."""
        try:
            self._flush()
        finally:
            if self._fd is not None:
                os.close(self._fd)
                self._fd = None
            self._stream = None
            self._failed = True  # nothing more is written

    def __enter__(self):
        return self

    def __exit__(self, *exc) -> None:
        self.close()


class CsvRowWriter(_RowWriter):
    """Rows as CSV with a header line.

    Booleans are written ``1``/``0``; missing values (the angles of a
    no-hand frame) as empty cells.

    Parameters
    ----------
    target : str, os.PathLike or text stream
        File to create (overwritten when the first row comes: a run that
        writes no row leaves it as it was), ``"-"`` for standard output, or
        an open text stream.
    columns : sequence of str, keyword-only, optional
        :func:`live_columns` by default; any of the columns of
        ``live_columns(keypoints=True, truth=True)``, in any order.
    flush_every : int, keyword-only
        Flush after this many rows (1: every row).
    """

    format = "csv"

    def _header(self) -> None:
        self._pending.append(",".join(self.columns) + "\n")

    def _line(self, row: dict) -> str:
        buf = io.StringIO()
        cells = []
        for c in self.columns:
            v = row.get(c)
            cells.append("" if v is None else int(v) if isinstance(v, (bool, np.bool_)) else v)
        csv.writer(buf, lineterminator="\n").writerow(cells)
        return buf.getvalue()


class JsonlRowWriter(_RowWriter):
    """Rows as JSON lines: one object per line, keys in column order.

    Missing values are ``null``, booleans ``true``/``false``.  Parameters as
    :class:`CsvRowWriter`.
    """

    format = "jsonl"

    def _line(self, row: dict) -> str:
        obj = {c: row[c] for c in self.columns if c in row}
        return json.dumps(obj, allow_nan=False, separators=(",", ":")) + "\n"


_WRITERS = {"csv": CsvRowWriter, "jsonl": JsonlRowWriter}
_SUFFIXES = {".csv": "csv", ".jsonl": "jsonl", ".ndjson": "jsonl"}


def open_row_writer(target, *, format: str | None = None, columns=None,
                    flush_every: int = 1, inputs=()):
    """A CSV or JSON-lines row writer for `target`.

    Parameters
    ----------
    target : str, os.PathLike or text stream
        File (format from its suffix ``.csv``, ``.jsonl`` or ``.ndjson``
        unless `format` is given), ``"-"`` for standard output, or a stream.
    format : {"csv", "jsonl"}, keyword-only, optional
        Required when the suffix does not tell.
    columns : sequence of str, keyword-only, optional
        :func:`live_columns` by default.
    flush_every : int, keyword-only
    inputs : iterable of path-like, keyword-only
        Files the run reads (video, database, measurements); `target` must
        be none of them.

    Returns
    -------
    CsvRowWriter or JsonlRowWriter

    Raises
    ------
    InvalidInputError
        Unknown format, a suffix that does not tell the format, or a column
        that no row has (it would be written empty on every row), named.
    OutputError
        A file that cannot be created: its folder is missing, it is a
        folder, or it is one of `inputs`.
    """
    if columns is not None:
        if isinstance(columns, str):
            raise InvalidInputError(f"columns must be a sequence of column names, got str {columns!r}")
        known = live_columns(keypoints=True, truth=True)
        unknown = [c for c in columns if c not in known]
        if unknown:
            raise InvalidInputError(f"columns: no row has a column {unknown[0]!r}; the columns are "
                                    f"those of live_columns(keypoints=True, truth=True), e.g. "
                                    f"{', '.join(known[:7])}, ...")
    if format is None:
        suffix = Path(str(target)).suffix.lower() if isinstance(target, (str, os.PathLike)) else ""
        if suffix not in _SUFFIXES:
            raise InvalidInputError(
                f"cannot tell the row format of {str(target)!r} from its suffix (expected .csv, "
                ".jsonl or .ndjson); give the format (csv or jsonl)")
        format = _SUFFIXES[suffix]
    if format not in _WRITERS:
        raise InvalidInputError(f"format must be 'csv' or 'jsonl', got {format!r}")
    return _WRITERS[format](target, columns=columns, flush_every=flush_every, inputs=inputs)
