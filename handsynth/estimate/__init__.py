"""Runtime pose lookup of the back-of-hand camera estimator (SPEC.md section 1).

* Database selection from hand measurements, formulas (1)-(4):
  :class:`HandMeasurements`, :func:`model_measurements`, :func:`shape_ratios`,
  :func:`select_shape`.
* The paper's two-stage pruned search: :class:`SearchOptions`,
  :class:`SearchTables`, :func:`search` (compiled) and
  :func:`search_reference` (numpy, the specification).
* :class:`PoseLookup`, the pose-lookup service (frame in, :class:`PoseEstimate`
  out), implementing the :class:`PoseEstimator` protocol.
* The live loop: frame sources (:class:`CameraSource`, :class:`VideoSource`,
  :class:`SyntheticSource`, all :class:`FrameSource`), :func:`run_live`,
  row writers (:func:`open_row_writer`) and :class:`SideBySideWriter`.
* :func:`measure_photo`: the measurements of formulas (1)-(4) from a
  top-down photo of the open hand.
* Calibration from one open-hand frame (beyond the paper):
  :func:`select_shape_from_frame`, :class:`Calibration`,
  :func:`masked_search` / :func:`masked_search_reference`,
  :meth:`PoseLookup.calibrated`, :meth:`PoseLookup.from_open_frame` and
  :func:`first_hand_frame`.
"""

from ._ann import ApproximateIndex, ApproximateOptions
from ._calibration import (
    Calibration,
    FrameSelection,
    MaskedMatch,
    masked_band_areas,
    masked_search,
    masked_search_reference,
    select_shape_from_frame,
)
from ._eval import EvalOptions, EvalReport, evaluate
from ._live import (
    CameraSource,
    CsvRowWriter,
    FrameSource,
    JsonlRowWriter,
    LiveOptions,
    LiveSummary,
    SideBySideWriter,
    SyntheticMotion,
    SyntheticSource,
    VideoSource,
    first_hand_frame,
    live_columns,
    open_row_writer,
    run_live,
)
from ._lookup import PoseEstimate, PoseEstimator, PoseLookup
from ._measure import PhotoMeasurement, annotate_measurement, measure_photo
from ._search import SearchOptions, SearchResult, SearchTables, search, search_reference
from ._selection import (
    SEGMENTS,
    HandMeasurements,
    Selection,
    SelectionOptions,
    database_path,
    model_measurements,
    select_shape,
    shape_ratios,
)

__all__ = [
    "SEGMENTS",
    "ApproximateIndex",
    "ApproximateOptions",
    "Calibration",
    "FrameSelection",
    "MaskedMatch",
    "masked_band_areas",
    "masked_search",
    "masked_search_reference",
    "select_shape_from_frame",
    "EvalOptions",
    "EvalReport",
    "evaluate",
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
    "PhotoMeasurement",
    "annotate_measurement",
    "first_hand_frame",
    "live_columns",
    "measure_photo",
    "open_row_writer",
    "run_live",
    "HandMeasurements",
    "PoseEstimate",
    "PoseEstimator",
    "PoseLookup",
    "SearchOptions",
    "SearchResult",
    "SearchTables",
    "Selection",
    "SelectionOptions",
    "database_path",
    "model_measurements",
    "search",
    "search_reference",
    "select_shape",
    "shape_ratios",
]
