"""The live pose-lookup loop: frames in, one row of joint angles per frame out.

A frame source (:class:`FrameSource`: a camera, a video file or a rendered
moving hand) feeds :func:`run_live`, which looks every frame up with a
:class:`~handsynth.estimate.PoseEstimator` (normally a
:class:`~handsynth.estimate.PoseLookup`), writes one row per frame to a row
sink (:class:`CsvRowWriter`, :class:`JsonlRowWriter`), optionally writes a
side-by-side video (:class:`SideBySideWriter`: the input frame and the
matched database entry's render) and returns a :class:`LiveSummary`
(frames, drops, rates, and the error against the true angles when the
source knows them).

What a live loop must survive
-----------------------------
Cameras drop frames: ``read()`` gives ``None`` or an empty array, or a
frame the estimator refuses (wrong dtype or shape, NaN).  Each such read is
counted (``dropped`` or ``invalid``) and the loop goes on after
``retry_delay_s``; only :attr:`LiveOptions.max_dead_reads` *consecutive*
unusable reads end the run (``stop_reason="dead"``).  Ctrl-C ends the run
cleanly (``stop_reason="interrupted"``): the rows written so far are
complete and the summary is returned.

Rows
----
Columns, in this order (:func:`live_columns`): ``frame`` (index of the
read, counting drops, so gaps show dropped reads), ``timestamp_s`` (the
source's media time, or seconds since the loop started), ``no_hand``,
``confidence``, ``low_confidence``, ``entry``, the 20 angles in degrees
under their :data:`~handsynth.JOINT_NAMES`; optionally the 21 keypoints in
metres (``<site>_x_m``, ``<site>_y_m``, ``<site>_z_m``, sites of
:data:`~handsynth.models.KEYPOINT_SITES`) and, for sources that know them,
the true angles (``true_<joint>``).  Angles and keypoints of a no-hand
frame are missing (empty CSV cell, JSON ``null``).  Each row is written with
one ``write`` call of a complete line and flushed (every row by default),
so a run that is killed leaves only complete lines.
"""

from __future__ import annotations

import csv
import io
import json
import math
import os
import sys
import time
from array import array
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Protocol, runtime_checkable

import numpy as np

from ..errors import EstimationError, InvalidInputError, RecordingError
from ..models import JOINT_LIMITS_DEG, JOINT_NAMES, KEYPOINT_SITES, HandShape, as_angles
from ..models import pose_set as make_pose_set
from ..render import CameraMount

__all__ = [
    "CameraSource",
    "CsvRowWriter",
    "FrameSource",
    "JsonlRowWriter",
    "LiveOptions",
    "LiveSummary",
    "SideBySideWriter",
    "SyntheticMotion",
    "SyntheticSource",
    "VideoSource",
    "default_database_dir",
    "first_hand_frame",
    "live_columns",
    "open_row_writer",
    "run_live",
]

#: Fixed leading columns of every row.
BASE_COLUMNS: tuple[str, ...] = ("frame", "timestamp_s", "no_hand", "confidence",
                                 "low_confidence", "entry")
#: Keypoint columns, metres, hand frame.
KEYPOINT_COLUMNS: tuple[str, ...] = tuple(f"{s}_{a}_m" for s in KEYPOINT_SITES for a in "xyz")
#: True-angle columns (sources that know the truth), degrees.
TRUTH_COLUMNS: tuple[str, ...] = tuple(f"true_{n}" for n in JOINT_NAMES)

#: Named poses a ``SyntheticMotion(poses="named")`` cycles through.
NAMED_CYCLE: tuple[str, ...] = ("open", "spread", "pinch", "grasp", "fist", "point")

_STOP_REASONS = ("frames", "seconds", "ended", "dead", "interrupted")


def _check_int(value, name: str, *, minimum: int, allow_none: bool = False):
    if value is None and allow_none:
        return None
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < minimum:
        raise InvalidInputError(f"{name} must be an integer >= {minimum}, got {value!r}")
    return int(value)


def _check_float(value, name: str, *, positive: bool = True, allow_none: bool = False):
    if value is None and allow_none:
        return None
    ok = (not isinstance(value, bool) and isinstance(value, (int, float, np.integer, np.floating))
          and math.isfinite(value) and (value > 0 if positive else value >= 0))
    if not ok:
        raise InvalidInputError(
            f"{name} must be a finite number {'> 0' if positive else '>= 0'}, got {value!r}")
    return float(value)


@contextmanager
def _quiet_opencv():
    """Silence OpenCV's own warnings (printed from C++ to stderr) for a moment."""
    import cv2

    log = getattr(getattr(cv2, "utils", None), "logging", None)
    if log is None:  # pragma: no cover - very old OpenCV
        yield
        return
    previous = log.getLogLevel()
    log.setLogLevel(log.LOG_LEVEL_ERROR)
    try:
        yield
    finally:
        log.setLogLevel(previous)


# --------------------------------------------------------------------------- sources


@runtime_checkable
class FrameSource(Protocol):
    """Where live frames come from.

    ``read()`` returns the next frame, an ndarray of shape (H, W, 3) uint8
    (BGR), (H, W) uint8 or (H, W) bool, or ``None`` when no frame came this
    time (a dropped frame: the loop counts it and reads again).
    ``close()`` releases the device or file.

    Optional attributes :func:`run_live` reads when a source has them:

    ``ended`` : bool
        The source has no more frames (end of a file); a ``None`` from
        ``read()`` then ends the run instead of counting as a drop.
    ``timestamp_s`` : float or None
        Media time of the last frame, seconds (wall clock if absent).
    ``truth_deg`` : ndarray, shape (20,), or None
        True joint angles of the last frame, degrees (synthetic sources).
    ``fps`` : float or None
        Nominal frame rate (used for the output video).
    """

    def read(self) -> np.ndarray | None:
        """The next frame, or ``None`` for a dropped frame."""
        ...

    def close(self) -> None:
        """Release the source."""
        ...


class _Source:
    ended: bool = False
    timestamp_s: float | None = None
    truth_deg: np.ndarray | None = None
    fps: float | None = None

    def __enter__(self):
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def close(self) -> None:  # pragma: no cover - overridden
        pass


def _capture_fps(cap) -> float | None:
    import cv2

    fps = float(cap.get(cv2.CAP_PROP_FPS) or 0.0)
    return fps if math.isfinite(fps) and 0 < fps < 10_000 else None


class CameraSource(_Source):
    """Frames of a camera through OpenCV (``cv2.VideoCapture(index)``).

    Parameters
    ----------
    index : int
        Camera index (0 for the first camera).
    width_px, height_px : int, keyword-only, optional
        Frame size to ask the camera for (the camera's default otherwise;
        the camera may give another size).

    Raises
    ------
    InvalidInputError
        `index` is not a non-negative integer, or no camera with that index
        can be opened (the message names the index).

    Notes
    -----
    A failed ``read`` (the driver gave no frame) returns ``None``: a drop.
    A camera never ends by itself; :func:`run_live` stops on its limits,
    on Ctrl-C or after too many consecutive drops.
    """

    def __init__(self, index: int, *, width_px: int | None = None,
                 height_px: int | None = None) -> None:
        import cv2

        self.index = _check_int(index, "camera index", minimum=0)
        width_px = _check_int(width_px, "width_px", minimum=8, allow_none=True)
        height_px = _check_int(height_px, "height_px", minimum=8, allow_none=True)
        with _quiet_opencv():
            cap = cv2.VideoCapture(self.index)
            opened = cap.isOpened()
        if not opened:
            cap.release()
            raise InvalidInputError(
                f"camera {self.index} could not be opened (no camera with that index, or it is "
                "in use); on a machine without a camera use --video FILE or --synthetic")
        if width_px:
            cap.set(cv2.CAP_PROP_FRAME_WIDTH, width_px)
        if height_px:
            cap.set(cv2.CAP_PROP_FRAME_HEIGHT, height_px)
        self._cap = cap
        self.fps = _capture_fps(cap)

    def read(self) -> np.ndarray | None:
        if self._cap is None:
            return None
        import cv2

        try:
            with _quiet_opencv():
                ok, frame = self._cap.read()
        except cv2.error:
            return None
        if not ok or frame is None or frame.size == 0:
            return None
        return frame

    def close(self) -> None:
        cap, self._cap = getattr(self, "_cap", None), None
        if cap is not None:
            cap.release()


class VideoSource(_Source):
    """Frames of a video file (anything OpenCV's FFmpeg backend decodes).

    Parameters
    ----------
    path : str or os.PathLike

    Raises
    ------
    InvalidInputError
        The file does not exist or OpenCV cannot decode it (the message
        names the file).

    Notes
    -----
    The end of the file sets :attr:`ended`.  :attr:`timestamp_s` is the
    frame's index divided by the file's frame rate (OpenCV's position in
    milliseconds when the file has no rate).
    """

    def __init__(self, path) -> None:
        import cv2

        self.path = Path(path)
        if not self.path.is_file():
            raise InvalidInputError(f"video file {str(self.path)!r} does not exist")
        with _quiet_opencv():
            cap = cv2.VideoCapture(str(self.path))
            opened = cap.isOpened()
        if not opened:
            cap.release()
            raise InvalidInputError(
                f"cannot open video file {str(self.path)!r}: OpenCV cannot decode it")
        self._cap = cap
        self.fps = _capture_fps(cap)
        self._count = 0

    def read(self) -> np.ndarray | None:
        if self._cap is None:
            self.ended = True
            return None
        import cv2

        try:
            with _quiet_opencv():
                ok, frame = self._cap.read()
        except cv2.error:
            ok, frame = False, None
        if not ok or frame is None:
            self.ended = True
            return None
        self.timestamp_s = (self._count / self.fps if self.fps
                            else float(self._cap.get(cv2.CAP_PROP_POS_MSEC)) / 1e3)
        self._count += 1
        return frame if frame.size else None

    def close(self) -> None:
        cap, self._cap = getattr(self, "_cap", None), None
        if cap is not None:
            cap.release()


@dataclass(frozen=True)
class SyntheticMotion:
    """How the rendered hand of :class:`SyntheticSource` moves.

    The hand passes through a loop of key poses, easing from one to the
    next with ``w = (1 - cos(pi s)) / 2`` (``s`` in [0, 1) the fraction of
    the way), so the angles are continuous with continuous velocity and
    every frame is a convex combination of two valid poses (inside the joint
    limits).

    Parameters
    ----------
    poses : {"paper", "natural", "named"}
        Key poses: `count` poses of the paper or natural pose set
        (:func:`handsynth.models.pose_set`, seed `seed`), or the named
        poses in the order of :data:`NAMED_CYCLE`.  ``"paper"`` by default,
        the pose set of the default databases: multi-finger motions
        (``"natural"``, ``"named"``) are poorly covered by a paper-set
        database (measured on the 3,000-entry default: 27.6 deg mean
        absolute error for ``"natural"``, 2.2-2.7 deg for ``"paper"``).
    seconds_per_pose : float
        Media time from one key pose to the next, seconds.
    count : int
        Number of key poses for ``"natural"`` and ``"paper"``.
    seed : int
        Seed of the key poses.

    Raises
    ------
    InvalidInputError
        A value of the wrong type or range (the message names the field).
    """

    poses: str = "paper"
    seconds_per_pose: float = 1.0
    count: int = 16
    seed: int = 0

    def __post_init__(self) -> None:
        if self.poses not in ("natural", "paper", "named"):
            raise InvalidInputError(
                f"poses must be 'natural', 'paper' or 'named', got {self.poses!r}")
        _check_float(self.seconds_per_pose, "seconds_per_pose")
        _check_int(self.count, "count", minimum=2)
        _check_int(self.seed, "seed", minimum=0)

    def keyframes(self) -> np.ndarray:
        """Key poses, shape (K, 20), degrees, canonical order."""
        if self.poses == "named":
            from ..models import named_pose

            return np.stack([named_pose(n) for n in NAMED_CYCLE])
        return make_pose_set(self.poses, self.count, seed=self.seed)


def interpolate_keyframes(keyframes: np.ndarray, t_s: float, seconds_per_pose: float) -> np.ndarray:
    """Joint angles at media time `t_s` of a looping cosine-eased key-pose motion.

    Parameters
    ----------
    keyframes : ndarray, shape (K, 20)
        Key poses, degrees.
    t_s : float
        Media time, seconds (>= 0).
    seconds_per_pose : float
        Time between consecutive key poses, seconds.

    Returns
    -------
    ndarray, shape (20,), float64
        ``(1 - w) P_i + w P_(i+1)`` with ``i = floor(t / T) mod K``,
        ``s = t / T - floor(t / T)``, ``w = (1 - cos(pi s)) / 2``; the pose
        after the last key pose is the first (a loop).
    """
    k = t_s / seconds_per_pose
    i = math.floor(k)
    s = k - i
    w = 0.5 * (1.0 - math.cos(math.pi * s))
    n = len(keyframes)
    return (1.0 - w) * keyframes[i % n] + w * keyframes[(i + 1) % n]


class SyntheticSource(_Source):
    """A rendered moving hand, as the device camera would see it.

    Frame ``i`` shows the pose of :func:`interpolate_keyframes` at media
    time ``i / fps``; :attr:`truth_deg` holds its angles after each
    :meth:`read`, so the loop can report the error against the truth.

    Parameters
    ----------
    shape : HandShape, optional
        The rendered hand (any ratios; off the grid to test a database of
        another shape).  The standard hand by default.
    mount : CameraMount, optional
        The camera (must be the database's; the paper's by default).
    motion : SyntheticMotion or array_like of shape (K, 20), keyword-only
        How the hand moves: a :class:`SyntheticMotion` or key poses in
        degrees (passed through at one second per pose).
    fps : float, keyword-only
        Frame rate of the media time (the loop itself runs as fast as it can).
    frames : int, keyword-only, optional
        Number of frames before the source ends (endless by default).
    side : {"right", "left"}, keyword-only
    width_px, height_px : int, keyword-only, optional
        Frame size; the mount's (720x480 for the paper's device) by default.

    Examples
    --------
    >>> src = SyntheticSource(HandShape(length=1.02), width_px=180, height_px=120)  # doctest: +SKIP
    >>> src.read().shape, src.truth_deg.shape                                       # doctest: +SKIP
    ((120, 180), (20,))
    """

    def __init__(self, shape: HandShape | None = None, mount: CameraMount | None = None, *,
                 motion: SyntheticMotion | np.ndarray | None = None, fps: float = 30.0,
                 frames: int | None = None, side: str = "right", width_px: int | None = None,
                 height_px: int | None = None) -> None:
        from ..render import SilhouetteRenderer

        if shape is not None and not isinstance(shape, HandShape):
            raise InvalidInputError(f"shape must be a HandShape, got {type(shape).__name__}")
        if mount is not None and not isinstance(mount, CameraMount):
            raise InvalidInputError(f"mount must be a CameraMount, got {type(mount).__name__}")
        self.fps = _check_float(fps, "fps")
        self.frames = _check_int(frames, "frames", minimum=0, allow_none=True)
        if motion is None or isinstance(motion, SyntheticMotion):
            self.motion = motion or SyntheticMotion()
            self._keys = self.motion.keyframes()
            self._period_s = self.motion.seconds_per_pose
        else:
            keys = as_angles(motion, argname="motion")
            if keys.ndim != 2 or len(keys) < 2:
                raise InvalidInputError(
                    f"motion key poses must have shape (K, 20) with K >= 2, got {keys.shape}")
            self.motion, self._keys, self._period_s = None, keys, 1.0
        self.shape = shape or HandShape()
        self._renderer = SilhouetteRenderer(self.shape, mount, side=side, width_px=width_px,
                                            height_px=height_px)
        self.mount = self._renderer.mount
        self._count = 0

    def pose_at(self, index: int) -> np.ndarray:
        """True joint angles of frame `index`, shape (20,), degrees."""
        return interpolate_keyframes(self._keys, index / self.fps, self._period_s)

    def read(self) -> np.ndarray | None:
        if self._renderer is None or (self.frames is not None and self._count >= self.frames):
            self.ended = True
            return None
        truth = np.clip(self.pose_at(self._count), JOINT_LIMITS_DEG[:, 0], JOINT_LIMITS_DEG[:, 1])
        frame = self._renderer.mask(truth)
        self.timestamp_s = self._count / self.fps
        self.truth_deg = truth
        self._count += 1
        return frame

    def open_frame(self) -> np.ndarray:
        """The hand open and flat (all angles 0), as a user holds it to calibrate.

        Not a frame of the motion: :meth:`read` is not advanced.
        """
        if self._renderer is None:
            raise InvalidInputError("the synthetic source is closed")
        return self._renderer.mask(np.zeros(len(JOINT_NAMES)))

    def close(self) -> None:
        r, self._renderer = getattr(self, "_renderer", None), None
        if r is not None:
            r.close()


# --------------------------------------------------------------------------- rows


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


# --------------------------------------------------------------------------- video out

_CODECS = {".mp4": "mp4v", ".m4v": "mp4v", ".mov": "mp4v", ".avi": "MJPG", ".mkv": "MJPG"}
_MATCH_BGR = (90, 220, 90)


def _to_bgr(frame: np.ndarray) -> np.ndarray:
    if frame.dtype == bool:
        grey = frame.view(np.uint8) * np.uint8(255)
        return np.repeat(grey[:, :, None], 3, axis=2)
    if frame.ndim == 2:
        return np.repeat(frame[:, :, None], 3, axis=2)
    return np.ascontiguousarray(frame)


class SideBySideWriter:
    """A video of the input frames (left) and the matched entries' renders (right).

    The right half is the database hand (the lookup's shape, mount and
    side) rendered in the matched entry's pose at the input frame's size,
    in green; black with "no hand" when the frame showed none.  Every
    output frame is ``2 W x H`` for input frames of ``W x H`` (the first
    frame's size; later frames of another size are resized).

    Parameters
    ----------
    path : str or os.PathLike
        ``.mp4``/``.m4v``/``.mov`` (codec ``mp4v``) or ``.avi``/``.mkv``
        (``MJPG``).
    lookup : PoseLookup
        The lookup whose entries are matched (its database, mount, side).
    fps : float, keyword-only
    codec : str, keyword-only, optional
        A four-character code overriding the suffix's codec.
    labels : bool, keyword-only
        Draw frame index, entry and confidence on the frames.

    Raises
    ------
    InvalidInputError
        Unknown suffix or codec, or OpenCV cannot open a writer for the file.
    """

    def __init__(self, path, lookup, *, fps: float = 30.0, codec: str | None = None,
                 labels: bool = True) -> None:
        self.path = Path(path)
        suffix = self.path.suffix.lower()
        if codec is None:
            if suffix not in _CODECS:
                raise InvalidInputError(
                    f"video output {str(self.path)!r} must end in one of "
                    f"{', '.join(sorted(_CODECS))}")
            codec = _CODECS[suffix]
        if not (isinstance(codec, str) and len(codec) == 4):
            raise InvalidInputError(f"codec must be a four-character code, got {codec!r}")
        for attr in ("database", "mount", "side"):
            if not hasattr(lookup, attr):
                raise InvalidInputError(
                    f"lookup must be a PoseLookup (renders of its entries), got "
                    f"{type(lookup).__name__}")
        self.lookup = lookup
        self.fps = _check_float(fps, "fps")
        self.codec = codec
        self.labels = bool(labels)
        self.frames = 0
        self._writer = None
        self._renderer = None
        self._size = None

    def _open(self, w: int, h: int) -> None:
        import cv2

        from ..render import SilhouetteRenderer

        with _quiet_opencv():
            writer = cv2.VideoWriter(str(self.path), cv2.VideoWriter_fourcc(*self.codec),
                                     self.fps, (2 * w, h))
            opened = writer.isOpened()
        if not opened:
            writer.release()
            raise InvalidInputError(f"OpenCV cannot write video {str(self.path)!r} with codec "
                                    f"{self.codec!r}")
        self._writer, self._size = writer, (w, h)
        self._renderer = SilhouetteRenderer(self.lookup.shape, self.lookup.mount,
                                            side=self.lookup.side, width_px=w, height_px=h)

    def write(self, frame: np.ndarray, estimate, *, index: int | None = None) -> None:
        """Append one side-by-side frame.

        Parameters
        ----------
        frame : ndarray, shape (H, W) or (H, W, 3), bool or uint8
            The input frame as the estimator got it.
        estimate : PoseEstimate
            Its result.
        index : int, keyword-only, optional
            Frame index for the label.
        """
        import cv2

        left = _to_bgr(frame)
        if self._writer is None:
            self._open(left.shape[1], left.shape[0])
        w, h = self._size
        if left.shape[:2] != (h, w):
            left = cv2.resize(left, (w, h), interpolation=cv2.INTER_NEAREST)
        right = np.zeros_like(left)
        if not estimate.no_hand:
            pose = np.clip(np.asarray(self.lookup.database.angles[estimate.entry], np.float64),
                           JOINT_LIMITS_DEG[:, 0], JOINT_LIMITS_DEG[:, 1])
            right[self._renderer.mask(pose)] = _MATCH_BGR
        if self.labels:
            scale, thick = max(0.35, h / 600), max(1, round(h / 300))
            y = max(12, round(22 * scale * 1.6))
            text = "" if index is None else f"#{index}"
            cv2.putText(left, f"input {text}", (6, y), cv2.FONT_HERSHEY_SIMPLEX, scale,
                        (0, 160, 255), thick, cv2.LINE_AA)
            label = ("no hand" if estimate.no_hand else
                     f"entry {estimate.entry} conf {estimate.confidence:.2f}"
                     + (" low" if estimate.low_confidence else ""))
            cv2.putText(right, label, (6, y), cv2.FONT_HERSHEY_SIMPLEX, scale, (0, 160, 255),
                        thick, cv2.LINE_AA)
        self._writer.write(np.hstack([left, right]))
        self.frames += 1

    def close(self) -> None:
        """Finish the file and release the renderer."""
        writer, self._writer = self._writer, None
        if writer is not None:
            writer.release()
        r, self._renderer = self._renderer, None
        if r is not None:
            r.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc) -> None:
        self.close()


# --------------------------------------------------------------------------- the loop


@dataclass(frozen=True)
class LiveOptions:
    """Limits and behaviour of :func:`run_live`.

    Parameters
    ----------
    max_frames : int, optional
        Stop after this many looked-up frames (rows).
    max_seconds : float, optional
        Stop after this much wall-clock time, seconds.
    max_dead_reads : int
        Stop when this many consecutive reads gave no usable frame (dropped
        or refused); a healthy camera that drops a few frames never hits it.
    retry_delay_s : float
        Pause after an unusable read before reading again, seconds (so that
        ``max_dead_reads * retry_delay_s`` is how long a dead camera is
        waited for).
    keypoints : bool
        Put the 21 keypoints in the rows.
    progress_interval_s : float
        Seconds between calls of the `progress` callback.

    Raises
    ------
    InvalidInputError
        A value of the wrong type or range (the message names the field).
    """

    max_frames: int | None = None
    max_seconds: float | None = None
    max_dead_reads: int = 100
    retry_delay_s: float = 0.01
    keypoints: bool = False
    progress_interval_s: float = 1.0

    def __post_init__(self) -> None:
        _check_int(self.max_frames, "max_frames", minimum=0, allow_none=True)
        _check_float(self.max_seconds, "max_seconds", allow_none=True)
        _check_int(self.max_dead_reads, "max_dead_reads", minimum=1)
        _check_float(self.retry_delay_s, "retry_delay_s", positive=False)
        if not isinstance(self.keypoints, bool):
            raise InvalidInputError(f"keypoints must be True or False, got {self.keypoints!r}")
        _check_float(self.progress_interval_s, "progress_interval_s")


@dataclass(frozen=True)
class LiveSummary:
    """What a run of :func:`run_live` did.

    Attributes
    ----------
    reads : int
        Calls of the source's ``read`` (including drops and the final one).
    frames : int
        Frames looked up (one row each).
    dropped : int
        Reads that gave no frame (``None`` or an empty array).
    invalid : int
        Frames the estimator refused (wrong dtype or shape, NaN...).
    no_hand, low_confidence : int
        Looked-up frames with no hand / with a fallback answer.
    lookup_s : float
        Time spent in ``estimate`` alone for all frames but the first, seconds.
    wall_s : float
        Wall-clock time of the whole loop, seconds (reading, rendering
        synthetic frames, lookup, writing).
    steady_wall_s : float
        The part of `wall_s` after the first frame was done, seconds.
    read_s : float
        Time spent in the source's ``read`` (waiting for the camera,
        decoding, rendering synthetic frames) after the first frame, seconds.
    first_lookup_ms : float
        Lookup time of the first frame, milliseconds (it pays one-off
        costs: loading compiled code, first-touch of the database), left out
        of the rates and percentiles; NaN without frames.
    lookup_ms_median, lookup_ms_p99 : float
        Per-frame lookup latency after the first frame, milliseconds (NaN
        with fewer than two frames).

    Notes
    -----
    Rates leave the first frame out: :attr:`fps_lookup` is
    ``(frames - 1) / lookup_s`` and :attr:`fps_loop` is
    ``(frames - 1) / steady_wall_s``.
    stop_reason : {"frames", "seconds", "ended", "dead", "interrupted"}
    message : str
        One line saying why the run stopped.
    truth_frames : int
        Frames with known true angles and a hand found (the MAE's frames).
    mae_deg : float or None
        Mean absolute error over joints and `truth_frames`, degrees.
    mae_per_joint_deg : tuple of 20 float, or None
        Mean absolute error per joint, canonical order, degrees.
    """

    reads: int
    frames: int
    dropped: int
    invalid: int
    no_hand: int
    low_confidence: int
    lookup_s: float
    wall_s: float
    steady_wall_s: float
    read_s: float
    first_lookup_ms: float
    lookup_ms_median: float
    lookup_ms_p99: float
    stop_reason: str
    message: str
    truth_frames: int = 0
    mae_deg: float | None = None
    mae_per_joint_deg: tuple[float, ...] | None = None

    @property
    def fps_lookup(self) -> float:
        """Frames per second of the lookup alone, first frame left out."""
        n = self.frames - 1
        return n / self.lookup_s if n > 0 and self.lookup_s > 0 else float("nan")

    @property
    def fps_loop(self) -> float:
        """Frames per second of the whole loop, first frame left out."""
        n = self.frames - 1
        return n / self.steady_wall_s if n > 0 and self.steady_wall_s > 0 else float("nan")

    def _per_frame_ms(self, seconds: float) -> float:
        return 1e3 * seconds / (self.frames - 1) if self.frames > 1 else float("nan")

    def format(self) -> str:
        """A few human-readable lines."""
        lines = [
            (f"frames {self.frames} (reads {self.reads}, dropped {self.dropped}, invalid "
             f"{self.invalid}); no hand {self.no_hand}, low confidence {self.low_confidence}"),
            (f"lookup {self.fps_lookup:.1f} fps alone (median {self.lookup_ms_median:.2f} ms, "
             f"p99 {self.lookup_ms_p99:.2f} ms); whole loop {self.fps_loop:.1f} fps "
             f"({self.wall_s:.2f} s; first frame {self.first_lookup_ms:.1f} ms, not counted)"),
            (f"per frame after the first: reading the source {self._per_frame_ms(self.read_s):.2f}"
             f" ms, lookup {self._per_frame_ms(self.lookup_s):.2f} ms, whole loop "
             f"{self._per_frame_ms(self.steady_wall_s):.2f} ms"),
        ]
        if self.mae_deg is not None:
            j = self.mae_per_joint_deg
            lines.append(
                f"mean absolute error vs truth {self.mae_deg:.2f} deg over {self.truth_frames} "
                f"frames (index PIP {j[JOINT_NAMES.index('index_pip_flex')]:.2f}, thumb CMC "
                f"flex {j[JOINT_NAMES.index('thumb_cmc_flex')]:.2f})")
        lines.append(f"stopped: {self.message}")
        return "\n".join(lines)


class _Tally:
    def __init__(self) -> None:
        self.reads = self.frames = self.dropped = self.invalid = 0
        self.no_hand = self.low_confidence = self.truth_frames = 0
        self.latencies = array("d")
        self.abs_err = np.zeros(len(JOINT_NAMES))
        self.first_done_s = None  # loop time when the first frame was done
        self.read_s = 0.0  # time in read() after the first frame

    def summary(self, wall_s: float, stop_reason: str, message: str) -> LiveSummary:
        lat = np.frombuffer(self.latencies, dtype=np.float64)
        first_ms = float(lat[0]) * 1e3 if lat.size else float("nan")
        lat = lat[1:]
        med, p99 = ((float(np.median(lat)) * 1e3, float(np.percentile(lat, 99)) * 1e3)
                    if lat.size else (float("nan"), float("nan")))
        steady = wall_s - self.first_done_s if self.first_done_s is not None else 0.0
        per_joint = mae = None
        if self.truth_frames:
            pj = self.abs_err / self.truth_frames
            per_joint, mae = tuple(float(v) for v in pj), float(pj.mean())
        return LiveSummary(
            reads=self.reads, frames=self.frames, dropped=self.dropped, invalid=self.invalid,
            no_hand=self.no_hand, low_confidence=self.low_confidence,
            lookup_s=float(lat.sum()), wall_s=wall_s, steady_wall_s=steady, read_s=self.read_s,
            first_lookup_ms=first_ms, lookup_ms_median=med, lookup_ms_p99=p99, stop_reason=stop_reason,
            message=message, truth_frames=self.truth_frames, mae_deg=mae,
            mae_per_joint_deg=per_joint)


def _usable(frame) -> bool:
    return frame is not None and not (isinstance(frame, np.ndarray) and frame.size == 0)


def first_hand_frame(source: FrameSource, *, mount: CameraMount | None = None,
                     side: str = "right", max_reads: int = 100,
                     retry_delay_s: float = 0.01) -> np.ndarray:
    """The first frame of `source` that shows a hand: the open-hand frame of a calibration.

    The user holds the hand open and flat in front of the device before the
    run (:meth:`PoseLookup.from_open_frame
    <handsynth.estimate.PoseLookup.from_open_frame>`).  Frames are read
    until one's silhouette (:func:`handsynth.render.preprocess` with `mount`
    and `side`) is not empty; empty, dropped or unreadable frames are
    skipped.  The frames read are consumed.

    Parameters
    ----------
    source : FrameSource
    mount : CameraMount, keyword-only, optional
        The device (the paper's by default).
    side : {"right", "left"}, keyword-only
    max_reads : int, keyword-only
        Reads before giving up.
    retry_delay_s : float, keyword-only
        Pause after a dropped read, seconds.

    Raises
    ------
    EstimationError
        No frame of the first `max_reads` shows a hand, or the source ended.
    """
    from ..render import preprocess

    mount = mount or CameraMount()
    max_reads = _check_int(max_reads, "max_reads", minimum=1)
    delay = _check_float(retry_delay_s, "retry_delay_s", positive=False)
    for _ in range(max_reads):
        frame = source.read()
        if not _usable(frame):
            if getattr(source, "ended", False):
                raise EstimationError("the source ended before a frame showed a hand to "
                                      "calibrate with")
            time.sleep(delay)
            continue
        try:
            if preprocess(frame, mount, side=side).any():
                return frame
        except InvalidInputError:
            continue
    raise EstimationError(f"no frame showed a hand to calibrate with in {max_reads} reads")


def run_live(lookup, source: FrameSource, *, sink=None, video_out=None,
             options: LiveOptions | None = None, progress=None) -> LiveSummary:
    """Look up every frame of `source` until a limit, the source's end, or Ctrl-C.

    Parameters
    ----------
    lookup : PoseEstimator
        Normally a :class:`~handsynth.estimate.PoseLookup` (required for
        `video_out`).  Its mount must be the one the frames were taken with.
    source : FrameSource
        A camera, video file, synthetic hand or any object with ``read()``
        and ``close()``.  Not closed here (the caller owns it).
    sink : row writer, keyword-only, optional
        Any object with ``write(row: dict)``, e.g. from
        :func:`open_row_writer` with ``columns=live_columns(keypoints=...,
        truth=...)``.  Not closed here.  The rows carry the true angles when
        the source has ``truth_deg`` and the sink's ``columns`` (if it has
        that attribute) include them.
    video_out : str, os.PathLike or SideBySideWriter, keyword-only, optional
        Side-by-side video of input and matched render; a path is opened
        (at the source's ``fps``, 30 if unknown) and closed here, a writer
        is used and left open.
    options : LiveOptions, keyword-only, optional
        Limits (none by default: runs until the source ends or dies).
    progress : callable, keyword-only, optional
        Called with a provisional :class:`LiveSummary` every
        ``options.progress_interval_s`` seconds.

    Returns
    -------
    LiveSummary
        Counts, rates (:attr:`LiveSummary.fps_lookup`,
        :attr:`LiveSummary.fps_loop`), why the run stopped, and the mean
        absolute error against the truth when the source knows it.

    Raises
    ------
    InvalidInputError
        Bad `options`, `source` or `video_out`.

    Notes
    -----
    Unusable reads never raise: ``None``/empty frames count as ``dropped``,
    frames the estimator refuses (:class:`~handsynth.errors.InvalidInputError`,
    :class:`~handsynth.errors.EstimationError`) as ``invalid``.  After
    ``options.max_dead_reads`` of them in a row the run stops with
    ``stop_reason="dead"``; it is for the caller to treat that as an error.
    """
    opts = options if options is not None else LiveOptions()
    if not isinstance(opts, LiveOptions):
        raise InvalidInputError(f"options must be LiveOptions, got {type(opts).__name__}")
    if not callable(getattr(source, "read", None)):
        raise InvalidInputError(f"source must have a read() method, got {type(source).__name__}")
    if not callable(getattr(lookup, "estimate", None)):
        raise InvalidInputError(
            f"lookup must have an estimate(frame) method, got {type(lookup).__name__}")
    video, own_video = None, False
    if isinstance(video_out, SideBySideWriter):
        video = video_out
    elif video_out is not None:
        video = SideBySideWriter(video_out, lookup, fps=getattr(source, "fps", None) or 30.0)
        own_video = True

    sink_columns = getattr(sink, "columns", None)
    truth_in_rows = sink_columns is None or TRUTH_COLUMNS[0] in sink_columns
    tally = _Tally()
    clock = time.perf_counter
    t0 = clock()
    next_progress = t0 + opts.progress_interval_s
    dead = 0
    stop, message = "ended", "the source has no more frames"
    try:
        while True:
            if opts.max_frames is not None and tally.frames >= opts.max_frames:
                stop, message = "frames", f"reached {opts.max_frames} frames"
                break
            if opts.max_seconds is not None and clock() - t0 >= opts.max_seconds:
                stop, message = "seconds", f"reached {opts.max_seconds:g} s"
                break
            t = clock()
            frame = source.read()
            if tally.frames:
                tally.read_s += clock() - t
            index = tally.reads
            tally.reads += 1
            if not _usable(frame):
                if getattr(source, "ended", False):
                    break
                tally.dropped += 1
                dead += 1
            else:
                t = clock()
                try:
                    est = lookup.estimate(frame)
                except (InvalidInputError, EstimationError):
                    est = None
                    tally.invalid += 1
                    dead += 1
                else:
                    tally.latencies.append(clock() - t)
                    dead = 0
            if dead:
                if dead >= opts.max_dead_reads:
                    stop = "dead"
                    message = (f"no usable frame in {dead} consecutive reads "
                               f"({tally.dropped} dropped, {tally.invalid} refused in all); "
                               "the source looks dead")
                    break
                if opts.retry_delay_s:
                    time.sleep(opts.retry_delay_s)
                continue
            tally.frames += 1
            tally.no_hand += bool(est.no_hand)
            tally.low_confidence += bool(est.low_confidence and not est.no_hand)
            truth = getattr(source, "truth_deg", None)
            if truth is not None and not est.no_hand:
                tally.abs_err += np.abs(np.asarray(est.angles, np.float64) - truth)
                tally.truth_frames += 1
            if sink is not None:
                ts = getattr(source, "timestamp_s", None)
                sink.write(_make_row(index, clock() - t0 if ts is None else ts, est,
                                     keypoints=opts.keypoints,
                                     truth=truth if truth_in_rows else None))
            if video is not None:
                video.write(frame, est, index=index)
            if tally.frames == 1:
                tally.first_done_s = clock() - t0
            if progress is not None and clock() >= next_progress:
                next_progress = clock() + opts.progress_interval_s
                progress(tally.summary(clock() - t0, "running", "running"))
    except KeyboardInterrupt:
        stop, message = "interrupted", "interrupted (Ctrl-C)"
    finally:
        if own_video:
            video.close()
    return tally.summary(clock() - t0, stop, message)


def default_database_dir() -> Path:
    """Folder of the cached embedded default database.

    ``$HANDSYNTH_CACHE_DIR/db`` if set, else ``$XDG_CACHE_HOME/handsynth/db``,
    else ``~/.cache/handsynth/db``.
    """
    root = os.environ.get("HANDSYNTH_CACHE_DIR")
    if root:
        return Path(root) / "db"
    xdg = os.environ.get("XDG_CACHE_HOME")
    base = Path(xdg) if xdg else Path.home() / ".cache"
    return base / "handsynth" / "db"
