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

Figures are in docs/lookup.md ("Calibrated lookup") and ``docs/eval``.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from .._checks import check_side, is_number, short_repr
from ..db import pack_mask, unpack_mask
from ..errors import EstimationError, InvalidInputError
from ..models import HandShape
from ..render import CameraMount, as_mount, preprocess
from ._hand import MIN_HAND_COVERAGE, no_hand_error

__all__ = ["MIN_OPEN_IOU", "Calibration", "FrameSelection", "reference_silhouette",
           "select_shape_from_frame"]

_MAX_DILATION_PX = 8
_MAX_TEMPERATURE_PX = 8.0
#: Least overlap (IoU) of a calibration frame's silhouette with the database's open hand.
#: Measured against the standard hand's open entry: model hands with all ratios 0.8 or
#: 1.2 (or mixed) open give 0.73-0.84 at 720x480, the off-grid hands of the evaluation
#: (``handsynth eval``, small renders) down to 0.55, the standard hand with four fingers
#: flexed 60 deg at the MCP 0.53, frames of uniform random noise 0.30.
MIN_OPEN_IOU = 0.45
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
                         temperature_px: float = 1.0,
                         min_open_iou: float | None = None) -> Calibration:
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
            seeds 2-5, which the recorded evaluations do not use (docs/lookup.md,
            "Calibrated lookup").

        min_open_iou : float, keyword-only, optional
            Least overlap (IoU) of the two silhouettes: below it the user's
            frame is not taken for an open hand (:data:`MIN_OPEN_IOU` by
            default; 0 accepts anything).

        Raises
        ------
        InvalidInputError
            Silhouettes of different or non-square shapes, an empty one, or
            a `dilation_px`, `temperature_px` or `min_open_iou` out of range.
        EstimationError
            The silhouettes overlap less than `min_open_iou`: the frame does
            not show an open hand (random noise overlaps about 0.3).
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
        if not is_number(temperature_px) or not 0.0 <= temperature_px <= _MAX_TEMPERATURE_PX:
            raise InvalidInputError(f"temperature_px must be a number in [0, "
                                    f"{_MAX_TEMPERATURE_PX:g}], got {temperature_px!r}")
        floor = MIN_OPEN_IOU if min_open_iou is None else min_open_iou
        if not is_number(floor) or not 0.0 <= floor <= 1.0:
            raise InvalidInputError(f"min_open_iou must be a number in [0, 1], got {floor!r}")
        iou = float((u & o).sum() / (u | o).sum())
        if iou < floor:
            raise EstimationError(
                f"the open-hand frame does not look like an open hand: its silhouette overlaps "
                f"the database's open hand by IoU {iou:.2f}, at least {floor:g} is needed; "
                "hold the hand open and flat in front of the device (a hand-free or noisy "
                "frame gives about 0.3)")
        ignore = u ^ o
        if dilation_px > 0:  # scipy's default structure in 2-D is the 4-neighbour cross
            from scipy.ndimage import binary_dilation

            ignore = binary_dilation(ignore, iterations=int(dilation_px))
        ignore.setflags(write=False)
        keep = pack_mask(~ignore)
        keep.setflags(write=False)
        return cls(ignore=ignore, keep_bits=keep, open_iou=iou, dilation_px=int(dilation_px),
                   temperature_px=float(temperature_px))


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
        The frame is not an image or shows no hand (what stands out covers
        less than :data:`~handsynth.estimate.MIN_HAND_COVERAGE` of it); `shapes` is empty or
        holds something else than HandShape objects; `mount` is not a
        CameraMount or `side` not ``"right"`` or ``"left"``.
    """
    mount = as_mount(mount)
    check_side(side)
    try:
        cands = HandShape.grid() if shapes is None else list(shapes)
    except TypeError:
        cands = []
    if not cands or not all(isinstance(s, HandShape) for s in cands):
        raise InvalidInputError(f"shapes must be a non-empty sequence of HandShape, got {shapes!r}")
    user = preprocess(open_frame, mount, side=side, min_coverage=MIN_HAND_COVERAGE)
    if not user.any():
        raise no_hand_error("open_frame")
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

    Parameters
    ----------
    database : Database
        Read: its ``angles`` (N, 20) in degrees, its ``sil_bits`` (N, 64)
        uint64 and its ``path`` (for the message).

    Returns
    -------
    ndarray of bool, shape (64, 64)
        That entry's stored silhouette, unpacked (:func:`~handsynth.db.unpack_mask`).

    Raises
    ------
    InvalidInputError
        `database` lacks those three (not a database), or has no entry with
        all 20 angles 0.
    """
    if not all(hasattr(database, a) for a in ("angles", "sil_bits", "path")):
        raise InvalidInputError(f"database must be a Database (its angles, sil_bits and path), "
                                f"got {type(database).__name__} {short_repr(database)}")
    angles = np.asarray(database.angles)
    rows = np.flatnonzero(np.all(angles == 0, axis=1))
    if rows.size == 0:
        raise InvalidInputError(
            f"database {database.path} has no open-hand entry (all angles 0) to calibrate "
            "against")
    return unpack_mask(np.asarray(database.sil_bits[rows[0]]))
