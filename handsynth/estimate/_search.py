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
:func:`search` is exact (same answer as :func:`search_reference`) but
scores only the few entries whose lower bound of ``E`` does not exceed the
best ``E`` found.  :meth:`SearchTables.prepare` builds, once per database:

* *Distinct rows.*  Entries whose features (HLAC, silhouette, ridge lines)
  are all equal have equal ``E`` for every input, so only the first of
  each group (the lowest index, which the tie rule picks) is searched.  In
  a 20,448-entry paper-set database about 44 % of the entries repeat
  another's features (a finger folded behind the palm is invisible from
  the dorsum).
* *Penalty bounds.*  Silhouette and ridge lines at 4x4-block resolution
  (one bit per block, 256 bits): ``P1 >= sum of the input's ridge pixels
  in blocks where the entry's silhouette has no pixel`` and ``P2 >= number
  of blocks holding an entry ridge pixel and no input silhouette pixel``.
* *HLAC bound.*  An orthonormal basis ``U`` (k = 16 principal directions
  of the HLAC vectors, by randomized subspace iteration) splits
  ``h - m = U^T p + r`` with ``r`` orthogonal to ``U``; then
  ``|h - h_i|^2 = |p - p_i|^2 + |r - r_i|^2 >= |p - p_i|^2 + (|r| - |r_i|)^2``.
  Each entry stores ``p_i`` and ``|r_i|`` (float32).  The bound is lowered
  by a relative margin of 1 % (:data:`_BOUND_MARGIN`), far more than float32
  rounding of uint8 HLAC vectors can take away, so it never exceeds the true
  distance (tested); any basis gives a valid bound, a good one a tight one.

A search then (1) scores the previous frame's answer (``seed``) if given,
(2) computes ``C3 lb1 + C4 lb2 + hlac bound`` for every distinct row in one
vectorized pass over column-major tables (140 bytes per row), dropping rows
whose penalty bounds already fail a pruning stage, (3) scores the 8 rows
with the smallest bounds, which brings the best ``E`` near its final
value, (4) scores, in layout order (:class:`_ExactIndex`), every other row
whose bound does not exceed the best ``E`` so far.  Scoring is
:func:`handsynth.estimate._score.score`, shared with the approximate index:
it counts P1, P2, then the HLAC distance with early exit, stopping as soon
as the bound with the exact penalties exceeds the best ``E``.  Nothing is
copied per entry.
``survivors`` of the result counts the entries (with their repeats) that
passed both stages among those scored (a lower bound of the total, which
:func:`search_reference` reports).  When no row passes
both stages the same steps run without pruning (the fallback).
"""

from __future__ import annotations

import math
import threading
from dataclasses import dataclass, field, fields
from typing import NamedTuple

import numpy as np
from numba import njit

from .._checks import check_integer, check_number, check_options
from ..db import HLAC_SIZE, popcount64
from ..errors import InvalidInputError
from ._score import SURVIVOR, SURVIVOR_ABOVE_BEST, Constants, Query, Rows, score

__all__ = ["SearchOptions", "SearchResult", "SearchTables", "search", "search_reference"]

_BASIS_DIMS = 16  # principal directions of the HLAC bound
_BASIS_SAMPLE = 4096  # distinct rows used to find them
_BOUND_MARGIN = 1e-2  # relative margin of the float32 HLAC bound
_TOP = 8  # rows scored first, by smallest bound
_COMPACT_MAX_BYTES = 512 * 2**20  # largest compact copy of the distinct rows


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
            object.__setattr__(self, f.name,
                               check_number(v, f"SearchOptions.{f.name}", minimum=0))


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
    tied : ndarray of int64, shape (M,), or None
        Every entry (among those that passed pruning, or all in the
        fallback) whose ``E`` equals `error`, ascending; ``index`` is the
        first.  Usually entries with the same features as ``index`` (a
        finger folded out of the camera's view); their angles differ, so
        :class:`~handsynth.estimate.PoseLookup` can report their mean.
        ``None`` where the search does not track ties (the approximate
        index).  Not compared by ``==``.
    """

    index: int
    error: float
    hlac_distance: int
    p1: int
    p2: int
    survivors: int = field(compare=False)  # diagnostic: not part of the answer
    low_confidence: bool
    tied: np.ndarray | None = field(default=None, compare=False, repr=False)


def _table(value, name: str, row_shape: tuple, top: int | None, n: int | None = None, *,
           whole_floats: bool = False) -> np.ndarray:
    """`value` as an array of shape (N,) + `row_shape` of integers in [0, `top`].

    `top` None: any non-negative integer of the dtype.  `whole_floats`:
    floats that are whole numbers are accepted too.
    """
    arr = np.asarray(value)
    ok = arr.ndim == 1 + len(row_shape) and arr.shape[1:] == row_shape and arr.shape[0] >= 1
    if not ok or (n is not None and arr.shape[0] != n):
        rows = "N" if n is None else str(n)
        raise InvalidInputError(f"{name} must have shape ({', '.join([rows, *map(str, row_shape)])}"
                                f"{',' if not row_shape else ''}), got {arr.shape}")
    if arr.dtype.kind == "f" and whole_floats:
        bad = ~np.isfinite(arr) | (arr != np.round(arr))
        if bad.any():
            i = tuple(int(v) for v in np.argwhere(bad)[0])
            raise InvalidInputError(f"{name} must hold whole numbers, got {arr[i].item()!r} at "
                                    f"index {i}")
    elif arr.dtype.kind not in "iu":
        raise InvalidInputError(f"{name} must be an integer array, got dtype {arr.dtype}")
    bad = arr < 0 if top is None else (arr < 0) | (arr > top)
    if bad.any():
        i = tuple(int(v) for v in np.argwhere(bad)[0])
        span = ">= 0" if top is None else f"in [0, {top}]"
        raise InvalidInputError(f"{name} must lie {span}, got {arr[i].item()!r} at index {i}")
    return arr


@dataclass(frozen=True, eq=False)
class SearchTables:
    """The database columns the search reads; read-only, shared between threads.

    Parameters
    ----------
    hlac : ndarray of uint8, shape (N, 1600)
    sil_bits, ridge_bits : ndarray of uint64, shape (N, 64)
    ridge_area : ndarray, shape (N,)
        Integer ridge pixel counts (stored here as float64 for the threshold).

    Notes
    -----
    The exact search's index (distinct rows and lower bounds, see the
    module docstring) is built by :meth:`prepare`, at most once, on first
    use; about 0.2 s for 20,448 entries.
    """

    hlac: np.ndarray
    sil_bits: np.ndarray
    ridge_bits: np.ndarray
    ridge_area: np.ndarray
    _index: list = field(default_factory=list, repr=False)
    _lock: threading.Lock = field(default_factory=threading.Lock, repr=False)
    _scratch: threading.local = field(default_factory=threading.local, repr=False)

    @classmethod
    def from_arrays(cls, *, hlac, sil_bits, ridge_bits, ridge_area) -> SearchTables:
        """Validate and convert (C-contiguous, native dtypes, read-only).

        Parameters
        ----------
        hlac : array_like of int, shape (N, 1600)
            Integers in [0, 255].
        sil_bits, ridge_bits : array_like of int, shape (N, 64)
            Packed masks: non-negative integers (uint64).
        ridge_area : array_like, shape (N,)
            Whole numbers of pixels in [0, 4096] (integers, or floats that
            are whole).

        Raises
        ------
        InvalidInputError
            A wrong shape, dtype or value (a value that would wrap or be
            truncated in conversion, NaN, a negative area); the message names
            the array, the first bad index and its value.
        """
        h = _table(hlac, "hlac", (HLAC_SIZE,), 255)
        n = h.shape[0]
        s = _table(sil_bits, "sil_bits", (64,), None, n)
        r = _table(ridge_bits, "ridge_bits", (64,), None, n)
        a = _table(ridge_area, "ridge_area", (), 64 * 64, n, whole_floats=True)
        h = np.ascontiguousarray(h, dtype=np.uint8)
        s = np.ascontiguousarray(s, dtype=np.uint64)
        r = np.ascontiguousarray(r, dtype=np.uint64)
        a = np.ascontiguousarray(a, dtype=np.float64)
        for table in (h, s, r, a):
            table.setflags(write=False)
        return cls(hlac=h, sil_bits=s, ridge_bits=r, ridge_area=a)

    def __len__(self) -> int:
        return self.hlac.shape[0]

    def _buffers(self, n: int) -> _Scratch:
        """Scratch arrays of one search for `n` distinct rows, reused by each thread
        (allocating them per call costs page faults of the order of the search itself)."""
        bufs = getattr(self._scratch, "bufs", None)
        if bufs is None or bufs.key.size != n:
            bufs = _Scratch(
                key=np.empty(n), lb=np.empty(n), ties=np.empty(n, np.int64),
                top=np.empty(_TOP, np.int64), lb1=np.empty(n, np.int32),
                lb2=np.empty(n, np.int32), hb=np.empty(n, np.float32))
            self._scratch.bufs = bufs
        return bufs

    def prepare(self) -> _ExactIndex:
        """Build (once, thread-safe) and return the exact search's index."""
        if not self._index:
            with self._lock:
                if not self._index:
                    self._index.append(_ExactIndex.build(self))
        return self._index[0]


@dataclass(frozen=True, eq=False)
class _ExactIndex:
    """Distinct rows of a :class:`SearchTables` and their bounds (module docstring).

    The distinct rows are laid out in *layout order*: sorted by their first
    two principal coordinates (the first in bins of 20), so that rows with
    similar HLAC vectors, which a frame's search tends to score together,
    lie together in memory (measured: a third less time per frame when the
    caches are cold).  Position ``u`` below is a place in that order.

    Attributes
    ----------
    rows : ndarray of int64, shape (U,)
        Entry index of the distinct row at ``u`` (the lowest of its group).
    group : ndarray of int64, shape (N,)
        Position of each entry's distinct row.
    sizes : ndarray of int64, shape (U,)
        Entries per distinct row.
    members, starts : ndarray of int64, shapes (N,) and (U + 1,)
        The entries of row ``u`` are ``members[starts[u]:starts[u + 1]]``,
        ascending.
    hlac : ndarray of uint8, shape (U', 1600)
    sil_bits, ridge_bits : ndarray of uint64, shape (U', 64)
    source_area : ndarray of float64, shape (U',)
        Ridge areas of the rows of the three arrays above.
    source : ndarray of int64, shape (U,)
        Row of the four arrays above holding the row at ``u``: a compact copy in
        layout order (``source = arange(U)``) when it takes at most
        :data:`_COMPACT_MAX_BYTES`, else the database's own rows.
    sil_coarse_t, ridge_coarse_t : ndarray of uint64, shape (4, U)
        Masks at 4x4-block resolution, block ``k = 16 * row + col`` at bit
        ``k % 64`` of word ``k // 64`` (word first: column-major).
    ridge_area : ndarray of float64, shape (U,)
    mean : ndarray of float64, shape (1600,)
    basis : ndarray of float64, shape (k, 1600)
        Orthonormal rows.
    proj_t : ndarray of float32, shape (k, U)
        ``basis @ (h_i - mean)``, column-major.
    resid : ndarray of float32, shape (U,)
        ``|h_i - mean - basis.T @ proj_i|``.
    arrays : tuple
        The fields of an :class:`_IndexArrays` (the arrays above the
        compiled search reads), in order, for :func:`_search_kernel`.
    """

    rows: np.ndarray
    group: np.ndarray
    sizes: np.ndarray
    members: np.ndarray
    starts: np.ndarray
    hlac: np.ndarray
    sil_bits: np.ndarray
    ridge_bits: np.ndarray
    source_area: np.ndarray
    source: np.ndarray
    sil_coarse_t: np.ndarray
    ridge_coarse_t: np.ndarray
    ridge_area: np.ndarray
    mean: np.ndarray
    basis: np.ndarray
    proj_t: np.ndarray
    resid: np.ndarray
    arrays: tuple = field(init=False, repr=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "arrays", tuple(_IndexArrays(
            **{name: getattr(self, name) for name in _IndexArrays._fields})))

    @classmethod
    def build(cls, tables: SearchTables) -> _ExactIndex:
        h64 = tables.hlac.view(np.uint64)
        hashes = _row_hashes(h64, tables.sil_bits, tables.ridge_bits)
        first = _first_equal(h64, tables.sil_bits, tables.ridge_bits,
                             np.argsort(hashes, kind="stable"), hashes)
        distinct = np.flatnonzero(first == np.arange(len(first)))
        mean, basis = _hlac_basis(tables.hlac, distinct)
        proj, resid = _project_rows(tables.hlac, distinct, mean, basis)
        layout = np.lexsort((proj[:, 1], np.round(proj[:, 0] / 20.0))) if proj.shape[1] >= 2 \
            else np.arange(distinct.size)
        rows, proj, resid = distinct[layout], proj[layout], resid[layout]
        position = np.empty(len(first), np.int64)
        position[rows] = np.arange(rows.size)
        group = position[first]
        sizes = np.bincount(group, minlength=rows.size)
        compact = rows.size * (HLAC_SIZE + 128 * 8) <= _COMPACT_MAX_BYTES
        source = np.arange(rows.size) if compact else rows  # else read the database's rows
        ridge_area = np.ascontiguousarray(tables.ridge_area[rows])
        out = cls(rows=rows, group=group, sizes=sizes, members=np.argsort(group, kind="stable"),
                  starts=np.concatenate([[0], np.cumsum(sizes)]),
                  hlac=tables.hlac[rows] if compact else tables.hlac,
                  sil_bits=tables.sil_bits[rows] if compact else tables.sil_bits,
                  ridge_bits=tables.ridge_bits[rows] if compact else tables.ridge_bits,
                  source_area=ridge_area if compact else tables.ridge_area, source=source,
                  sil_coarse_t=_coarse_presence_rows(tables.sil_bits, rows).T.copy(),
                  ridge_coarse_t=_coarse_presence_rows(tables.ridge_bits, rows).T.copy(),
                  ridge_area=ridge_area, mean=mean,
                  basis=basis, proj_t=np.ascontiguousarray(proj.T, dtype=np.float32),
                  resid=resid.astype(np.float32))
        for f in fields(out):
            if f.name != "arrays":
                getattr(out, f.name).setflags(write=False)
        return out

    def entries_of(self, rows: np.ndarray) -> np.ndarray:
        """All entries of distinct rows at positions `rows`, ascending."""
        if rows.size == 1:
            u = rows[0]
            return self.members[self.starts[u]:self.starts[u + 1]].copy()
        return np.sort(np.concatenate([self.members[self.starts[u]:self.starts[u + 1]]
                                       for u in rows]))


@njit(cache=True, nogil=True)
def _row_hashes(h64, sil_bits, ridge_bits):
    """A 64-bit hash (FNV-1a over words) of each entry's features."""
    prime = np.uint64(1099511628211)
    out = np.empty(h64.shape[0], np.uint64)
    for i in range(h64.shape[0]):
        x = np.uint64(14695981039346656037)
        for w in range(h64.shape[1]):
            x = (x ^ h64[i, w]) * prime
        for w in range(sil_bits.shape[1]):
            x = (x ^ sil_bits[i, w]) * prime
            x = (x ^ ridge_bits[i, w]) * prime
        out[i] = x
    return out


@njit(cache=True, nogil=True)
def _same_row(h64, sil_bits, ridge_bits, i, j):
    for w in range(h64.shape[1]):
        if h64[i, w] != h64[j, w]:
            return False
    for w in range(sil_bits.shape[1]):
        if sil_bits[i, w] != sil_bits[j, w] or ridge_bits[i, w] != ridge_bits[j, w]:
            return False
    return True


@njit(cache=True, nogil=True)
def _first_equal(h64, sil_bits, ridge_bits, order, hashes):
    """Per entry, the lowest index of an entry with equal features.

    `order` sorts the entries by hash, ascending index within equal hashes;
    rows of a run of equal hashes are compared word by word.
    """
    n = order.shape[0]
    first = np.empty(n, np.int64)
    k = 0
    while k < n:
        m = k + 1
        while m < n and hashes[order[m]] == hashes[order[k]]:
            m += 1
        for a in range(k, m):
            i = order[a]
            first[i] = i
            for b in range(k, a):
                j = order[b]
                if first[j] == j and _same_row(h64, sil_bits, ridge_bits, i, j):
                    first[i] = j
                    break
        k = m
    return first


def _hlac_basis(hlac: np.ndarray, rows: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Mean and orthonormal principal directions of the HLAC vectors of `rows`.

    Randomized subspace iteration with two power steps (N. Halko,
    P.-G. Martinsson and J. A. Tropp, "Finding structure with randomness",
    SIAM Review 53(2), 2011, algorithm 4.4) on at most 4,096 evenly spaced
    rows; deterministic (fixed generator seed).
    """
    pick = rows[np.unique(np.linspace(0, rows.size - 1, min(rows.size, _BASIS_SAMPLE))
                          .astype(np.int64))]
    x = hlac[pick].astype(np.float64)
    mean = x.mean(axis=0)
    x -= mean
    k = min(_BASIS_DIMS, x.shape[0] - 1)
    if k <= 0:
        return mean, np.zeros((0, HLAC_SIZE))
    q = x.T @ (x @ np.random.default_rng(0).standard_normal((HLAC_SIZE, k + 8)))
    for _ in range(3):
        q = np.linalg.qr(q)[0]
        q = x.T @ (x @ q)
    q = np.linalg.qr(q)[0]
    vt = np.linalg.svd(x @ q, full_matrices=False)[2]
    basis = np.ascontiguousarray((q @ vt.T).T[:k])
    return mean, basis


def _project_rows(hlac, rows, mean, basis, chunk: int = 8192):
    """``proj`` and ``resid`` of :class:`_ExactIndex` for `rows`, in chunks."""
    proj = np.empty((rows.size, basis.shape[0]))
    resid = np.empty(rows.size)
    for s in range(0, rows.size, chunk):
        x = hlac[rows[s:s + chunk]].astype(np.float64) - mean
        p = x @ basis.T
        x -= p @ basis
        proj[s:s + chunk] = p
        resid[s:s + chunk] = np.sqrt(np.einsum("ij,ij->i", x, x))
    return proj, resid


@njit(cache=True, nogil=True, fastmath={"reassoc", "contract"})
def _query_projection(q_hlac, mean, basis):
    """``(p, |r|)`` of the input's HLAC vector (see :class:`_ExactIndex`)."""
    k, n = basis.shape
    qc = np.empty(n)
    total = 0.0
    for j in range(n):
        qc[j] = q_hlac[j] - mean[j]
        total += qc[j] * qc[j]
    p = np.empty(k)
    explained = 0.0
    for a in range(k):
        s = 0.0
        for j in range(n):
            s += basis[a, j] * qc[j]
        p[a] = s
        explained += s * s
    return p, math.sqrt(max(total - explained, 0.0))


@njit(cache=True, nogil=True)
def _block_counts(bits):
    """Pixels per 4x4 block (16, 16) of a packed 64x64 mask."""
    counts = np.zeros((16, 16), np.int64)
    for r in range(64):
        w = bits[r]
        for cx in range(16):
            counts[r >> 2, cx] += popcount64((w >> np.uint64(4 * cx)) & np.uint64(15))
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
def _coarse_presence_rows(bits, rows):
    out = np.empty((rows.shape[0], 4), np.uint64)
    for u in range(rows.shape[0]):
        out[u] = _pack_blocks(_block_counts(bits[rows[u]]) > 0)
    return out


@njit(cache=True, nogil=True)
def _count_planes(bits):
    """Bit planes (5, 4) of the per-block pixel counts (0..16) of a packed mask."""
    counts = _block_counts(bits)
    planes = np.empty((5, 4), np.uint64)
    for k in range(5):
        planes[k] = _pack_blocks(((counts >> k) & 1) == 1)
    return planes


class _QueryBounds(NamedTuple):
    """The input's side of the lower bounds of :func:`_bounds`.

    Attributes
    ----------
    planes : ndarray of uint64, shape (5, 4)
        Bit planes of the input's ridge pixels per 4x4 block (:func:`_count_planes`).
    sil_coarse : ndarray of uint64, shape (4,)
        Blocks holding an input silhouette pixel.
    proj : ndarray of float64, shape (k,)
        ``p``, the input's HLAC vector on the basis.
    resid : float
        ``|r|``, the length of the rest.
    """

    planes: np.ndarray
    sil_coarse: np.ndarray
    proj: np.ndarray
    resid: float


class _IndexArrays(NamedTuple):
    """The arrays of an :class:`_ExactIndex` that the compiled search reads (same names)."""

    hlac: np.ndarray
    sil_bits: np.ndarray
    ridge_bits: np.ndarray
    source_area: np.ndarray
    source: np.ndarray
    rows: np.ndarray
    sizes: np.ndarray
    sil_coarse_t: np.ndarray
    ridge_coarse_t: np.ndarray
    ridge_area: np.ndarray
    mean: np.ndarray
    basis: np.ndarray
    proj_t: np.ndarray
    resid: np.ndarray


class _Scratch(NamedTuple):
    """Scratch arrays of one search (:meth:`SearchTables._buffers`), U distinct rows.

    Attributes
    ----------
    key, lb : ndarray of float64, shape (U,)
        Penalty bound and lower bound of ``E`` per row (:func:`_bounds`).
    ties : ndarray of int64, shape (U,)
        Rows tied with the best.
    top : ndarray of int64, shape (8,)
        Rows with the smallest bounds.
    lb1, lb2 : ndarray of int32, shape (U,)
        Lower bounds of P1 and P2.
    hb : ndarray of float32, shape (U,)
        Lower bound of the squared HLAC distance before the margin.
    """

    key: np.ndarray
    lb: np.ndarray
    ties: np.ndarray
    top: np.ndarray
    lb1: np.ndarray
    lb2: np.ndarray
    hb: np.ndarray


@njit(cache=True, nogil=True, fastmath={"reassoc", "contract"})
def _bounds(qb, ix, k, cap, s):
    """Pass over the distinct rows: bounds, and the rows with the smallest ones.

    Parameters
    ----------
    qb : _QueryBounds
    ix : _IndexArrays
    k : Constants
    cap : float
        A known ``E``: rows whose bound exceeds it are left out.
    s : _Scratch
        Receives ``key``, ``lb`` and ``top``; ``lb1``, ``lb2``, ``hb`` are
        working space.

    Returns
    -------
    int
        Rows in ``s.top``.

    Notes
    -----
    ``key[u] = C3 lb1 + C4 lb2`` (-1 when a penalty bound already fails a
    pruning stage); ``lb[u] = key[u] + HLAC bound``, a lower bound of E (inf
    when the row fails pruning or the bound exceeds `cap`).  ``top``
    receives the rows with the smallest ``lb``, ascending (ties: the first
    row first).  The tables are column-major (word or dimension first) so
    that the loops over rows vectorize; ``key`` and ``lb`` are written in a
    pass without branches, which vectorizes too, and the top rows found in a
    second pass where a row seldom enters (the two in one branching pass,
    measured on 2026-11-27: this pass 0.077 against 0.063-0.067 ms and the
    search 0.18-0.19 against 0.16-0.17 ms for 11,434 distinct rows, one
    process; in alternating runs of the whole lookup its part after
    preprocessing 0.28-0.38 against 0.24-0.32 ms).
    """
    sil_coarse_t, ridge_coarse_t, proj_t = ix.sil_coarse_t, ix.ridge_coarse_t, ix.proj_t
    key, lb, top, lb1, lb2, hb = s.key, s.lb, s.top, s.lb1, s.lb2, s.hb
    n = sil_coarse_t.shape[1]
    lb1[:] = 0
    lb2[:] = 0
    hb[:] = 0.0
    for plane in range(qb.planes.shape[0]):
        for w in range(4):
            qw = qb.planes[plane, w]
            if qw == 0:
                continue
            col = sil_coarse_t[w]
            for u in range(n):
                lb1[u] += np.int32(popcount64(qw & ~col[u])) << plane
    for w in range(4):
        qw = ~qb.sil_coarse[w]
        col = ridge_coarse_t[w]
        for u in range(n):
            lb2[u] += np.int32(popcount64(col[u] & qw))
    for j in range(proj_t.shape[0]):
        qj = np.float32(qb.proj[j])
        col32 = proj_t[j]
        for u in range(n):
            t = col32[u] - qj
            hb[u] += t * t
    qr = np.float32(qb.resid)
    resid = ix.resid
    for u in range(n):
        t = resid[u] - qr
        hb[u] += t * t
    ridge_area = ix.ridge_area
    th1, c1, c2, c3, c4, prune = k.th1, k.c1, k.c2, k.c3, k.c4, k.prune
    for u in range(n):  # without branches, so that it vectorizes
        a = ridge_area[u]
        ok = not prune or (lb1[u] <= th1 and lb2[u] <= c1 * a * a + c2 * a)
        kk = c3 * lb1[u] + c4 * lb2[u]
        d = np.float64(hb[u])
        b = kk + max(d - _BOUND_MARGIN * (1.0 + d), 0.0)
        key[u] = kk if ok else -1.0
        lb[u] = b if ok and b <= cap else np.inf
    # the rows with the smallest bounds, in row order (ties: the first row first)
    ntop = 0
    ntop_max = top.shape[0]
    last = np.inf  # the largest bound in a full top, else inf: any finite bound enters
    for u in range(n):
        b = lb[u]
        if b < last or (ntop < ntop_max and b != np.inf):
            pos = ntop if ntop < ntop_max else ntop_max - 1
            while pos > 0 and lb[top[pos - 1]] > b:
                top[pos] = top[pos - 1]
                pos -= 1
            top[pos] = u
            if ntop < ntop_max:
                ntop += 1
            if ntop == ntop_max:
                last = lb[top[ntop_max - 1]]
    return ntop


@njit(cache=True, nogil=True)
def _best(query, qb, ix, constants, seed, s):
    """Best distinct row over the rows that pass pruning (all when ``prune`` is False).

    Parameters
    ----------
    query : tuple
        The fields of a :class:`Query`, in order.
    qb : _QueryBounds
    ix : _IndexArrays
    constants : tuple
        The fields of a :class:`Constants`, in order.
    seed : int
        Position of a row to score first, or -1.
    s : _Scratch

    Returns
    -------
    tuple
        (row, E, d, p1, p2, scored survivors, number of tied rows); row -1
        when none passes.  ``s.ties[:n]`` receives the rows whose E equals
        the best (the best row among them), in no particular order.

    Notes
    -----
    The groups that :func:`score` reads in the loop are named here, in this
    function: named tuples received as arguments cost a reference count
    update per field per call in the loop (measured: a quarter slower).
    """
    q = Query(*query)
    k = Constants(*constants)
    table = Rows(ix.hlac, ix.sil_bits, ix.ridge_bits, ix.source_area)
    rows, sizes, source, lb, key, ties = ix.rows, ix.sizes, ix.source, s.lb, s.key, s.ties
    best_u, best_e, best_d, best_p1, best_p2 = -1, np.inf, 0, 0, 0
    survivors = 0
    nties = 0
    if seed >= 0:
        st, e, d, p1, p2 = score(source[seed], 0.0, np.inf, q, table, k)
        if st == SURVIVOR:
            best_u, best_e, best_d, best_p1, best_p2 = seed, e, d, p1, p2
            survivors += sizes[seed]
            ties[0] = seed
            nties = 1
    ntop = _bounds(qb, ix, k, best_e, s)
    if seed >= 0:
        lb[seed] = np.inf  # scored
    top = s.top
    for t in range(ntop + rows.shape[0]):
        # the rows with the smallest bounds first, then every row that may still win
        u = top[t] if t < ntop else t - ntop
        if lb[u] > best_e or lb[u] == np.inf:  # cannot win, pruned or scored
            continue
        hl_bound = lb[u] - key[u]
        lb[u] = np.inf  # scored
        st, e, d, p1, p2 = score(source[u], hl_bound, best_e, q, table, k)
        if st < SURVIVOR_ABOVE_BEST:
            continue
        survivors += sizes[u]
        if st != SURVIVOR:
            continue
        if e < best_e:
            best_u, best_e, best_d, best_p1, best_p2 = u, e, d, p1, p2
            ties[0] = u
            nties = 1
        else:  # e == best_e, exact: early exits only drop rows above best_e
            ties[nties] = u
            nties += 1
            if rows[u] < rows[best_u]:  # ties: the lowest entry index
                best_u, best_d, best_p1, best_p2 = u, d, p1, p2
    return best_u, best_e, best_d, best_p1, best_p2, survivors, nties


@njit(cache=True, nogil=True)
def _search_kernel(query, q_area, index, constants, seed, scratch):
    """Best entry of the exact search.

    Parameters
    ----------
    query : tuple
        The fields of a :class:`Query`, in order.
    q_area : float
        ``A_input``, pixels.
    index : tuple
        The fields of an :class:`_IndexArrays`, in order
        (:attr:`_ExactIndex.arrays`).
    constants : tuple
        ``(c, c1, c2, c3, c4, prune)`` of :class:`SearchOptions`.
    seed : int
        Position of a row to score first, or -1.
    scratch : tuple
        The fields of a :class:`_Scratch`, in order.

    Returns
    -------
    tuple
        (entry, E, d, p1, p2, survivors, fallback, tied rows).

    Notes
    -----
    The groups arrive as plain tuples (cheap to dispatch from Python) and
    are named here.
    """
    q = Query(*query)
    ix = _IndexArrays(*index)
    s = _Scratch(*scratch)
    c, c1, c2, c3, c4, prune = constants
    q_sil_coarse = _pack_blocks(_block_counts(q.sil_bits) > 0)
    q_proj, q_resid = _query_projection(q.hlac, ix.mean, ix.basis)
    qb = _QueryBounds(_count_planes(q.ridge_bits), q_sil_coarse, q_proj, q_resid)
    u, e, d, p1, p2, surv, nt = _best(query, qb, ix, (c * q_area, c1, c2, c3, c4, prune), seed,
                                      s)
    if u >= 0:
        return ix.rows[u], e, d, p1, p2, surv, False, nt
    u, e, d, p1, p2, surv, nt = _best(query, qb, ix, (0.0, c1, c2, c3, c4, False), seed, s)
    return ix.rows[u], e, d, p1, p2, 0, True, nt


def _query(features) -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
    missing = [k for k in ("hlac", "sil_bits", "ridge_bits", "ridge_area")
               if not hasattr(features, k)]
    if missing:
        raise InvalidInputError(
            "features must be the Features of a silhouette (handsynth.db.extract_features), "
            f"got {type(features).__name__} without {', '.join(missing)}")
    h = np.ascontiguousarray(features.hlac, dtype=np.uint8)
    s = np.ascontiguousarray(features.sil_bits, dtype=np.uint64)
    r = np.ascontiguousarray(features.ridge_bits, dtype=np.uint64)
    for name, arr, shape in (("hlac", h, (HLAC_SIZE,)), ("sil_bits", s, (64,)),
                             ("ridge_bits", r, (64,))):
        if arr.shape != shape:
            raise InvalidInputError(f"features.{name} must have shape {shape}, got {arr.shape}")
    return h, s, r, float(features.ridge_area)


def _check_search_arguments(tables, options):
    """`options` (None: the paper's), after checking it and `tables`."""
    if not isinstance(tables, SearchTables):
        raise InvalidInputError(f"tables must be SearchTables (SearchTables.from_arrays), got "
                                f"{type(tables).__name__}")
    return check_options(options, SearchOptions)


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
        `seed` outside ``[0, N)``; `features`, `tables` or `options` of the
        wrong type (naming it).
    """
    opts = _check_search_arguments(tables, options)
    n = len(tables)
    s = -1 if seed is None else check_integer(seed, "seed", minimum=0)
    if not -1 <= s < n:
        raise InvalidInputError(f"seed must be an entry index in [0, {n}), got {seed!r}")
    h, sb, rb, area = _query(features)
    ix = tables.prepare()
    scratch = tables._buffers(ix.rows.size)
    i, e, d, p1, p2, surv, fallback, nt = _search_kernel(
        (h, sb, rb), area, ix.arrays, (opts.c, opts.c1, opts.c2, opts.c3, opts.c4, opts.prune),
        -1 if s < 0 else int(ix.group[s]), tuple(scratch))
    return SearchResult(index=int(i), error=float(e), hlac_distance=int(d), p1=int(p1),
                        p2=int(p2), survivors=int(surv), low_confidence=bool(fallback),
                        tied=ix.entries_of(scratch.ties[:nt]))


def search_reference(features, tables: SearchTables, *,
                     options: SearchOptions | None = None) -> SearchResult:
    """The same search written plainly with numpy (slow; the specification for tests).

    Parameters and result as :func:`search` (no `seed`).
    ``survivors`` counts the entries left after both stages.
    """
    opts = _check_search_arguments(tables, options)
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
                        low_confidence=fallback, tied=np.flatnonzero(pool & (e == e[i])))
