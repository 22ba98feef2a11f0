"""OpenCV's log level, quieted for a moment.

The live modules' numbers are checked by :mod:`handsynth._checks`.
"""

from __future__ import annotations

from contextlib import contextmanager

__all__: list[str] = []


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
