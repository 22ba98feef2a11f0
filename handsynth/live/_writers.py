"""Row writers of the live loop: one complete, flushed line per frame (CSV or JSON Lines)."""

from __future__ import annotations

import csv
import io
import json
import math
import os
import sys
from pathlib import Path

import numpy as np

from ..errors import InvalidInputError, RecordingError
from ..models import JOINT_NAMES, KEYPOINT_SITES
from ._checks import _check_int

__all__ = ["CsvRowWriter", "JsonlRowWriter", "live_columns", "open_row_writer"]

#: Fixed leading columns of every row.
BASE_COLUMNS: tuple[str, ...] = ("frame", "timestamp_s", "no_hand", "confidence",
                                 "low_confidence", "entry")
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
           "low_confidence": bool(est.low_confidence), "entry": int(est.entry)}
    row.update((n, _finite_or_none(v, 4)) for n, v in zip(JOINT_NAMES, est.angles, strict=True))
    if keypoints:
        kp = np.asarray(est.keypoints, dtype=np.float64).reshape(-1)
        row.update((n, _finite_or_none(v, 6)) for n, v in zip(KEYPOINT_COLUMNS, kp, strict=True))
    if truth is not None:
        row.update((n, round(float(v), 4)) for n, v in zip(TRUTH_COLUMNS, truth, strict=True))
    return row


class _RowWriter:
    format = ""

    def __init__(self, target, *, columns=None, flush_every: int = 1) -> None:
        self.flush_every = _check_int(flush_every, "flush_every", minimum=1)
        self.columns = tuple(columns) if columns is not None else live_columns()
        if isinstance(target, (str, os.PathLike)) and str(target) != "-":
            self.path = Path(target)
            try:
                self._stream = open(self.path, "w", encoding="utf-8", newline="")  # noqa: SIM115
            except OSError as exc:
                raise InvalidInputError(f"cannot write rows to {str(self.path)!r}: "
                                        f"{exc.strerror or exc}") from None
            self._owned = True
        else:
            self.path = None
            self._stream = sys.stdout if str(target) == "-" else target
            self._owned = False
        self.rows = 0
        self._header()

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
        """
        extra = set(row).difference(self.columns)
        if extra:
            raise InvalidInputError(f"row has columns {sorted(extra)} that this writer "
                                    f"was not opened with")
        self._emit(self._line(row))
        self.rows += 1
        if self.rows % self.flush_every == 0:
            self._stream.flush()

    def _emit(self, line: str) -> None:
        try:
            self._stream.write(line)
        except OSError as exc:
            raise RecordingError(f"cannot write rows to {self.path or 'the output'}: "
                                 f"{exc.strerror or exc}") from None

    def close(self) -> None:
        """Flush, and close the file if this writer opened it."""
        stream = getattr(self, "_stream", None)
        if stream is None:
            return
        stream.flush()
        if self._owned:
            stream.close()
        self._stream = None

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
        File to create (overwritten), ``"-"`` for standard output, or an
        open text stream.
    columns : sequence of str, keyword-only, optional
        :func:`live_columns` by default.
    flush_every : int, keyword-only
        Flush after this many rows (1: every row).
    """

    format = "csv"

    def _header(self) -> None:
        self._emit(",".join(self.columns) + "\n")
        self._stream.flush()

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
                    flush_every: int = 1):
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

    Returns
    -------
    CsvRowWriter or JsonlRowWriter

    Raises
    ------
    InvalidInputError
        Unknown format, a suffix that does not tell the format, or a file
        that cannot be created.
    """
    if format is None:
        suffix = Path(str(target)).suffix.lower() if isinstance(target, (str, os.PathLike)) else ""
        if suffix not in _SUFFIXES:
            raise InvalidInputError(
                f"cannot tell the row format of {str(target)!r} from its suffix (expected .csv, "
                ".jsonl or .ndjson); give the format (csv or jsonl)")
        format = _SUFFIXES[suffix]
    if format not in _WRITERS:
        raise InvalidInputError(f"format must be 'csv' or 'jsonl', got {format!r}")
    return _WRITERS[format](target, columns=columns, flush_every=flush_every)
