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
:func:`search` is exact (same answer as :func:`search_reference`) but reads
far less than every entry's masks.  Each entry also carries its silhouette
and ridge lines at 4x4-block resolution (one bit per block, 256 bits), and
the input its ridge pixel count per block.  These give lower bounds that
never exceed the true penalties:

* ``P1 >= sum of the input's ridge pixels in blocks where the entry's
  silhouette has no pixel``;
* ``P2 >= number of blocks holding an entry ridge pixel and no input
  silhouette pixel``.

A first pass over these 64-byte summaries drops every entry whose bound
already fails a pruning stage and keeps ``C3 lb1 + C4 lb2`` as a lower bound
of its penalty.  The entry with the smallest bound (or the previous frame's
answer, ``seed``) is scored first; then, in index order, an entry is scored
exactly only when its bound does not exceed the best ``E`` so far: P1 (its
popcount abandoned as soon as it fails stage 1 or alone exceeds the best E),
P2, then the HLAC distance with its block-sum lower bound and early exit.
Ties go to the lowest index.  When no entry passes both stages the same
pass runs without pruning (the fallback).  Nothing is copied per entry.
``survivors`` of the result counts the entries that passed both stages
among those scored exactly (a lower bound of the total, which
:func:`search_reference` reports).

Cost: the first pass reads 64 bytes per entry (1.3 MB for 20,448
entries); the exact scoring touches a few hundred entries per frame.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, fields

import numpy as np
from numba import njit

from ..db import HLAC_SIZE, count_outside
from ..db._bits import _popcount64
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
        :func:`search` counts only the survivors it scored (a lower bound
        of the total; it skips entries that cannot win),
        :func:`search_reference` all of them.  Not compared by ``==``.
    low_confidence : bool
        ``True`` when pruning left nothing and the answer is the best ``E``
        over all entries.
    """

    index: int
    error: float
    hlac_distance: int
    p1: int
    p2: int
    survivors: int = field(compare=False)  # diagnostic: not part of the answer
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
    sil_coarse, ridge_coarse : ndarray of uint64, shape (N, 4)
        Silhouette and ridge lines at 4x4-block resolution, one bit per
        block (set when the block holds a pixel), 16x16 blocks in row-major
        order, bit ``k % 64`` of word ``k // 64``.  Computed by
        :meth:`from_arrays`.
    """

    hlac: np.ndarray
    sil_bits: np.ndarray
    ridge_bits: np.ndarray
    ridge_area: np.ndarray
    block_sums: np.ndarray
    sil_coarse: np.ndarray
    ridge_coarse: np.ndarray

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
        sc, rc = _coarse_presence_batch(s), _coarse_presence_batch(r)
        for arr in (h, s, r, a, sums, sc, rc):
            arr.setflags(write=False)
        return cls(hlac=h, sil_bits=s, ridge_bits=r, ridge_area=a, block_sums=sums,
                   sil_coarse=sc, ridge_coarse=rc)

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
def _block_counts(bits):
    """Pixels per 4x4 block (16, 16) of a packed 64x64 mask."""
    counts = np.zeros((16, 16), np.int64)
    for r in range(64):
        w = bits[r]
        for cx in range(16):
            counts[r >> 2, cx] += _popcount64((w >> np.uint64(4 * cx)) & np.uint64(15))
    return counts


@njit(cache=True, nogil=True)
def _pack_blocks(flags):
    """(16, 16) bool -> (4,) uint64, block k = 16 * row + col at bit k % 64 of word k // 64."""
    out = np.zeros(4, np.uint64)
    for cy in range(16):
        for cx in range(16):
            if flags[cy, cx]:
                k = 16 * cy + cx
                out[k >> 6] |= np.uint64(1) << np.uint64(k & 63)
    return out


@njit(cache=True, nogil=True)
def _coarse_presence_batch(bits):
    out = np.empty((bits.shape[0], 4), np.uint64)
    for i in range(bits.shape[0]):
        out[i] = _pack_blocks(_block_counts(bits[i]) > 0)
    return out


@njit(cache=True, nogil=True)
def _count_planes(bits):
    """Bit planes (5, 4) of the per-block pixel counts (0..16) of a packed mask."""
    counts = _block_counts(bits)
    planes = np.empty((5, 4), np.uint64)
    for k in range(5):
        planes[k] = _pack_blocks(((counts >> k) & 1) == 1)
    return planes


@njit(cache=True, nogil=True)
def _count_outside_limited(a_bits, b_bits, limit):
    """``count_outside(a_bits, b_bits)``, abandoned (returned) once it exceeds `limit`."""
    total = 0
    for r in range(a_bits.shape[0]):
        total += _popcount64(a_bits[r] & ~b_bits[r])
        if total > limit:
            return total
    return total


@njit(cache=True, nogil=True)
def _bounds(q_planes, q_sil_coarse, sil_coarse, ridge_coarse, ridge_area, th1, c1, c2, c3, c4,
            prune, key):
    """Pass 1: key[i] = C3 lb1 + C4 lb2 (a lower bound of the penalty), -1 when a bound
    already fails a pruning stage.  Returns the entry with the smallest key (-1: none)."""
    best = -1
    for i in range(sil_coarse.shape[0]):
        lb1 = 0
        for k in range(5):
            for w in range(4):
                lb1 += _popcount64(q_planes[k, w] & ~sil_coarse[i, w]) << k
        key[i] = -1.0
        if prune and lb1 > th1:
            continue
        lb2 = 0
        for w in range(4):
            lb2 += _popcount64(ridge_coarse[i, w] & ~q_sil_coarse[w])
        a = ridge_area[i]
        if prune and lb2 > c1 * a * a + c2 * a:
            continue
        key[i] = c3 * lb1 + c4 * lb2
        if best < 0 or key[i] < key[best]:
            best = i
    return best


@njit(cache=True, nogil=True)
def _score(i, q_hlac, q_sums, q_sil, q_ridge, hlac, sums, sil_bits, ridge_bits, ridge_area,
           th1, c1, c2, c3, c4, prune, best_e):
    """Entry i against the best E so far: (status, E, d, p1, p2).

    status 0: fails pruning; 1: passes both stages, E exact or, when it
    cannot beat `best_e`, some value above it; 2: cannot beat `best_e`,
    abandoned before its stage-1 test was decided.
    """
    limit = th1 if prune else np.inf
    if c3 > 0.0:
        limit = min(limit, best_e / c3)
    p1 = _count_outside_limited(q_ridge, sil_bits[i], limit)
    if prune and p1 > th1:
        return 0, 0.0, 0, p1, 0
    pen = c3 * p1
    if pen > best_e:
        return 2, pen, 0, p1, 0
    p2 = count_outside(ridge_bits[i], q_sil)
    a = ridge_area[i]
    if prune and p2 > c1 * a * a + c2 * a:
        return 0, 0.0, 0, p1, p2
    pen += c4 * p2
    if pen > best_e or pen + _distance_bound(q_sums, sums[i]) > best_e:
        return 1, np.inf, 0, p1, p2
    d = _hlac_distance(q_hlac, hlac[i], best_e - pen)
    return 1, d + pen, d, p1, p2


@njit(cache=True, nogil=True)
def _best(q_hlac, q_sums, q_sil, q_ridge, q_planes, q_sil_coarse, hlac, sums, sil_bits,
          ridge_bits, ridge_area, sil_coarse, ridge_coarse, th1, c1, c2, c3, c4, prune, seed, key):
    """Best entry over the entries that pass pruning (all when `prune` is False).

    Returns (index, E, d, p1, p2, scored survivors); index -1 when none passes.
    """
    first = _bounds(q_planes, q_sil_coarse, sil_coarse, ridge_coarse, ridge_area, th1, c1, c2,
                    c3, c4, prune, key)
    best_i, best_e, best_d, best_p1, best_p2 = -1, np.inf, 0, 0, 0
    survivors = 0
    start = seed if seed >= 0 and key[seed] >= 0.0 else first
    if start >= 0:
        st, e, d, p1, p2 = _score(start, q_hlac, q_sums, q_sil, q_ridge, hlac, sums, sil_bits,
                                  ridge_bits, ridge_area, th1, c1, c2, c3, c4, prune, np.inf)
        if st == 1:
            best_i, best_e, best_d, best_p1, best_p2 = start, e, d, p1, p2
            survivors += 1
    for i in range(sil_coarse.shape[0]):
        k = key[i]
        if k < 0.0 or k > best_e or i == start:
            continue
        st, e, d, p1, p2 = _score(i, q_hlac, q_sums, q_sil, q_ridge, hlac, sums, sil_bits,
                                  ridge_bits, ridge_area, th1, c1, c2, c3, c4, prune, best_e)
        if st != 1:
            continue
        survivors += 1
        if e < best_e or (e == best_e and i < best_i):
            best_i, best_e, best_d, best_p1, best_p2 = i, e, d, p1, p2
    return best_i, best_e, best_d, best_p1, best_p2, survivors


@njit(cache=True, nogil=True)
def _search_kernel(q_hlac, q_sums, q_sil, q_ridge, q_area, hlac, sums, sil_bits, ridge_bits,
                   ridge_area, sil_coarse, ridge_coarse, c, c1, c2, c3, c4, prune, seed, key):
    """Best entry; returns (index, E, d, p1, p2, survivors, fallback)."""
    q_planes = _count_planes(q_ridge)
    q_sil_coarse = _pack_blocks(_block_counts(q_sil) > 0)
    i, e, d, p1, p2, surv = _best(q_hlac, q_sums, q_sil, q_ridge, q_planes, q_sil_coarse, hlac,
                                  sums, sil_bits, ridge_bits, ridge_area, sil_coarse,
                                  ridge_coarse, c * q_area, c1, c2, c3, c4, prune, seed, key)
    if i >= 0:
        return i, e, d, p1, p2, surv, False
    i, e, d, p1, p2, surv = _best(q_hlac, q_sums, q_sil, q_ridge, q_planes, q_sil_coarse, hlac,
                                  sums, sil_bits, ridge_bits, ridge_area, sil_coarse,
                                  ridge_coarse, 0.0, c1, c2, c3, c4, False, seed, key)
    return i, e, d, p1, p2, 0, True


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
    key = np.empty(n, np.float64)  # per-call scratch (never shared: the search is thread-safe)
    i, e, d, p1, p2, surv, fallback = _search_kernel(
        h, _block_sums(h[None])[0], sb, rb, area, tables.hlac, tables.block_sums,
        tables.sil_bits, tables.ridge_bits, tables.ridge_area, tables.sil_coarse,
        tables.ridge_coarse, opts.c, opts.c1, opts.c2, opts.c3, opts.c4, opts.prune, s, key)
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
