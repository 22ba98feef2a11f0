"""The database build job: many hand shapes, many poses, in parallel, resumable.

One HDF5 file per hand shape and side, ``<out_dir>/<shape.name>.h5`` for
the right hand and ``<out_dir>/<shape.name>_left.h5`` for the left hand
(:func:`database_path`), written by :func:`write_database` (atomic,
deterministic, checksummed).  The name gives the ratios to 0.001, so a
build refuses a shape with finer ratios (round it with
``HandShape.from_name(shape.name)``), and an existing file that holds
another shape or side than its name promises is refused
(:class:`DatabaseMismatchError`), never overwritten.

How a build runs
----------------
1. For every shape the expected metadata (:func:`database_meta`) is
   computed.  A file that already exists is *checked*, not assumed: it is
   skipped only if :func:`verify` accepts it with that metadata (complete
   mark, checksum, same parameters); otherwise it is rebuilt.  Temporary
   files ``<name>.h5.tmp-<pid>`` left by killed builds are removed.
2. The pose set is drawn once (``pose_set(name, count, seed=seed)``, the
   same poses for every shape).  Each shape to build is probed: the open
   hand, a fist and a few poses of the set are rendered, and a shape the
   mount sees in none of them refuses the whole build before any file is
   written.  Each shape's poses are then cut into chunks;
   the chunks are the tasks of the executor.  A worker keeps one
   :class:`SilhouetteRasterizer` per shape (one model load for many poses).
3. When all chunks of a shape are back they are joined in pose order and
   written.  Rendering is a pure function of (shape, pose), so the bytes do
   not depend on the chunking, the number of workers or the executor: same
   seed, same bytes.

Interrupting at any moment leaves finished files and, at worst, a
temporary file that no reader opens; the next run resumes from there.
"""

from __future__ import annotations

import os
import time
import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, fields
from pathlib import Path

import numpy as np

from .._checks import check_integer, check_options, check_path, check_side, short_repr
from .._cores import usable_cores
from .._io import make_folder, os_error_reason
from ..errors import (
    DatabaseError,
    DatabaseMismatchError,
    InvalidCameraError,
    InvalidInputError,
    InvalidShapeError,
    OutputError,
)
from ..models import PAPER_SIZE, HandShape
from ..models import pose_set as make_pose_set
from ..render import CameraMount, as_mount
from ._entries import DEFAULT_RENDER_SIZE, check_render_size, database_meta, render_entries
from ._executors import EXECUTORS, run_tasks
from ._store import LEFT_SUFFIX, verify, write_database
from ._validation import IMAGE_SIZE

__all__ = [
    "DEFAULT_DATABASE",
    "MAX_COUNT",
    "BuildOptions",
    "BuildProgress",
    "BuildSummary",
    "build_database",
    "build_databases",
    "build_default_database",
    "check_database_hand",
    "database_path",
    "find_database",
]

_STORED = ("angles", "hlac", "sil_bits", "ridge_bits", "ridge_area", "keypoints")
_MAX_CHUNK = 4096  # poses per task: progress granularity and parent memory
_MIN_CHUNK = 128
#: Most poses per shape: a database is read into memory whole, 2,832 bytes per
#: entry (57.9 MB for the paper's 20,448), so 5,000,000 entries need 14 GB.
MAX_COUNT = 5_000_000
#: Lock file of a build in its output folder (one build per folder at a time).
LOCK_NAME = ".handsynth-build.lock"


@dataclass(frozen=True)
class BuildOptions:
    """What every database of a build is made of.

    Parameters
    ----------
    side : {"right", "left"}
        Hand side.
    pose_set : {"paper", "natural"}
        Pose set (:func:`handsynth.models.pose_set`).
    count : int
        Poses per shape (20,448 in the paper).
    seed : int
        Seed of the pose set; same seed, same bytes.
    render_size : (int, int)
        (width, height) in pixels of the masks before preprocessing.

    Raises
    ------
    InvalidInputError
        A field with an unusable value; the message names it.
    """

    side: str = "right"
    pose_set: str = "paper"
    count: int = PAPER_SIZE
    seed: int = 0
    render_size: tuple[int, int] = DEFAULT_RENDER_SIZE

    def __post_init__(self) -> None:
        check_side(self.side)
        from ..models import POSE_SETS

        if not isinstance(self.pose_set, str) or self.pose_set not in POSE_SETS:
            raise InvalidInputError(
                f"pose_set must be one of {', '.join(POSE_SETS)}, got "
                f"{type(self.pose_set).__name__} {short_repr(self.pose_set)}")
        for name in ("count", "seed"):
            v = check_integer(getattr(self, name), name, minimum=1 if name == "count" else 0)
            object.__setattr__(self, name, v)
        if self.count > MAX_COUNT:
            raise InvalidInputError(
                f"count must be at most {MAX_COUNT:,} poses per shape (a database is held in "
                f"memory, 2.8 kB per entry: {self.count:,} would need "
                f"{self.count * 2832 / 1e9:,.0f} GB), got {self.count}")
        object.__setattr__(self, "render_size", check_render_size(self.render_size))

    def meta(self, shape: HandShape, mount: CameraMount) -> dict:
        """The metadata a database of `shape` built with these options carries."""
        return database_meta(shape, mount, side=self.side, pose_set=self.pose_set,
                             count=self.count, seed=self.seed, render_size=self.render_size)


@dataclass(frozen=True)
class BuildProgress:
    """State of a running build, passed to the ``progress`` callback.

    Attributes
    ----------
    entries_done, entries_total : int
        Entries rendered so far and to render in this run (skipped shapes
        are not counted).
    shapes_done, shapes_total : int
        Databases written or skipped so far, and all shapes of the build.
    elapsed_s : float
        Seconds since rendering started.
    finished : bool
        True for the last call.
    """

    entries_done: int
    entries_total: int
    shapes_done: int
    shapes_total: int
    elapsed_s: float
    finished: bool = False

    @property
    def rate(self) -> float:
        """Entries per second so far (0 before the first chunk)."""
        return self.entries_done / self.elapsed_s if self.elapsed_s > 0 else 0.0

    @property
    def eta_s(self) -> float | None:
        """Estimated seconds left, ``None`` until a rate is known."""
        if self.entries_done == 0 or self.elapsed_s <= 0:
            return None
        return (self.entries_total - self.entries_done) / self.rate

    @property
    def fraction(self) -> float:
        """Share of the entries done, 0..1."""
        return 1.0 if self.entries_total == 0 else self.entries_done / self.entries_total


@dataclass(frozen=True)
class BuildSummary:
    """Outcome of :func:`build_databases`.

    Attributes
    ----------
    paths : tuple of pathlib.Path
        One database per requested shape, in the order of the shapes.
    built, skipped : tuple of str
        Shape names written in this run, and those whose file was verified
        and kept.
    rebuilt : dict of str to str
        Shapes whose existing file was refused, with the reason (they are
        also in `built`).
    entries : int
        Entries rendered in this run.
    seconds : float
        Wall time of the run.
    workers : int
    executor : str
    """

    paths: tuple[Path, ...]
    built: tuple[str, ...]
    skipped: tuple[str, ...]
    rebuilt: dict = field(default_factory=dict)
    entries: int = 0
    seconds: float = 0.0
    workers: int = 1
    executor: str = "process"

    def format(self) -> str:
        """A short human-readable report (several lines)."""
        rate = self.entries / self.seconds if self.seconds > 0 else 0.0
        lines = [
            (f"{len(self.paths)} database(s) in {self.paths[0].parent if self.paths else '-'}: "
             f"{len(self.built)} built, {len(self.skipped)} verified and kept"),
            (f"{self.entries} entries in {self.seconds:.1f} s ({rate:.0f} entries/s, "
             f"{self.workers} worker(s), executor {self.executor})"),
        ]
        for name, reason in self.rebuilt.items():
            lines.append(f"rebuilt {name}: {reason}")
        return "\n".join(lines)


#: The small database the demo builds: the standard shape, 3000 paper poses.
DEFAULT_DATABASE: dict = {"shape": HandShape(), "pose_set": "paper", "count": 3000, "seed": 0}


def _as_shape(shape, name: str = "shape") -> HandShape:
    """`shape` as a HandShape: a HandShape or its :attr:`HandShape.name`."""
    if isinstance(shape, str):
        return HandShape.from_name(shape)
    if not isinstance(shape, HandShape):
        raise InvalidInputError(
            f"{name} must be a HandShape or a shape name such as {HandShape().name!r}, "
            f"got {type(shape).__name__}")
    return shape


def _check_named_resolution(shape: HandShape, name: str) -> None:
    """Refuse a shape that its file name (ratios to 0.001) would not tell apart."""
    named = HandShape.from_name(shape.name)
    off = [f"{k}={getattr(shape, k)!r}" for k, v in named.as_dict().items()
           if abs(getattr(shape, k) - v) > 1e-9]
    if off:
        raise InvalidShapeError(
            f"{name} has ratios finer than its database file name {shape.name} tells apart "
            f"(0.001): {', '.join(off)}; round it with HandShape.from_name(shape.name)")


def database_path(out_dir, shape: HandShape | str, side: str = "right") -> Path:
    """File of `shape`'s database in `out_dir`.

    Parameters
    ----------
    out_dir : str or os.PathLike
    shape : HandShape or str
        A shape or its :attr:`HandShape.name`.
    side : {"right", "left"}
        Hand side.

    Returns
    -------
    pathlib.Path
        ``<out_dir>/<shape.name>.h5`` for the right hand,
        ``<out_dir>/<shape.name>_left.h5`` for the left hand.

    Raises
    ------
    InvalidInputError
        `out_dir` is not a folder name (None, a number, an empty name),
        `shape` is neither a HandShape nor a shape name, or `side` is not
        ``"right"`` or ``"left"``.
    """
    out_dir = check_path(out_dir, "out_dir", kind="folder")
    shape = _as_shape(shape)
    suffix = LEFT_SUFFIX if check_side(side) == "left" else ""
    return out_dir / f"{shape.name}{suffix}.h5"


def check_database_hand(meta, shape: HandShape, side: str, path) -> None:
    """Refuse a database whose metadata holds another hand than `shape`'s `side` hand.

    Parameters
    ----------
    meta : dict
        The database's metadata (:func:`database_meta`); a missing
        ``shape`` is not checked, a missing ``side`` means the right hand.
    shape : HandShape
        The shape asked for; its ratios must equal the stored ones exactly.
    side : {"right", "left"}
        The side asked for.
    path : path-like
        The file, for the message.

    Raises
    ------
    DatabaseMismatchError
        Naming the file, the stored hand and the hand asked for.
    """
    stored_side = meta.get("side", "right")
    stored_shape = meta.get("shape")
    same_shape = not isinstance(stored_shape, dict) or stored_shape == shape.as_dict()
    if stored_side == side and same_shape:
        return
    if isinstance(stored_shape, dict):
        ratios = ", ".join(f"{k}={v!r}" for k, v in sorted(stored_shape.items()))
    else:
        ratios = "unknown shape"
    asked = ", ".join(f"{k}={v!r}" for k, v in sorted(shape.as_dict().items()))
    raise DatabaseMismatchError(
        f"database {path} holds the {stored_side} hand ({ratios}) but the {side} hand "
        f"({asked}) was asked for; it is not overwritten: move or delete it, or build "
        "into another folder")


def find_database(folder, shape: HandShape | str, side: str = "right") -> Path:
    """The existing database file of `shape` in `folder`, or an error that says what is there.

    Parameters
    ----------
    folder : str or os.PathLike
    shape : HandShape or str
        A shape or its :attr:`HandShape.name`.
    side : {"right", "left"}
        Hand side (see :func:`database_path`).

    Returns
    -------
    pathlib.Path
        :func:`database_path` of `shape` and `side`, a file (not yet
        checked: see :func:`open_database`).

    Raises
    ------
    InvalidInputError
        `folder` is not a folder name (None, a number, an empty name),
        `shape` is neither a HandShape nor a shape name, or `side` is not
        ``"right"`` or ``"left"``.
    DatabaseError
        `folder` is missing or a file; the name is a folder or a link to
        nothing; or there is no such file (the message lists the database
        files that are there).
    """
    folder = check_path(folder, "folder", kind="folder")
    path = database_path(folder, shape, side)
    if not folder.is_dir():
        why = "is a file, not a folder" if folder.exists() else "does not exist"
        raise DatabaseError(f"database folder {str(folder)!r} {why}")
    if path.is_dir():
        raise DatabaseError(f"database {path} is a folder, not a file")
    if path.is_symlink() and not path.exists():
        raise DatabaseError(f"database {path} is a link to {os.readlink(path)!r}, which does "
                            "not exist")
    if not path.is_file():
        have = sorted(p.stem for p in folder.glob("*.h5") if p.is_file())
        raise DatabaseError(f"no database for the {side} hand of shape {path.stem} in {folder} "
                            f"(database files there: {', '.join(have) or 'none'})")
    return path


# --------------------------------------------------------------------------- workers

# One open renderer per worker process, reused while tasks are of one shape.
_RENDERER: dict = {}


def _renderer_for(key):
    from ..render import SilhouetteRasterizer

    r = _RENDERER.get(key)
    if r is None:
        for old in _RENDERER.values():
            old.close()
        _RENDERER.clear()
        shape, mount, side, (w, h) = key
        r = _RENDERER[key] = SilhouetteRasterizer(shape, mount, side=side, width_px=w,
                                                  height_px=h)
    return r


def _render_chunk(task) -> dict[str, np.ndarray]:
    """Worker: the stored rows of one chunk of poses of one shape."""
    key, angles = task
    rows = render_entries(angles, render_size=key[3], renderer=_renderer_for(key))
    return {k: rows[k] for k in _STORED}


# --------------------------------------------------------------------------- planning


def _remove_stale_tmp(path: Path) -> None:
    for tmp in path.parent.glob(f"{path.name}.tmp-*"):
        pid = tmp.name.rsplit("-", 1)[-1]
        if pid.isdigit() and int(pid) != os.getpid() and _alive(int(pid)):
            continue  # another build is writing it right now
        tmp.unlink(missing_ok=True)


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


class _FolderLock:
    """An exclusive lock on a build's output folder (``fcntl.flock`` on :data:`LOCK_NAME`).

    A second build of the same folder -- same or other parameters -- is
    refused while the first runs; the lock goes with the process that holds
    it, even when that process is killed.
    """

    def __init__(self, folder: Path, what: str) -> None:
        import fcntl

        self.path = folder / LOCK_NAME
        try:
            fd = os.open(self.path, os.O_RDWR | os.O_CREAT, 0o644)
        except OSError as exc:
            raise DatabaseError(f"cannot lock the output folder {str(folder)!r}: "
                                f"{os_error_reason(exc)}") from None
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            other = os.pread(fd, 4096, 0).decode("utf-8", "replace").strip()
            os.close(fd)
            raise OutputError(
                f"output folder {str(folder)!r} is in use by another build ({other or 'running'}); "
                "wait for it to finish, or build into another folder") from None
        os.ftruncate(fd, 0)
        os.pwrite(fd, f"pid {os.getpid()}: {what}\n".encode(), 0)
        self._fd: int | None = fd

    def release(self) -> None:
        if self._fd is not None:
            os.close(self._fd)  # closing releases the lock
            self._fd = None


def _check_existing(path: Path, meta: dict, shape: HandShape,
                    side: str) -> tuple[bool, str | None]:
    """(keep, reason it is refused) for an existing file.

    Raises
    ------
    DatabaseMismatchError
        The file is sound but holds another hand (shape or side): it is not
        overwritten.
    """
    if not path.exists():
        return False, None
    try:
        verify(path, expect=meta)
    except DatabaseMismatchError as exc:
        try:
            stored = verify(path)
        except DatabaseError:
            return False, str(exc)  # damaged or misnamed: rebuilt
        check_database_hand(stored, shape, side, path)
        return False, str(exc)
    except DatabaseError as exc:
        return False, str(exc)
    return True, None


def _chunk_size(count: int, n_shapes: int, workers: int, chunk_size: int | None) -> int:
    if chunk_size is not None:
        if isinstance(chunk_size, bool) or not isinstance(chunk_size, (int, np.integer)) \
                or chunk_size < 1:
            raise InvalidInputError(f"chunk_size must be a positive integer, got {chunk_size!r}")
        return int(chunk_size)
    # enough tasks to keep every worker busy to the end, few enough to keep
    # per-task overhead small
    want_tasks = max(1, -(-4 * workers // n_shapes))
    return int(min(count, _MAX_CHUNK, max(_MIN_CHUNK, -(-count // want_tasks))))


def _as_shapes(shapes) -> list[HandShape]:
    if isinstance(shapes, HandShape):
        shapes = [shapes]
    out = []
    for i, given in enumerate(shapes):
        s = _as_shape(given, f"shapes[{i}]")
        _check_named_resolution(s, f"shapes[{i}]")
        out.append(s)
    if not out:
        raise InvalidInputError("shapes must name at least one hand shape, got none")
    names = [s.name for s in out]
    dup = {n for n in names if names.count(n) > 1}
    if dup:
        raise InvalidInputError(f"shapes must be distinct, got {min(dup)} more than once")
    return out


def _options_from(option_fields: dict, caller: str) -> BuildOptions:
    """:class:`BuildOptions` of the option keywords given to `caller`, an unknown one refused."""
    known = [f.name for f in fields(BuildOptions)]
    unknown = [k for k in option_fields if k not in known]
    if unknown:
        raise InvalidInputError(
            f"{caller} got an unexpected keyword argument {unknown[0]!r} (the option keywords "
            f"are {', '.join(known)})")
    return BuildOptions(**option_fields)


def _check_progress(progress) -> None:
    if progress is not None and not callable(progress):
        raise InvalidInputError(
            f"progress must be None or a callable taking a BuildProgress, got "
            f"{type(progress).__name__} {short_repr(progress)}")


def _check_in_view(sil_bits: np.ndarray, mount: CameraMount, shape: HandShape, side: str,
                   path: Path) -> None:
    """Refuse the rows of a database whose every silhouette is empty: the mount never sees
    the hand, and such a database would match every frame equally badly."""
    if len(sil_bits) and not sil_bits.any():
        raise InvalidCameraError(
            f"mount {mount!r} never sees the hand: all {len(sil_bits)} silhouettes of shape "
            f"{shape.name} ({side} hand) are empty, so {path.name} is not written; place the "
            "camera where it sees the back of the hand")


#: Poses of the pose set that :func:`_probe_in_view` renders for each shape, besides the open
#: hand and a fist (spread evenly over the set).
_PROBE_POSES = 8


def _probe_in_view(todo, mount: CameraMount, options: BuildOptions, angles: np.ndarray) -> None:
    """Refuse a build, before anything is rendered or written, when `mount` sees none of a
    few poses of one of its shapes: the open hand, a fist and :data:`_PROBE_POSES` poses of
    the set `angles`, rendered as the build renders them (`options`' side and render size).

    A shape it sees in one of them is built; :func:`_check_in_view` still refuses one whose
    every rendered silhouette is empty.  A few model loads and renders per shape.
    """
    from ..models import named_pose
    from ..render import SilhouetteRasterizer, preprocess

    picks = np.unique(np.linspace(0, len(angles) - 1, min(_PROBE_POSES, len(angles))).astype(int))
    poses = np.vstack([np.zeros((1, angles.shape[1])), named_pose("fist")[None], angles[picks]])
    w, h = options.render_size
    for shape, path, _ in todo:
        with SilhouetteRasterizer(shape, mount, side=options.side, width_px=w,
                                  height_px=h) as r:
            seen = any(preprocess(m, mount, side=options.side, size=IMAGE_SIZE).any()
                       for m in r.masks(poses))
        if not seen:
            raise InvalidCameraError(
                f"mount {mount!r} never sees the hand: all {len(poses)} probed silhouettes of "
                f"shape {shape.name} ({options.side} hand; the open hand, a fist and "
                f"{len(picks)} poses of the set) are empty, so neither {path.name} nor any "
                "other database of this build is written; place the camera where it sees the "
                "back of the hand")


# --------------------------------------------------------------------------- public


def build_databases(out_dir, shapes: Sequence[HandShape | str], mount: CameraMount | None = None,
                    *, options: BuildOptions | None = None, workers: int | None = None,
                    executor: str = "process", chunk_size: int | None = None,
                    force: bool = False,
                    progress: Callable[[BuildProgress], None] | None = None,
                    **option_fields) -> BuildSummary:
    """Build (or resume building) the databases of several hand shapes in parallel.

    Parameters
    ----------
    out_dir : str or os.PathLike
        Output folder, created if missing.
    shapes : sequence of HandShape or str
        Shapes (or their :attr:`HandShape.name`), e.g. ``HandShape.grid()``;
        ratios to 0.001, as in the file name (:func:`database_path`).
    mount : CameraMount, optional
        The paper's device by default.
    options : BuildOptions, keyword-only, optional
        Side, pose set, count, seed and render size.  Instead, the same
        fields may be given as keywords (``count=3000, seed=1``).
    workers : int, keyword-only, optional
        Worker processes; every core this process may use by default, and at
        most that many with ``executor="process"``.  One worker renders in
        this process.  Workers exit when this process dies and ignore Ctrl-C
        (this process stops them).
    executor : {"process", "ray"}, keyword-only
        A local process pool, or Ray (optional dependency; a local instance
        with `workers` CPUs, or the cluster of ``RAY_ADDRESS``).
    chunk_size : int, keyword-only, optional
        Poses per task; chosen from the work and `workers` by default.  It
        does not change the result.
    force : bool, keyword-only
        Rebuild even the files that verify (never a file that holds another
        shape or side: that is refused as without `force`).
    progress : callable, keyword-only, optional
        Called with a :class:`BuildProgress` after each finished chunk and
        once at the end.
    **option_fields
        Fields of :class:`BuildOptions`: ``side``, ``pose_set``, ``count``,
        ``seed``, ``render_size``.

    Returns
    -------
    BuildSummary
        Paths, built / skipped / rebuilt shapes, entries and time.

    Raises
    ------
    InvalidInputError
        Bad shapes, options, workers or executor (the message names it); an
        `out_dir` that is not a folder name (None, a number, an empty name);
        a keyword that is not an option field (``build_databases got an
        unexpected keyword argument 'bogus'``); a `progress` that is neither
        None nor callable; an
        :class:`~handsynth.errors.InvalidShapeError` for a shape with ratios
        finer than 0.001, which its file name would not tell apart.
    InvalidCameraError
        `mount` never sees one of the shapes to build (the message names
        the mount and the shape): refused before any database of the build
        is written when a probe of each shape (the open hand, a fist and a
        few poses of the set) shows no hand; and, should the probe see it
        but every rendered silhouette be empty, that database is not
        written.
    DatabaseMismatchError
        An existing file under a shape's name holds another shape or the
        other side (:func:`check_database_hand`); it is left as it is.
    OutputError
        Another build holds the folder's lock (:data:`LOCK_NAME`): one build
        per folder at a time.
    DatabaseError
        The folder cannot be created or locked, or a database could not be
        written (full disk, read-only folder); finished files stay.
    """
    out_dir = check_path(out_dir, "out_dir", kind="folder")
    if options is None:
        options = _options_from(option_fields, "build_databases")
    elif option_fields:
        raise InvalidInputError(
            f"give either options or option keywords, got both (keywords {sorted(option_fields)})")
    options = check_options(options, BuildOptions)
    _check_progress(progress)
    if workers is None:
        workers = usable_cores()
    if isinstance(workers, bool) or not isinstance(workers, (int, np.integer)) or workers < 1:
        raise InvalidInputError(f"workers must be a positive integer, got {workers!r}")
    workers = int(workers)
    cores = usable_cores()
    if executor == "process" and workers > cores:
        raise InvalidInputError(
            f"workers must be at most the {cores} CPU cores this process may use (each worker "
            f"process renders on one core and holds its own model), got {workers}")
    if executor not in EXECUTORS:
        raise InvalidInputError(
            f"executor must be one of {', '.join(EXECUTORS)}, got {executor!r}")
    mount = as_mount(mount)
    shape_list = _as_shapes(shapes)
    _chunk_size(options.count, len(shape_list), workers, chunk_size)  # checked before any file
    out = make_folder(out_dir, what="output folder", error=DatabaseError)

    what = (f"{len(shape_list)} shape(s), {options.pose_set} poses x {options.count}, "
            f"seed {options.seed}, {options.side} hand")
    lock = _FolderLock(out, what)
    try:
        return _build_locked(out, shape_list, mount, options, workers, executor, chunk_size,
                             force, progress)
    finally:
        lock.release()


def _build_locked(out: Path, shape_list, mount, options, workers, executor, chunk_size, force,
                  progress) -> BuildSummary:
    t0 = time.perf_counter()
    paths, todo, skipped, rebuilt = [], [], [], {}
    for shape in shape_list:
        path = database_path(out, shape, options.side)
        paths.append(path)
        _remove_stale_tmp(path)
        meta = options.meta(shape, mount)
        keep, reason = _check_existing(path, meta, shape, options.side)
        if force:
            keep = False
        if keep:
            skipped.append(shape.name)
            continue
        if reason is not None:
            rebuilt[shape.name] = reason
        todo.append((shape, path, meta))

    total = len(todo) * options.count
    done_entries, done_shapes = 0, len(skipped)
    t_render = time.perf_counter()

    def report(finished: bool = False) -> None:
        if progress is not None:
            progress(BuildProgress(done_entries, total, done_shapes, len(shape_list),
                                   time.perf_counter() - t_render, finished))

    report()
    if todo:
        angles = make_pose_set(options.pose_set, options.count, seed=options.seed)
        _probe_in_view(todo, mount, options, angles)  # every shape, before any file is written
        step = _chunk_size(options.count, len(todo), workers, chunk_size)
        bounds = [(a, min(a + step, options.count)) for a in range(0, options.count, step)]
        tasks, owner = [], []
        for k, (shape, _, _) in enumerate(todo):
            key = (shape, mount, options.side, options.render_size)
            for a, b in bounds:
                tasks.append((key, angles[a:b]))
                owner.append((k, a))
        parts: dict[int, dict[int, dict]] = {k: {} for k in range(len(todo))}
        for i, rows in run_tasks(_render_chunk, tasks, workers=workers, executor=executor):
            k, start = owner[i]
            parts[k][start] = rows
            done_entries += len(rows["angles"])
            if len(parts[k]) == len(bounds):
                shape, path, meta = todo[k]
                got = parts.pop(k)
                chunks = [got[a] for a, _ in bounds]
                joined = {name: np.concatenate([c[name] for c in chunks]) for name in _STORED}
                _check_in_view(joined["sil_bits"], mount, shape, options.side, path)
                write_database(path, meta=meta, **joined)
                done_shapes += 1
            report()
    summary = BuildSummary(paths=tuple(paths), built=tuple(s.name for s, _, _ in todo),
                           skipped=tuple(skipped), rebuilt=rebuilt, entries=total,
                           seconds=time.perf_counter() - t0, workers=workers, executor=executor)
    report(finished=True)
    return summary


def build_database(out_dir, shape: HandShape | str | None = None,
                   mount: CameraMount | None = None, *, workers: int = 1,
                   executor: str = "process", force: bool = False,
                   progress: Callable[[BuildProgress], None] | None = None,
                   **option_fields) -> Path:
    """Build the database of one hand shape (or keep the verified existing one).

    Parameters
    ----------
    out_dir : str or os.PathLike
        Output folder, created if missing; the file is
        :func:`database_path` of the shape and side.
    shape : HandShape or str, optional
        The standard hand by default.
    mount : CameraMount, optional
        The paper's device by default.
    workers : int, keyword-only
        1 (default) renders in this process with one model load; more split
        the poses across worker processes.
    executor, force, progress : keyword-only
        As in :func:`build_databases`.
    **option_fields
        Fields of :class:`BuildOptions`: ``side``, ``pose_set``, ``count``,
        ``seed``, ``render_size``.

    Returns
    -------
    pathlib.Path
        The database file.

    Warns
    -----
    UserWarning
        ``built again, replacing an existing file: <why>`` when the file
        existed but was damaged or built with other parameters (another
        count, seed or pose set): this function returns only the path, so the
        replacement is said here (:func:`build_databases` lists it in its
        summary's ``rebuilt``).

    Raises
    ------
    InvalidInputError
        `out_dir` is not a folder name (None, a number, an empty name); a
        keyword that is not an option field (``build_database got an
        unexpected keyword argument 'bogus'``); a `progress` that is neither
        None nor callable; bad options, shape, workers or executor, as in
        :func:`build_databases`.
    InvalidCameraError
        `mount` never sees the hand (the message names the mount): none of
        the probed poses (:func:`build_databases`) or, should one be seen,
        none of the rendered silhouettes shows it; nothing is written.
    DatabaseMismatchError, OutputError, DatabaseError
        As in :func:`build_databases`.
    """
    shape = check_options(shape, HandShape, name="shape")
    options = _options_from(option_fields, "build_database")  # names this function, not the next
    summary = build_databases(out_dir, [shape], mount, options=options, workers=workers,
                              executor=executor, force=force, progress=progress)
    for reason in summary.rebuilt.values():
        warnings.warn(f"built again, replacing an existing file: {reason}", stacklevel=2)
    return summary.paths[0]


def build_default_database(out_dir, *, workers: int | None = None,
                           progress: Callable[[BuildProgress], None] | None = None,
                           side: str = "right") -> Path:
    """Build the small embedded default database (:data:`DEFAULT_DATABASE`).

    The standard hand shape, 3000 paper poses, seed 0, the paper's device,
    right hand (or `side`): a few seconds on a laptop.  Reused when it already
    exists and verifies.

    Parameters
    ----------
    out_dir : str or os.PathLike
    workers : int, keyword-only, optional
        All cores by default.
    progress : callable, keyword-only, optional
    side : {"right", "left"}, keyword-only

    Returns
    -------
    pathlib.Path
    """
    d = DEFAULT_DATABASE
    workers = usable_cores() if workers is None else workers
    return build_database(out_dir, d["shape"], CameraMount.paper(), workers=workers,
                          progress=progress, pose_set=d["pose_set"],
                          count=d["count"], seed=d["seed"], side=side)
