"""The two-stage pruned search of SPEC.md section 1 ("Search"), exact and fast.

For an input with HLAC vector ``h``, packed silhouette ``S``, packed ridge
lines ``R`` and ridge area ``A_input``, and database entry ``i`` with
``h_i, S_i, R_i, A_i``:

1. ``P1[i] = |R & ~S_i|`` (input ridge pixels outside the entry's
   silhouette); entries with ``P1 > th1 = C * A_input`` are dropped.
2. ``P2[i] = |R_i & ~S|`` (entry ridge pixels outside the input
   silhouette); entries with ``P2 > th2 = C1 * A_i**2 + C2 * A_i`` are dropped.
3. ``E[i] = sum_k (h_k - h_i,k)**2 + C3 * P1[i] + C4 * P2[i]`` over the
   survivors; the answer is the smallest ``E`` (ties: the lowest index).

When no entry survives both stages the answer is the smallest ``E`` over all
entries and the result is marked ``low_confidence``.

Implementation
--------------
:func:`search` runs one compiled loop over the entries: P1 from the packed
masks first (64 AND-NOT-popcounts), P2 only for stage-1 survivors, and the
HLAC distance (int32 arithmetic on the uint8 vectors) only for stage-2
survivors.  The penalties of all entries are computed in a first pass; the second pass
skips every survivor whose penalty plus a block-sum lower bound of its HLAC
distance exceeds the best ``E`` so far, and abandons each distance as soon
as its partial sum does; neither can change the answer.  Nothing is copied
per survivor.
:func:`search_reference` is the plain numpy statement of the same method,
kept for tests.

Beyond the paper: ``seed`` (temporal coherence) scores the previous frame's
answer first, so the early exits are tight from the first entry on; the
answer is unchanged (exact), only the time changes.  An approximate index
(faiss IVF over HLAC) for 10^5-10^6 entries is not implemented yet.

Cost: pass 1 streams both packed masks of every entry (1 KiB per entry,
20 MiB for 20,448 entries), which is memory-bound at a few hundred
microseconds per frame; pass 2 is usually smaller.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields

import numpy as np
from numba import njit

from ..db import HLAC_SIZE, count_outside
from ..errors import InvalidInputError

__all__ = ["SearchOptions", "SearchResult", "SearchTables", "search", "search_reference"]

_BLOCK = 200  # HLAC dims between early-exit checks (8 blocks of 25 patterns)
_PATTERNS = 25  # HLAC patterns per 8x8 block


@dataclass(frozen=True)
class SearchOptions:
    """Constants of the two-stage search (defaults: the paper's, SPEC.md section 1).

    Parameters
    ----------
    c : float
        Stage-1 threshold factor, ``th1 = c * A_input``.
    c1, c2 : float
        Stage-2 threshold ``th2 = c1 * A_ds**2 + c2 * A_ds``.
    c3, c4 : float
        Weights of P1 and P2 in ``E``.
    prune : bool
        ``False`` scores every entry by ``E`` without the two stages.

    Raises
    ------
    InvalidInputError
        A constant that is not a finite number >= 0, naming it; unknown
        keywords raise ``TypeError``.
    """

    c: float = 0.2
    c1: float = 0.002
    c2: float = 0.03
    c3: float = 800.0
    c4: float = 800.0
    prune: bool = True

    def __post_init__(self) -> None:
        for f in fields(self):
            v = getattr(self, f.name)
            if f.name == "prune":
                if not isinstance(v, bool):
                    raise InvalidInputError(f"SearchOptions.prune must be a bool, got {v!r}")
                continue
            if isinstance(v, bool) or not isinstance(v, (int, float, np.number)) \
                    or not math.isfinite(v) or v < 0:
                raise InvalidInputError(
                    f"SearchOptions.{f.name} must be a finite number >= 0, got {v!r}")
            object.__setattr__(self, f.name, float(v))


@dataclass(frozen=True)
class SearchResult:
    """Outcome of one search.

    Attributes
    ----------
    index : int
        Matched database entry.
    error : float
        Its ``E`` (HLAC squared distance plus the weighted penalties).
    hlac_distance : int
        Its squared HLAC distance.
    p1, p2 : int
        Its penalties (pixels).
    survivors : int
        Entries left after both pruning stages (0: fallback was used).
    low_confidence : bool
        ``True`` when pruning left nothing and the answer is the best ``E``
        over all entries.
    """

    index: int
    error: float
    hlac_distance: int
    p1: int
    p2: int
    survivors: int
    low_confidence: bool


@dataclass(frozen=True, eq=False)
class SearchTables:
    """The database columns the search reads; read-only, shared between threads.

    Parameters
    ----------
    hlac : ndarray of uint8, shape (N, 1600)
    sil_bits, ridge_bits : ndarray of uint64, shape (N, 64)
    ridge_area : ndarray, shape (N,)
        Integer ridge pixel counts (stored here as float64 for the threshold).
    block_sums : ndarray of int32, shape (N, 64)
        Sum of each 25-pattern HLAC block; gives the lower bound
        ``|h - h_i|^2 >= sum_b (s_b - s_i,b)^2 / 25`` (Cauchy-Schwarz) that
        lets the search skip most HLAC distances.  Computed by
        :meth:`from_arrays`.
    """

    hlac: np.ndarray
    sil_bits: np.ndarray
    ridge_bits: np.ndarray
    ridge_area: np.ndarray
    block_sums: np.ndarray

    @classmethod
    def from_arrays(cls, *, hlac, sil_bits, ridge_bits, ridge_area) -> SearchTables:
        """Validate and convert (C-contiguous, native dtypes, read-only)."""
        h = np.ascontiguousarray(hlac, dtype=np.uint8)
        n = h.shape[0] if h.ndim == 2 else -1
        if h.ndim != 2 or n < 1 or h.shape[1] != HLAC_SIZE:
            raise InvalidInputError(f"hlac must have shape (N, 1600), got {np.shape(hlac)}")
        s = np.ascontiguousarray(sil_bits, dtype=np.uint64)
        r = np.ascontiguousarray(ridge_bits, dtype=np.uint64)
        a = np.ascontiguousarray(ridge_area, dtype=np.float64)
        for name, arr, shape in (("sil_bits", s, (n, 64)), ("ridge_bits", r, (n, 64)),
                                 ("ridge_area", a, (n,))):
            if arr.shape != shape:
                raise InvalidInputError(f"{name} must have shape {shape}, got {arr.shape}")
        sums = _block_sums(h)
        for arr in (h, s, r, a, sums):
            arr.setflags(write=False)
        return cls(hlac=h, sil_bits=s, ridge_bits=r, ridge_area=a, block_sums=sums)

    def __len__(self) -> int:
        return self.hlac.shape[0]


def _block_sums(hlac: np.ndarray) -> np.ndarray:
    n = hlac.shape[0]
    return np.ascontiguousarray(
        hlac.reshape(n, -1, _PATTERNS).sum(axis=2, dtype=np.int32), dtype=np.int32)


@njit(cache=True, nogil=True)
def _distance_bound(q_sums, sums):
    """Lower bound of the squared HLAC distance from block sums (Cauchy-Schwarz)."""
    acc = 0
    for b in range(q_sums.shape[0]):
        diff = q_sums[b] - sums[b]
        acc += diff * diff
    return acc / _PATTERNS


@njit(cache=True, nogil=True)
def _hlac_distance(q_hlac, row, bound):
    """Squared distance (int32 arithmetic), abandoned once it exceeds `bound` (returns it then)."""
    d = 0
    n = row.shape[0]
    for start in range(0, n, _BLOCK):
        stop = min(start + _BLOCK, n)
        acc = np.int32(0)
        for k in range(start, stop):
            diff = np.int32(q_hlac[k]) - np.int32(row[k])
            acc += diff * diff
        d += acc
        if d > bound:
            return d
    return d


@njit(cache=True, nogil=True)
def _penalties(q_sil, q_ridge, sil_bits, ridge_bits, ridge_area, th1, c1, c2, c3, c4,
               prune, pen, p1s, p2s):
    """Pass 1 over all entries: P1, P2 and the pruning; pen[i] = C3 P1 + C4 P2 or -1 if pruned.

    Returns the number of survivors and the survivor with the smallest penalty.
    """
    survivors = 0
    best_i = -1
    for i in range(sil_bits.shape[0]):
        p1 = count_outside(q_ridge, sil_bits[i])
        p1s[i] = p1
        p2s[i] = -1
        pen[i] = -1.0
        if prune and p1 > th1:
            continue
        a = ridge_area[i]
        p2 = count_outside(ridge_bits[i], q_sil)
        p2s[i] = p2
        if prune and p2 > c1 * a * a + c2 * a:
            continue
        pen[i] = c3 * p1 + c4 * p2
        survivors += 1
        if best_i < 0 or pen[i] < pen[best_i]:
            best_i = i
    return survivors, best_i


@njit(cache=True, nogil=True)
def _search_kernel(q_hlac, q_sums, q_sil, q_ridge, q_area, hlac, sums, sil_bits, ridge_bits,
                   ridge_area, c, c1, c2, c3, c4, prune, seed, pen, p1s, p2s):
    """Best entry; returns (index, E, d, p1, p2, survivors, fallback).

    Pass 1 computes the penalties of every entry (:func:`_penalties`).  Pass
    2 starts from the previous answer `seed` (when it survives) or the
    survivor with the smallest penalty, then scores only survivors whose
    penalty alone does not exceed the best E so far, abandoning each HLAC
    distance as soon as it cannot win.  Ties go to the lowest index.
    """
    n = hlac.shape[0]
    survivors, first = _penalties(q_sil, q_ridge, sil_bits, ridge_bits, ridge_area, c * q_area,
                                  c1, c2, c3, c4, prune, pen, p1s, p2s)
    fallback = survivors == 0
    if fallback:  # best E over all entries
        survivors, first = _penalties(q_sil, q_ridge, sil_bits, ridge_bits, ridge_area, 0.0,
                                      c1, c2, c3, c4, False, pen, p1s, p2s)
        survivors = 0
    start = seed if seed >= 0 and pen[seed] >= 0.0 else first
    best_i = start
    best_d = _hlac_distance(q_hlac, hlac[start], np.iinfo(np.int64).max)
    best_e = best_d + pen[start]
    for i in range(n):
        p = pen[i]
        if p < 0.0 or p > best_e or i == start:
            continue
        if p + _distance_bound(q_sums, sums[i]) > best_e:
            continue
        d = _hlac_distance(q_hlac, hlac[i], best_e - p)
        e = d + p
        if e < best_e or (e == best_e and i < best_i):
            best_e, best_i, best_d = e, i, d
    return best_i, best_e, best_d, p1s[best_i], p2s[best_i], survivors, fallback


def _query(features) -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
    h = np.ascontiguousarray(features.hlac, dtype=np.uint8)
    s = np.ascontiguousarray(features.sil_bits, dtype=np.uint64)
    r = np.ascontiguousarray(features.ridge_bits, dtype=np.uint64)
    return h, s, r, float(features.ridge_area)


def search(features, tables: SearchTables, *, options: SearchOptions | None = None,
           seed: int | None = None) -> SearchResult:
    """Find the database entry of an input by the paper's two-stage pruned search.

    Parameters
    ----------
    features : handsynth.db.Features
        Features of the input silhouette (``hlac``, ``sil_bits``,
        ``ridge_bits``, ``ridge_area``).
    tables : SearchTables
        The database columns.
    options : SearchOptions, keyword-only, optional
        Paper constants by default.
    seed : int, keyword-only, optional
        An entry to score first (the previous frame's answer, temporal
        coherence): same answer, usually faster.

    Returns
    -------
    SearchResult

    Raises
    ------
    InvalidInputError
        `seed` outside ``[0, N)``.
    """
    opts = options or SearchOptions()
    n = len(tables)
    s = -1 if seed is None else int(seed)
    if not -1 <= s < n:
        raise InvalidInputError(f"seed must be an entry index in [0, {n}), got {seed!r}")
    h, sb, rb, area = _query(features)
    # per-call scratch (never shared: the search is thread-safe)
    pen = np.empty(n, np.float64)
    p1s = np.empty(n, np.int64)
    p2s = np.empty(n, np.int64)
    i, e, d, p1, p2, surv, fallback = _search_kernel(
        h, _block_sums(h[None])[0], sb, rb, area, tables.hlac, tables.block_sums,
        tables.sil_bits, tables.ridge_bits, tables.ridge_area,
        opts.c, opts.c1, opts.c2, opts.c3, opts.c4, opts.prune, s, pen, p1s, p2s)
    return SearchResult(index=int(i), error=float(e), hlac_distance=int(d), p1=int(p1),
                        p2=int(p2), survivors=int(surv), low_confidence=bool(fallback))


def search_reference(features, tables: SearchTables, *,
                     options: SearchOptions | None = None) -> SearchResult:
    """The same search written plainly with numpy (slow; the specification for tests).

    Parameters and result as :func:`search` (no `seed`).
    ``survivors`` counts the entries left after both stages.
    """
    opts = options or SearchOptions()
    h, sb, rb, area = _query(features)
    p1 = np.bitwise_count(rb[None, :] & ~tables.sil_bits).sum(axis=1)
    p2 = np.bitwise_count(tables.ridge_bits & ~sb[None, :]).sum(axis=1)
    a = tables.ridge_area
    keep = (p1 <= opts.c * area) & (p2 <= opts.c1 * a * a + opts.c2 * a)
    if not opts.prune:
        keep[:] = True
    d = ((tables.hlac.astype(np.int32) - h.astype(np.int32)) ** 2).sum(axis=1)
    e = d + (opts.c3 * p1 + opts.c4 * p2)
    fallback = not keep.any()
    pool = np.ones_like(keep) if fallback else keep
    i = int(np.flatnonzero(pool)[np.argmin(e[pool])])
    return SearchResult(index=i, error=float(e[i]), hlac_distance=int(d[i]), p1=int(p1[i]),
                        p2=int(p2[i]), survivors=0 if fallback else int(keep.sum()),
                        low_confidence=fallback)
