"""All per-image features of the lookup estimator in one call (SPEC.md section 1).

Database renders and live frames go through the same function, so the two
sides of the search are computed identically: contour, block HLAC
(:mod:`._hlac`), Hilditch ridge lines (:mod:`._thinning`) and the packed
silhouette / ridge masks with the ridge area (:mod:`._bits`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numba import njit

from .._validation import IMAGE_SIZE, as_silhouette, as_silhouette_batch
from ._contour import _contour_into
from ._hlac import _LUT, _NB_DC, _NB_DR, HLAC_SIZE, _hlac_into
from ._thinning import _DC, _DR, _thin_into

__all__ = ["Features", "extract_features", "extract_features_batch"]


@dataclass(frozen=True, eq=False)
class Features:
    """Features of one 64x64 silhouette; all arrays are read-only.

    Attributes
    ----------
    silhouette : ndarray of bool, shape (64, 64)
        The input foreground mask.
    contour : ndarray of bool, shape (64, 64)
        Foreground pixels with a background 4-neighbour (:func:`contour`).
    hlac : ndarray of uint8, shape (1600,)
        Block HLAC of the contour, block-major (:func:`hlac`).
    ridge : ndarray of bool, shape (64, 64)
        Ridge lines, Hilditch thinning of the silhouette.
    sil_bits : ndarray of uint64, shape (64,)
        Packed `silhouette`, bit ``c`` of word ``r`` = pixel ``(r, c)``.
    ridge_bits : ndarray of uint64, shape (64,)
        Packed `ridge`.
    ridge_area : int
        Number of ridge pixels (A_input / A_ds of SPEC.md section 1).
    """

    silhouette: np.ndarray
    contour: np.ndarray
    hlac: np.ndarray
    ridge: np.ndarray
    sil_bits: np.ndarray
    ridge_bits: np.ndarray
    ridge_area: int


@njit(cache=True, nogil=True)
def _pack_into(mask, out):
    for r in range(mask.shape[0]):
        word = np.uint64(0)
        for c in range(mask.shape[1]):
            if mask[r, c]:
                word |= np.uint64(1) << np.uint64(c)
        out[r] = word


@njit(cache=True, nogil=True)
def _features_into(sil, cont, hl, ridge, sil_bits, ridge_bits, work, lut, nb_dr, nb_dc, dr, dc):
    """Compute every feature of one silhouette into preallocated outputs."""
    _contour_into(sil, cont)
    _hlac_into(cont, lut, nb_dr, nb_dc, hl)
    _thin_into(sil, ridge, work, dr, dc)
    _pack_into(sil, sil_bits)
    _pack_into(ridge, ridge_bits)
    area = 0
    for r in range(ridge.shape[0]):
        for c in range(ridge.shape[1]):
            area += ridge[r, c]
    return area


@njit(cache=True, nogil=True)
def _features_batch_into(
    sils, cont, hl, ridge, sil_bits, ridge_bits, area, lut, nb_dr, nb_dc, dr, dc
):
    work = np.empty((sils.shape[1] + 2, sils.shape[2] + 2), dtype=np.int8)
    for i in range(sils.shape[0]):
        area[i] = _features_into(
            sils[i],
            cont[i],
            hl[i],
            ridge[i],
            sil_bits[i],
            ridge_bits[i],
            work,
            lut,
            nb_dr,
            nb_dc,
            dr,
            dc,
        )


def _readonly(arr: np.ndarray) -> np.ndarray:
    arr.setflags(write=False)
    return arr


def extract_features(silhouette) -> Features:
    """Compute all lookup features of one silhouette (SPEC.md section 1).

    Parameters
    ----------
    silhouette : array_like of bool, shape (64, 64)
        Output of preprocessing; 0/1 numbers are accepted.

    Returns
    -------
    Features
        Contour, HLAC (1600 uint8), ridge lines, packed masks and ridge area.

    Raises
    ------
    InvalidInputError
        If `silhouette` is not a 64x64 array of 0/1 values; the message names
        the shape, dtype or offending value.

    See Also
    --------
    extract_features_batch : the same for a stack of silhouettes.
    """
    sil = as_silhouette(silhouette).copy()
    n = IMAGE_SIZE
    cont = np.empty((n, n), dtype=bool)
    hl = np.empty(HLAC_SIZE, dtype=np.uint8)
    ridge = np.empty((n, n), dtype=bool)
    sil_bits = np.empty(n, dtype=np.uint64)
    ridge_bits = np.empty(n, dtype=np.uint64)
    work = np.empty((n + 2, n + 2), dtype=np.int8)
    area = _features_into(
        sil, cont, hl, ridge, sil_bits, ridge_bits, work, _LUT, _NB_DR, _NB_DC, _DR, _DC
    )
    return Features(
        silhouette=_readonly(sil),
        contour=_readonly(cont),
        hlac=_readonly(hl),
        ridge=_readonly(ridge),
        sil_bits=_readonly(sil_bits),
        ridge_bits=_readonly(ridge_bits),
        ridge_area=int(area),
    )


def extract_features_batch(silhouettes) -> dict[str, np.ndarray]:
    """Compute the features of a stack of silhouettes in one compiled loop.

    Parameters
    ----------
    silhouettes : array_like of bool, shape (N, 64, 64)

    Returns
    -------
    dict of str to ndarray
        ``"contour"`` (N, 64, 64) bool, ``"hlac"`` (N, 1600) uint8,
        ``"ridge"`` (N, 64, 64) bool, ``"sil_bits"`` (N, 64) uint64,
        ``"ridge_bits"`` (N, 64) uint64, ``"ridge_area"`` (N,) uint16.
        Row ``i`` equals the fields of ``extract_features(silhouettes[i])``.

    Raises
    ------
    InvalidInputError
        If `silhouettes` is not an (N, 64, 64) array of 0/1 values.
    """
    sils = as_silhouette_batch(silhouettes)
    count, n = sils.shape[0], IMAGE_SIZE
    out = {
        "contour": np.empty((count, n, n), dtype=bool),
        "hlac": np.empty((count, HLAC_SIZE), dtype=np.uint8),
        "ridge": np.empty((count, n, n), dtype=bool),
        "sil_bits": np.empty((count, n), dtype=np.uint64),
        "ridge_bits": np.empty((count, n), dtype=np.uint64),
        "ridge_area": np.empty(count, dtype=np.uint16),
    }
    _features_batch_into(
        sils,
        out["contour"],
        out["hlac"],
        out["ridge"],
        out["sil_bits"],
        out["ridge_bits"],
        out["ridge_area"],
        _LUT,
        _NB_DR,
        _NB_DC,
        _DR,
        _DC,
    )
    return out
