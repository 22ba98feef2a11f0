"""Ridge lines: Hilditch thinning of a silhouette (SPEC.md section 1, "Ridge lines").

C. J. Hilditch, "Linear skeletons from square cupboards", in B. Meltzer and
D. Michie (eds.), *Machine Intelligence 4*, Edinburgh University Press, 1969,
pp. 403-420.  scikit-image and OpenCV implement other thinnings (Zhang-Suen,
Guo-Hall), so Hilditch's method is written here.

The algorithm is the sequential form in which Hilditch's method is usually
stated (e.g. H. Tamura, "A comparison of line thinning algorithms from
digital geometry viewpoint", Proc. 4th IJCPR, 1978, pp. 715-719).  Neighbours
of a pixel ``p`` are numbered counter-clockwise from the east::

    x4 x3 x2
    x5 p  x1
    x6 x7 x8

A raster scan visits every foreground pixel; a pixel deleted in the current
pass is only *marked* (value -1) and becomes background when the pass ends.
``p`` is marked when all six conditions hold:

1. ``p`` is foreground and not marked.
2. Boundary point: at least one of x1, x3, x5, x7 is background (0; a
   marked pixel does not count as background here).
3. End points are kept: at least two of the 8 neighbours are foreground or
   marked.
4. Isolated points are kept: at least one neighbour is foreground and
   unmarked.
5. Connectivity: Hilditch's crossing number is 1, with marked pixels counted
   as foreground.  With ``b_k = 1`` for background, the crossing number is
   ``sum_{k=1,3,5,7} b_k * (1 - b_{k+1} * b_{k+2})`` (indices modulo 8), the
   number of 8-connected foreground runs around ``p``; it equals Yokoi's
   8-connectivity number.
6. Lines of width two are not removed from both sides in one pass: for every
   marked neighbour, the crossing number is still 1 when that neighbour
   alone is taken as background.

Passes repeat until one deletes nothing.  Foreground is 8-connected and
background 4-connected; pixels outside the image are background.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ._validation import as_silhouette

__all__ = ["hilditch_thinning"]

# (row, col) offsets of x1..x8 (counter-clockwise from east, rows counting down).
_DR = np.array([0, -1, -1, -1, 0, 1, 1, 1], dtype=np.int64)
_DC = np.array([1, 1, 0, -1, -1, -1, 0, 1], dtype=np.int64)


@njit(cache=True, nogil=True, inline="always")
def _crossing_number(fg):
    """Hilditch's crossing number of the 8 neighbour flags ``fg`` (1 = foreground)."""
    n = 0
    for k in range(0, 8, 2):
        b0 = 1 - fg[k]
        b1 = 1 - fg[(k + 1) % 8]
        b2 = 1 - fg[(k + 2) % 8]
        n += b0 - b0 * b1 * b2
    return n


@njit(cache=True, nogil=True)
def _thin_into(sil, out, work, dr, dc):
    """Hilditch-thin ``sil`` (H, W) bool into ``out`` (H, W) bool.

    ``work`` is an (H + 2, W + 2) int8 scratch array (zero frame = outside).
    """
    h, w = sil.shape
    for r in range(h + 2):
        for c in range(w + 2):
            work[r, c] = 0
    for r in range(h):
        for c in range(w):
            if sil[r, c]:
                work[r + 1, c + 1] = 1
    x = np.empty(8, dtype=np.int64)
    fg = np.empty(8, dtype=np.int64)
    changed = True
    while changed:
        changed = False
        for r in range(1, h + 1):
            for c in range(1, w + 1):
                if work[r, c] != 1:  # condition 1
                    continue
                n_background4 = 0
                n_any = 0
                n_unmarked = 0
                for k in range(8):
                    v = work[r + dr[k], c + dc[k]]
                    x[k] = v
                    fg[k] = 1 if v != 0 else 0
                    n_any += fg[k]
                    if v == 1:
                        n_unmarked += 1
                    elif v == 0 and k % 2 == 0:
                        n_background4 += 1
                if n_background4 == 0:  # condition 2
                    continue
                if n_any < 2:  # condition 3
                    continue
                if n_unmarked < 1:  # condition 4
                    continue
                if _crossing_number(fg) != 1:  # condition 5
                    continue
                ok = True
                for k in range(8):  # condition 6
                    if x[k] == -1:
                        fg[k] = 0
                        if _crossing_number(fg) != 1:
                            ok = False
                        fg[k] = 1
                        if not ok:
                            break
                if not ok:
                    continue
                work[r, c] = -1
                changed = True
        if changed:
            for r in range(1, h + 1):
                for c in range(1, w + 1):
                    if work[r, c] == -1:
                        work[r, c] = 0
    for r in range(h):
        for c in range(w):
            out[r, c] = work[r + 1, c + 1] == 1


def _thin(sil: np.ndarray) -> np.ndarray:
    """Thin a validated contiguous bool image (any 2-D shape)."""
    out = np.empty_like(sil)
    work = np.empty((sil.shape[0] + 2, sil.shape[1] + 2), dtype=np.int8)
    _thin_into(sil, out, work, _DR, _DC)
    return out


def hilditch_thinning(silhouette) -> np.ndarray:
    """Ridge lines of a silhouette by Hilditch's thinning (Hilditch 1969).

    See the module docstring for the exact deletion conditions.  The result
    is a subset of `silhouette`, keeps its topology (8-connected components,
    4-connected holes) and the end points of its lines.

    Parameters
    ----------
    silhouette : array_like of bool, shape (64, 64)
        Foreground mask produced by preprocessing (SPEC.md section 1).

    Returns
    -------
    ndarray of bool, shape (64, 64)
        Ridge-line pixels.

    Raises
    ------
    InvalidInputError
        If `silhouette` is not a 64x64 array of 0/1 values.
    """
    return _thin(as_silhouette(silhouette))
