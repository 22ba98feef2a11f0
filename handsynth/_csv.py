"""Delimited text tables as spreadsheets and loggers write them.

Exports differ from the :mod:`csv` module's defaults in ways that are easy to
miss and turn a good recording into an error or, worse, into silently wrong
columns: a byte-order mark before the first name (a spreadsheet's "CSV
UTF-8"), ``;`` between the fields and a decimal comma (``1,5``; spreadsheets
in locales that write numbers so), tabs or spaces, quoted cells, CRLF line ends and
comment lines, a spreadsheet's ``sep=;`` first line, UTF-16 text (a
spreadsheet's "Unicode text").  :func:`read_rows` reads all of these into
rows of stripped cells and records what it found, so that the CSV readers of
recordings agree on it and can name the line of a bad cell.  It also guards
against two ways a file is read back as what it is not: a last line with no
line end, as a recording cut off while being written leaves it (a buffered
writer stops mid-number, ``12.3`` of ``12.345``), is left out with a warning,
and a number written with underscores (``1_000``, which Python's ``float``
reads but no exporter writes) is refused;
:func:`column_index` maps a header's names to columns and refuses a name
given twice (the last one would win, silently).
"""

from __future__ import annotations

import csv
import re
import warnings
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .errors import RecordingError

__all__ = [
    "NumberTable",
    "Rows",
    "column_index",
    "names_by_meaning",
    "read_number_table",
    "read_rows",
    "read_text",
    "reads_as_number",
]

_COMMA_NUMBER = re.compile(r"[-+]?\d*,\d+(?:[eE][-+]?\d+)?")
#: A number as Python's ``float`` reads it, underscores included.
_UNDERSCORE_NUMBER = re.compile(r"[-+]?[\d_]*\.?[\d_]*(?:[eE][-+]?[\d_]+)?")
#: A spreadsheet's first line naming the delimiter (``sep=;``).
_SEP_LINE = re.compile(r'\s*"?sep=(.)"?\s*', re.IGNORECASE)


@dataclass(frozen=True)
class Rows:
    """The content of a delimited text file.

    Attributes
    ----------
    rows : list of list of str
        Cells, stripped, with a decimal comma turned into a point; blank
        lines, lines of empty cells and lines starting with ``#`` are left
        out.
    lines : list of int
        Line of each row in the file (1 = the first line).
    delimiter : str
        ``","``, ``";"``, ``"\\t"`` or ``" "`` (runs of spaces).
    decimal_comma : bool
        Numbers were written with a decimal comma.
    """

    rows: list[list[str]]
    lines: list[int]
    delimiter: str
    decimal_comma: bool


def read_text(path, *, what: str, signatures: Mapping[bytes, str] | None = None) -> str:
    """The text of the file `path`, refusing binary content.

    Decoded as UTF-16 where it starts with that byte-order mark, else as
    UTF-8 without a byte-order mark, else as Latin-1 (any byte decodes, so
    names stay readable enough to report).

    Parameters
    ----------
    path : str or os.PathLike
    what : str, keyword-only
        What the file should be, for messages ("a Polhemus text export").
    signatures : mapping of bytes to str, keyword-only, optional
        Leading bytes of binary files users give by mistake, and what each is.

    Raises
    ------
    RecordingError
        Unreadable, or binary (a NUL byte in the first 64 KiB).
    """
    path = Path(path)
    try:
        raw = path.read_bytes()
    except OSError as exc:
        raise RecordingError(f"cannot read {str(path)!r}: {exc.strerror or exc}") from None
    for magic, kind in (signatures or {}).items():
        if raw.startswith(magic):
            raise RecordingError(f"{path}: {kind}; expected {what}")
    if raw.startswith((b"\xff\xfe", b"\xfe\xff")):
        try:
            return raw.decode("utf-16")
        except UnicodeDecodeError:
            raise RecordingError(f"{path}: starts as UTF-16 text but is not; expected "
                                 f"{what}") from None
    if b"\x00" in raw[:65536]:
        raise RecordingError(f"{path}: binary content; expected {what}")
    try:
        return raw.decode("utf-8-sig")
    except UnicodeDecodeError:
        return raw.decode("latin-1")


def _delimiter(sample: list[str]) -> str:
    """The delimiter of the lines `sample` (:func:`read_rows`' rule, no ``sep=`` line)."""
    for d in (";", "\t", ","):
        if sample and sum(d in ln for ln in sample) > len(sample) // 2:
            return d
    if sample and sum(len(ln.split()) > 1 for ln in sample) > len(sample) // 2:
        return " "  # a logger's text columns
    return ","


def _underscore_number(cell: str) -> bool:
    """`cell` is a number written with underscores (``1_000``), which Python reads."""
    return "_" in cell and bool(_UNDERSCORE_NUMBER.fullmatch(cell)) \
        and any(c.isdigit() for c in cell)


def reads_as_number(cell: str) -> bool:
    """Whether Python's ``float`` reads `cell` (a header line of numbers is no header)."""
    try:
        float(cell)
    except ValueError:
        return False
    return True


def read_rows(path, *, what: str = "CSV table") -> Rows:
    """Rows of the delimited text file `path` (module docstring).

    The delimiter is the one of ``;``, tab and ``,`` found on most of the
    first 50 lines (in that order of preference: ``;`` and tab files often
    hold decimal commas, a ``,`` file cannot), else runs of spaces where
    most lines have several fields.  Unless it is ``,``, cells that are
    numbers written with a decimal comma get a decimal point.  Where the
    file does not end with a line end and holds more than one row, its last
    row is left out with a warning (it may have been cut off mid-number).

    Parameters
    ----------
    path : str or os.PathLike
    what : str, keyword-only
        What the file is, for messages.

    Raises
    ------
    RecordingError
        No such file, unreadable, or binary; a number written with
        underscores (named by line and column).

    Warns
    -----
    UserWarning
        The last row was left out: the file ends without a line end.
    """
    path = Path(path)
    if not path.is_file():
        raise RecordingError(f"cannot read {what} {str(path)!r}: no such file")
    text = read_text(path, what=f"CSV text ({what})")
    all_lines = text.splitlines()
    content = [(no, ln) for no, ln in enumerate(all_lines, start=1)
               if ln.strip() and not ln.lstrip().startswith("#")]
    sep = _SEP_LINE.fullmatch(content[0][1]) if content else None
    if sep:
        content = content[1:]
    delimiter = sep.group(1) if sep else _delimiter([ln for _, ln in content[:50]])
    if len(content) > 1 and content[-1][0] == len(all_lines) and not text.endswith(("\n", "\r")):
        no = content.pop()[0]
        warnings.warn(f"{path}, line {no}: the file ends without a line end, as a recording cut "
                      f"off while being written does; line {no} was left out", stacklevel=2)
    rows, lines = [], []
    for no, ln in content:
        if delimiter == " ":
            cells = ln.split()
        else:
            cells = [c.strip() for c in next(csv.reader([ln], delimiter=delimiter))]
        for col, cell in enumerate(cells, start=1):
            if _underscore_number(cell):
                raise RecordingError(f"{path}, line {no}, column {col}: {cell!r} is not a number as "
                                     "recordings write them (an underscore)")
        if any(cells):  # a spreadsheet's empty row is a line of delimiters
            rows.append(cells)
            lines.append(no)
    decimal_comma = delimiter != "," and any(_COMMA_NUMBER.fullmatch(c) for r in rows[:50]
                                             for c in r)
    if decimal_comma:
        rows = [[c.replace(",", ".") if _COMMA_NUMBER.fullmatch(c) else c for c in r]
                for r in rows]
    return Rows(rows, lines, delimiter, decimal_comma)


def column_index(header, *, path, line: int | None = None) -> dict[str, int]:
    """Column of each name of `header`, refusing a name given twice.

    Parameters
    ----------
    header : sequence of str
        The header's names (empty names are left out).
    path : str or os.PathLike, keyword-only
        The file, for messages.
    line : int, keyword-only, optional
        The header's line in the file, for messages.

    Raises
    ------
    RecordingError
        A name stands in two columns (which one holds the data is unknown).
    """
    index: dict[str, int] = {}
    for i, name in enumerate(header):
        if not name:
            continue
        if name in index:
            where = f"{path}, line {line}" if line is not None else f"{path}"
            raise RecordingError(f"{where}: column {name!r} stands twice (columns "
                                 f"{index[name] + 1} and {i + 1}); which one holds the data "
                                 "is unknown: rename or remove one")
        index[name] = i
    return index


def names_by_meaning(header, meaning, *, path) -> tuple[list[str], list[tuple[str, str]]]:
    """`header` with each name replaced by the canonical name it means, and what was renamed.

    For the exports whose software names the columns its own way (``Hand1 AccX`` for
    ``Hand1_acc_x``); the reader warns with the renamed list.

    Parameters
    ----------
    header : sequence of str
    meaning : callable
        ``meaning(name) -> str or None``: the canonical name `name` means (itself
        for a canonical name), None for a column it does not know.
    path : str or os.PathLike, keyword-only
        The file, for messages.

    Raises
    ------
    RecordingError
        Two columns that mean one canonical name (which one holds the data is unknown).
    """
    out = list(header)
    renamed: list[tuple[str, str]] = []
    seen: dict[str, str] = {}
    for i, name in enumerate(header):
        canon = meaning(name)
        if canon is None:
            continue
        if canon in seen:
            raise RecordingError(f"{path}: columns {seen[canon]!r} and {name!r} both read as "
                                 f"{canon}: which one holds the data is unknown")
        seen[canon] = name
        if canon != name:
            out[i] = canon
            renamed.append((name, canon))
    return out, renamed


@dataclass(frozen=True)
class NumberTable:
    """A plain comma-separated file read straight into numbers (:func:`read_number_table`).

    Attributes
    ----------
    header : list of str
        The first row's names, stripped.
    lines : list of int
        Line of each data row in the file (1 = the first line).
    table : ndarray, shape (N, len(usecols)), float64
        The columns asked for, in the order asked.
    """

    header: list[str]
    lines: list[int]
    table: np.ndarray


def read_number_table(path, *, what: str, usecols) -> NumberTable | None:
    """A header and rows of numbers, parsed straight into floats; None when not plain.

    :func:`read_rows` holds every cell as a string (about ten times the file's
    size in memory); a long recording written plainly needs none of that.
    Plain: ``,`` between the fields (as :func:`read_rows` would find it), no
    ``sep=`` line, quote or NUL byte, no number written with underscores, no
    row of empty cells, as many fields on every row as in the header, a line
    end after the last row, and every cell asked for a number.  Any other
    file is left to :func:`read_rows` (None), which reads it, or names what
    is wrong with it, as it always has; where this reads a file, both give
    the same numbers.  Peak memory is about twice the file's size.

    Parameters
    ----------
    path : str or os.PathLike
        An existing file.
    what : str, keyword-only
        What the file is, for messages.
    usecols : callable, keyword-only
        ``usecols(header, line) -> list of int``: the columns to read, from
        the header's names and its line in the file.  It may raise (a
        missing column, named): the error is the file's either way.

    Returns
    -------
    NumberTable or None
    """
    text = read_text(path, what=f"CSV text ({what})")
    ends_open = not text.endswith(("\n", "\r"))
    all_lines = text.splitlines()
    del text
    nos = [no for no, ln in enumerate(all_lines, start=1)
           if ln.strip() and not ln.lstrip().startswith("#")]
    if len(nos) < 2 or _SEP_LINE.fullmatch(all_lines[nos[0] - 1]) \
            or (ends_open and nos[-1] == len(all_lines)):
        return None
    if _delimiter([all_lines[no - 1] for no in nos[:50]]) != ",":
        return None
    if any('"' in all_lines[no - 1] or "\x00" in all_lines[no - 1] for no in nos):
        return None  # quoted cells and NUL bytes are csv.reader's business
    header = [c.strip() for c in all_lines[nos[0] - 1].split(",")]
    if not any(header) or any(_underscore_number(c) for c in header):
        return None
    commas = len(header) - 1
    data = [all_lines[no - 1] for no in nos[1:]]
    del all_lines
    for ln in data:
        if ln.count(",") != commas or "_" in ln or not ln.replace(",", "").strip():
            return None
    cols = list(usecols(header, nos[0]))
    try:
        table = np.loadtxt(data, dtype=np.float64, delimiter=",", comments=None,
                           quotechar=None, usecols=cols, ndmin=2)
    except ValueError:  # a cell that is not a number: read_rows names it
        return None
    return NumberTable(header, nos[1:], table)


def stream_rows(lines):
    """The cells of each line of a stream of delimited text, as it comes.

    Blank lines and lines starting with ``#`` are passed over; the first other line (the
    header) sets the delimiter: ``,``, else a spreadsheet's ``;`` (whose numbers then have
    decimal commas, read as points), else a tab.  Cells are stripped of spaces, quotes and
    a byte-order mark.

    Yields
    ------
    number : int
        The line's number, from 1.
    cells : list of str
    """
    delimiter = None
    for number, line in enumerate(lines, start=1):
        text = line.strip().lstrip("\ufeff")
        if not text or text.startswith("#"):
            continue
        if delimiter is None:
            delimiter = next((d for d in (",", ";", "\t") if d in text), ",")
        cells = [c.strip().strip('"') for c in text.split(delimiter)]
        yield number, (cells if delimiter == "," else [c.replace(",", ".") for c in cells])


def row_numbers(cells: list[str], where, header: list[str], *, source: str,
                line: int) -> np.ndarray:
    """The numbers in the columns `where` (an index array of any shape) of one streamed row
    (:func:`stream_rows`), float64 of `where`'s shape; an empty cell is NaN (a reading lost).

    Raises
    ------
    RecordingError
        A cell that is no number, naming `source`, the line and the column.
    """
    where = np.asarray(where)
    try:
        return np.array([float(cells[j]) if cells[j] else np.nan for j in where.ravel()]
                        ).reshape(where.shape)
    except ValueError:
        bad = next(j for j in where.ravel() if cells[j] and not reads_as_number(cells[j]))
        raise RecordingError(f"{source}, line {line}: {header[bad]} is {cells[bad]!r:.40}, "
                             "not a number") from None

