"""Features and pose databases of the back-of-hand camera estimator (SPEC.md section 1).

Features (identical for database renders and live frames; :mod:`handsynth.db.features`):

* :func:`contour` -- inner boundary of the 64x64 silhouette;
* :func:`hlac` -- 25 HLAC masks (Otsu & Kurita 1988) per 8x8 block, 1600 uint8;
* :func:`hilditch_thinning` -- ridge lines (Hilditch 1969);
* :func:`pack_mask` / :func:`count_outside` -- bit-packed masks for the
  P1/P2 pixel counts of the two-stage search;
* :func:`extract_features` / :func:`extract_features_batch` -- all of them.

Databases (one HDF5 file per hand shape): :func:`write_database`,
:func:`open_database`, :func:`verify`, :class:`Database`.

Building them (resumable, parallel, optionally on Ray): :func:`build_database`,
:func:`build_databases`, :func:`build_default_database`.

Learning sets for the estimators of unseen hands (coverage grids of randomised model
hands): :func:`render_learning_set`, :func:`learning_set` (:class:`LearningSetOptions`),
and the rest frames seen and mirrored that the mirror check learns from,
:func:`render_mirror_set`.
"""

from ._bits import (
    complement_bits,
    count_outside,
    count_outside_batch,
    pack_mask,
    popcount64,
    popcount_bits,
    unpack_mask,
)
from ._build import (
    DEFAULT_DATABASE,
    MAX_COUNT,
    BuildOptions,
    BuildProgress,
    BuildSummary,
    build_database,
    build_databases,
    build_default_database,
    check_database_hand,
    database_path,
    find_database,
)
from ._entries import DEFAULT_RENDER_SIZE, check_render_size, database_meta, render_entries
from ._learning import (
    MAX_LEARNING_HANDS,
    LearningSet,
    LearningSetOptions,
    learning_poses,
    learning_set,
    learning_workers,
    random_rest_posture,
    render_learning_set,
    render_mirror_set,
)
from ._store import (
    FORMAT_VERSION,
    KEYPOINT_SCALE_M,
    Database,
    check_rows,
    open_database,
    verify,
    write_database,
)
from ._validation import IMAGE_SIZE
from .features import (
    HLAC_PATTERNS,
    HLAC_SIZE,
    Features,
    contour,
    extract_features,
    extract_features_batch,
    hilditch_thinning,
    hlac,
)

__all__ = [
    "DEFAULT_DATABASE",
    "DEFAULT_RENDER_SIZE",
    "FORMAT_VERSION",
    "HLAC_PATTERNS",
    "HLAC_SIZE",
    "IMAGE_SIZE",
    "KEYPOINT_SCALE_M",
    "MAX_COUNT",
    "MAX_LEARNING_HANDS",
    "BuildOptions",
    "BuildProgress",
    "BuildSummary",
    "Database",
    "Features",
    "LearningSet",
    "LearningSetOptions",
    "build_database",
    "build_databases",
    "build_default_database",
    "check_database_hand",
    "check_render_size",
    "check_rows",
    "complement_bits",
    "contour",
    "count_outside",
    "count_outside_batch",
    "database_meta",
    "database_path",
    "extract_features",
    "extract_features_batch",
    "find_database",
    "hilditch_thinning",
    "hlac",
    "learning_poses",
    "learning_set",
    "learning_workers",
    "open_database",
    "pack_mask",
    "popcount64",
    "popcount_bits",
    "random_rest_posture",
    "render_entries",
    "render_learning_set",
    "render_mirror_set",
    "unpack_mask",
    "verify",
    "write_database",
]
