"""Runtime pose lookup of the back-of-hand camera estimator (SPEC.md section 1).

* Database selection from hand measurements, formulas (1)-(4):
  :class:`HandMeasurements`, :func:`model_measurements`, :func:`shape_ratios`,
  :func:`select_shape`.
* The paper's two-stage pruned search: :class:`SearchOptions`,
  :class:`SearchTables`, :func:`search` (compiled) and
  :func:`search_reference` (numpy, the specification).
* :class:`PoseLookup`, the pose-lookup service (frame in, :class:`PoseEstimate`
  out), implementing the :class:`PoseEstimator` protocol.
"""

from ._lookup import PoseEstimate, PoseEstimator, PoseLookup
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
