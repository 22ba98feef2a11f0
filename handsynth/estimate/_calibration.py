"""Calibration from one open-hand frame: a user's own ignore mask (beyond the paper).

A user's hand is never the database's model hand: thicker fingers, a longer
palm, a web between thumb and index show in every frame.  On the realistic
mesh hand (``handsynth eval --hand mesh``) that fixed mismatch is about 450
of the 4,096 pixels of the 64x64 silhouette, while an index finger flexing at
its PIP changes about 100.  The paper's ``E`` then prefers open-hand entries
whose other fingers are a few degrees off (they happen to fit the mismatch)
to the entry of the true pose, and never reports the index PIP flexed
(``docs/eval/README.md``).

Calibration removes the fixed part of the mismatch:

1. The user holds the hand open and flat once (all 20 angles 0, the pose of
   the database's open-hand entry) and the device takes one frame.
2. Its 64x64 silhouette ``U`` (the database's preprocessing) is compared
   with the silhouette ``O`` of the database's open-hand entry.  The pixels
   where they differ, grown by `dilation_px` steps of 4-neighbour dilation
   (edges a pixel off from frame to frame), form the *ignore mask* ``M``.
3. A frame's silhouette ``S`` is then matched by the smallest masked pixel
   difference ``X_i = |(S xor S_i) & ~M|`` over all entries ``i`` (ties: all
   entries with the smallest ``X``, as the exact search reports them).
4. The pose reported is the mean over the entries near the best, weighted
   ``w_i = exp(-(X_i - X_min) / T)`` with ``T = temperature_px`` (entries
   with ``X_i - X_min > 10 T`` weigh less than ``e^-10`` and are left out).
   Read ``X / T`` as a negative log-likelihood: the weighted mean is then
   the posterior mean of the pose, the estimate of least squared error when
   several poses explain the frame almost equally well, as a finger flexed
   at its MCP and one flexed at its PIP do from the back of the hand.
   ``T = 0`` gives the plain mean of the tied entries.

Step 3 replaces the paper's ``E``: its HLAC vector sums over the whole image
and cannot leave pixels out, and its ridge penalties are built for a
silhouette that fits.  :func:`select_shape_from_frame` chooses the database
from the same frame: the shape whose open hand overlaps ``U`` most.

Figures are in the README ("Calibrated lookup") and ``docs/eval``.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np
from numba import njit

from ..db import pack_mask, unpack_mask
from ..db._bits import _popcount64
from ..errors import InvalidInputError
from ..models import HandShape
from ..render import CameraMount, preprocess

__all__ = ["Calibration", "FrameSelection", "MaskedMatch", "masked_band_areas", "masked_search",
           "masked_search_reference", "select_shape_from_frame"]

_MAX_DILATION_PX = 8
_MAX_TEMPERATURE_PX = 8.0
#: Entries farther than this many temperatures above the best are left out of the mean.
WINDOW_TEMPERATURES = 10.0


@dataclass(frozen=True, eq=False)
class Calibration:
    """A user's ignore mask for :func:`masked_search` (module docstring).

    Attributes
    ----------
    ignore : ndarray of bool, shape (64, 64)
        Pixels left out of the match (read-only).
    keep_bits : ndarray of uint64, shape (64,)
        The complement of `ignore`, packed as the database's silhouettes.
    open_iou : float
        IoU of the user's and the database's open-hand silhouettes before
        masking (1: the same hand).
    dilation_px : int
        4-neighbour dilation steps applied to the mismatch.
    temperature_px : float
        ``T`` of the weighted mean of the entries near the best (module
        docstring, step 4), pixels; 0: the mean of the tied entries.
    """

    ignore: np.ndarray
    keep_bits: np.ndarray
    open_iou: float
    dilation_px: int
    temperature_px: float

    @property
    def window_px(self) -> int:
        """Entries with ``X <= X_min + window_px`` enter the weighted mean."""
        return int(np.floor(WINDOW_TEMPERATURES * self.temperature_px))

    @classmethod
    def from_silhouettes(cls, user, reference, *, dilation_px: int = 1,
                         temperature_px: float = 1.0) -> Calibration:
        """The calibration of a user's open-hand silhouette against the database's.

        Parameters
        ----------
        user, reference : array_like of bool, shape (S, S)
            Preprocessed silhouettes of the user's open hand and of the
            database's open-hand entry (same size).
        dilation_px : int, keyword-only
            Dilation steps of the mismatch, 0 to 8.
        temperature_px : float, keyword-only
            ``T`` of the weighted mean (module docstring, step 4), 0 to 8
            pixels.  The default 1 was chosen on the mesh hand's frames of
            seeds 2-5, which the recorded evaluations do not use (README,
            "Calibrated lookup").

        Raises
        ------
        InvalidInputError
            Silhouettes of different or non-square shapes, an empty one, or
            a `dilation_px` or `temperature_px` out of range.
        """
        u = np.asarray(user)
        o = np.asarray(reference)
        if u.dtype != bool or o.dtype != bool or u.ndim != 2 or u.shape != o.shape \
                or u.shape[0] != u.shape[1]:
            raise InvalidInputError(
                "user and reference must be square bool silhouettes of one size, got "
                f"{u.dtype} {u.shape} and {o.dtype} {o.shape}")
        if not u.any() or not o.any():
            which = "user" if not u.any() else "reference"
            raise InvalidInputError(f"the {which} silhouette shows no hand")
        if isinstance(dilation_px, bool) or not isinstance(dilation_px, (int, np.integer)) \
                or not 0 <= dilation_px <= _MAX_DILATION_PX:
            raise InvalidInputError(
                f"dilation_px must be an int in [0, {_MAX_DILATION_PX}], got {dilation_px!r}")
        if isinstance(temperature_px, bool) \
                or not isinstance(temperature_px, (int, float, np.integer, np.floating)) \
                or not 0.0 <= temperature_px <= _MAX_TEMPERATURE_PX:
            raise InvalidInputError(f"temperature_px must be a number in [0, "
                                    f"{_MAX_TEMPERATURE_PX:g}], got {temperature_px!r}")
        ignore = u ^ o
        if dilation_px > 0:  # scipy's default structure in 2-D is the 4-neighbour cross
            from scipy.ndimage import binary_dilation

            ignore = binary_dilation(ignore, iterations=int(dilation_px))
        ignore.setflags(write=False)
        keep = pack_mask(~ignore)
        keep.setflags(write=False)
        iou = float((u & o).sum() / (u | o).sum())
        return cls(ignore=ignore, keep_bits=keep, open_iou=iou, dilation_px=int(dilation_px),
                   temperature_px=float(temperature_px))


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
    """
    table = np.asarray(sil_bits, dtype=np.uint64)
    if table.ndim != 2 or table.shape[1] % _BANDS:
        raise InvalidInputError(f"sil_bits must have shape (N, W) with W a multiple of {_BANDS}, "
                                f"got {table.shape}")
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
            e += _popcount64((sil_bits[i, w] ^ q[w]) & keep[w])
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
    if not isinstance(calibration, Calibration):
        raise InvalidInputError(
            f"calibration must be a Calibration, got {type(calibration).__name__}")
    s = np.asarray(silhouette)
    if s.dtype != bool or s.shape != calibration.ignore.shape:
        raise InvalidInputError(f"silhouette must be bool of shape {calibration.ignore.shape}, "
                                f"got {s.dtype} {s.shape}")
    q = pack_mask(s)
    if sil_bits.ndim != 2 or sil_bits.shape[1] != q.size:
        raise InvalidInputError(f"sil_bits must have shape (N, {q.size}), got {sil_bits.shape}")
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
    """:func:`masked_search` written plainly with numpy (the specification for tests)."""
    table = np.asarray(sil_bits, dtype=np.uint64)
    q = _check_query(silhouette, calibration, table)
    x = np.bitwise_count((table ^ q[None, :]) & calibration.keep_bits[None, :]).sum(axis=1)
    near = np.flatnonzero(x <= x.min() + calibration.window_px)
    return _match(q, calibration, table, near, x[near].astype(np.int64))


@dataclass(frozen=True)
class FrameSelection:
    """Outcome of :func:`select_shape_from_frame`.

    Attributes
    ----------
    shape : HandShape
        The shape whose open hand overlaps the frame's most.
    iou : float
        That overlap (64x64 silhouette IoU).
    ious : dict
        Shape name -> IoU, for every candidate.
    """

    shape: HandShape
    iou: float
    ious: dict


@lru_cache(maxsize=8)
def _open_hand_silhouettes(shapes: tuple, mount: CameraMount, side: str, width_px: int,
                           height_px: int) -> np.ndarray:
    """Preprocessed open-hand silhouettes of model hands, shape (len(shapes), 64, 64).

    Cached (read-only): every user of one device is compared with the same renders.
    """
    from ..render import SilhouetteRasterizer

    out = np.empty((len(shapes), 64, 64), bool)
    zero = np.zeros((1, 20))
    for k, shape in enumerate(shapes):
        with SilhouetteRasterizer(shape, mount, side=side, width_px=width_px,
                                  height_px=height_px) as r:
            out[k] = preprocess(r.masks(zero)[0], mount, side=side)
    out.setflags(write=False)
    return out


def select_shape_from_frame(open_frame, *, mount: CameraMount | None = None,
                            side: str = "right", shapes=None) -> FrameSelection:
    """The database shape that fits a user's open-hand frame best (beyond the paper).

    Each candidate model hand is rendered open and flat through `mount` at
    the frame's size; the one whose 64x64 silhouette has the highest IoU with
    the frame's is chosen (ties: the first).  The paper chose by measured
    lengths (:func:`select_shape`); this chooses by what the device sees.

    Parameters
    ----------
    open_frame : ndarray, shape (H, W) or (H, W, 3)
        The user's open, flat hand through the device camera (a frame as
        :meth:`PoseLookup.estimate` takes).
    mount : CameraMount, keyword-only, optional
        The device (the paper's by default).
    side : {"right", "left"}, keyword-only
    shapes : sequence of HandShape, keyword-only, optional
        Candidates; the 81 grid shapes by default (about 2 s the first time;
        the renders are kept for later calls with the same mount, side and
        frame size).

    Returns
    -------
    FrameSelection

    Raises
    ------
    InvalidInputError
        The frame is not an image or shows no hand; `shapes` is empty or
        holds something else than HandShape objects.
    """
    mount = mount or CameraMount()
    cands = HandShape.grid() if shapes is None else list(shapes)
    if not cands or not all(isinstance(s, HandShape) for s in cands):
        raise InvalidInputError(f"shapes must be a non-empty sequence of HandShape, got {shapes!r}")
    user = preprocess(open_frame, mount, side=side)
    if not user.any():
        raise InvalidInputError("open_frame shows no hand")
    h, w = np.shape(open_frame)[:2]
    sils = _open_hand_silhouettes(tuple(cands), mount, side, w, h)
    inter = (sils & user[None]).sum(axis=(1, 2))
    union = (sils | user[None]).sum(axis=(1, 2))
    ious = inter / np.maximum(union, 1)
    k = int(np.argmax(ious))
    return FrameSelection(shape=cands[k], iou=float(ious[k]),
                          ious={s.name: float(v) for s, v in zip(cands, ious)})


def reference_silhouette(database) -> np.ndarray:
    """The 64x64 silhouette of a database's open-hand entry (the first with all angles 0).

    Raises
    ------
    InvalidInputError
        The database has no entry with all 20 angles 0.
    """
    angles = np.asarray(database.angles)
    rows = np.flatnonzero(np.all(angles == 0, axis=1))
    if rows.size == 0:
        raise InvalidInputError(
            f"database {database.path} has no open-hand entry (all angles 0) to calibrate "
            "against")
    return unpack_mask(np.asarray(database.sil_bits[rows[0]]))
