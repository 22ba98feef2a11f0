"""Features of a 64x64 silhouette, identical for database renders and live frames.

* :func:`contour` -- inner boundary of the silhouette;
* :func:`hlac` -- 25 HLAC masks (Otsu & Kurita 1988) per 8x8 block, 1600 uint8;
* :func:`hilditch_thinning` -- ridge lines (Hilditch 1969);
* :func:`extract_features` / :func:`extract_features_batch` -- all of them in one pass.
"""

from ._contour import contour
from ._features import Features, extract_features, extract_features_batch
from ._hlac import HLAC_PATTERNS, HLAC_SIZE, hlac
from ._thinning import hilditch_thinning

__all__ = [
    "HLAC_PATTERNS",
    "HLAC_SIZE",
    "Features",
    "contour",
    "extract_features",
    "extract_features_batch",
    "hilditch_thinning",
    "hlac",
]
