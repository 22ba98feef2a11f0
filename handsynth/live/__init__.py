"""The live loop: frames in, one row of joint angles per frame out.

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
``confidence``, ``low_confidence``, ``moved``, ``entry``, the 20 angles in degrees
under their :data:`~handsynth.JOINT_NAMES`; optionally the 21 keypoints in
metres (``<site>_x_m``, ``<site>_y_m``, ``<site>_z_m``, sites of
:data:`~handsynth.models.KEYPOINT_SITES`) and, for sources that know them,
the true angles (``true_<joint>``).  Angles and keypoints of a no-hand
frame are missing (empty CSV cell, JSON ``null``).  Each row is written with
one ``write`` call of a complete line and flushed (every row by default),
so a run that is killed leaves only complete lines.
"""

from ._loop import (
    LiveOptions,
    LiveSummary,
    default_database_dir,
    first_hand_frame,
    run_live,
)
from ._sources import (
    CameraSource,
    CorrectedSource,
    FrameSource,
    MirroredSource,
    SyntheticMotion,
    SyntheticSource,
    VideoSource,
)
from ._video import SideBySideWriter
from ._writers import CsvRowWriter, JsonlRowWriter, live_columns, open_row_writer

__all__ = [
    "CameraSource",
    "CorrectedSource",
    "CsvRowWriter",
    "FrameSource",
    "JsonlRowWriter",
    "LiveOptions",
    "LiveSummary",
    "MirroredSource",
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
