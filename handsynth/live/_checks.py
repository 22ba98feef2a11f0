"""OpenCV's log level, quieted for a moment.

The live modules' numbers are checked by :mod:`handsynth._checks`.
"""

from __future__ import annotations

from contextlib import contextmanager

__all__: list[str] = []


@contextmanager
def _quiet_opencv():
    """Silence OpenCV's own warnings (printed from C++ to stderr) for a moment.

    FFmpeg's messages inside OpenCV (e.g. ``moov atom not found`` before a
    file is refused) follow ``OPENCV_FFMPEG_LOGLEVEL``, which OpenCV reads
    when it first opens a video: unless the caller has set it, it is set to
    quiet (-8) here, so that a damaged video gives the one error that names
    it and no lines of FFmpeg's before it.
    """
    import os

    os.environ.setdefault("OPENCV_FFMPEG_LOGLEVEL", "-8")
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
