"""Frame -> pose: the back-of-hand camera estimator (SPEC.md section 1).

* :class:`PoseLookup` -- the pose-lookup service (frame in,
  :class:`PoseEstimate` out), implementing the :class:`PoseEstimator`
  protocol; it opens, builds, selects and calibrates its database.
* Database selection from hand measurements, formulas (1)-(4):
  :func:`shape_ratios`, :func:`select_shape` (:class:`SelectionOptions`,
  :class:`Selection`); the measurements themselves are
  :class:`handsynth.models.HandMeasurements`.
* The paper's two-stage pruned search: :class:`SearchOptions`,
  :class:`SearchTables`, :func:`search` (compiled) and
  :func:`search_reference` (numpy, the specification); the approximate
  index for large databases: :class:`ApproximateIndex`,
  :class:`ApproximateOptions`.
* Estimators for hands no database was made from (beyond the paper,
  issue 15): :class:`LearnedEstimator` reads the camera's whole fixed
  frame (:func:`handsynth.render.coverage`) with a per-digit nearest-neighbour
  search or a perceptron learnt from randomised model hands
  (:func:`learned_estimator`, :class:`LearnedOptions`, :func:`train_learned`,
  :func:`fit_mlp`), calibrated by a frame of the user's relaxed hand;
  :class:`EnsembleEstimator` averages several, :func:`learned_ensemble`
  makes the default one (:data:`LEARNED_ENSEMBLE`), whose perceptrons are
  shipped in ``shipped/`` (:func:`shipped_members`; for the default and
  the relaxed-rest learning set, :func:`shipped_perceptrons`), so that
  :data:`LEARNED_PERCEPTRONS`, those perceptrons alone, learns nothing.
* Whether the device has moved on the wrist since the rest frame (beyond
  the paper): :class:`MoveCheck` (:class:`MoveCheckOptions`,
  :class:`MoveCheckState`), which sets :attr:`PoseEstimate.moved`; whether
  the rest frame is seen as the device sees it or turned (the other hand, a camera
  upside down, a camera that mirrors its image): :func:`read_rest_frame`
  (:class:`RestFrameReading`, :data:`TURNS`) and :class:`MirrorCheck`
  (:class:`MirrorCheckOptions`, :class:`MirrorReading`, :func:`mirror_check`).
* Steady angles over time (beyond the paper): the One Euro filter
  (:class:`OneEuroFilter`, :class:`OneEuroOptions`, :func:`one_euro`) and
  :class:`SmoothedEstimator`, which wraps any estimator with it.
* Keypoints for the estimators that read angles only (beyond the paper):
  :class:`KeypointEstimator` poses the handsynth hand of a given shape by
  any estimator's angles and reports its 21 keypoints.
* Calibration from one open-hand frame (beyond the paper):
  :func:`select_shape_from_frame`, :class:`Calibration` and the masked search
  (:func:`masked_search` / :func:`masked_search_reference`,
  :class:`MaskedMatch`, :func:`masked_band_areas`).

The live loop is :mod:`handsynth.live`, photo measurement
:mod:`handsynth.measure`, the evaluation :mod:`handsynth.eval`.
"""

from ._ann import ApproximateIndex, ApproximateOptions
from ._calibration import (
    Calibration,
    FrameSelection,
    reference_silhouette,
    select_shape_from_frame,
)
from ._ensemble import (
    LEARNED_ENSEMBLE,
    LEARNED_ENSEMBLES,
    LEARNED_PERCEPTRONS,
    SHIPPED_LEARNING_SETS,
    EnsembleEstimator,
    largest_learning_set,
    learned_ensemble,
    member_learning_set,
    shipped_members,
    shipped_perceptrons,
)
from ._hand import MIN_HAND_COVERAGE
from ._keypoints import KeypointEstimator
from ._learned import (
    AUTO_OVERLAP,
    LearnedEstimator,
    LearnedOptions,
    fit_mlp,
    learned_estimator,
    local_linear,
    train_learned,
)
from ._lookup import PoseEstimate, PoseEstimator, PoseLookup
from ._masked import (
    MaskedMatch,
    masked_band_areas,
    masked_search,
    masked_search_reference,
)
from ._moved import MoveCheck, MoveCheckOptions, MoveCheckState
from ._rest_view import (
    TURNS,
    MirrorCheck,
    MirrorCheckOptions,
    MirrorReading,
    RestFrameReading,
    mirror_check,
    read_rest_frame,
)
from ._search import SearchOptions, SearchResult, SearchTables, search, search_reference
from ._selection import Selection, SelectionOptions, select_shape, shape_ratios
from ._smoothing import (
    OneEuroFilter,
    OneEuroOptions,
    OneEuroState,
    SmoothedEstimator,
    one_euro,
)

__all__ = [
    "AUTO_OVERLAP",
    "LEARNED_ENSEMBLE",
    "LEARNED_ENSEMBLES",
    "LEARNED_PERCEPTRONS",
    "MIN_HAND_COVERAGE",
    "SHIPPED_LEARNING_SETS",
    "TURNS",
    "ApproximateIndex",
    "ApproximateOptions",
    "Calibration",
    "EnsembleEstimator",
    "FrameSelection",
    "KeypointEstimator",
    "LearnedEstimator",
    "LearnedOptions",
    "MaskedMatch",
    "MirrorCheck",
    "MirrorCheckOptions",
    "MirrorReading",
    "MoveCheck",
    "MoveCheckOptions",
    "MoveCheckState",
    "OneEuroFilter",
    "OneEuroOptions",
    "OneEuroState",
    "PoseEstimate",
    "PoseEstimator",
    "PoseLookup",
    "RestFrameReading",
    "SearchOptions",
    "SearchResult",
    "SearchTables",
    "Selection",
    "SelectionOptions",
    "SmoothedEstimator",
    "fit_mlp",
    "largest_learning_set",
    "learned_ensemble",
    "learned_estimator",
    "local_linear",
    "masked_band_areas",
    "masked_search",
    "masked_search_reference",
    "member_learning_set",
    "mirror_check",
    "one_euro",
    "read_rest_frame",
    "reference_silhouette",
    "search",
    "search_reference",
    "select_shape",
    "select_shape_from_frame",
    "shape_ratios",
    "shipped_members",
    "shipped_perceptrons",
    "train_learned",
]
