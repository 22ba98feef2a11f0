"""The calibrated lookup's search: the smallest pixel difference outside an ignore mask.

:func:`masked_search` (compiled) and :func:`masked_search_reference` (numpy,
the specification; tests compare them) score every entry ``i`` by
``X_i = |(S xor S_i) & ~M|`` for the frame's silhouette ``S`` and the
calibration's ignore mask ``M`` (:class:`~handsynth.estimate.Calibration`),
skipping entries whose lower bound from their kept area per 8-row band
(:func:`masked_band_areas`) already exceeds the window.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numba import njit

from .._checks import check_instance
from ..db import pack_mask, popcount64
from ..errors import InvalidInputError
from ._calibration import Calibration

__all__ = ["MaskedMatch", "masked_band_areas", "masked_search", "masked_search_reference"]


@dataclass(frozen=True)
class MaskedMatch:
    """Outcome of :func:`masked_search`.

    Attributes
    ----------
    index : int
        Matched entry (the first of `tied`).
    error : int
        Its masked pixel difference ``X``.
    union : int
        Kept pixels in the input's or the entry's silhouette (``1 - error /
        union`` is their IoU outside the ignore mask).
    tied : ndarray of int64, shape (M,)
        Every entry with the same ``X``, ascending.
    near : ndarray of int64, shape (K,)
        Every entry with ``X <= error + calibration.window_px``, ascending
        (`tied` is among them).
    weights : ndarray of float64, shape (K,)
        Weights of `near` in the reported pose, ``exp(-(X - error) / T)``
        normalised to sum 1 (uniform over the tied entries when ``T = 0``).
    """

    index: int
    error: int
    union: int
    tied: np.ndarray
    near: np.ndarray
    weights: np.ndarray


#: Row bands of the lower bound of :func:`masked_search` (8 rows, one 64-bit word each).
_BANDS = 8


def masked_band_areas(sil_bits, calibration: Calibration) -> np.ndarray:
    """Kept pixels of every entry per band of 8 rows, shape (N, 8), int32.

    ``sum_b |area_ib - area_qb|`` bounds the masked difference ``X_i`` of a
    query ``q`` from below (the pixels of a band that one silhouette has and
    the other has not).  :func:`masked_search` computes it when not given;
    :meth:`PoseLookup.calibrated` computes it once per calibration.

    Parameters
    ----------
    sil_bits : array_like of uint64, shape (N, 64)
        Packed silhouettes, one 64-bit word per row (``Database.sil_bits``,
        or :func:`~handsynth.db.pack_mask` of a query as ``(1, 64)``).
    calibration : Calibration
        Its `keep_bits` (the complement of the ignore mask) select the pixels
        counted.

    Returns
    -------
    ndarray of int32, shape (N, 8)
        Column ``b`` counts the kept pixels of rows ``8 b`` to ``8 b + 7``.
    """
    check_instance(calibration, Calibration, name="calibration")
    table = np.asarray(sil_bits, dtype=np.uint64)
    words = calibration.keep_bits.size
    if table.ndim != 2 or table.shape[1] != words or not len(table):
        raise InvalidInputError(f"sil_bits must have shape (N, {words}) with N >= 1 (the "
                                f"calibration's silhouette size), got {table.shape}")
    counts = np.bitwise_count(table & calibration.keep_bits[None, :]).astype(np.int32)
    return counts.reshape(len(table), _BANDS, -1).sum(axis=2, dtype=np.int32)


@njit(cache=True, nogil=True)
def _masked_kernel(q, keep, sil_bits, bands, q_bands, window, near, near_err):
    """Entries with popcount((S_i ^ q) & keep) <= best + window into `near`, `near_err`.

    `bands` / `q_bands` are the kept areas per row band of the entries and of
    `q`; their absolute difference bounds the count from below, so most
    entries are skipped without counting.  Returns the best count and how
    many entries were stored (ascending).
    """
    best = 1 << 62
    n = 0
    n_bands = bands.shape[1]
    for i in range(sil_bits.shape[0]):
        limit = best + window
        bound = 0
        for b in range(n_bands):
            d = bands[i, b] - q_bands[b]
            bound += d if d >= 0 else -d
        if bound > limit:
            continue
        e = 0
        for w in range(q.shape[0]):
            e += popcount64((sil_bits[i, w] ^ q[w]) & keep[w])
            if e > limit:
                break
        if e > limit:
            continue
        if e < best:
            best = e
            m = 0
            for k in range(n):  # drop what the new best leaves outside the window
                if near_err[k] <= best + window:
                    near[m] = near[k]
                    near_err[m] = near_err[k]
                    m += 1
            n = m
        near[n] = i
        near_err[n] = e
        n += 1
    return best, n


def _check_query(silhouette, calibration, sil_bits) -> np.ndarray:
    check_instance(calibration, Calibration, name="calibration")
    s = np.asarray(silhouette)
    if s.dtype != bool or s.shape != calibration.ignore.shape:
        raise InvalidInputError(f"silhouette must be bool of shape {calibration.ignore.shape}, "
                                f"got {s.dtype} {s.shape}")
    q = pack_mask(s)
    if sil_bits.ndim != 2 or sil_bits.shape[1] != q.size or not len(sil_bits):
        raise InvalidInputError(f"sil_bits must have shape (N, {q.size}) with N >= 1, got "
                                f"{sil_bits.shape}")
    return q


def _match(q, calibration: Calibration, table, near, near_err) -> MaskedMatch:
    best = int(near_err.min())
    tied = near[near_err == best]
    if calibration.temperature_px > 0:
        w = np.exp(-(near_err - best) / calibration.temperature_px)
    else:
        w = (near_err == best).astype(np.float64)
    union = int(np.bitwise_count((q | table[tied[0]]) & calibration.keep_bits).sum())
    return MaskedMatch(index=int(tied[0]), error=best, union=union, tied=tied, near=near,
                       weights=w / w.sum())


def masked_search(silhouette, sil_bits, calibration: Calibration, *,
                  band_areas: np.ndarray | None = None) -> MaskedMatch:
    """The entry whose silhouette differs least from the input outside the ignore mask.

    Parameters
    ----------
    silhouette : ndarray of bool, shape (64, 64)
        The input's preprocessed silhouette.
    sil_bits : ndarray of uint64, shape (N, 64)
        The database's packed silhouettes (``Database.sil_bits``).
    calibration : Calibration
    band_areas : ndarray of int32, shape (N, 8), keyword-only, optional
        :func:`masked_band_areas` of `sil_bits` and `calibration`, when the
        caller keeps them (computed here otherwise).

    Returns
    -------
    MaskedMatch

    Notes
    -----
    Compiled.  Every entry is bounded from below by its kept area per band
    of 8 rows; only entries whose bound is within the window of the best so
    far are counted, with an early exit once the count leaves it.
    :func:`masked_search_reference` is the plain numpy specification.
    """
    table = np.ascontiguousarray(sil_bits, dtype=np.uint64)
    q = _check_query(silhouette, calibration, table)
    bands = masked_band_areas(table, calibration) if band_areas is None else band_areas
    if not (isinstance(bands, np.ndarray) and bands.dtype == np.int32
            and bands.shape == (table.shape[0], _BANDS)):
        raise InvalidInputError(f"band_areas must be int32 of shape ({table.shape[0]}, {_BANDS}) "
                                "from masked_band_areas")
    q_bands = masked_band_areas(q[None, :], calibration)[0]
    near = np.empty(table.shape[0], np.int64)
    near_err = np.empty(table.shape[0], np.int64)
    _, n = _masked_kernel(q, calibration.keep_bits, table, bands, q_bands,
                          calibration.window_px, near, near_err)
    return _match(q, calibration, table, near[:n].copy(), near_err[:n].copy())


def masked_search_reference(silhouette, sil_bits, calibration: Calibration) -> MaskedMatch:
    """:func:`masked_search` written plainly with numpy (the specification for tests).

    Every entry's masked difference is counted; there is no lower bound and
    no early exit.

    Parameters
    ----------
    silhouette : ndarray of bool, shape (64, 64)
        The input's preprocessed silhouette.
    sil_bits : array_like of uint64, shape (N, 64)
        The database's packed silhouettes (``Database.sil_bits``).
    calibration : Calibration

    Returns
    -------
    MaskedMatch
        Equal to :func:`masked_search`'s for the same arguments.
    """
    table = np.asarray(sil_bits, dtype=np.uint64)
    q = _check_query(silhouette, calibration, table)
    x = np.bitwise_count((table ^ q[None, :]) & calibration.keep_bits[None, :]).sum(axis=1)
    near = np.flatnonzero(x <= x.min() + calibration.window_px)
    return _match(q, calibration, table, near, x[near].astype(np.int64))
