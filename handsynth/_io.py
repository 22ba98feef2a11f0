"""Output files written whole or not at all, and never over an input.

Every file handsynth writes (database files, JSON reports, pictures, plots,
measurement files, videos, recordings) goes through :func:`atomic_path` or
one of the helpers built on it:

1. the name is checked first (:func:`check_output`): it must not be a
   folder, its folder must exist, and it must not be one of the run's input
   files -- the same path or, through links, the same file;
2. the content is written to ``<name>.tmp-<pid>`` in the same folder (the
   same file system, so the rename is atomic), flushed and fsynced;
3. the temporary file is renamed onto the name with :func:`os.replace` and
   the folder is fsynced.

On any error -- a full disk, a read-only folder, Ctrl-C -- the temporary
file is removed and the name keeps its old content (or stays absent).  When
even the removal fails (a read-only file system refuses it) the original
error is raised all the same, with a note; a cleanup never hides the error
that made it necessary.  ``OSError`` becomes the caller's
:class:`~handsynth.errors.HandsynthError` class (``OutputError`` by
default) with the file, what it is and the system's reason.

A reader never opens a name containing ``.tmp-``: such a file is at best the
unfinished write of another process.
"""

from __future__ import annotations

import contextlib
import errno
import json
import math
import os
from collections.abc import Iterable, Iterator
from pathlib import Path

from .errors import HandsynthError, OutputError

__all__ = [
    "TMP_MARK",
    "PendingOutput",
    "atomic_open",
    "atomic_path",
    "check_output",
    "is_tmp_name",
    "json_text",
    "os_error_reason",
    "same_file",
    "write_bytes",
    "write_json",
    "write_text",
]

#: Part of the name of every temporary file of an unfinished write.
TMP_MARK = ".tmp-"


def is_tmp_name(path) -> bool:
    """True for the name of a temporary file of an unfinished write."""
    return TMP_MARK in Path(path).name


def same_file(a, b) -> bool:
    """True when paths `a` and `b` name the same file (same path, or linked to it)."""
    a, b = Path(a), Path(b)
    with contextlib.suppress(OSError, RuntimeError):
        if a.resolve() == b.resolve():
            return True
    try:
        return os.path.samefile(a, b)
    except (OSError, ValueError):
        return False


def os_error_reason(exc: BaseException) -> str:
    """The reason of an ``OSError`` in words (a full disk and a read-only file system named)."""
    if isinstance(exc, OSError):
        if exc.errno == errno.ENOSPC:
            return "no space left on the device (the disk is full)"
        if exc.errno == errno.EROFS:
            return "the file system is read-only"
        if exc.strerror:
            return exc.strerror[0].lower() + exc.strerror[1:]
    return str(exc)


def make_folder(path, *, what: str = "output folder", writable: bool = False,
                error: type[HandsynthError] = OutputError) -> Path:
    """Create the folder `path` (and its parents) unless it exists.

    Parameters
    ----------
    path : str or os.PathLike
    what : str, keyword-only
        What the folder is, for messages (``"--plots folder"``).
    writable : bool, keyword-only
        Also refuse a folder this process cannot write into (a read-only
        file system, no write permission), so that a run whose outputs go
        there stops before its work rather than after it.  False for a
        folder that may only be read (a cache that already holds what is
        asked for).
    error : HandsynthError subclass, keyword-only
        Class of the error raised.

    Returns
    -------
    pathlib.Path

    Raises
    ------
    HandsynthError
        (`error`) it cannot be made: a file stands in the way, no
        permission, a full disk (the reason in words); or, with `writable`,
        it cannot be written into.
    """
    path = Path(path)
    try:
        path.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise error(f"cannot create the {what} {str(path)!r}: {os_error_reason(exc)}") from None
    if writable and (why := _unwritable(path)):
        raise error(f"cannot write into the {what} {str(path)!r}: {why}")
    return path


def _unwritable(folder: Path) -> str | None:
    """Why this process cannot create a file in the existing `folder`, or None when it can."""
    if os.access(folder, os.W_OK | os.X_OK):
        return None
    try:
        if os.statvfs(folder).f_flag & os.ST_RDONLY:
            return "the file system is read-only"
    except OSError:
        pass
    return "this user may not write into it"


def check_output(path, *, what: str = "output file", inputs: Iterable = (),
                 error: type[HandsynthError] = OutputError) -> Path:
    """Check that `path` can become an output file without replacing anything it must not.

    Parameters
    ----------
    path : str or os.PathLike
        The output file.
    what : str, keyword-only
        What the file is, for messages (``"row file"``, ``"database"``...).
    inputs : iterable of path-like, keyword-only
        Files the run reads; `path` must be none of them (``None`` items are
        skipped).
    error : HandsynthError subclass, keyword-only
        Class of the error raised.

    Returns
    -------
    pathlib.Path
        `path`, or the file it links to when it is a symbolic link.

    Raises
    ------
    HandsynthError
        (`error`) `path` is a folder, its folder does not exist, is not a
        folder or cannot be written into (a read-only file system, no write
        permission: refused now rather than after the run's work), it is not
        a regular file (a device such as ``/dev/null``, a pipe), or it names
        an input file.
    """
    path = Path(path)
    if path.name in ("", ".", ".."):
        raise error(f"cannot write the {what} {str(path)!r}: it names a folder, not a file")
    if path.is_dir():
        raise error(f"cannot write the {what} {str(path)!r}: it is a folder")
    if path.is_symlink():  # write where the link points: renaming onto it would replace the link
        path = Path(os.path.realpath(path))
    if path.exists() and not path.is_file():
        raise error(f"cannot write the {what} {str(path)!r}: it is not a regular file (a "
                    "device, pipe or socket, which the finished file would replace); give "
                    "a file name")
    parent = path.parent
    if not parent.is_dir():
        why = "is not a folder" if parent.exists() else "does not exist"
        raise error(f"cannot write the {what} {str(path)!r}: folder {str(parent)!r} {why} "
                    "(create it first)")
    if reason := _unwritable(parent):
        raise error(f"cannot write the {what} {str(path)!r} into folder {str(parent)!r}: "
                    f"{reason}")
    for source in inputs:
        if source is not None and same_file(path, source):
            raise error(f"the {what} {str(path)!r} is the input {str(source)!r}; an output "
                        "never replaces an input: choose another name")
    return path


def check_outputs(outputs: Iterable, *, inputs: Iterable = (),
                  error: type[HandsynthError] = OutputError) -> None:
    """:func:`check_output` for each output of a run, and no two of them one file.

    Parameters
    ----------
    outputs : iterable of (str, path-like or None)
        ``(option, path)`` pairs, e.g. ``("--json", "r.json")``; ``None``
        paths (options not given) are skipped.
    inputs, error : keyword-only
        As in :func:`check_output`.

    Raises
    ------
    HandsynthError
        (`error`) as :func:`check_output`, or two outputs that name the same
        file (one would overwrite the other).
    """
    given = [(flag, path) for flag, path in outputs if path]
    inputs = tuple(inputs)
    for i, (flag, path) in enumerate(given):
        check_output(path, what=f"{flag} file", inputs=inputs, error=error)
        for other, prev in given[:i]:
            if same_file(path, prev):
                raise error(f"{other} and {flag} name the same file {str(path)!r}; one would "
                            "overwrite the other: choose two names")


def _fsync(path: Path, *, directory: bool = False) -> None:
    flags = os.O_RDONLY | (getattr(os, "O_DIRECTORY", 0) if directory else 0)
    try:
        fd = os.open(path, flags)
    except OSError:
        if directory:  # not every platform can open a folder
            return
        raise
    try:
        os.fsync(fd)
    except OSError:
        if not directory:
            raise
    finally:
        os.close(fd)


class PendingOutput:
    """An output file being written under a temporary name, until :meth:`commit`.

    For writers that stay open for a while (a video encoder): write to
    :attr:`tmp`, then :meth:`commit` (fsync and rename onto :attr:`path`) or
    :meth:`discard` (remove it).  :func:`atomic_path` wraps the two in a
    ``with`` block.

    Parameters
    ----------
    path : str or os.PathLike
    what, inputs, error : keyword-only
        As in :func:`check_output` (checked here, before anything is written).
    keep_suffix : bool, keyword-only
        End the temporary name with `path`'s suffix too (``x.mp4.tmp-<pid>.mp4``),
        for writers that choose the format from the suffix.

    Attributes
    ----------
    path : pathlib.Path
        The final name.
    tmp : pathlib.Path
        ``<path>.tmp-<pid>`` in the same folder.
    """

    def __init__(self, path, *, what: str = "output file", inputs: Iterable = (),
                 error: type[HandsynthError] = OutputError, keep_suffix: bool = False) -> None:
        self.path = check_output(path, what=what, inputs=inputs, error=error)
        self.what, self.error = what, error
        suffix = self.path.suffix if keep_suffix else ""
        self.tmp = self.path.with_name(f"{self.path.name}{TMP_MARK}{os.getpid()}{suffix}")

    def commit(self) -> Path:
        """Fsync the temporary file and rename it onto :attr:`path`."""
        try:
            if not self.tmp.is_file():
                raise self.error(f"the {self.what} {str(self.path)!r} was not written "
                                 "(no data came)")
            _fsync(self.tmp)
            os.replace(self.tmp, self.path)
            _fsync(self.path.parent, directory=True)
        except BaseException as exc:
            self.discard(exc)
            wrapped = self.wrap(exc)
            if wrapped is exc:
                raise
            raise wrapped from exc
        return self.path

    def discard(self, exc: BaseException | None = None) -> None:
        """Remove the temporary file; a failure is noted on `exc`, never raised."""
        try:
            self.tmp.unlink()
        except FileNotFoundError:
            pass
        except OSError as cleanup:
            if exc is not None:
                exc.add_note(f"the temporary file {self.tmp} could not be removed: "
                             f"{os_error_reason(cleanup)}")

    def wrap(self, exc: BaseException) -> BaseException:
        """`exc` as this output's error when it is an ``OSError``, else unchanged."""
        if isinstance(exc, OSError):
            wrapped = self.error(f"cannot write the {self.what} {str(self.path)!r}: "
                                 f"{os_error_reason(exc)}")
            for note in getattr(exc, "__notes__", ()):
                wrapped.add_note(note)
            return wrapped
        return exc


@contextlib.contextmanager
def atomic_path(path, *, what: str = "output file", inputs: Iterable = (),
                error: type[HandsynthError] = OutputError,
                keep_suffix: bool = False) -> Iterator[Path]:
    """Context manager: a temporary name to write, renamed onto `path` on success.

    The caller writes the whole file to the yielded path (a writer that
    needs a file name: a video encoder, a library that opens the file
    itself).  On leaving the block without an error the file is fsynced and
    renamed onto `path`; on any error it is removed and the error propagates
    (``OSError`` as `error`, naming the file).

    Parameters
    ----------
    path : str or os.PathLike
    what, inputs, error, keep_suffix : keyword-only
        As in :class:`PendingOutput`.

    Yields
    ------
    pathlib.Path
        ``<path>.tmp-<pid>`` in `path`'s folder.
    """
    pending = PendingOutput(path, what=what, inputs=inputs, error=error,
                            keep_suffix=keep_suffix)
    try:
        yield pending.tmp
    except BaseException as exc:
        pending.discard(exc)
        wrapped = pending.wrap(exc)
        if wrapped is exc:
            raise
        raise wrapped from exc
    pending.commit()


@contextlib.contextmanager
def atomic_open(path, mode: str = "w", *, what: str = "output file", inputs: Iterable = (),
                error: type[HandsynthError] = OutputError, encoding: str | None = "utf-8",
                newline: str | None = None) -> Iterator:
    """Context manager: a file object whose content appears under `path` only when complete.

    Parameters
    ----------
    path : str or os.PathLike
    mode : {"w", "wb"}
        Text (UTF-8 by default) or binary.
    what, inputs, error : keyword-only
        As in :func:`check_output`.
    encoding, newline : keyword-only
        As in :func:`open` (text mode only).

    Yields
    ------
    file object
    """
    if mode not in ("w", "wb"):
        raise ValueError(f"mode must be 'w' or 'wb', got {mode!r}")
    with atomic_path(path, what=what, inputs=inputs, error=error) as tmp:
        if mode == "wb":
            with open(tmp, "wb") as fb:
                yield fb
                fb.flush()
        else:
            with open(tmp, "w", encoding=encoding, newline=newline) as ft:
                yield ft
                ft.flush()


def write_bytes(path, data, *, what: str = "output file", inputs: Iterable = (),
                error: type[HandsynthError] = OutputError) -> Path:
    """Write `data` (bytes-like) to `path` atomically; return `path` as a Path."""
    with atomic_open(path, "wb", what=what, inputs=inputs, error=error) as f:
        f.write(data)
    return Path(path)


def write_text(path, text: str, *, what: str = "output file", inputs: Iterable = (),
               error: type[HandsynthError] = OutputError) -> Path:
    """Write `text` as UTF-8 to `path` atomically; return `path` as a Path."""
    with atomic_open(path, "w", what=what, inputs=inputs, error=error) as f:
        f.write(text)
    return Path(path)


def _finite_or_null(obj):
    """`obj` with every NaN or infinite number, at any depth, replaced by ``None``.

    Dicts, lists and tuples are walked (a tuple becomes a list, as JSON has
    it); numpy scalars become Python numbers and numpy arrays nested lists.
    Anything else is returned unchanged, for :func:`json.dumps` to judge.
    """
    if isinstance(obj, float):  # float and numpy.float64
        return float(obj) if math.isfinite(obj) else None
    if isinstance(obj, dict):
        return {k: _finite_or_null(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_finite_or_null(v) for v in obj]
    if isinstance(obj, (bool, int, str)) or obj is None:
        return obj
    import numpy as np

    if isinstance(obj, (np.generic, np.ndarray)):
        return _finite_or_null(obj.tolist())
    return obj


def write_json(path, obj, *, what: str = "JSON file", inputs: Iterable = (),
               error: type[HandsynthError] = OutputError, indent: int | None = 2) -> Path:
    """Write `obj` as JSON to `path` atomically; return `path` as a Path.

    The file is always valid JSON (:rfc:`8259`): a NaN or infinite number
    anywhere in `obj` -- a Python ``float`` or a numpy scalar or array
    element, at any depth of dicts, lists and tuples -- is written as
    ``null``, never as the bare ``NaN``/``Infinity`` tokens that
    :func:`json.dumps` writes by default and that strict readers refuse.
    numpy scalars and arrays are written as numbers and (nested) lists.

    Parameters
    ----------
    path : str or os.PathLike
    obj : JSON-like
        Dicts, lists, tuples, strings, numbers (Python or numpy), booleans,
        ``None`` and numpy arrays.
    what, inputs, error : keyword-only
        As in :func:`check_output`.
    indent : int or None, keyword-only
        As in :func:`json.dumps`; the text ends with a newline.

    Returns
    -------
    pathlib.Path

    Raises
    ------
    HandsynthError
        (`error`) as :func:`check_output`, or the file cannot be written.
    TypeError
        `obj` holds a value JSON cannot represent (a set, a path...).
    """
    return write_text(path, json_text(obj, indent=indent) + "\n", what=what, inputs=inputs,
                      error=error)


def json_text(obj, *, indent: int | None = 2) -> str:
    """`obj` as JSON text, non-finite numbers as ``null`` (see :func:`write_json`).

    Parameters
    ----------
    obj : JSON-like
        As in :func:`write_json`.
    indent : int or None, keyword-only
        As in :func:`json.dumps`.

    Returns
    -------
    str
        Without a final newline.
    """
    return json.dumps(_finite_or_null(obj), indent=indent, allow_nan=False)
