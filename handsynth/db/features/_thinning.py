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

:func:`_thin_into_reference` is that statement, pixel by pixel.
:func:`_thin_into`, used by :func:`hilditch_thinning` and the feature
extraction, gives the identical result on bit-packed rows by visiting only
the boundary pixels that a pass can delete and looking conditions 3-6 up in
two tables (see its docstring); it is about 20 times faster on a hand
silhouette.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from .._validation import as_silhouette

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
def _thin_into_reference(sil, out, work, dr, dc):
    """Hilditch-thin ``sil`` (H, W) bool into ``out`` (H, W) bool, plainly.

    The direct statement of the module docstring: every pass scans every
    pixel and tests the six conditions on the int8 neighbourhood.  It is the
    reference that :func:`_thin_into` is tested against, and its fallback for
    images wider than 64 columns.

    Parameters
    ----------
    sil : ndarray of bool, shape (H, W)
        Input mask.
    out : ndarray of bool, shape (H, W)
        Receives the ridge lines.
    work : ndarray of int8, shape (H + 2, W + 2)
        Scratch (its zero frame is the outside of the image).
    dr, dc : ndarray of int64, shape (8,)
        `_DR`, `_DC`: offsets of the neighbours x1..x8.
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


# --- Fast implementation ---------------------------------------------------
#
# Bit k of a 3x3 *window* index is the pixel at (row offset k // 3 - 1,
# column offset k % 3 - 1), i.e. the window is read in raster order and bit 4
# is the centre p.  ``_WINDOW_BIT[k]`` is the window bit of x(k + 1).
_WINDOW_BIT = np.array([5, 2, 1, 0, 3, 6, 7, 8], dtype=np.int64)
_CENTRE = np.uint16(1 << 4)


def _decision_tables() -> tuple[np.ndarray, np.ndarray]:
    """Conditions 3, 5 and 6 as two tables over the 3x3 window index.

    Returns
    -------
    simple : ndarray of bool, shape (512,)
        ``simple[F]``: conditions 3 and 5 hold when the foreground-or-marked
        neighbours are the window bits `F` (the centre bit is ignored).
    keep : ndarray of uint16, shape (512,)
        ``keep[F]``: window bits of the neighbours in `F` that, taken alone
        as background, make the crossing number differ from 1; condition 6
        holds iff no marked neighbour is among them (``M & keep[F] == 0``).
    """
    simple = np.zeros(512, dtype=bool)
    keep = np.zeros(512, dtype=np.uint16)
    fg = np.zeros(8, dtype=np.int64)
    crossing = _crossing_number.py_func
    for index in range(512):
        for k in range(8):
            fg[k] = (index >> _WINDOW_BIT[k]) & 1
        simple[index] = fg.sum() >= 2 and crossing(fg) == 1
        for k in range(8):
            if fg[k]:
                fg[k] = 0
                if crossing(fg) != 1:
                    keep[index] |= 1 << _WINDOW_BIT[k]
                fg[k] = 1
    return simple, keep


_SIMPLE, _KEEP = _decision_tables()

# Trailing-zero count of a uint64 with one bit set: de Bruijn multiplication
# (C. E. Leiserson, H. Prokop, K. H. Randall, "Using de Bruijn sequences to
# index a 1 in a computer word", MIT, 1998).
_DE_BRUIJN = np.uint64(0x03F79D71B4CB0A89)
_DE_BRUIJN_INDEX = np.zeros(64, dtype=np.int64)
for _i in range(64):
    _DE_BRUIJN_INDEX[(((1 << _i) * int(_DE_BRUIJN)) % 2**64) >> 58] = _i
del _i

_ONE = np.uint64(1)
_SEVEN = np.uint64(7)


@njit(cache=True, nogil=True, inline="always")
def _window_row(word, c):
    """Bits ``c - 1, c, c + 1`` of `word` as a 3-bit number (bit -1 is 0)."""
    if c == 0:
        return (word << _ONE) & _SEVEN
    return (word >> np.uint64(c - 1)) & _SEVEN


@njit(cache=True, nogil=True)
def _thin_into(sil, out, work, dr, dc):
    """Hilditch-thin ``sil`` (H, W) bool into ``out`` (H, W) bool.

    Gives exactly the result of :func:`_thin_into_reference` (the module
    docstring's algorithm), pixel for pixel, by visiting far fewer pixels:

    * Rows are bit-packed (bit ``c`` of ``fg[r + 1]`` is pixel ``(r, c)``),
      so this path needs ``W <= 64``; wider images go to the reference.
    * Within a pass no pixel becomes 0 (marks become background only when
      the pass ends) and a value-1 pixel stays 1 until the scan reaches it.
      Condition 2 therefore selects exactly the *boundary* of the foreground
      at the start of the pass, ``fg & ~(up & down & west & east)`` per
      row; only those pixels are visited, in raster order (lowest set bit
      first, row after row).
    * Conditions 3 and 5 depend only on which neighbours are foreground or
      marked; conditions 4 and 6 only get harder with more marked
      neighbours.  A boundary pixel whose 3x3 neighbourhood lost no pixel in
      the previous pass had no marked neighbour then and the same
      neighbourhood, and was rejected (or would have been, by induction from
      the first pass, which visits the whole boundary), so it is rejected
      again whatever is marked now.  After the first pass only the boundary
      pixels next to the previous pass's deletions are visited; the passes
      stop when one marks nothing.
    * Conditions 3, 5 and 6 depend only on the foreground-or-marked and the
      marked bits of the 3x3 window: they are looked up in `_SIMPLE` and
      `_KEEP`; condition 4 says the two differ outside the centre.

    Parameters
    ----------
    sil : ndarray of bool, shape (H, W)
        Input mask.
    out : ndarray of bool, shape (H, W)
        Receives the ridge lines.
    work : ndarray of int8, shape (H + 2, W + 2)
        Scratch for the reference fallback (``W > 64``); unused otherwise.
    dr, dc : ndarray of int64, shape (8,)
        `_DR`, `_DC`, for the reference fallback.
    """
    h, w = sil.shape
    if w > 64:
        _thin_into_reference(sil, out, work, dr, dc)
        return
    # Rows 0 and h + 1 stay zero: the outside of the image.  `fg` (foreground
    # or marked) is constant within a pass.
    fg = np.zeros(h + 2, dtype=np.uint64)
    mk = np.zeros(h + 2, dtype=np.uint64)  # marked in this pass
    gone = np.zeros(h + 2, dtype=np.uint64)  # deleted by the previous pass
    zero = np.uint64(0)
    for r in range(h):
        word = zero
        for c in range(w):
            if sil[r, c]:
                word |= _ONE << np.uint64(c)
        fg[r + 1] = word
        gone[r + 1] = word  # first pass: visit the whole boundary
    gone_lo, gone_hi = 1, h
    while True:
        mark_lo, mark_hi = h + 1, 0
        for r in range(max(gone_lo - 1, 1), min(gone_hi + 1, h) + 1):
            up, row, down = fg[r - 1], fg[r], fg[r + 1]
            boundary = row & ~(up & down & (row << _ONE) & (row >> _ONE))
            near = gone[r - 1] | gone[r] | gone[r + 1]
            todo = boundary & (near | (near << _ONE) | (near >> _ONE))
            mk_up = mk[r - 1]
            mk_row = zero
            while todo != zero:
                low = todo & (~todo + _ONE)
                todo ^= low
                c = _DE_BRUIJN_INDEX[(low * _DE_BRUIJN) >> np.uint64(58)]
                f = (
                    _window_row(up, c)
                    | (_window_row(row, c) << np.uint64(3))
                    | (_window_row(down, c) << np.uint64(6))
                )
                m = _window_row(mk_up, c) | (_window_row(mk_row, c) << np.uint64(3))
                if _SIMPLE[f] and (f ^ m) != _CENTRE and (m & _KEEP[f]) == zero:
                    mk_row |= low
            if mk_row != zero:
                mk[r] = mk_row
                mark_lo = min(mark_lo, r)
                mark_hi = r
        if mark_hi == 0:
            break
        for r in range(gone_lo, gone_hi + 1):
            gone[r] = zero
        for r in range(mark_lo, mark_hi + 1):
            fg[r] &= ~mk[r]
            gone[r] = mk[r]
            mk[r] = zero
        gone_lo, gone_hi = mark_lo, mark_hi
    for r in range(h):
        word = fg[r + 1]
        for c in range(w):
            out[r, c] = (word >> np.uint64(c)) & _ONE != zero


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
