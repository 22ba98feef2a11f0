"""The paper's matching error ``E`` of one database row, compiled (SPEC.md section 1, "Search").

For an input with HLAC vector ``h``, packed silhouette ``S``, packed ridge
lines ``R`` and ridge area ``A_input``, and a database row ``i`` with
``h_i, S_i, R_i, A_i`` (SPEC.md section 1, "Search", steps 1-3):

1. ``P1[i] = |R & ~S_i|`` (input ridge pixels outside the row's
   silhouette); the row is pruned when ``P1 > th1 = C * A_input``.
2. ``P2[i] = |R_i & ~S|`` (row ridge pixels outside the input silhouette);
   the row is pruned when ``P2 > th2 = C1 * A_i**2 + C2 * A_i``.
3. ``E[i] = sum_k (h_k - h_i,k)**2 + C3 * P1[i] + C4 * P2[i]``.

:func:`score` is the one implementation of these steps; the exact search
(:mod:`handsynth.estimate._search`) and the approximate index
(:mod:`handsynth.estimate._ann`) differ only in which rows they hand it and
in what order.  It compares a row with the best ``E`` found so far and
stops as soon as the row cannot beat it: P1 first (it decides stage 1),
then P2, then the HLAC distance in blocks with early exit.  The outcome is
one of four status codes, :data:`PRUNED`, :data:`ABOVE_BEST`,
:data:`SURVIVOR_ABOVE_BEST` and :data:`SURVIVOR`.

Its arguments come in three groups, each a named tuple that the compiled
code reads by field name: the input (:class:`Query`), the database columns
(:class:`Rows`) and the search constants (:class:`Constants`).  Callers
receive the groups as plain tuples and name them (``Query(*query)``) in the
compiled function that holds the loop over rows: plain tuples are as cheap
to pass from Python as the arrays one by one, and named tuples made in that
function cost nothing in the loop, whereas reading the fields of a named
tuple received as an argument costs a reference count update per read and
call (measured: a quarter slower).  :func:`score` is inlined into its
callers and reads each field once, up front.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit

from ..db import HLAC_SIZE, count_outside

__all__ = ["ABOVE_BEST", "PRUNED", "SURVIVOR", "SURVIVOR_ABOVE_BEST", "Constants", "Query",
           "Rows", "hlac_distance", "score"]

#: The row fails stage 1 (``P1 > th1``) or stage 2 (``P2 > th2``).
PRUNED = 0
#: The row passes stage 1 but cannot beat the best ``E`` so far; stage 2 is not
#: decided (``P2`` not counted), so it is neither pruned nor a survivor.
ABOVE_BEST = 1
#: The row passes both stages (a survivor) and its ``E`` exceeds the best so far
#: (``E`` not computed to the end).
SURVIVOR_ABOVE_BEST = 2
#: The row passes both stages and its exact ``E`` does not exceed the best so far.
SURVIVOR = 3

_BLOCK = 200  # HLAC dims between early-exit checks (divides HLAC_SIZE)


class Query(NamedTuple):
    """The input's features as :func:`score` reads them.

    Attributes
    ----------
    hlac : ndarray of uint8, shape (1600,)
        HLAC vector ``h``.
    sil_bits, ridge_bits : ndarray of uint64, shape (64,)
        Packed 64x64 silhouette ``S`` and ridge lines ``R``.
    """

    hlac: np.ndarray
    sil_bits: np.ndarray
    ridge_bits: np.ndarray


class Rows(NamedTuple):
    """Database columns as :func:`score` reads them (row ``i`` is ``hlac[i]``...).

    Attributes
    ----------
    hlac : ndarray of uint8, shape (N, 1600)
    sil_bits, ridge_bits : ndarray of uint64, shape (N, 64)
    ridge_area : ndarray of float64, shape (N,)
        ``A_i``, pixels.
    """

    hlac: np.ndarray
    sil_bits: np.ndarray
    ridge_bits: np.ndarray
    ridge_area: np.ndarray


class Constants(NamedTuple):
    """Constants of one search pass.

    Attributes
    ----------
    th1 : float
        Stage-1 threshold ``C * A_input``, pixels.
    c1 : float
        Stage-2 factor of ``A_i**2``, 1/pixel.
    c2 : float
        Stage-2 factor of ``A_i`` (dimensionless).
    c3, c4 : float
        Weights of ``P1`` and ``P2`` in ``E`` (HLAC units squared per pixel).
    prune : bool
        ``False``: no row is pruned (the fallback pass, or
        ``SearchOptions(prune=False)``).
    """

    th1: float
    c1: float
    c2: float
    c3: float
    c4: float
    prune: bool


@njit(cache=True, nogil=True)
def hlac_distance(q_hlac, row, bound):
    """Squared distance of two (1600,) uint8 vectors, abandoned once it exceeds `bound`.

    Returns the partial sum then (a value above `bound`).  Blocks of a fixed
    200 dims (int32 sums) keep the inner loop vectorized.
    """
    d = 0
    for start in range(0, HLAC_SIZE, _BLOCK):
        acc = np.int32(0)
        for k in range(_BLOCK):
            diff = np.int32(q_hlac[start + k]) - np.int32(row[start + k])
            acc += diff * diff
        d += acc
        if d > bound:
            return d
    return d


@njit(cache=True, nogil=True, inline="always")
def score(i, hl_bound, best_e, q, rows, k):
    """Row `i` against the best ``E`` so far (module docstring, steps 1-3).

    Parameters
    ----------
    i : int
        Row of `rows`.
    hl_bound : float
        A lower bound of the row's squared HLAC distance (0.0 when none is
        known); with it the row is given up before its HLAC vector is read.
    best_e : float
        Smallest ``E`` so far (``inf`` when none).
    q : Query
    rows : Rows
    k : Constants

    Returns
    -------
    status : int
        :data:`PRUNED`, :data:`ABOVE_BEST`, :data:`SURVIVOR_ABOVE_BEST` or
        :data:`SURVIVOR`.
    e : float
        ``E``, exact when `status` is :data:`SURVIVOR` (then ``e <=
        best_e``), else ``inf``.
    d : int
        Squared HLAC distance when :data:`SURVIVOR`, else 0.
    p1, p2 : int
        ``P1`` (always counted) and ``P2`` (0 when not counted: pruned at
        stage 1 or :data:`ABOVE_BEST`), pixels.
    """
    # the fields are read once, up front (module docstring)
    q_hlac, q_sil, q_ridge = q.hlac, q.sil_bits, q.ridge_bits
    hlac, sil_bits, ridge_bits, ridge_area = rows.hlac, rows.sil_bits, rows.ridge_bits, \
        rows.ridge_area
    th1, c1, c2, c3, c4, prune = k.th1, k.c1, k.c2, k.c3, k.c4, k.prune
    p1 = count_outside(q_ridge, sil_bits[i])  # in full: 12 ns, less than a limit check
    if prune and p1 > th1:
        return PRUNED, np.inf, 0, p1, 0
    pen = c3 * p1
    if pen + hl_bound > best_e:
        return ABOVE_BEST, np.inf, 0, p1, 0
    p2 = count_outside(ridge_bits[i], q_sil)
    a = ridge_area[i]
    if prune and p2 > c1 * a * a + c2 * a:
        return PRUNED, np.inf, 0, p1, p2
    pen += c4 * p2
    if pen + hl_bound > best_e:
        return SURVIVOR_ABOVE_BEST, np.inf, 0, p1, p2
    d = hlac_distance(q_hlac, hlac[i], best_e - pen)
    e = d + pen
    if e > best_e:
        return SURVIVOR_ABOVE_BEST, np.inf, 0, p1, p2
    return SURVIVOR, e, d, p1, p2
