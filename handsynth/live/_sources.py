"""Frame sources of the live loop: a camera, a video file, a rendered moving hand."""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass
from typing import TYPE_CHECKING, Protocol, runtime_checkable

import numpy as np

from .._checks import check_instance, check_integer, check_number, check_path
from ..errors import InvalidInputError
from ..models import JOINT_LIMITS_DEG, JOINT_NAMES, HandShape, as_angles
from ..models import pose_set as make_pose_set
from ..render import CameraMount, as_mount
from ._checks import _quiet_opencv

if TYPE_CHECKING:
    import cv2

    from ..render import SilhouetteRenderer

__all__ = ["CameraSource", "CorrectedSource", "FrameSource", "SyntheticMotion", "SyntheticSource",
           "VideoSource"]

#: Named poses a ``SyntheticMotion(poses="named")`` cycles through.
NAMED_CYCLE: tuple[str, ...] = ("open", "spread", "pinch", "grasp", "fist", "point")



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

    _cap: cv2.VideoCapture | None

    def __init__(self, index: int, *, width_px: int | None = None,
                 height_px: int | None = None) -> None:
        import cv2

        self.index = check_integer(index, "camera index", minimum=0)
        width_px = check_integer(width_px, "width_px", minimum=8, allow_none=True)
        height_px = check_integer(height_px, "height_px", minimum=8, allow_none=True)
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


#: Damaged frames in a row :class:`VideoSource` looks past before it takes a failed read
#: for the end of the file.
MAX_BROKEN_FRAMES = 12

#: Codecs of what FFmpeg opens as a "video" that is not one: ``ansi``, the pictures of a
#: text file's characters (FFmpeg's tty demuxer takes any ``.txt`` of a few hundred bytes).
_NOT_VIDEO_CODECS = ("ansi",)


def _not_a_video(cap) -> str:
    """Why the opened capture `cap` is not a video (``" (...)"``), or ``""`` when it is one.

    OpenCV opens some files that hold no video: a damaged image (no frame size,
    and no frame is ever read) or a text file (FFmpeg draws its characters).
    A real video, even one without frames, has its frame size in its header.
    """
    import cv2

    fourcc = int(cap.get(cv2.CAP_PROP_FOURCC) or 0) & 0xFFFFFFFF
    codec = fourcc.to_bytes(4, "little").decode("latin-1").rstrip("\0 ").lower()
    if codec in _NOT_VIDEO_CODECS:
        return " (it is text, not a video)"
    width = cap.get(cv2.CAP_PROP_FRAME_WIDTH)
    height = cap.get(cv2.CAP_PROP_FRAME_HEIGHT)
    if not (width > 0 and height > 0):
        return " (it has no frame size: not a video, or a damaged one)"
    return ""


class VideoSource(_Source):
    """Frames of a video file (anything OpenCV's FFmpeg backend decodes).

    Parameters
    ----------
    path : str or os.PathLike

    Raises
    ------
    InvalidInputError
        `path` is not a file name (None, a number, ``""``); the file does not
        exist, is a folder, device or pipe, or OpenCV cannot decode it: it
        does not open, or it is not a video (no frame size; a text file,
        which FFmpeg would draw as pictures of its characters) (the message
        names the file).

    Notes
    -----
    The end of the file sets :attr:`ended`.  :attr:`timestamp_s` is the
    frame's own media time (its presentation time in the file, so that a
    variable-frame-rate video, as phones record, gets its real times), or
    the frame's index divided by the file's frame rate where the file gives
    no increasing times.  A frame that cannot be decoded (a damaged frame
    in the middle of the file) is a dropped frame (``None``, not the end):
    the frames after it are read, up to :data:`MAX_BROKEN_FRAMES` damaged
    frames in a row.
    """

    _cap: cv2.VideoCapture | None

    def __init__(self, path) -> None:
        import cv2

        self.path = check_path(path, "path", kind="file")
        if self.path.is_dir():
            raise InvalidInputError(f"video file {str(self.path)!r} is a folder")
        if not self.path.exists():
            raise InvalidInputError(f"video file {str(self.path)!r} does not exist")
        if not self.path.is_file():  # was "does not exist" for /dev/null or a named pipe
            raise InvalidInputError(f"video file {str(self.path)!r} is not a regular file (a "
                                    "device, pipe or socket); give a video file")
        with _quiet_opencv():
            cap = cv2.VideoCapture(str(self.path))
            opened = cap.isOpened()
        why = _not_a_video(cap) if opened else ""
        if not opened or why:
            cap.release()
            raise InvalidInputError(
                f"cannot open video file {str(self.path)!r}: OpenCV cannot decode it{why}")
        self._cap = cap
        self.fps = _capture_fps(cap)
        self._count = 0  # frames of the file passed, damaged ones included
        #: Damaged frames skipped (each read as a dropped frame).
        self.broken = 0
        self._broken_left = 0
        self._next: np.ndarray | None = None
        self._times: list[float] = []  # media times of decoded frames not yet delivered
        self._media_time = True  # the file's own times are used while they increase

    def read(self) -> np.ndarray | None:
        if self._broken_left:  # damaged frames found while looking past them: drops
            self._broken_left -= 1
            return None
        if self._next is not None:  # the frame after them
            after, self._next = self._next, None
            return self._deliver(after)
        if self._cap is None:
            self.ended = True
            return None
        frame = self._decode()
        if frame is None:
            # a damaged frame and the end of the file read alike: look past it
            for broken in range(1, MAX_BROKEN_FRAMES + 1):
                later = self._decode()
                if later is not None:
                    self.broken += broken
                    self._count += broken  # the damaged frames' places in the file
                    self._broken_left, self._next = broken - 1, later
                    return None
            if not self.ended:
                import cv2

                self._check_complete(cv2)
            self.ended = True
            return None
        return self._deliver(frame)

    def _decode(self) -> np.ndarray | None:
        """The next decoded frame of the file, or None (a damaged frame or the end)."""
        import cv2

        assert self._cap is not None
        try:
            with _quiet_opencv():
                ok, frame = self._cap.read()
        except cv2.error:
            ok, frame = False, None
        if not ok or frame is None:
            return None
        ms = float(self._cap.get(cv2.CAP_PROP_POS_MSEC))
        self._times.append(ms / 1e3 if math.isfinite(ms) else math.nan)
        return frame

    def _deliver(self, frame: np.ndarray) -> np.ndarray | None:
        """`frame`, its :attr:`timestamp_s` set: its media time where the file gives
        increasing ones, else its index over the frame rate."""
        import cv2

        media = self._times.pop(0)
        previous = self.timestamp_s
        if self._media_time and math.isfinite(media) and media >= 0 and (
                previous is None or media > previous):
            self.timestamp_s = media
        else:
            if self._count:  # times that stop increasing are not the frames' times
                self._media_time = False
            self.timestamp_s = (self._count / self.fps if self.fps else
                                float(self._cap.get(cv2.CAP_PROP_POS_MSEC)) / 1e3
                                if self._cap is not None else math.nan)
            if previous is not None and not self.timestamp_s > previous:
                self.timestamp_s = previous + (1.0 / self.fps if self.fps else 1e-3)
        self._count += 1
        return frame if frame.size else None

    def _check_complete(self, cv2) -> None:
        """Warn when the video ends well before the frame count its header gives."""
        assert self._cap is not None
        declared = self._cap.get(cv2.CAP_PROP_FRAME_COUNT)
        short = max(2, 0.02 * declared)
        if self.fps and self.timestamp_s is not None and self._media_time and \
                self.timestamp_s >= (declared - short) / self.fps:
            # the frames reach the duration the header gives: a variable frame rate, whose
            # count FFmpeg estimates from the duration at the nominal rate, not a cut file
            return
        if declared > 0 and self._count < declared - short:
            warnings.warn(f"video file {str(self.path)!r} ended after {self._count} of the "
                          f"{declared:.0f} frames its header gives: is it truncated?",
                          stacklevel=3)

    def close(self) -> None:
        cap, self._cap = getattr(self, "_cap", None), None
        if cap is not None:
            cap.release()


class _TransformedSource:
    """Frames of another source, each changed by :meth:`_apply` (the subclasses').

    ``read()`` gives the changed frame (``None``, and an empty frame, as ``None``); a frame
    that is not an image passes unchanged, for the estimator to refuse and the loop to
    count.  ``ended``, ``timestamp_s``, ``fps`` and ``truth_deg`` are the source's.
    """

    def __init__(self, source: FrameSource) -> None:
        if not callable(getattr(source, "read", None)):
            raise InvalidInputError(f"source must have a read() method, got "
                                    f"{type(source).__name__}")
        self.source = source

    def __getattr__(self, name: str):
        if name in ("ended", "timestamp_s", "fps", "truth_deg"):
            return getattr(self.source, name, None if name != "ended" else False)
        raise AttributeError(name)

    def _apply(self, frame: np.ndarray) -> np.ndarray:
        raise NotImplementedError

    def read(self) -> np.ndarray | None:
        from ..render import check_frame

        frame = self.source.read()
        if frame is None or (isinstance(frame, np.ndarray) and frame.size == 0):
            return None
        try:
            check_frame(frame)
        except InvalidInputError:
            return frame  # not an image: the estimator refuses it and the loop counts it
        return self._apply(frame)

    def close(self) -> None:
        self.source.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc) -> None:
        self.close()


class CorrectedSource(_TransformedSource):
    """Frames of another source through a real camera's lens correction.

    Parameters
    ----------
    source : FrameSource
        A camera or video of the real camera.
    correction : handsynth.render.LensCorrection
        Its calibration and the device's view
        (:class:`~handsynth.render.LensCorrection`).

    Notes
    -----
    ``read()`` gives the corrected frame (``None`` passes through);
    ``ended``, ``timestamp_s``, ``fps`` and ``truth_deg`` are the source's.  A
    frame the correction cannot take (a size of another width-to-height
    ratio than the calibration's) raises :class:`InvalidInputError` naming
    both sizes: every frame of a camera or video has the same size.  A
    frame that is not an image passes unchanged, for the estimator to refuse
    and the loop to count.
    """

    def __init__(self, source: FrameSource, correction) -> None:
        from ..render import LensCorrection

        super().__init__(source)
        self.correction = check_instance(correction, LensCorrection, name="correction")

    def _apply(self, frame: np.ndarray) -> np.ndarray:
        return self.correction(frame)


class MirroredSource(_TransformedSource):
    """Frames of another source turned back left to right.

    For a camera, or its driver, set to mirror its image (as for a video call): through
    the device such frames read with no skill, and
    :class:`~handsynth.estimate.MirrorCheck` tells it from the rest frame.

    Parameters
    ----------
    source : FrameSource

    Notes
    -----
    ``read()`` gives ``frame[:, ::-1]`` (contiguous); ``None`` and frames that are not
    images pass as :class:`CorrectedSource` passes them; ``ended``, ``timestamp_s``,
    ``fps`` and ``truth_deg`` are the source's.
    """

    def _apply(self, frame: np.ndarray) -> np.ndarray:
        return np.ascontiguousarray(frame[:, ::-1])


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
        check_number(self.seconds_per_pose, "seconds_per_pose", above=0)
        check_integer(self.count, "count", minimum=2)
        check_integer(self.seed, "seed", minimum=0)

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
        degrees (passed through at `seconds_per_pose`).
    seconds_per_pose : float, keyword-only, optional
        With key poses, the time from one to the next (1 s by default; ``1 / fps`` shows
        pose ``i`` in frame ``i``: a recorded motion replayed).
    loop : bool, keyword-only
        With key poses, start again after the last (True, the default), or end there.
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

    fps: float
    motion: SyntheticMotion | None
    _renderer: SilhouetteRenderer | None

    def __init__(self, shape: HandShape | None = None, mount: CameraMount | None = None, *,
                 motion: SyntheticMotion | np.ndarray | None = None, fps: float = 30.0,
                 frames: int | None = None, side: str = "right", width_px: int | None = None,
                 height_px: int | None = None, seconds_per_pose: float | None = None,
                 loop: bool = True) -> None:
        from ..render import SilhouetteRenderer

        if shape is not None:
            check_instance(shape, HandShape, name="shape")
        as_mount(mount)  # None is the paper's device
        self.fps = check_number(fps, "fps", above=0)
        self.frames = check_integer(frames, "frames", minimum=0, allow_none=True)
        self._last_frame: int | None = None  # the last frame of a motion that does not loop
        if motion is None or isinstance(motion, SyntheticMotion):
            if seconds_per_pose is not None or not loop:
                raise InvalidInputError("seconds_per_pose and loop apply to key poses given as "
                                        "an array; a SyntheticMotion has its own")
            self.motion = SyntheticMotion() if motion is None else motion
            self._keys = self.motion.keyframes()
            self._period_s = self.motion.seconds_per_pose
        else:
            keys = as_angles(motion, argname="motion")
            if keys.ndim != 2 or len(keys) < 2:
                raise InvalidInputError(
                    f"motion key poses must have shape (K, 20) with K >= 2, got {keys.shape}")
            period = 1.0 if seconds_per_pose is None else check_number(
                seconds_per_pose, "seconds_per_pose", above=0)
            self.motion, self._keys, self._period_s = None, keys, float(period)
            if not loop:
                # frames up to the last pose's time (a tolerance for 1/fps steps in floats)
                self._last_frame = int(math.floor((len(keys) - 1) * period * self.fps + 1e-6))
        self.shape = HandShape() if shape is None else shape
        self._renderer = SilhouetteRenderer(self.shape, mount, side=side, width_px=width_px,
                                            height_px=height_px)
        self.mount = self._renderer.mount
        self._count = 0

    def pose_at(self, index: int) -> np.ndarray:
        """True joint angles of frame `index`, shape (20,), degrees."""
        return interpolate_keyframes(self._keys, index / self.fps, self._period_s)

    def read(self) -> np.ndarray | None:
        if self._renderer is None or (self.frames is not None and self._count >= self.frames) \
                or (self._last_frame is not None and self._count > self._last_frame):
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
