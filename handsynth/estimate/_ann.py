"""Approximate search for large databases (10^5-10^6 entries): inverted lists over HLAC.

Beyond the paper (SPEC.md section 1, "Search"), switchable and compared
against the exact search of :mod:`handsynth.estimate._search`.

Method
------
An inverted-file (IVF) index chooses *which* entries are scored; the
scoring itself is the paper's, unchanged:

1. **Coarse quantizer.**  The 1600-dimensional HLAC vectors are projected
   onto their first ``dims`` principal directions, ``y = A h`` (PCA trained
   by faiss on a float32 sample of the database), and the projections are
   clustered by k-means (faiss) into ``nlist`` cells.  Each entry belongs to
   the cell of its nearest centroid; the entries of a cell form its inverted
   list (entry indices, ascending).
2. **Probe.**  A query's HLAC is projected the same way and the ``nprobe``
   cells with the nearest centroids are chosen.
3. **Exact scoring of the candidates.**  Among the entries of the probed
   lists the answer is the paper's: the smallest
   ``E = |h - h_i|^2 + C3 P1 + C4 P2`` over the candidates that pass both
   stages (P1, P2 pruning), ties to the lowest entry index.  Most
   candidates are never read: the rows of ``A`` are orthonormal, so
   ``|h - h_i|^2 >= |A h - A h_i|^2 / g`` (``g`` the largest eigenvalue of
   ``A A^T`` for the stored float32 ``A``, 1 up to rounding).  ``A h_i`` is
   kept as int16 codes with a per-dimension step, stored cell by cell; the
   bound subtracts half a step from each coordinate difference, so it stays
   a true lower bound and skipping by it never changes the answer.  The
   codes of the probed cells are streamed once; the candidates with the
   smallest bounds are scored until one survives the pruning, then every
   candidate whose bound does not exceed the best E so far is scored by
   the exact search's compiled scoring function
   (:func:`handsynth.estimate._score.score`: P1, P2 from the packed masks,
   HLAC distance in int32 with early abandon).
4. **Widening and fallback.**  When no candidate survives both stages,
   the probe doubles (next-nearest cells) up to ``max_nprobe`` cells.  If
   still none survives, the answer is the smallest ``E`` over the
   candidates, marked ``low_confidence`` (the exact search does the same
   over all entries).

   At most ``max_scored`` candidates are scored exactly per query (once
   one survives): frames of compact poses (a fist seen from the back) can
   have tens of thousands of near-identical candidates whose HLAC
   differences lie outside the PCA subspace, so the bound cannot skip
   them; the cap keeps such frames at a few milliseconds.

Consequences: with ``nprobe >= nlist`` and ``max_scored=None`` the
candidates are all entries and the answer equals the exact search's (the
same :class:`SearchResult`; ``survivors``, not compared by ``==``, counts
the survivors among the candidates scored).  Otherwise the answer's ``E``
is never smaller than the exact one's, except when the approximate answer
is a fallback (``low_confidence``) while the exact search found survivors;
with ``max_nprobe=None`` (the default: widen up to every cell before
falling back) that case cannot happen.

Why not "the k nearest by HLAC, then E": scoring the whole probed lists by
``E`` costs little more (the bound skips nearly all of them) and its
candidates include the k HLAC-nearest entries of those lists, so its
answer is never worse.

Memory
------
The index keeps no copy of the database rows.  For ``N`` entries it holds
the int16 codes (``2 * dims`` bytes per entry: 128 MB for 10^6 entries at
``dims=64``), the list order and its inverse (8 bytes per entry), ``A``
(``dims x 1600``, float32 and float64) and the centroids (``nlist x dims``
float64).  Per query it allocates 16 bytes and one flag per candidate.
Building it converts at most ``train_size`` rows to float32 for training
and keeps the float64 projections of all entries until they are quantised
(``8 * dims`` bytes per entry, 512 MB for 10^6 entries at ``dims=64``).

Persistence
-----------
:meth:`ApproximateIndex.open` keeps the trained index next to the database
file as ``<database>.ann.npz`` (written to a temporary name, fsynced and
renamed).  The file is keyed by the database file's checksum (which covers all its
datasets) together with a hash of a sample of the rows in memory -- or, for
a database without a file, a SHA-256 of all searched columns (HLAC, packed
masks, ridge areas) -- and by the build options and the seed; a file with
another key (another or a rebuilt database, other options) is rebuilt and
replaced.
"""

from __future__ import annotations

import copy
import hashlib
import json
import math
import zipfile
import zlib
from dataclasses import asdict, dataclass, fields, replace
from pathlib import Path
from typing import NamedTuple

import numpy as np
from numba import njit

from .._checks import check_integer, check_options
from .._io import atomic_open
from ..db import HLAC_SIZE
from ..errors import DatabaseError, InvalidInputError
from ._score import SURVIVOR, SURVIVOR_ABOVE_BEST, Constants, Query, Rows, score
from ._search import SearchOptions, SearchResult, SearchTables, _query

__all__ = ["ApproximateIndex", "ApproximateOptions", "ann_path", "tables_fingerprint"]

_FORMAT = "handsynth.ann_index"
_FORMAT_VERSION = 2  # 2: codes stored in cell order
_MAX_DIMS = 256
_CHUNK_ROWS = 16384  # rows projected at a time when building
_CODE_MAX = 32767.0  # int16 code range
_SUFFIX = ".ann.npz"


@dataclass(frozen=True)
class ApproximateOptions:
    """Parameters of the approximate (IVF) search.

    Parameters
    ----------
    nlist : int or None
        Number of cells (inverted lists).  ``None``: ``sqrt(N)`` rounded to
        a power of two (1024 for 10^6 entries, 256 for 10^5).
    nprobe : int
        Cells whose entries are scored per query (nearest centroids first);
        values of ``nlist`` or more probe every cell (the exact answer).
    max_nprobe : int or None
        When no candidate survives the pruning, the probe doubles up to this
        many cells before falling back.  ``None`` (default): up to every
        cell, so the answer is marked ``low_confidence`` exactly when the
        exact search's is (such frames cost up to an exact search).
    max_scored : int or None
        At most this many candidates are scored exactly (masks and HLAC
        read) per query, once one of them survives the pruning; the best so
        far is then the answer.  Bounds the time of frames whose probed
        cells hold thousands of near-identical entries (compact poses whose
        HLAC differences the PCA codes cannot tell apart).  ``None``: no
        limit, so that probing every cell gives the exact answer.
    dims : int
        PCA dimensions of the coarse quantizer and of the lower-bound codes,
        1 to 256.
    train_size : int
        At most this many database rows (a random sample drawn with the
        build's seed) train the PCA and k-means; at least ``nlist``.
    niter : int
        k-means iterations.

    Raises
    ------
    InvalidInputError
        A value of the wrong type or out of range, naming the field and the
        value received.  Unknown keywords raise ``TypeError`` in the
        constructor (as for every dataclass) and ``InvalidInputError``
        naming the key in :meth:`from_dict`.
    """

    nlist: int | None = None
    nprobe: int = 16
    max_nprobe: int | None = None
    max_scored: int | None = 2048
    dims: int = 64
    train_size: int = 65536
    niter: int = 20

    def __post_init__(self) -> None:
        for f in fields(self):
            v = getattr(self, f.name)
            optional = f.name in ("nlist", "max_nprobe", "max_scored")
            if v is None and optional:
                continue
            if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or v < 1:
                what = "an integer >= 1" + (" or None" if optional else "")
                raise InvalidInputError(f"ApproximateOptions.{f.name} must be {what}, got {v!r}")
            object.__setattr__(self, f.name, int(v))
        if self.dims > _MAX_DIMS:
            raise InvalidInputError(
                f"ApproximateOptions.dims must be at most {_MAX_DIMS}, got {self.dims!r}")
        if self.max_nprobe is not None and self.max_nprobe < self.nprobe:
            raise InvalidInputError(
                f"ApproximateOptions.max_nprobe must be >= nprobe ({self.nprobe}) or None, "
                f"got {self.max_nprobe!r}")

    @classmethod
    def from_dict(cls, values) -> ApproximateOptions:
        """Options from a mapping (configuration file, command-line keywords).

        Raises
        ------
        InvalidInputError
            An unknown key (named, with the known ones) or a bad value.
        """
        if not hasattr(values, "keys"):
            raise InvalidInputError(
                f"ApproximateOptions values must be a mapping, got {type(values).__name__}")
        known = [f.name for f in fields(cls)]
        unknown = sorted(str(k) for k in set(values) - set(known))
        if unknown:
            raise InvalidInputError(
                f"unknown ApproximateOptions key {unknown[0]!r} (known: {', '.join(known)})")
        return cls(**dict(values))


def ann_path(database_path) -> Path:
    """File of the persisted index of a database file: ``<database>.ann.npz``."""
    p = Path(database_path)
    return p.with_name(p.name + _SUFFIX)


def tables_fingerprint(tables: SearchTables) -> str:
    """SHA-256 of the searched columns (HLAC, packed masks, ridge areas) and their shapes.

    Reads every byte once (about 2.7 GB, a few seconds, for 10^6 entries).
    """
    h = hashlib.sha256()
    for name in ("hlac", "sil_bits", "ridge_bits", "ridge_area"):
        arr = np.ascontiguousarray(getattr(tables, name))
        h.update(f"{name}\0{arr.dtype.str}\0{arr.shape}\0".encode())
        h.update(arr.data.cast("B"))  # .data: the array's memoryview
    return "sha256:" + h.hexdigest()


def _sample_fingerprint(tables: SearchTables, rows: int = 4096) -> str:
    """SHA-256 of `rows` evenly spaced rows of the searched columns (milliseconds)."""
    n = len(tables)
    pick = np.unique(np.linspace(0, n - 1, min(n, rows)).astype(np.int64))
    h = hashlib.sha256(f"{n}\0".encode())
    for name in ("hlac", "sil_bits", "ridge_bits", "ridge_area"):
        h.update(np.ascontiguousarray(getattr(tables, name)[pick]).tobytes())
    return "sha256:" + h.hexdigest()


def _file_checksum(path) -> str | None:
    """The ``checksum`` attribute of a database file (see :mod:`handsynth.db._store`), or None."""
    if path is None or not Path(str(path)).is_file():
        return None
    try:
        import h5py

        with h5py.File(path, "r") as f:
            value = f.attrs.get("checksum")
            complete = bool(f.attrs.get("complete", False))
    except (OSError, ValueError):
        return None
    return str(value) if value is not None and complete else None


def _database_fingerprint(database, tables: SearchTables) -> str:
    """Key of the searched data: the database file's checksum and a row sample, or all bytes.

    With a database file, its stored checksum (which covers every dataset)
    plus a sample of the rows actually held (so tables that do not come
    from that file's current content do not match); without one, the
    SHA-256 of all searched columns (:func:`tables_fingerprint`).
    """
    checksum = _file_checksum(getattr(database, "path", None))
    if checksum is None:
        return tables_fingerprint(tables)
    return f"file:{checksum}:rows:{_sample_fingerprint(tables)}"


def _default_nlist(n: int) -> int:
    return max(1, min(n, 2 ** round(math.log2(max(1.0, math.sqrt(n))))))


def _resolve(options: ApproximateOptions, n: int) -> ApproximateOptions:
    """`options` with ``nlist`` filled in for `n` entries; checks ``nlist <= n``."""
    nlist = _default_nlist(n) if options.nlist is None else options.nlist
    if nlist > n:
        raise InvalidInputError(
            f"ApproximateOptions.nlist must be at most the number of entries ({n}), got {nlist}")
    return ApproximateOptions(**{**asdict(options), "nlist": nlist})


def _index_key(fingerprint: str, options: ApproximateOptions, seed: int) -> str:
    build = {k: getattr(options, k) for k in ("nlist", "dims", "train_size", "niter")}
    text = json.dumps({"tables": fingerprint, "build": build, "seed": int(seed),
                       "version": _FORMAT_VERSION}, sort_keys=True)
    return "sha256:" + hashlib.sha256(text.encode()).hexdigest()


# --------------------------------------------------------------------------- training


def _train(sample: np.ndarray, *, dims: int, nlist: int, niter: int, seed: int):
    """PCA and k-means (faiss) on float32 rows (M, 1600).

    Returns ``A`` (dims, 1600) float32 with orthonormal rows and the
    centroids (nlist, dims) of the projections ``A h`` (the PCA's centring
    is left out: it shifts every point alike).  faiss uses its current
    OpenMP thread count.
    """
    import faiss  # the one place handsynth imports faiss

    pca = faiss.PCAMatrix(HLAC_SIZE, dims)
    pca.train(sample)
    a = faiss.vector_to_array(pca.A).astype(np.float32).reshape(dims, HLAC_SIZE)
    y = np.ascontiguousarray(sample @ a.T, dtype=np.float32)
    km = faiss.Kmeans(dims, nlist, niter=niter, seed=int(seed) % (2**31), verbose=False,
                      max_points_per_centroid=max(1, -(-y.shape[0] // nlist)))
    km.train(y)
    return a, np.ascontiguousarray(km.centroids, dtype=np.float64)


def _nearest(y: np.ndarray, centroids: np.ndarray, c_norms: np.ndarray) -> np.ndarray:
    """Squared L2 distance ranks: nearest centroid of each row of `y` (float64)."""
    return np.argmin(c_norms[None, :] - 2.0 * (y @ centroids.T), axis=1).astype(np.int32)


# --------------------------------------------------------------------------- kernels


@njit(cache=True, nogil=True, fastmath=True)
def _code_bound(q_y, code, step, band):
    """Lower bound of ``|A h_q - A h_i|^2`` from the int16 code of ``A h_i``.

    Branch-free so that it vectorises (the reassociated float64 sum differs
    from the ordered one by far less than the quantisation band).
    """
    acc = 0.0
    for k in range(q_y.shape[0]):
        diff = max(abs(q_y[k] - code[k] * step[k]) - band[k], 0.0)
        acc += diff * diff
    return acc


class _Probe(NamedTuple):
    """Which candidates :func:`_ivf_kernel` scores, and how.

    Attributes
    ----------
    starts, stops : ndarray of int64, shape (P,)
        Code positions ``[starts[r], stops[r])`` of the probed cells.
    extra_j : int
        One more code position (the seed outside the probed cells), or -1.
    seed_j : int
        Code position scored first (the seed), or -1.
    fallback_ok : bool
        With no survivor, score every candidate again without pruning
        (else return -1 so that the caller widens the probe).
    max_scored : int
        Candidates scored exactly once one survives (0: no limit).
    """

    starts: np.ndarray
    stops: np.ndarray
    extra_j: int
    seed_j: int
    fallback_ok: bool
    max_scored: int


class _Codes(NamedTuple):
    """The index's arrays that :func:`_ivf_kernel` reads (:class:`ApproximateIndex`).

    Attributes
    ----------
    order : ndarray of int32, shape (N,)
    codes : ndarray of int16, shape (N, dims)
    step, band : ndarray of float64, shape (dims,)
    inv_gain : float
    """

    order: np.ndarray
    codes: np.ndarray
    step: np.ndarray
    band: np.ndarray
    inv_gain: float


@njit(cache=True, nogil=True)
def _ivf_kernel(query, q_area, q_y, table, index, constants, probe):
    """Best candidate among the probed code positions and ``extra_j``.

    Parameters
    ----------
    query : tuple
        The fields of a :class:`~handsynth.estimate._score.Query`, in order.
    q_area : float
        ``A_input``, pixels.
    q_y : ndarray of float64, shape (dims,)
        ``A h`` of the input.
    table : tuple
        The fields of a :class:`~handsynth.estimate._score.Rows`, in order
        (the database's columns, entry order).
    index : tuple
        The fields of a :class:`_Codes`, in order.
    constants : tuple
        ``(c, c1, c2, c3, c4, prune)`` of :class:`SearchOptions`.
    probe : tuple
        The fields of a :class:`_Probe`, in order.

    Returns
    -------
    tuple
        (entry, E, d, p1, p2, survivors, fallback); entry -1 when no
        candidate survives the pruning and not ``fallback_ok``.

    Notes
    -----
    Pass 1 computes the code bound of every candidate (codes are stored in
    cell order, so this streams).  Pass 2 scores the seed and then the
    candidates with the smallest bounds until one survives; pass 3 visits
    the rest in order and scores only those whose bound does not exceed the
    best E so far, stopping after ``max_scored`` scored candidates (when > 0)
    once one survivor is known.  ``survivors`` counts the survivors among
    the candidates scored (as the exact search does).  Ties go to the lowest
    entry index.  With no survivor and ``fallback_ok``, the passes run again
    without pruning and the result is marked as a fallback.  The groups
    arrive as plain tuples (cheap to dispatch from Python) and are named
    here.
    """
    q = Query(*query)
    rows = Rows(*table)
    ix = _Codes(*index)
    p = _Probe(*probe)
    c, c1, c2, c3, c4, prune = constants
    # fields read once, into locals: a field read in a loop costs a reference count
    # update per iteration
    order, codes, step, band, inv_gain = ix.order, ix.codes, ix.step, ix.band, ix.inv_gain
    starts, stops, extra_j, seed_j = p.starts, p.stops, p.extra_j, p.seed_j
    fallback_ok, max_scored = p.fallback_ok, p.max_scored
    m = 0
    for r in range(starts.shape[0]):
        m += stops[r] - starts[r]
    if extra_j >= 0:
        m += 1
    js = np.empty(m, np.int64)
    low = np.empty(m, np.float64)
    k = 0
    for r in range(starts.shape[0]):
        for j in range(starts[r], stops[r]):
            js[k] = j
            low[k] = _code_bound(q_y, codes[j], step, band) * inv_gain
            k += 1
    if extra_j >= 0:
        js[k] = extra_j
        low[k] = _code_bound(q_y, codes[extra_j], step, band) * inv_gain
    seen = np.zeros(m, np.bool_)
    consts = Constants(c * q_area, c1, c2, c3, c4, prune)
    for attempt in range(2):
        if attempt == 1:
            if not (prune and fallback_ok):
                break
            consts = Constants(c * q_area, c1, c2, c3, c4, False)
            seen[:] = False
        best_e = np.inf
        best_i = -1
        best_d = best_p1 = best_p2 = 0
        survivors = 0
        # the seed first, then the smallest bounds until one candidate survives
        tries = 0
        scored = 0
        while best_i < 0 and tries < 16 and tries < m:
            kk = -1
            if tries == 0 and seed_j >= 0:
                for t in range(m):
                    if js[t] == seed_j:
                        kk = t
                        break
            if kk < 0:
                for t in range(m):
                    if not seen[t] and (kk < 0 or low[t] < low[kk]):
                        kk = t
            tries += 1
            if kk < 0 or seen[kk]:
                continue
            seen[kk] = True
            scored += 1
            i = order[js[kk]]
            st, e, d, p1, p2 = score(i, 0.0, best_e, q, rows, consts)
            if st >= SURVIVOR_ABOVE_BEST:
                survivors += 1
            if st == SURVIVOR:
                best_e, best_i, best_d, best_p1, best_p2 = e, i, d, p1, p2
        for t in range(m):
            if seen[t] or low[t] > best_e:
                continue
            if max_scored > 0 and scored >= max_scored and best_i >= 0:
                break  # enough candidates scored: keep the best so far
            scored += 1
            i = order[js[t]]
            st, e, d, p1, p2 = score(i, 0.0, best_e, q, rows, consts)
            if st < SURVIVOR_ABOVE_BEST:
                continue
            survivors += 1
            if st == SURVIVOR and (e < best_e or i < best_i):  # ties: the lowest entry index
                best_e, best_i, best_d, best_p1, best_p2 = e, i, d, p1, p2
        if best_i >= 0:
            if attempt == 1:
                survivors = 0
            return best_i, best_e, best_d, best_p1, best_p2, survivors, attempt == 1
    return -1, 0.0, 0, 0, 0, 0, True


# --------------------------------------------------------------------------- the index


class ApproximateIndex:
    """Inverted lists over PCA-projected HLAC for the search of large databases.

    Build with :meth:`build`, or :meth:`open` to load it from or save it
    next to the database file.  Read-only afterwards and safe to share
    between threads (:meth:`search` allocates its scratch per call; the
    compiled kernel releases the GIL).

    Attributes
    ----------
    tables : SearchTables
        The database columns it searches (referenced, not copied).
    options : ApproximateOptions
        Options it was built with, ``nlist`` filled in.
    seed : int
        Seed of the training sample and of k-means.
    projection : ndarray of float32, shape (dims, 1600)
        ``A``, orthonormal rows (PCA directions).
    centroids : ndarray of float64, shape (nlist, dims)
        Cell centres in the projected space.
    order : ndarray of int32, shape (N,)
        Entry indices grouped by cell, ascending within a cell.
    offsets : ndarray of int64, shape (nlist + 1,)
        Cell ``c`` holds ``order[offsets[c]:offsets[c + 1]]``.
    position : ndarray of int32, shape (N,)
        Where each entry is in `order` (the inverse permutation).
    codes : ndarray of int16, shape (N, dims)
        ``A h_i`` in units of `step`, in the order of `order` (row ``j`` is
        entry ``order[j]``), so that probing a cell streams its codes.
    step : ndarray of float64, shape (dims,)
        Size of one code unit per dimension.
    key : str
        Fingerprint of the tables, build options and seed (see :meth:`open`).
    """

    def __init__(self, tables: SearchTables, *, options: ApproximateOptions, seed: int,
                 projection, centroids, order, offsets, codes, step, key: str) -> None:
        self.tables = tables
        self.options = options
        self.seed = int(seed)
        self.projection = np.ascontiguousarray(projection, dtype=np.float32)
        self.centroids = np.ascontiguousarray(centroids, dtype=np.float64)
        self.order = np.ascontiguousarray(order, dtype=np.int32)
        self.offsets = np.ascontiguousarray(offsets, dtype=np.int64)
        self.position = np.empty_like(self.order)
        self.position[self.order] = np.arange(len(self.order), dtype=np.int32)
        self.codes = np.ascontiguousarray(codes, dtype=np.int16)
        self.step = np.ascontiguousarray(step, dtype=np.float64)
        self.key = key
        self._a64 = self.projection.astype(np.float64)
        self._c_norms = (self.centroids ** 2).sum(axis=1)
        # half a code step, plus a margin for the float64 rounding of A h
        self._band = 0.5 * self.step + 1e-9 * (1.0 + np.abs(self.codes).max(axis=0) * self.step)
        # |A x|^2 <= gain |x|^2 with gain the largest eigenvalue of A A^T (1 up to rounding)
        gain = float(np.linalg.eigvalsh(self._a64 @ self._a64.T).max()) * (1.0 + 1e-9)
        self._inv_gain = (1.0 - 1e-12) / max(gain, 1.0)
        self._kernel_codes = tuple(_Codes(order=self.order, codes=self.codes, step=self.step,
                                          band=self._band, inv_gain=self._inv_gain))
        for arr in (self.projection, self.centroids, self.order, self.offsets, self.position,
                    self.codes, self.step, self._a64, self._c_norms, self._band):
            arr.setflags(write=False)

    # ----------------------------------------------------------------- construction

    @classmethod
    def build(cls, tables: SearchTables, *, options: ApproximateOptions | None = None,
              seed: int = 0, key: str | None = None) -> ApproximateIndex:
        """Train the coarse quantizer on `tables`, fill the lists and the codes.

        Parameters
        ----------
        tables : SearchTables
            The database columns (referenced, not copied).
        options : ApproximateOptions, keyword-only, optional
        seed : int, keyword-only
            Seed of the training sample and of k-means.
        key : str, keyword-only, optional
            Fingerprint to record (:meth:`open` passes it; computed when
            omitted, reading every searched column once).

        Returns
        -------
        ApproximateIndex

        Raises
        ------
        InvalidInputError
            `tables` is not :class:`SearchTables`, `options` not
            :class:`ApproximateOptions`, ``options.nlist`` exceeds the number
            of entries, or `seed` is not an integer >= 0.
        """
        opts = check_options(options, ApproximateOptions)
        _check_tables(tables)
        seed = _check_seed(seed)
        n = len(tables)
        used = _resolve(opts, n)
        nlist = used.nlist
        assert nlist is not None  # _resolve fills it in
        m = min(n, max(used.train_size, nlist))
        pick = np.arange(n) if m >= n else np.sort(
            np.random.default_rng(seed).choice(n, size=m, replace=False))
        a, centroids = _train(tables.hlac[pick].astype(np.float32), dims=used.dims, nlist=nlist,
                              niter=used.niter, seed=seed)
        a64 = a.astype(np.float64)
        c_norms = (centroids ** 2).sum(axis=1)
        y = np.empty((n, used.dims), np.float64)
        cell = np.empty(n, np.int32)
        for s in range(0, n, _CHUNK_ROWS):
            y[s:s + _CHUNK_ROWS] = tables.hlac[s:s + _CHUNK_ROWS].astype(np.float64) @ a64.T
            cell[s:s + _CHUNK_ROWS] = _nearest(y[s:s + _CHUNK_ROWS], centroids, c_norms)
        order = np.argsort(cell, kind="stable").astype(np.int32)
        peak = np.abs(y).max(axis=0)
        step = np.where(peak > 0, peak / _CODE_MAX, 1.0)
        codes = np.empty((n, used.dims), np.int16)
        for s in range(0, n, _CHUNK_ROWS):
            codes[s:s + _CHUNK_ROWS] = np.rint(y[order[s:s + _CHUNK_ROWS]] / step)
        del y
        offsets = np.zeros(nlist + 1, np.int64)
        np.cumsum(np.bincount(cell, minlength=nlist), out=offsets[1:])
        if key is None:
            key = _index_key(tables_fingerprint(tables), used, seed)
        return cls(tables, options=used, seed=seed, projection=a, centroids=centroids,
                   order=order, offsets=offsets, codes=codes, step=step, key=key)

    @classmethod
    def open(cls, database, tables: SearchTables | None = None, *,
             options: ApproximateOptions | None = None, seed: int = 0,
             path=None) -> ApproximateIndex:
        """The index of a database, loaded from ``<database>.ann.npz`` or built and saved there.

        Parameters
        ----------
        database : handsynth.db.Database
            An opened database; the index file goes next to its file.
        tables : SearchTables, optional
            The database's search columns (made from `database` when omitted).
        options : ApproximateOptions, keyword-only, optional
        seed : int, keyword-only
        path : str or os.PathLike, keyword-only, optional
            Index file; default :func:`ann_path` of ``database.path``.  For a
            database without a file (in memory) nothing is saved unless
            `path` is given.

        Returns
        -------
        ApproximateIndex
            Loaded when the file's key matches the database (its file's
            checksum and a sample of `tables`), the build options
            (``nlist``, ``dims``, ``train_size``, ``niter``) and the seed;
            otherwise built and written atomically (replacing a stale or
            damaged file).  ``nprobe`` and ``max_nprobe`` come from `options`.

        Raises
        ------
        InvalidInputError
            As :meth:`build`.
        DatabaseError
            The index file cannot be written.
        """
        opts = check_options(options, ApproximateOptions)
        seed = _check_seed(seed)
        if tables is None:
            tables = SearchTables.from_arrays(hlac=database.hlac, sil_bits=database.sil_bits,
                                              ridge_bits=database.ridge_bits,
                                              ridge_area=database.ridge_area)
        _check_tables(tables)
        if path is None:
            db_path = Path(str(getattr(database, "path", "")))
            path = ann_path(db_path) if db_path.is_file() else None
        used = _resolve(opts, len(tables))
        key = _index_key(_database_fingerprint(database, tables), used, seed)
        if path is not None:
            loaded = cls._load(Path(path), tables, key=key, options=used, seed=seed)
            if loaded is not None:
                return loaded
        index = cls.build(tables, options=used, seed=seed, key=key)
        if path is not None:
            index.save(path)
        return index

    def save(self, path) -> Path:
        """Write the index (not the database) to `path` atomically; returns the path.

        Raises
        ------
        DatabaseError
            The file cannot be written.
        """
        path = Path(path)
        meta = {"format": _FORMAT, "version": _FORMAT_VERSION, "key": self.key,
                "options": asdict(self.options), "seed": self.seed, "entries": len(self.tables)}
        meta_bytes = np.frombuffer(json.dumps(meta, sort_keys=True).encode(), np.uint8)
        with atomic_open(path, "wb", what="approximate index", error=DatabaseError) as f:
            np.savez(f, projection=self.projection, centroids=self.centroids, order=self.order,
                     offsets=self.offsets, codes=self.codes, step=self.step, meta=meta_bytes)
        return path

    @classmethod
    def _load(cls, path: Path, tables: SearchTables, *, key: str, options: ApproximateOptions,
              seed: int) -> ApproximateIndex | None:
        """The index stored at `path` if its key is `key`; ``None`` if missing, stale or damaged."""
        if not path.is_file():
            return None
        try:
            with np.load(path, allow_pickle=False) as z:
                meta = json.loads(bytes(z["meta"]).decode())
                if (meta.get("format") != _FORMAT or meta.get("version") != _FORMAT_VERSION
                        or meta.get("key") != key):
                    return None
                wanted = ("projection", "centroids", "order", "offsets", "codes", "step")
                arrays = {k: z[k] for k in wanted if k in z.files}
        except (OSError, ValueError, KeyError, EOFError, AttributeError, TypeError,
                zipfile.BadZipFile, zlib.error):
            return None  # a damaged file (bad CRC, cut short, not a zip): built again
        n, nlist, dims = len(tables), options.nlist, options.dims
        assert nlist is not None  # the options went through _resolve
        shapes = {"projection": (dims, HLAC_SIZE), "centroids": (nlist, dims), "order": (n,),
                  "offsets": (nlist + 1,), "codes": (n, dims), "step": (dims,)}
        if any(name not in arrays or arrays[name].shape != shape
               for name, shape in shapes.items()):
            return None
        order, offsets = arrays["order"], arrays["offsets"]
        if (offsets[0] != 0 or offsets[-1] != n or (np.diff(offsets) < 0).any()
                or order.min() < 0 or order.max() >= n
                or (np.bincount(order, minlength=n) != 1).any()):
            return None
        return cls(tables, options=options, seed=seed, key=key, **arrays)

    # ----------------------------------------------------------------- queries

    def __len__(self) -> int:
        return len(self.tables)

    @property
    def nlist(self) -> int:
        """Number of cells."""
        return self.centroids.shape[0]

    @property
    def nbytes(self) -> int:
        """Bytes the index holds besides the database."""
        arrays = (self.projection, self.centroids, self.order, self.offsets, self.position,
                  self.codes, self.step, self._a64, self._c_norms, self._band)
        return sum(a.nbytes for a in arrays)

    def check_matches(self, tables: SearchTables) -> None:
        """Check that `tables` hold the rows this index was built on (cheap: a row sample).

        Raises
        ------
        InvalidInputError
            Another number of entries or other rows, naming both sizes.
        """
        _check_tables(tables)
        if tables is self.tables:
            return
        if len(tables) != len(self.tables) or (
                _sample_fingerprint(tables) != _sample_fingerprint(self.tables)):
            raise InvalidInputError(
                f"the approximate index was built on other database rows ({len(self.tables)} "
                f"entries) than the tables given ({len(tables)} entries)")

    def with_options(self, **changes) -> ApproximateIndex:
        """The same index (arrays shared) with other probing options.

        Parameters
        ----------
        **changes
            ``nprobe``, ``max_nprobe`` or ``max_scored``.

        Raises
        ------
        InvalidInputError
            Another field (those need a new build) or a bad value.
        """
        probing = ("nprobe", "max_nprobe", "max_scored")
        for name in changes:
            if name not in probing:
                raise InvalidInputError(
                    f"with_options can change {', '.join(probing)}, not {name!r} (build a new "
                    f"index for that)")
        twin = copy.copy(self)
        twin.options = replace(self.options, **changes)
        return twin

    def cells(self, hlac) -> np.ndarray:
        """All cells, nearest centroid first, for one HLAC vector.

        Parameters
        ----------
        hlac : array_like of uint8, shape (1600,)

        Returns
        -------
        ndarray of int64, shape (nlist,)
        """
        return self._rank(self._a64 @ np.asarray(hlac, dtype=np.float64))

    def _rank(self, y: np.ndarray) -> np.ndarray:
        """Cells by squared distance of their centroid to the projection `y`."""
        return np.argsort(self._c_norms - 2.0 * (self.centroids @ y), kind="stable")

    def search(self, features, options: SearchOptions | None = None, *,
               nprobe: int | None = None, seed: int | None = None) -> SearchResult:
        """The database entry of an input: the paper's search over the probed cells.

        Parameters
        ----------
        features : handsynth.db.Features
            Features of the input silhouette (``hlac``, ``sil_bits``,
            ``ridge_bits``, ``ridge_area``).
        options : SearchOptions, optional
            Search constants (the paper's by default).
        nprobe : int, keyword-only, optional
            Cells to probe (``self.options.nprobe`` by default).
        seed : int, keyword-only, optional
            An entry (the previous frame's answer) added to the candidates
            and scored first; the answer's E can only get smaller.

        Returns
        -------
        SearchResult
            As :func:`handsynth.estimate.search`; ``survivors`` counts the
            surviving candidates among those scored exactly.

        Raises
        ------
        InvalidInputError
            `options` not :class:`SearchOptions`, `nprobe` not an integer
            >= 1, `seed` outside ``[0, N)``.
        """
        opts = check_options(options, SearchOptions)
        probe = check_integer(self.options.nprobe if nprobe is None else nprobe, "nprobe",
                              minimum=1)
        n, nlist = len(self.tables), self.nlist
        s = -1 if seed is None else seed
        if isinstance(s, bool) or not isinstance(s, (int, np.integer)) or not -1 <= s < n:
            raise InvalidInputError(f"seed must be an entry index in [0, {n}), got {seed!r}")
        s = int(s)
        probe = min(int(probe), nlist)
        cap = self.options.max_nprobe
        limit = max(probe, nlist if cap is None else min(nlist, cap))
        h, sb, rb, area = _query(features)
        q_y = self._a64 @ h.astype(np.float64)
        ranked = self._rank(q_y) if probe < nlist else np.arange(nlist)
        t = self.tables
        seed_j = int(self.position[s]) if s >= 0 else -1
        while True:
            cells = np.ascontiguousarray(ranked[:probe], dtype=np.int64)
            starts, stops = self.offsets[cells], self.offsets[cells + 1]
            inside = seed_j >= 0 and bool(((starts <= seed_j) & (seed_j < stops)).any())
            extra_j = seed_j if seed_j >= 0 and not inside else -1
            i, e, d, p1, p2, surv, fb = _ivf_kernel(
                (h, sb, rb), area, q_y, (t.hlac, t.sil_bits, t.ridge_bits, t.ridge_area),
                self._kernel_codes, (opts.c, opts.c1, opts.c2, opts.c3, opts.c4, opts.prune),
                (starts, stops, extra_j, seed_j, probe >= limit, self.options.max_scored or 0))
            if i >= 0:
                return SearchResult(index=int(i), error=float(e), hlac_distance=int(d),
                                    p1=int(p1), p2=int(p2), survivors=int(surv),
                                    low_confidence=bool(fb))
            # no survivor (or only empty cells): widen, up to every cell
            limit = nlist if probe >= limit else limit
            probe = min(2 * probe, limit)


def _check_tables(tables) -> None:
    if not isinstance(tables, SearchTables):
        raise InvalidInputError(f"tables must be SearchTables, got {type(tables).__name__}")


def _check_seed(seed) -> int:
    return check_integer(seed, "seed", minimum=0)
