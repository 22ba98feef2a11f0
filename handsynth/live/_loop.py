"""The live loop: read, look up, write a row, keep count (:func:`run_live`)."""

from __future__ import annotations

import os
import time
from array import array
from dataclasses import dataclass
from pathlib import Path
from typing import TypeGuard

import numpy as np
from threadpoolctl import threadpool_limits

from .._checks import check_integer, check_number, check_path, check_side, short_repr
from ..errors import EstimationError, InvalidInputError
from ..models import JOINT_NAMES
from ..render import CameraMount, as_mount
from ._sources import FrameSource, SyntheticSource
from ._video import SideBySideWriter
from ._writers import TRUTH_COLUMNS, _make_row, live_columns, open_row_writer

__all__ = ["LiveOptions", "LiveSummary", "default_database_dir", "first_hand_frame", "run_live"]

_STOP_REASONS = ("frames", "seconds", "ended", "dead", "interrupted")



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
        check_integer(self.max_frames, "max_frames", minimum=0, allow_none=True)
        check_number(self.max_seconds, "max_seconds", above=0, allow_none=True)
        check_integer(self.max_dead_reads, "max_dead_reads", minimum=1)
        check_number(self.retry_delay_s, "retry_delay_s", minimum=0)
        if not isinstance(self.keypoints, bool):
            raise InvalidInputError(f"keypoints must be True or False, got {self.keypoints!r}")
        check_number(self.progress_interval_s, "progress_interval_s", above=0)


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
    first_refusal : str or None
        Why the estimator refused the first frame it refused.
    no_hand, low_confidence : int
        Looked-up frames with no hand / with a fallback answer.
    moved : int
        Looked-up frames read after the device seemed to have moved on the
        wrist since the estimator's rest frame (:attr:`PoseEstimate.moved`):
        take the rest frame again.
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
    constant_mae_deg : float or None
        The same of the constant answer, the open hand (every angle 0), on the
        same frames: the trivial baseline beside `mae_deg`.
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
    constant_mae_deg: float | None = None
    moved: int = 0
    first_refusal: str | None = None

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
             f"{self.invalid}); no hand {self.no_hand}, low confidence {self.low_confidence}")]
        if self.frames < 2:
            lines.append("no rates: fewer than two frames were looked up")
        else:
            lines += [
                (f"estimate {self.fps_lookup:.1f} fps alone (median {self.lookup_ms_median:.2f} "
                 f"ms, p99 {self.lookup_ms_p99:.2f} ms); whole loop {self.fps_loop:.1f} fps "
                 f"({self.wall_s:.2f} s; first frame {self.first_lookup_ms:.1f} ms, not "
                 "counted)"),
                (f"per frame after the first: reading the source "
                 f"{self._per_frame_ms(self.read_s):.2f} ms, estimate "
                 f"{self._per_frame_ms(self.lookup_s):.2f} ms, whole loop "
                 f"{self._per_frame_ms(self.steady_wall_s):.2f} ms"),
            ]
        if self.moved:
            lines.append(f"device moved: {self.moved} frames were read after the device seemed to "
                         "have moved on the wrist since the rest frame; take it again")
        j = self.mae_per_joint_deg
        if self.mae_deg is not None and j is not None:
            lines.append(
                f"mean absolute error vs truth {self.mae_deg:.2f} deg over {self.truth_frames} "
                f"frames (index PIP {j[JOINT_NAMES.index('index_pip_flex')]:.2f}, thumb CMC "
                f"flex {j[JOINT_NAMES.index('thumb_cmc_flex')]:.2f})"
                + ("" if self.constant_mae_deg is None else
                   f"; the open hand answered on every frame: {self.constant_mae_deg:.2f} deg"))
        if self.first_refusal is not None:
            lines.append(f"first frame refused: {self.first_refusal}")
        lines.append(f"stopped: {self.message}")
        return "\n".join(lines)


class _Tally:
    def __init__(self) -> None:
        self.reads = self.frames = self.dropped = self.invalid = 0
        self.no_hand = self.low_confidence = self.truth_frames = self.moved = 0
        self.latencies = array("d")
        self.abs_err = np.zeros(len(JOINT_NAMES))
        self.abs_truth = np.zeros(len(JOINT_NAMES))  # the open hand's error
        self.first_done_s: float | None = None  # loop time when the first frame was done
        self.read_s = 0.0  # time in read() after the first frame
        self.first_refusal: str | None = None

    def summary(self, wall_s: float, stop_reason: str, message: str) -> LiveSummary:
        lat = np.frombuffer(self.latencies, dtype=np.float64)
        first_ms = float(lat[0]) * 1e3 if lat.size else float("nan")
        lat = lat[1:]
        med, p99 = ((float(np.median(lat)) * 1e3, float(np.percentile(lat, 99)) * 1e3)
                    if lat.size else (float("nan"), float("nan")))
        steady = wall_s - self.first_done_s if self.first_done_s is not None else 0.0
        per_joint = mae = constant = None
        if self.truth_frames:
            pj = self.abs_err / self.truth_frames
            per_joint, mae = tuple(float(v) for v in pj), float(pj.mean())
            constant = float(self.abs_truth.mean() / self.truth_frames)
        return LiveSummary(
            reads=self.reads, frames=self.frames, dropped=self.dropped, invalid=self.invalid,
            no_hand=self.no_hand, low_confidence=self.low_confidence,
            lookup_s=float(lat.sum()), wall_s=wall_s, steady_wall_s=steady, read_s=self.read_s,
            first_lookup_ms=first_ms, lookup_ms_median=med, lookup_ms_p99=p99, stop_reason=stop_reason,
            message=message, truth_frames=self.truth_frames, mae_deg=mae,
            mae_per_joint_deg=per_joint, constant_mae_deg=constant, moved=self.moved,
            first_refusal=self.first_refusal)


def _usable(frame: np.ndarray | None) -> TypeGuard[np.ndarray]:
    return frame is not None and not (isinstance(frame, np.ndarray) and frame.size == 0)


def first_hand_frame(source: FrameSource, *, mount: CameraMount | None = None,
                     side: str = "right", max_reads: int = 100,
                     retry_delay_s: float = 0.01, accept=None) -> np.ndarray:
    """The first frame of `source` that shows a hand: the open-hand frame of a calibration.

    The user holds the hand open and flat in front of the device before the
    run (:meth:`PoseLookup.from_open_frame
    <handsynth.estimate.PoseLookup.from_open_frame>`).  Frames are read
    until one shows a hand: its silhouette (:func:`handsynth.render.preprocess`
    with `mount` and `side`) is not empty and its hand component (the
    largest after the wrist cut) covers at least
    :data:`~handsynth.estimate.MIN_HAND_COVERAGE` (1 %) of the frame's
    pixels, as the lookup and the learnt estimators require.  Empty,
    dropped or unreadable frames are skipped, and so are frames where what
    stands out covers less (a speck, one bright pixel) and uint8 frames of
    almost one grey level (fewer than :data:`~handsynth.render.MIN_CONTRAST`
    levels: a flat grey or white view, whose silhouette is empty).  The
    frames read are consumed.

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
    accept : callable, keyword-only, optional
        ``accept(frame) -> bool``, asked of each frame that shows a hand: a
        frame it refuses is skipped too (e.g. a learnt estimator calibrated
        to the frame finds the frame itself unlike any hand it learnt: half
        the view white, noise, a hand coming into the view).

    Raises
    ------
    InvalidInputError
        `mount`, `side`, `source`, `max_reads`, `retry_delay_s` or `accept`
        is unusable (checked before the first read; only a frame that is not
        an image is skipped).
    EstimationError
        No frame of the first `max_reads` shows a hand (that `accept`
        takes), or the source ended; the message counts the frames `accept`
        refused.
    """
    from ..estimate import MIN_HAND_COVERAGE
    from ..render import preprocess

    mount = as_mount(mount)
    check_side(side)
    if not callable(getattr(source, "read", None)):
        raise InvalidInputError(f"source must have a read() method, got {type(source).__name__}")
    max_reads = check_integer(max_reads, "max_reads", minimum=1)
    delay = check_number(retry_delay_s, "retry_delay_s", minimum=0)
    if accept is not None and not callable(accept):
        raise InvalidInputError(f"accept must be a function of a frame, got "
                                f"{type(accept).__name__}")
    refused = 0
    for _ in range(max_reads):
        frame = source.read()
        if not _usable(frame):
            if getattr(source, "ended", False):
                raise EstimationError("the source ended before a frame showed a hand to "
                                      f"calibrate with{_refused_note(refused)}")
            time.sleep(delay)
            continue
        try:
            if not preprocess(frame, mount, side=side, min_coverage=MIN_HAND_COVERAGE).any():
                continue
        except InvalidInputError:  # this frame is not an image: the arguments were checked above
            continue
        if accept is None or accept(frame):
            return frame
        refused += 1
    raise EstimationError(f"no frame showed a hand to calibrate with in {max_reads} "
                          f"reads{_refused_note(refused)}")


def _refused_note(refused: int) -> str:
    return (f" ({refused} frames where something stood out read as no hand at rest: half "
            "the view bright, noise, a hand only partly in view)" if refused else "")


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
    sink : row writer, str or os.PathLike, keyword-only, optional
        Any object with ``write(row: dict)``, e.g. from
        :func:`open_row_writer` with ``columns=live_columns(keypoints=...,
        truth=...)``: not closed here.  The rows carry the true angles when
        the source has ``truth_deg`` and the sink's ``columns`` (if it has
        that attribute) include them.  A file name (``.csv``, ``.jsonl`` or
        ``.ndjson``) is opened here with :func:`open_row_writer` (as the
        command line does: the columns of ``options.keypoints``, the true
        angles for a :class:`SyntheticSource` or a source that has
        ``truth_deg``) before any frame is read, and closed here.
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
        Bad `options`, `source` or `video_out` (a `video_out` that is
        neither a writer nor a file name named); a `sink` that is neither a
        row writer (no ``write`` method) nor a file name, or a file name
        whose suffix does not tell the row format (checked before any read).
    OutputError
        A `sink` file name that cannot be written (a missing or read-only
        folder, a folder, the source video or the database file), before
        any read.
    EstimationError
        Before any read, when the estimator cannot read any frame as it is:
        its ``check_ready()`` method, if it has one, refuses (e.g. a
        :class:`~handsynth.estimate.LearnedEstimator` that reads the rest
        frame and was not calibrated).

    Notes
    -----
    A uint8 frame of almost one grey level (fewer than
    :data:`~handsynth.render.MIN_CONTRAST` levels: a flat grey, white or
    covered view) is a no-hand row where the estimator tells the hand by
    brightness: Otsu's threshold finds no hand in it.
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
    if sink is not None and not callable(getattr(sink, "write", None)) \
            and not isinstance(sink, (str, os.PathLike)):
        raise InvalidInputError(
            f"sink must be a row writer (an object with write(row)) or a row file name (.csv, "
            f".jsonl or .ndjson), got {type(sink).__name__} {short_repr(sink)}")
    ready = getattr(lookup, "check_ready", None)
    if callable(ready):
        ready()  # an estimator that cannot read any frame: its reason, before a read
    own_sink = None  # opened here, so closed here
    if isinstance(sink, (str, os.PathLike)):
        sink = own_sink = _open_sink(sink, lookup, source, keypoints=opts.keypoints)
    try:
        return _run(lookup, source, sink, video_out, opts, progress)
    finally:
        if own_sink is not None:
            own_sink.close()


def _open_sink(sink, lookup, source, *, keypoints: bool):
    """The row writer of the file name `sink`, with the columns the command line gives."""
    check_path(sink, "sink", kind="file")
    inputs = [p for p in (getattr(source, "path", None),
                          getattr(getattr(lookup, "database", None), "path", None))
              if isinstance(p, (str, os.PathLike))]
    truth = isinstance(source, SyntheticSource) or getattr(source, "truth_deg", None) is not None
    return open_row_writer(sink, columns=live_columns(keypoints=keypoints, truth=truth),
                           inputs=inputs)


def _run(lookup, source: FrameSource, sink, video_out, opts: LiveOptions,
         progress) -> LiveSummary:
    """The loop of :func:`run_live`, its arguments checked."""
    video: SideBySideWriter | None = None
    own_video: SideBySideWriter | None = None  # opened here, so closed here
    if isinstance(video_out, SideBySideWriter):
        video = video_out
    elif video_out is not None:
        check_path(video_out, "video_out", kind="file")
        video = own_video = SideBySideWriter(video_out, lookup,
                                             fps=getattr(source, "fps", None) or 30.0)

    sink_columns = getattr(sink, "columns", None)
    truth_in_rows = sink_columns is None or TRUTH_COLUMNS[0] in sink_columns
    tally = _Tally()
    clock = time.perf_counter
    t0 = clock()
    next_progress = t0 + opts.progress_interval_s
    dead = 0
    stop, message = "ended", "the source has no more frames"
    # Small matrices, one frame at a time: a second BLAS thread only waits on the first,
    # and with the other core busy it made a learnt estimator's frame 13 times slower
    # (19.5 ms against 1.5 ms for the perceptrons, load average 2).
    with threadpool_limits(limits=1, user_api="blas"):
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
                    except (InvalidInputError, EstimationError) as exc:
                        est = None
                        tally.invalid += 1
                        if tally.first_refusal is None:
                            tally.first_refusal = str(exc)
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
                # dead is 0 only when this read was usable and its estimate succeeded
                assert frame is not None
                tally.frames += 1
                tally.no_hand += bool(est.no_hand)
                tally.low_confidence += bool(est.low_confidence and not est.no_hand)
                tally.moved += bool(getattr(est, "moved", False))
                truth = getattr(source, "truth_deg", None)
                if truth is not None and not est.no_hand:
                    tally.abs_err += np.abs(np.asarray(est.angles, np.float64) - truth)
                    tally.abs_truth += np.abs(truth)
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
            if own_video is not None:
                own_video.close()
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
