"""Contour (inner boundary) of a silhouette, the input of HLAC (SPEC.md section 1).

Definition used throughout handsynth: a pixel is on the contour when it is
foreground and at least one of its four edge neighbours (up, down, left,
right) is background.  Pixels outside the image count as background, so a
foreground pixel on the image border is always a contour pixel.  The contour
is therefore 8-connected along the boundary of each region and one pixel
thick.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from .._validation import as_silhouette

__all__ = ["contour"]


@njit(cache=True, nogil=True)
def _contour_into(sil, out):
    """Write the contour of ``sil`` (H, W) bool into ``out`` (H, W) bool."""
    h, w = sil.shape
    for r in range(h):
        for c in range(w):
            if not sil[r, c]:
                out[r, c] = False
            elif r == 0 or c == 0 or r == h - 1 or c == w - 1:
                out[r, c] = True
            else:
                out[r, c] = not (
                    sil[r - 1, c] and sil[r + 1, c] and sil[r, c - 1] and sil[r, c + 1]
                )


def contour(silhouette) -> np.ndarray:
    """Return the contour image of a silhouette.

    A contour pixel is a foreground pixel with at least one background pixel
    among its 4 edge neighbours; pixels outside the image are background
    (SPEC.md section 1, "HLAC": "Extract the contour of the 64x64 silhouette").

    Parameters
    ----------
    silhouette : array_like of bool, shape (64, 64)
        Foreground mask produced by preprocessing.

    Returns
    -------
    ndarray of bool, shape (64, 64)
        Contour pixels; a subset of `silhouette`.

    Raises
    ------
    InvalidInputError
        If `silhouette` is not a 64x64 array of 0/1 values.
    """
    sil = as_silhouette(silhouette)
    out = np.empty_like(sil)
    _contour_into(sil, out)
    return out
