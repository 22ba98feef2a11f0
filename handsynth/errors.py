"""Exception hierarchy of handsynth.

Every error that a user can cause with bad input derives from
:class:`HandsynthError`, so the command line can turn it into one line and a
non-zero exit status instead of a traceback.
"""

from __future__ import annotations

__all__ = [
    "DatabaseCorruptError",
    "DatabaseError",
    "DatabaseMismatchError",
    "EstimationError",
    "HandsynthError",
    "InvalidCameraError",
    "InvalidInputError",
    "InvalidPoseError",
    "InvalidShapeError",
    "OutputError",
    "RecordingError",
    "RenderError",
]


class HandsynthError(Exception):
    """Base class of every error handsynth raises on purpose."""


class InvalidInputError(HandsynthError, ValueError):
    """An argument, file field or array has a value handsynth cannot use."""


class InvalidPoseError(InvalidInputError):
    """Joint angles that are unknown, non-finite or outside their limits."""


class InvalidShapeError(InvalidInputError):
    """Hand-shape ratios or measurements that are not usable."""


class InvalidCameraError(InvalidInputError):
    """A camera mount or image size that is not usable."""


class RenderError(HandsynthError, RuntimeError):
    """The off-screen renderer could not be created or failed."""


class DatabaseError(HandsynthError):
    """A pose database could not be written or read."""


class DatabaseMismatchError(DatabaseError):
    """A database was built with parameters other than the reader's."""


class DatabaseCorruptError(DatabaseError):
    """A database file is incomplete, truncated or fails its checksum."""


class OutputError(HandsynthError):
    """An output file or folder could not be written (missing or read-only folder, full
    disk, a name that is an input or a folder, a folder locked by another run).

    Nothing half-written is left under the output's name.
    """


class RecordingError(InvalidInputError):
    """A sensor recording that cannot be parsed or used."""


class EstimationError(HandsynthError):
    """An estimator could not produce a result from otherwise valid input."""
