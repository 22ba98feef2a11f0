"""Higher-order local autocorrelation (HLAC) of a contour image.

SPEC.md section 1, "HLAC": the contour of the 64x64 silhouette is split into
8x8 blocks of 8x8 pixels; in every block the 25 binary HLAC masks of order
0, 1 and 2 in a 3x3 window are counted (N. Otsu and T. Kurita, "A new scheme
for practical flexible and intelligent vision systems", Proc. IAPR Workshop
on Computer Vision, 1988, pp. 431-435).  25 x 64 = 1600 values.

Conventions
-----------
* Offsets are ``(row, col)`` from the reference pixel, rows counting down.
  A mask counts the reference pixel when it and every offset pixel are 1.
* Block borders: a reference pixel belongs to the block it lies in, while the
  offset pixels may lie in a neighbouring block.  Pixels outside the 64x64
  image are 0.  Every contour pixel is thus counted by the order-0 mask of
  exactly one block, and the sum over blocks equals the HLAC of the whole
  image.
* Output order is block-major: index ``(block_row * 8 + block_col) * 25 + k``
  where ``k`` indexes :data:`HLAC_PATTERNS`.  Block ``(0, 0)`` is the top-left.
* One mask counts at most 64 reference pixels per block, so uint8 holds it.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from .._validation import IMAGE_SIZE

__all__ = [
    "HLAC_BLOCK",
    "HLAC_N_BLOCKS",
    "HLAC_PATTERNS",
    "HLAC_SIZE",
    "hlac",
    "hlac_from_contour",
]

#: The 25 HLAC masks of SPEC.md section 1, each a tuple of ``(row, col)``
#: offsets from the reference pixel (rows counting down), order 0, 1, 2.
HLAC_PATTERNS: tuple[tuple[tuple[int, int], ...], ...] = (
    # order 0
    (),
    # order 1
    ((0, 1),),
    ((-1, 1),),
    ((-1, 0),),
    ((-1, -1),),
    # order 2
    ((0, -1), (0, 1)),
    ((-1, 1), (1, -1)),
    ((-1, 0), (1, 0)),
    ((-1, -1), (1, 1)),
    ((-1, 1), (0, -1)),
    ((-1, 0), (1, -1)),
    ((-1, -1), (1, 0)),
    ((0, -1), (1, 1)),
    ((0, 1), (1, -1)),
    ((-1, 1), (1, 0)),
    ((-1, 0), (1, 1)),
    ((-1, -1), (0, 1)),
    ((-1, 0), (0, -1)),
    ((-1, -1), (1, -1)),
    ((0, -1), (1, 0)),
    ((1, -1), (1, 1)),
    ((0, 1), (1, 0)),
    ((-1, 1), (1, 1)),
    ((-1, 0), (0, 1)),
    ((-1, -1), (-1, 1)),
)

#: Side of one HLAC block in pixels (SPEC.md section 1, "HLAC": 8x8 blocks of
#: 8x8 pixels of the 64x64 contour).
HLAC_BLOCK: int = 8
#: Number of blocks along each image axis.
HLAC_N_BLOCKS: int = IMAGE_SIZE // HLAC_BLOCK
#: Length of the HLAC vector: 25 masks x 64 blocks = 1600.
HLAC_SIZE: int = len(HLAC_PATTERNS) * HLAC_N_BLOCKS**2

# The 8 neighbours in a fixed order; bit k of a neighbourhood code is set when
# neighbour k is foreground.
_NEIGHBOURS = ((-1, -1), (-1, 0), (-1, 1), (0, -1), (0, 1), (1, -1), (1, 0), (1, 1))
_NB_DR = np.array([d[0] for d in _NEIGHBOURS], dtype=np.int64)
_NB_DC = np.array([d[1] for d in _NEIGHBOURS], dtype=np.int64)


def _pattern_lut() -> np.ndarray:
    """(256, 25) uint8: entry [code, k] is 1 when mask k is inside neighbourhood `code`."""
    masks = [sum(1 << _NEIGHBOURS.index(o) for o in p) for p in HLAC_PATTERNS]
    codes = np.arange(256)[:, None]
    return ((codes & np.array(masks)[None, :]) == np.array(masks)[None, :]).astype(np.uint8)


_LUT = _pattern_lut()
_N_PAT = len(HLAC_PATTERNS)


@njit(cache=True, nogil=True)
def _hlac_into(cont, lut, dr, dc, out):
    """Accumulate the block HLAC of ``cont`` (64, 64) bool into ``out`` (1600,) uint8."""
    n = cont.shape[0]
    npat = lut.shape[1]
    nb = n // 8
    for i in range(out.shape[0]):
        out[i] = 0
    for r in range(n):
        for c in range(n):
            if not cont[r, c]:
                continue
            code = 0
            for k in range(8):
                rr = r + dr[k]
                cc = c + dc[k]
                if rr >= 0 and rr < n and cc >= 0 and cc < n and cont[rr, cc]:
                    code |= 1 << k
            base = ((r // 8) * nb + (c // 8)) * npat
            for p in range(npat):
                out[base + p] += lut[code, p]


def hlac_from_contour(contour_image: np.ndarray) -> np.ndarray:
    """Block HLAC of a contour image (no validation; see :func:`handsynth.db.hlac`).

    Parameters
    ----------
    contour_image : ndarray of bool, shape (64, 64), C-contiguous

    Returns
    -------
    ndarray of uint8, shape (1600,)
        Block-major counts, see the module docstring.
    """
    out = np.empty(HLAC_SIZE, dtype=np.uint8)
    _hlac_into(contour_image, _LUT, _NB_DR, _NB_DC, out)
    return out


def _hlac_reference(contour_image: np.ndarray) -> np.ndarray:
    """Plain NumPy HLAC used to test the compiled one; same output convention.

    For each mask the image is ANDed with shifted copies of itself (shifting
    in zeros), then the products are summed per 8x8 block of reference pixels.
    """
    img = np.asarray(contour_image, dtype=bool)
    n = img.shape[0]
    padded = np.zeros((n + 2, n + 2), dtype=bool)
    padded[1:-1, 1:-1] = img
    counts = np.empty((HLAC_N_BLOCKS, HLAC_N_BLOCKS, _N_PAT), dtype=np.int64)
    for k, offsets in enumerate(HLAC_PATTERNS):
        hit = img.copy()
        for dr, dc in offsets:
            hit &= padded[1 + dr : 1 + dr + n, 1 + dc : 1 + dc + n]
        blocks = hit.reshape(HLAC_N_BLOCKS, HLAC_BLOCK, HLAC_N_BLOCKS, HLAC_BLOCK)
        counts[:, :, k] = blocks.sum(axis=(1, 3))
    return counts.reshape(-1).astype(np.uint8)


def hlac(silhouette) -> np.ndarray:
    """HLAC vector of a silhouette: the 25 masks counted on its contour per 8x8 block.

    SPEC.md section 1, "HLAC"; Otsu & Kurita (1988).  The contour is
    :func:`handsynth.db.contour`; see this module's docstring for the block
    borders and the output order.

    Parameters
    ----------
    silhouette : array_like of bool, shape (64, 64)

    Returns
    -------
    ndarray of uint8, shape (1600,)
        Count of mask ``k`` in block ``(i, j)`` at index ``(i * 8 + j) * 25 + k``.

    Raises
    ------
    InvalidInputError
        If `silhouette` is not a 64x64 array of 0/1 values.
    """
    from ._contour import contour

    return hlac_from_contour(contour(silhouette))
