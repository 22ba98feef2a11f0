"""The preprocessing of SPEC.md section 1, shared by database renders and live frames.

Steps, in order:

1. *Binarize*: a boolean mask is taken as it is.  A uint8 frame is
   thresholded on its grey levels (the hand is brighter than a dark
   background, as with the device's backlit skin): pixel ``(y, x)`` is hand
   when ``grey[y, x] > t``.  The grey level of a BGR pixel is OpenCV's
   ``COLOR_BGR2GRAY``, ``(3735 B + 19235 G + 9798 R + 2**14) >> 15``
   (BT.601 weights in 15-bit fixed point, exact); a grey frame is its own
   grey level.  `t` is ``int(threshold)`` when the keyword is given
   (below 0: every pixel is hand; 255 and above: none), else Otsu's
   threshold of the *sample* of the frame: the pixels ``(y, x)`` with `y`
   and `x` both multiples of :data:`OTSU_STEP` (4; rows 0, 4, 8, ... and in
   them columns 0, 4, 8, ..., every 16th pixel).  Otsu's threshold is the
   level `t` maximising the between-class variance of the sample's grey
   levels ``<= t`` and ``> t``, the first such level, computed as OpenCV's
   ``THRESH_OTSU`` does on that sample (:func:`otsu_threshold`).  When all
   the sample's pixels have the same grey level the frame shows no hand
   and the mask is empty.  The sample makes the threshold about 16 times
   cheaper than a full histogram.  With the two populations separated,
   Otsu's level is the top of the darker one, so a background pixel
   brighter than every sampled one comes out as hand; step 3 drops such
   specks unless they touch the hand.
2. *Wrist cut*: pixels that see the hand frame's ``y < mount.wrist_cut_mm``
   at dorsum height are cleared (see :func:`wrist_cut_keep`).  The cut is a
   fixed straight line in the image, because the camera is fixed to the
   wrist, so database renders (with the model's forearm stub) and live
   frames (with a real forearm) lose the same part.
3. *Largest connected component* (8-connectivity) is kept as the hand.
   With ``min_coverage`` (:func:`preprocess`), a component covering less
   than that share of the frame's pixels is too little to be a hand (a
   speck) and the silhouette is empty.
4. *Crop* to its bounding box and *resize* to ``size x size``: the box of
   ``bw x bh`` pixels is scaled by ``s = size / max(bw, bh)`` (the longer
   side becomes `size`) and centred, the shorter side padded with
   background, so the aspect ratio of the hand is kept.  The mapping is
   continuous (no rounding of the scaled box or its offset): an output
   cell is hand when at least half of its area is covered by the scaled
   component (exact area resampling, 0.5 threshold).  The result therefore
   converges as the frame resolution grows, so masks of different sizes
   of the same view agree (``scripts/bench_build.py`` measures it).

:func:`preprocess` runs steps 2-4 in one compiled pass over the mask's row
runs (:mod:`handsynth.render._runs`), and for a uint8 frame step 1 too, one
row at a time (no full-size grey image or mask is made, and only the
columns the wrist cut keeps are binarized); :func:`preprocess_reference`
chains the plain steps (:func:`binarize`, :func:`wrist_cut_keep`,
:func:`largest_component`, :func:`crop_resize`) and is kept as the
specification the tests compare against.

A hand cut by the frame border keeps its straight cut edge through every
step; the features then see the same cut edge in database and live frames
(the database is rendered with the same camera), and the cut is never
mistaken for a fingertip because no step closes or rounds it.
"""

from __future__ import annotations

import math
from functools import lru_cache

import numpy as np

from .._checks import check_integer, check_number, short_repr
from ..errors import InvalidInputError
from ..models import DORSUM_Z_MM
from ._camera import CameraMount, as_mount
from ._runs import (
    MIN_CONTRAST,
    OTSU_STEP,
    _frame_threshold,
    _threshold,
    binarize_frame,
    silhouette_from_frame,
    silhouette_from_mask,
)

__all__ = [
    "MAX_SIZE",
    "MIN_CONTRAST",
    "MIN_FRAME_SIDE",
    "MIN_SIZE",
    "OTSU_STEP",
    "binarize",
    "check_frame",
    "crop_resize",
    "largest_component",
    "otsu_threshold",
    "preprocess",
    "preprocess_reference",
    "wrist_cut_keep",
]


def binarize(frame: np.ndarray, *, threshold: int | None = None) -> np.ndarray:
    """Foreground mask of a frame (step 1 of the module docstring).

    Parameters
    ----------
    frame : ndarray, shape (H, W) or (H, W, 3)
        bool mask (returned as is), or uint8 grey / BGR image.
    threshold : int, keyword-only, optional
        Grey level above which a pixel is hand (``grey > threshold``); by
        default :func:`otsu_threshold` of the frame, and an empty mask when
        that is -1 (a flat frame, or one of fewer than :data:`MIN_CONTRAST`
        grey levels).

    Returns
    -------
    ndarray, shape (H, W), bool

    Raises
    ------
    InvalidInputError
        A frame that is not an image (:func:`check_frame`), or a `threshold`
        that is not a finite number.
    """
    frame = check_frame(frame)
    if threshold is not None:
        _threshold(threshold)  # checked for masks too
    if frame.dtype == bool:
        return frame
    return binarize_frame(frame, threshold=threshold)


def otsu_threshold(frame: np.ndarray) -> int:
    """Otsu's threshold of a uint8 grey or BGR frame, from its sample.

    Parameters
    ----------
    frame : ndarray, shape (H, W) or (H, W, 3), uint8

    Returns
    -------
    int
        OpenCV's ``THRESH_OTSU`` level (0-255) of the grey levels of the
        pixels ``(y, x)`` with `y` and `x` multiples of :data:`OTSU_STEP`;
        -1 when those all have the same grey level, or when their grey levels
        (largest above 1) span fewer than :data:`MIN_CONTRAST` (a flat grey or
        white view: no hand).
    """
    frame = check_frame(frame)
    if frame.dtype == bool:
        raise InvalidInputError("otsu_threshold needs a uint8 frame, got a bool mask")
    return int(_frame_threshold(np.ascontiguousarray(frame)))


#: Smallest frame side, pixels, that can hold a hand.
MIN_FRAME_SIDE = 8


def check_frame(frame) -> np.ndarray:
    """Validate a camera frame or mask and return it unchanged.

    Parameters
    ----------
    frame : ndarray, shape (H, W) or (H, W, 3), bool or uint8
        A mask, a grey frame or a BGR frame, at least
        :data:`MIN_FRAME_SIDE` pixels on each side.

    Returns
    -------
    ndarray
        `frame` itself.

    Raises
    ------
    InvalidInputError
        If `frame` is not a numpy array, has a shape other than (H, W) or
        (H, W, 3), a side under :data:`MIN_FRAME_SIDE` pixels, NaN/inf
        values, a dtype other than bool or uint8, or a bool (H, W, 3) array
        (a mask has one channel); the message names it.
    """
    if not isinstance(frame, np.ndarray):
        raise InvalidInputError(f"frame must be a numpy array, got {type(frame).__name__}")
    if frame.ndim not in (2, 3) or (frame.ndim == 3 and frame.shape[2] != 3):
        hint = ("; drop the alpha channel: frame[..., :3]"
                if frame.ndim == 3 and frame.shape[2] == 4 else "")
        raise InvalidInputError(
            f"frame must have shape (H, W) or (H, W, 3), got {frame.shape}{hint}")
    if min(frame.shape[:2]) < MIN_FRAME_SIDE:
        raise InvalidInputError(
            f"frame is too small to hold a hand: must be at least "
            f"{MIN_FRAME_SIDE}x{MIN_FRAME_SIDE} pixels, got shape {frame.shape}")
    if frame.dtype.kind == "f" and not np.isfinite(frame).all():
        raise InvalidInputError("frame must not contain NaN or inf; give a uint8 image or "
                                "a bool mask")
    if frame.dtype not in (np.bool_, np.uint8):
        hint = ("; a float image in [0, 1] is (frame * 255).astype(np.uint8), a float mask "
                "frame > 0.5" if frame.dtype.kind == "f" else "")
        raise InvalidInputError(
            f"frame must be a bool mask or a uint8 image, got dtype {frame.dtype}{hint}")
    if frame.dtype == np.bool_ and frame.ndim == 3:
        raise InvalidInputError(
            f"a bool frame is a mask and must have shape (H, W), got {frame.shape}; give a "
            "colour frame as uint8 (H, W, 3)")
    return frame


@lru_cache(maxsize=32)
def _keep_cached(mount: CameraMount, side: str, w: int, h: int) -> np.ndarray:
    cut_mm = mount.wrist_cut_mm
    assert cut_mm is not None  # callers skip mounts without a wrist cut
    y_cut = cut_mm * 1e-3
    z = DORSUM_Z_MM * 1e-3
    # two points of the cut line and one of the forearm, in homogeneous pixel
    # coordinates (u w, v w, w), w the depth along the optical axis (as
    # CameraMount.project computes them, before its division by w)
    pose = mount.pose_in_hand(side=side)
    pc = (np.array([[-0.2, y_cut, z], [0.2, y_cut, z], [0.0, y_cut - 0.05, z]])
          - pose[:3, 3]) @ pose[:3, :3]
    uvw = pc @ mount.intrinsics(w, h).T
    vv, uu = np.mgrid[0:h, 0:w]
    # The cut line has one depth along its length (the optical axis has no x
    # component), so its two points are both in front of the camera or both
    # at or behind it.  Pixels are kept on the side of the plane through the
    # camera centre and the cut line that does not hold the forearm point.
    # That point's side is taken from its homogeneous coordinates: behind
    # the camera (a tilted or low mount) it projects mirrored through the
    # centre, and its projection lies on the other side of the line.
    if uvw[0, 2] > 0:
        # line in front of the camera: through its two projected points
        (u0, v0), (u1, v1) = uvw[:2, :2] / uvw[:2, 2:3]
        def side_of(u, v, w_=1.0):
            return (u1 - u0) * (v - v0 * w_) - (v1 - v0) * (u - u0 * w_)
    else:
        # line at or behind the camera: its homogeneous image line (no division)
        line = np.cross(uvw[0], uvw[1])
        def side_of(u, v, w_=1.0):
            return line[0] * u + line[1] * v + line[2] * w_
    forearm_sign = np.sign(side_of(*uvw[2]))
    keep = np.sign(side_of(uu, vv)) != forearm_sign
    keep.setflags(write=False)
    return keep


def wrist_cut_keep(mount: CameraMount, *, side: str = "right",
                   width_px: int | None = None, height_px: int | None = None) -> np.ndarray | None:
    """Pixels kept by the wrist cut of `mount`, or ``None`` when the mount has no cut.

    The cut line is the image of the line ``y = mount.wrist_cut_mm`` across
    the hand at dorsum height: the pixels whose rays leave the camera on the
    forearm's side of the plane through the camera centre and that line are
    cleared.  This holds for every mount :class:`CameraMount` accepts: where
    a tilted or low camera has the forearm (or the cut line itself) behind
    it, the cleared side is still the forearm's, and a camera that sees no
    part of the dorsum behind the cut loses no pixel.

    Parameters
    ----------
    mount : CameraMount
        The device; its ``wrist_cut_mm`` places the cut (None: no cut).
    side : {"right", "left"}, keyword-only
        The hand wearing the device.
    width_px, height_px : int, keyword-only, optional
        Size of the frame in pixels; the mount's own image size by default.

    Returns
    -------
    ndarray, shape (height_px, width_px), bool, read-only, or None

    Raises
    ------
    InvalidCameraError
        A `mount` that is not a :class:`CameraMount`, a bad `side` or image
        size, naming it.
    """
    mount = as_mount(mount, optional=False)
    if mount.wrist_cut_mm is None:
        return None
    w, h = mount.size(width_px, height_px)
    return _keep_cached(mount, side, w, h)


@lru_cache(maxsize=32)
def _keep_rows(mount: CameraMount, side: str, w: int, h: int) -> tuple[np.ndarray, np.ndarray]:
    """The wrist cut as one kept column interval ``[lo[y], hi[y])`` per row."""
    keep = _keep_cached(mount, side, w, h) if mount.wrist_cut_mm is not None \
        else np.ones((h, w), dtype=bool)
    any_ = keep.any(axis=1)
    lo = np.where(any_, keep.argmax(axis=1), 0).astype(np.int32)
    hi = np.where(any_, w - keep[:, ::-1].argmax(axis=1), 0).astype(np.int32)
    if not (keep.sum(axis=1) == hi - lo).all():  # a half-plane keeps one interval per row
        raise AssertionError("wrist cut is not one interval per row")
    lo.setflags(write=False)
    hi.setflags(write=False)
    return lo, hi


_DEFAULT_MOUNT: list = []  # CameraMount(), made once
_LAST_ROWS: tuple = (None, None, -1, -1, None, None)  # (mount, side, w, h, lo, hi)


def _rows_kept(mount: CameraMount | None, side: str, w: int, h: int):
    """:func:`_keep_rows`, remembering the last answer by the mount's identity.

    A live stream asks for the same mount and frame size every frame; hashing
    the mount for the lru_cache would cost more than the rest of the lookup.
    """
    global _LAST_ROWS
    if mount is None:
        if not _DEFAULT_MOUNT:
            _DEFAULT_MOUNT.append(CameraMount())
        mount = _DEFAULT_MOUNT[0]
    last = _LAST_ROWS
    if last[0] is mount and last[2] == w and last[3] == h and last[1] == side:
        return last[4], last[5]
    lo, hi = _keep_rows(mount, side, w, h)
    _LAST_ROWS = (mount, side, w, h, lo, hi)
    return lo, hi


def _check_mask(mask) -> np.ndarray:
    """`mask` refused unless it is a non-empty 2-D bool or uint8 numpy array."""
    if not isinstance(mask, np.ndarray):
        raise InvalidInputError(f"mask must be a 2-D bool or uint8 numpy array, got "
                                f"{type(mask).__name__} {short_repr(mask)}")
    if mask.ndim != 2 or mask.dtype not in (np.bool_, np.uint8):
        raise InvalidInputError(f"mask must be a 2-D bool or uint8 numpy array, got dtype "
                                f"{mask.dtype} shape {mask.shape}")
    if mask.size == 0:
        raise InvalidInputError(f"mask must not be empty (at least 1x1 pixels), got shape "
                                f"{mask.shape}")
    return mask


def largest_component(mask: np.ndarray) -> np.ndarray:
    """The largest 8-connected foreground component of `mask` (all False if none).

    Ties (components of equal pixel count) go to the component whose first
    pixel comes first in raster order.

    Parameters
    ----------
    mask : ndarray, shape (H, W), bool or uint8
        Foreground where True (nonzero).

    Returns
    -------
    ndarray, shape (H, W), bool

    Raises
    ------
    InvalidInputError
        `mask` is not a numpy array, not 2-D, empty (a side of 0 pixels), or
        of a dtype other than bool or uint8; the message names it.
    """
    import cv2

    mask = _check_mask(mask)
    n, labels = cv2.connectedComponents(mask.view(np.uint8), connectivity=8)
    if n <= 1:
        return np.zeros(mask.shape, dtype=bool)
    flat = labels.ravel()
    area = np.bincount(flat, minlength=n)
    present, index = np.unique(flat, return_index=True)
    first = np.full(n, flat.size)  # first raster index of each label (label 0 may be absent)
    first[present] = index
    area[0] = -1
    best = int(np.lexsort((first, -area))[0])
    return labels == best


def _cell_weights(n_src: int, scale: float, offset: float, size: int) -> np.ndarray:
    """(size, n_src) overlap, in cell units, of source pixel k (``[offset + k*scale,
    offset + (k+1)*scale)``) with output cell j (``[j, j+1)``)."""
    a = offset + np.arange(n_src) * scale
    j = np.arange(size)[:, None]
    return np.clip(np.minimum(a + scale, j + 1.0) - np.maximum(a, j), 0.0, None)


def crop_resize(mask: np.ndarray, *, size: int = 64) -> np.ndarray:
    """Crop `mask` to its bounding box and fit it into ``size x size``, aspect kept.

    The box (``bw x bh`` pixels) is scaled by ``s = size / max(bw, bh)`` and
    centred; a cell is True when the scaled mask covers at least half of
    it (exact area resampling with dense weight matrices; the plain
    statement of what :func:`preprocess` computes in compiled form).

    Parameters
    ----------
    mask : ndarray, shape (H, W), bool or uint8
        Foreground where True (nonzero).
    size : int, keyword-only
        Side of the result in pixels (64 in the paper), 8 to 4096 (``MIN_SIZE``
        to ``MAX_SIZE``), as for :func:`preprocess`.

    Returns
    -------
    ndarray, shape (size, size), bool
        All False when `mask` is empty.

    Raises
    ------
    InvalidInputError
        `mask` is not a non-empty 2-D bool or uint8 numpy array, or `size` is
        not an integer in [8, 4096]; the message names it.
    """
    size = _check_size(size)
    mask = _check_mask(mask)
    if mask.dtype != np.bool_:
        mask = mask != 0
    out = np.zeros((size, size), dtype=bool)
    rows = np.flatnonzero(mask.any(axis=1))
    if rows.size == 0:
        return out
    cols = np.flatnonzero(mask.any(axis=0))
    box = mask[rows[0]:rows[-1] + 1, cols[0]:cols[-1] + 1].astype(np.float64)
    bh, bw = box.shape
    s = size / max(bh, bw)
    wy = _cell_weights(bh, s, 0.5 * (size - bh * s), size)
    wx = _cell_weights(bw, s, 0.5 * (size - bw * s), size)
    return wy @ box @ wx.T >= 0.5 - 1e-9


#: Smallest and largest side, pixels, of a silhouette (`size` of :func:`preprocess` and
#: :func:`crop_resize`); 4096 x 4096 is already 16 MB of mask.
MIN_SIZE = 8
MAX_SIZE = 4096


def _check_size(size) -> int:
    return check_integer(size, "size", minimum=MIN_SIZE, maximum=MAX_SIZE)


def _min_area(min_coverage, h: int, w: int) -> int:
    """Fewest pixels of an `h` x `w` frame's kept component that cover `min_coverage` of it.

    Raises
    ------
    InvalidInputError
        `min_coverage` is not a number in [0, 1], naming it and the value.
    """
    if type(min_coverage) is not float or not 0.0 <= min_coverage <= 1.0:  # fast path: a float
        min_coverage = check_number(min_coverage, "min_coverage", minimum=0, maximum=1)
    # a component of `a` pixels is too small when a < min_coverage * h * w (rounded to 1e-6
    # so that 0.01 of 720x480 is 3456 pixels, not 3457)
    return math.ceil(round(min_coverage * h * w, 6))


def preprocess(frame: np.ndarray, mount: CameraMount | None = None, *, side: str = "right",
               size: int = 64, threshold: int | None = None,
               min_coverage: float = 0.0) -> np.ndarray:
    """The silhouette of SPEC.md section 1: binarize, wrist cut, largest component, crop, resize.

    Parameters
    ----------
    frame : ndarray, shape (H, W) bool, or (H, W) / (H, W, 3) uint8
        A rendered mask or a camera frame (BGR) of any size.
    mount : CameraMount, optional
        The camera that took the frame (for the wrist cut); the paper's device
        by default.  The frame may have any size: the cut is computed for it.
    side : {"right", "left"}, keyword-only
    size : int, keyword-only
        Output side, 64 in the paper; 8 to 4096 (``MIN_SIZE`` to ``MAX_SIZE``).
    threshold : int, keyword-only, optional
        Fixed grey threshold for uint8 frames (``grey > threshold`` is hand);
        Otsu's threshold of the frame's sample by default (see :func:`binarize`).
    min_coverage : float, keyword-only
        Least share (0-1) of the frame's pixels that the kept component
        (step 3) must cover: a smaller one is too little to be a hand (a
        speck, one bright pixel) and the silhouette is empty.  Its pixel
        count comes from the same compiled pass, at no extra cost.  0 (the
        default) keeps any component; the lookup passes
        :data:`handsynth.estimate.MIN_HAND_COVERAGE`.

    Returns
    -------
    ndarray, shape (size, size), bool
        The silhouette; all False when the frame shows no hand.

    Raises
    ------
    InvalidInputError
        A frame that is not an image (:func:`check_frame`), a `size` that
        is not an integer in [8, 4096], a `threshold` that is not a finite number, a
        `min_coverage` that is not a number in [0, 1], or a `mount` that is
        not a :class:`CameraMount` (:class:`~handsynth.errors.InvalidCameraError`);
        the message names the argument.
    """
    size = _check_size(size)
    frame = check_frame(frame)
    if mount is not None and not isinstance(mount, CameraMount):
        as_mount(mount)  # refused, naming it
    if threshold is not None:
        _threshold(threshold)  # checked for masks too
    h, w = frame.shape[0], frame.shape[1]
    min_area = _min_area(min_coverage, h, w)
    lo, hi = _rows_kept(mount, side, w, h)
    if frame.dtype == bool:
        return silhouette_from_mask(frame, lo, hi, size, min_area=min_area)
    return silhouette_from_frame(frame, lo, hi, size, threshold=threshold, min_area=min_area)


def preprocess_reference(frame: np.ndarray, mount: CameraMount | None = None, *,
                         side: str = "right", size: int = 64,
                         threshold: int | None = None, min_coverage: float = 0.0) -> np.ndarray:
    """:func:`preprocess` as the plain chain of its steps (slow; the specification).

    Parameters, result and errors as :func:`preprocess`, which tests compare
    with it.
    """
    size = _check_size(size)
    mask = binarize(frame, threshold=threshold)
    min_area = _min_area(min_coverage, mask.shape[0], mask.shape[1])
    keep = wrist_cut_keep(as_mount(mount), side=side,
                          width_px=mask.shape[1], height_px=mask.shape[0])
    if keep is not None:
        mask = mask & keep
    hand = largest_component(mask)
    if hand.sum() < min_area:  # too little to be a hand
        hand[:] = False
    return crop_resize(hand, size=size)
