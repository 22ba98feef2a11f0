"""The side-by-side video of the live loop: the input frame beside the pose read from it."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from .._checks import check_instance, check_number, check_path, check_side
from .._io import PendingOutput
from ..errors import InvalidInputError, OutputError
from ..models import JOINT_LIMITS_DEG, HandShape
from ..render import as_mount
from ._checks import _quiet_opencv

if TYPE_CHECKING:
    import cv2

    from ..render import SilhouetteRenderer

__all__ = ["SideBySideWriter"]


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
    """A video of the input frames (left) and the poses read from them (right).

    The right half is a hand rendered through the device in the pose read,
    at the input frame's size, in green; black with "no hand" when the frame
    showed none.  For a database lookup (an estimator with ``database``,
    ``mount``, ``side`` and ``shape``: :class:`~handsynth.estimate.PoseLookup`)
    it is the database hand in the matched entry's pose; for another estimator
    (the learnt one) the hand `shape` posed by the estimated angles.  Every
    output frame is ``2 W x H`` for input frames of ``W x H`` (the first
    frame's size; later frames of another size are resized).

    Parameters
    ----------
    path : str or os.PathLike
        ``.mp4``/``.m4v``/``.mov`` (codec ``mp4v``) or ``.avi``/``.mkv``
        (``MJPG``).
    lookup : PoseEstimator
        The estimator whose results are drawn: a database lookup's matched
        entries, or any estimator's angles.
    fps : float, keyword-only
    codec : str, keyword-only, optional
        A four-character code overriding the suffix's codec.
    labels : bool, keyword-only
        Draw the frame index, the entry (a lookup) and the confidence on the
        frames.
    inputs : iterable of path-like, keyword-only
        Files the run reads; `path` must be none of them.
    shape : HandShape, keyword-only, optional
        The hand drawn in the estimated pose (not a lookup's): the standard
        hand by default.
    mount : CameraMount, keyword-only, optional
        The device it is drawn through (not a lookup's): the estimator's
        ``mount`` if it has one, else the paper's.
    side : {"right", "left"}, keyword-only, optional
        The hand drawn (not a lookup's): the estimator's ``side`` if it has
        one, else right.

    Notes
    -----
    The video is written under a temporary name and appears under `path`
    only when :meth:`close` has checked that it holds every frame written
    (OpenCV's encoders do not report a full disk; reading the file back
    does).

    Raises
    ------
    InvalidInputError
        `path` is not a file name (None, a number, ``""``), an unknown
        suffix or codec, `lookup` not an estimator, `shape`, `mount` or
        `side` unusable, or OpenCV cannot open a writer for the file.
    OutputError
        `path` is a folder, in a missing folder, or one of `inputs`; or, on
        :meth:`close`, the video could not be written completely.
    """

    def __init__(self, path, lookup, *, fps: float = 30.0, codec: str | None = None,
                 labels: bool = True, inputs=(), shape: HandShape | None = None,
                 mount=None, side: str | None = None) -> None:
        self.path = check_path(path, "path", kind="file")
        suffix = self.path.suffix.lower()
        if codec is None:
            if suffix not in _CODECS:
                raise InvalidInputError(
                    f"video output {str(self.path)!r} must end in one of "
                    f"{', '.join(sorted(_CODECS))}")
            codec = _CODECS[suffix]
        if not (isinstance(codec, str) and len(codec) == 4):
            raise InvalidInputError(f"codec must be a four-character code, got {codec!r}")
        self._matched = all(hasattr(lookup, a) for a in ("database", "mount", "side", "shape"))
        if not self._matched and not callable(getattr(lookup, "estimate", None)):
            raise InvalidInputError(f"lookup must be a pose estimator (with estimate(frame)), "
                                    f"got {type(lookup).__name__}")
        if self._matched:
            self._hand = (lookup.shape, lookup.mount, lookup.side)
        else:
            self._hand = (check_instance(shape or HandShape(), HandShape, name="shape"),
                          as_mount(mount if mount is not None else getattr(lookup, "mount", None)),
                          check_side(side or getattr(lookup, "side", None) or "right"))
        self.lookup = lookup
        self.fps = check_number(fps, "fps", above=0)
        self.codec = codec
        self.labels = bool(labels)
        self.frames = 0
        self._writer: cv2.VideoWriter | None = None
        self._renderer: SilhouetteRenderer | None = None
        self._size: tuple[int, int] | None = None
        self._pending: PendingOutput | None = PendingOutput(self.path, what="video",
                                                            inputs=inputs, keep_suffix=True)

    def _open(self, w: int, h: int) -> None:
        import cv2

        from ..render import SilhouetteRenderer

        pending = self._pending
        if pending is None:
            raise InvalidInputError(f"video {str(self.path)!r} is already closed")
        with _quiet_opencv():
            writer = cv2.VideoWriter(str(pending.tmp), cv2.VideoWriter.fourcc(*self.codec),
                                     self.fps, (2 * w, h))
            opened = writer.isOpened()
        if not opened:
            writer.release()
            pending.discard()
            raise InvalidInputError(f"OpenCV cannot write video {str(self.path)!r} with codec "
                                    f"{self.codec!r}")
        self._writer, self._size = writer, (w, h)
        shape, mount, side = self._hand
        self._renderer = SilhouetteRenderer(shape, mount, side=side, width_px=w, height_px=h)

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
        writer, renderer, size = self._writer, self._renderer, self._size
        # _open sets the writer, the renderer and the size together (or raises)
        assert writer is not None and renderer is not None and size is not None
        w, h = size
        if left.shape[:2] != (h, w):
            left = cv2.resize(left, (w, h), interpolation=cv2.INTER_NEAREST)
        right = np.zeros_like(left)
        if not estimate.no_hand:
            read = self.lookup.database.angles[estimate.entry] if self._matched else estimate.angles
            pose = np.clip(np.asarray(read, np.float64), JOINT_LIMITS_DEG[:, 0],
                           JOINT_LIMITS_DEG[:, 1])
            if np.isfinite(pose).all():
                right[renderer.mask(pose)] = _MATCH_BGR
        if self.labels:
            scale, thick = max(0.35, h / 600), max(1, round(h / 300))
            y = max(12, round(22 * scale * 1.6))
            text = "" if index is None else f"#{index}"
            cv2.putText(left, f"input {text}", (6, y), cv2.FONT_HERSHEY_SIMPLEX, scale,
                        (0, 160, 255), thick, cv2.LINE_AA)
            read = f"entry {estimate.entry}" if self._matched else "estimate"
            label = ("no hand" if estimate.no_hand else
                     f"{read} conf {estimate.confidence:.2f}"
                     + (" low" if estimate.low_confidence else "")
                     + (" moved" if getattr(estimate, "moved", False) else ""))
            cv2.putText(right, label, (6, y), cv2.FONT_HERSHEY_SIMPLEX, scale, (0, 160, 255),
                        thick, cv2.LINE_AA)
        writer.write(np.hstack([left, right]))
        self.frames += 1

    def close(self) -> None:
        """Finish the file, check that it holds every frame, and release the renderer.

        Raises
        ------
        OutputError
            The file does not hold the frames written (a full disk); it is
            removed.
        """
        import cv2

        writer, self._writer = self._writer, None
        r, self._renderer = self._renderer, None
        if r is not None:
            r.close()
        pending, self._pending = self._pending, None
        if writer is None:
            if pending is not None:
                pending.discard()
            return
        # _open makes a writer only for a pending output, and both are dropped together
        assert pending is not None
        writer.release()
        with _quiet_opencv():
            cap = cv2.VideoCapture(str(pending.tmp))
            readable = int(cap.get(cv2.CAP_PROP_FRAME_COUNT)) if cap.isOpened() else 0
            cap.release()
        if readable != self.frames:
            pending.discard()
            raise OutputError(
                f"cannot write the video {str(self.path)!r}: {readable} of {self.frames} frames "
                "could be read back (is the disk full?); nothing was kept")
        pending.commit()

    def discard(self) -> None:
        """Stop writing and remove the unfinished file (an interrupted or failed run)."""
        writer, self._writer = self._writer, None
        if writer is not None:
            writer.release()
        r, self._renderer = self._renderer, None
        if r is not None:
            r.close()
        pending, self._pending = self._pending, None
        if pending is not None:
            pending.discard()

    def __enter__(self):
        return self

    def __exit__(self, exc_type, exc, tb) -> None:
        if exc_type is None:
            self.close()
        else:
            self.discard()
