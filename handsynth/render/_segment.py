"""The hand told from its background by the colour of the user's own skin.

:func:`~handsynth.render.binarize` takes the hand to be brighter than all
else in the view (Otsu's threshold), which holds on a dark background and
fails on an ordinary one.  The device is strapped to the hand, so part of
its view is always the back of the hand (:func:`palm_region`); the colour
of the skin there, in the user's rest frame, tells the hand in later frames.

Method
------
1. *Work size*: the frame is reduced to :data:`WORK_WIDTH_PX` pixels across
   (area averaging), a quarter of the device's 720 (the learnt estimators
   read cells of 16x16 device pixels, 4x4 here).
2. *Palm region*: the pixels that 24 model hands of random geometry (at 1.5
   times the learning set's spread, :class:`HandVariation`), each in six
   poses from open to fist, all cover through the device, eroded by two
   pixels; computed once per device.
3. *Skin colour* (:func:`fit_skin_colour`): each pixel's chromaticity
   ``(g, r) / (b + g + r)``, which shading scales away, and its brightness
   ``b + g + r``; over the palm region of the rest frame the mean and
   covariance of the chromaticity, refitted three times without the pixels
   farther than the 99.9 % quantile of chi-square with two degrees of
   freedom or darker than half the median brightness (a palm region that
   strays off a hand unlike the model's).
4. *Mask* (:func:`skin_mask`): each channel of the reduced frame is scaled
   so that its median over the palm region is the rest frame's (the palm
   region is always hand, so a change of white balance or exposure since
   the rest frame is undone: without it a cast of 10 % made the mask
   useless); a frame that needs two channels' gains further apart than
   1.6 shows something else there and is read as showing no hand (a
   ground of the skin's own hue, such as a brown table, is not caught);
   then a pixel is hand when its chromaticity lies
   within that quantile of the skin's (Mahalanobis distance) and it is
   brighter than a quarter of the palm's median; an opening by 2x2 pixels
   removes specks, and only the regions connected to the palm region are
   kept: a background patch of skin colour elsewhere is not, nor a finger
   cut off by a seam of edge pixels mixed with the ground (joining regions
   across such one-pixel seams cost more than it gained on the
   development backgrounds: 9.93 against 9.16 deg).

The two thresholds are fixed by the chi-square distribution and a brightness
ratio chosen before any measurement, not fitted to test frames.  What it
cannot do: tell the hand from a background of the same chromaticity (wood,
another person's skin, beige walls); a grey hand in grey light is told only
by its brightness, and so is a skin close to grey (pale, or overexposed:
:attr:`SkinColour.tells_grey`).  Measured in docs/camera_estimator.md
("Telling the hand from an ordinary background").
"""

from __future__ import annotations

import functools
from dataclasses import dataclass, field

import numpy as np

from .._checks import check_side
from ..errors import InvalidInputError
from ._camera import CameraMount, as_mount
from ._preprocess import check_frame

__all__ = ["WORK_WIDTH_PX", "SkinColour", "brightness_overlap", "fit_skin_colour", "palm_region",
           "skin_inside", "skin_mask"]

#: Width of the reduced frame the skin is told in, pixels.
WORK_WIDTH_PX = 180
#: 99.9 % quantile of chi-square with 2 degrees of freedom (``-2 ln 0.001``).
_CHI2_2_999 = 13.815510557964274
#: A pixel darker than this share of the palm's median brightness is background.
_BRIGHTNESS_FLOOR = 0.25
#: Chromaticity variance added to the fitted covariance (s.d. 0.01: 8-bit steps and noise).
_CHROMA_VAR_FLOOR = 1e-4
#: Bits a channel loses in the look-up table (8 -> 6 bits: 64 levels of 4 grey levels each).
_SHIFT = 2
_LEVELS, _STEP = 256 >> _SHIFT, 1 << _SHIFT
_OPEN_KERNEL = np.ones((2, 2), np.uint8)
#: Largest ratio of two channels' gains a frame's white balance is corrected by: casts of
#: 20 % (gains 1.25 and 0.83, ratio 1.5) are undone; beyond, the palm region does not show
#: the rest frame's skin (no hand, as in 8 of 9 photographs without one, ratios 1.9-11),
#: and the frame shows no hand.  Chosen after measuring those ratios.
_MAX_CAST = 1.6


@dataclass(frozen=True)
class SkinColour:
    """The user's skin as the device sees it, from one rest frame.

    Attributes
    ----------
    mean : (float, float)
        Mean chromaticity ``(g, r) / (b + g + r)`` over the palm region.
    inverse_cov : ((float, float), (float, float))
        Inverse of its covariance (floored).
    brightness : float
        Median ``b + g + r`` over the palm region, 0-765.
    palm_bgr : (float, float, float)
        Median of each channel over the palm region: each later frame is
        scaled channel by channel to give its palm region these (step 4).
    work_size : (int, int)
        Width and height of the reduced frames, pixels.
    mount : CameraMount
    side : str
    """

    mean: tuple[float, float]
    inverse_cov: tuple[tuple[float, float], tuple[float, float]]
    brightness: float
    palm_bgr: tuple[float, float, float]
    work_size: tuple[int, int]
    mount: CameraMount
    side: str
    _table: np.ndarray = field(init=False, repr=False, compare=False)

    @property
    def tells_grey(self) -> bool:
        """Whether neutral grey lies outside the skin's ellipse of step 4.

        A skin close to grey in chromaticity (pale or overexposed, its
        channels clipped) cannot be told from white, grey or black
        surfaces by colour: their pixels would pass step 4's test.
        """
        grey = np.full(2, 1.0 / 3.0)
        d2 = _distance2(grey, np.asarray(self.mean), np.asarray(self.inverse_cov))
        return bool(d2 >= _CHI2_2_999)

    def __post_init__(self) -> None:
        # step 4's test for every colour quantised to 6 bits a channel (bin centres): one
        # table look-up a pixel instead of the arithmetic (skin_inside is the plain version)
        q = (np.arange(_LEVELS, dtype=np.float32) * _STEP + _STEP / 2.0)
        b, g, r = np.meshgrid(q, q, q, indexing="ij")
        table = skin_inside(np.stack([b, g, r], axis=-1), self).reshape(-1)
        table.setflags(write=False)
        object.__setattr__(self, "_table", table)


def _work_size(shape) -> tuple[int, int]:
    h, w = int(shape[0]), int(shape[1])
    return WORK_WIDTH_PX, max(2, round(WORK_WIDTH_PX * h / w))


@functools.lru_cache(maxsize=8)
def _palm_region_cached(mount: CameraMount, side: str, w: int, h: int
                        ) -> tuple[np.ndarray, np.ndarray]:
    """The palm region (h, w) and its flat pixel indices, both read-only."""
    import cv2

    from ..models import HandShape, named_pose
    from ._varied import HandVariation, VariedRasterizer

    rng = np.random.default_rng(0)
    acc = np.ones((h, w), bool)
    for _ in range(24):
        r = VariedRasterizer(HandShape(), mount, side=side, width_px=w, height_px=h,
                             forearm=False)
        r.vary(HandVariation.random(rng, spread=1.5))
        for pose in ("open", "spread", "fist", "point", "pinch", "grasp"):
            acc &= r.mask(named_pose(pose))
    out = cv2.erode(acc.astype(np.uint8), np.ones((5, 5), np.uint8)) > 0
    flat = np.flatnonzero(out)
    for a in (out, flat):
        a.setflags(write=False)
    return out, flat


def palm_region(mount: CameraMount | None = None, *, side: str = "right",
                width_px: int = WORK_WIDTH_PX, height_px: int | None = None) -> np.ndarray:
    """The part of the device's view that a hand covers whatever its pose.

    Parameters
    ----------
    mount : CameraMount, optional
        The paper's device by default.
    side : {"right", "left"}, keyword-only
    width_px, height_px : int, keyword-only
        Size of the region; the device's aspect ratio at :data:`WORK_WIDTH_PX`
        by default.

    Returns
    -------
    ndarray, shape (height_px, width_px), bool, read-only
        Step 2 of the module docstring.

    Raises
    ------
    InvalidInputError
        A `side` other than right or left, or a region no model hand covers.
    """
    mount = as_mount(mount)
    check_side(side)
    h = height_px or round(width_px * mount.height_px / mount.width_px)
    out = _palm_region_cached(mount, side, int(width_px), int(h))[0]
    if not out.any():
        raise InvalidInputError(f"no part of the view of {mount} is hand in every pose: "
                                "the skin cannot be sampled")
    return out


def _chroma_of(bgr: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Chromaticity (..., 2) and brightness (...) of BGR values (..., 3)."""
    bgr = np.asarray(bgr, np.float32)
    total = bgr.sum(axis=-1)
    return bgr[..., 1:] / np.maximum(total, 1.0)[..., None], total


def _reduce(frame: np.ndarray, size: tuple[int, int]) -> np.ndarray:
    """`frame` averaged down to `size` (area averaging)."""
    import cv2

    w, h = size
    while frame.shape[:2] in ((4 * h, 4 * w), (2 * h, 2 * w)):
        # halving by bilinear interpolation averages each 2x2 block exactly, three times
        # faster than INTER_AREA's general case (the device's 720x480 to 180x120: twice)
        frame = cv2.resize(frame, (frame.shape[1] // 2, frame.shape[0] // 2),
                           interpolation=cv2.INTER_LINEAR)
    if frame.shape[:2] == (h, w):
        return frame
    return cv2.resize(frame, size, interpolation=cv2.INTER_AREA)


def skin_inside(bgr: np.ndarray, skin: SkinColour) -> np.ndarray:
    """Step 4's colour test, plainly: which BGR values (..., 3) are of `skin`.

    :func:`skin_mask` looks the same test up in a table of 6-bit colours;
    this is the reference it is tested against.
    """
    chroma, total = _chroma_of(bgr)
    return ((_distance2(chroma, np.asarray(skin.mean), np.asarray(skin.inverse_cov))
             < _CHI2_2_999) & (total > _BRIGHTNESS_FLOOR * skin.brightness))


def _bgr(frame, what: str) -> np.ndarray:
    frame = check_frame(frame)
    if frame.ndim != 3 or frame.dtype != np.uint8:
        raise InvalidInputError(f"{what} must be a uint8 colour (H, W, 3) frame to tell the skin "
                                f"by its colour, got {frame.dtype} of shape {frame.shape}")
    return frame


def _distance2(chroma: np.ndarray, mean: np.ndarray, inv: np.ndarray) -> np.ndarray:
    d = chroma - mean
    return (d[..., 0] * (inv[0, 0] * d[..., 0] + inv[0, 1] * d[..., 1])
            + d[..., 1] * (inv[1, 0] * d[..., 0] + inv[1, 1] * d[..., 1]))


def fit_skin_colour(rest_frame: np.ndarray, mount: CameraMount | None = None, *,
                    side: str = "right") -> SkinColour:
    """The colour of the user's skin over the palm region of a rest frame (step 3).

    Parameters
    ----------
    rest_frame : ndarray, shape (H, W, 3), uint8
        BGR frame of the device's whole view, the hand in it.
    mount : CameraMount, optional
        The device (the paper's by default).
    side : {"right", "left"}, keyword-only

    Returns
    -------
    SkinColour

    Raises
    ------
    InvalidInputError
        Not a colour frame, or a palm region too dark to hold a hand.
    """
    frame = _bgr(rest_frame, "rest_frame")
    mount = as_mount(mount)
    size = _work_size(frame.shape)
    palm = palm_region(mount, side=side, width_px=size[0], height_px=size[1])
    small = _reduce(frame, size)
    chroma, total = _chroma_of(small)
    x, b = chroma[palm], total[palm]
    median = float(np.median(b))
    if median < 30.0:  # under 10 grey levels per channel: no lit skin there
        raise InvalidInputError(f"rest_frame: the back of the hand is dark (median brightness "
                                f"{median / 3:.0f} of 255 where the hand always is): it shows "
                                "no hand to take the skin's colour from")
    keep = b > 0.5 * median
    mean: np.ndarray = np.zeros(2)
    inv: np.ndarray = np.eye(2)
    for _ in range(3):
        if keep.sum() < 10:
            break
        mean = x[keep].mean(axis=0)
        inv = np.linalg.inv(np.cov(x[keep].T) + _CHROMA_VAR_FLOOR * np.eye(2))
        keep = (_distance2(x, mean, inv) < _CHI2_2_999) & (b > 0.5 * median)
    palm_bgr = np.median(small[palm], axis=0)
    return SkinColour(mean=(float(mean[0]), float(mean[1])),
                      inverse_cov=((float(inv[0, 0]), float(inv[0, 1])),
                                   (float(inv[1, 0]), float(inv[1, 1]))),
                      brightness=median,
                      palm_bgr=(float(palm_bgr[0]), float(palm_bgr[1]), float(palm_bgr[2])),
                      work_size=size, mount=mount, side=side)


def skin_mask(frame: np.ndarray, skin: SkinColour) -> np.ndarray:
    """The hand in a frame, told by the colour of `skin` (step 4).

    Parameters
    ----------
    frame : ndarray, shape (H, W, 3), uint8
        BGR frame of the device's whole view, of the rest frame's aspect ratio.
    skin : SkinColour

    Returns
    -------
    ndarray, shape (h, w), bool
        At ``skin.work_size`` (a quarter of the device's width): the learnt
        estimators and :func:`~handsynth.render.coverage` take masks of any
        size with the device's aspect ratio.

    Raises
    ------
    InvalidInputError
        Not a colour frame.
    """
    import cv2

    frame = _bgr(frame, "frame")
    w, h = skin.work_size
    palm, flat = _palm_region_cached(skin.mount, skin.side, w, h)
    small = _reduce(frame, (w, h))
    # white balance and exposure as in the rest frame: the palm region is always hand
    now = np.median(small.reshape(-1, 3)[flat], axis=0)
    gain = np.asarray(skin.palm_bgr, np.float32) / np.maximum(now, 1.0).astype(np.float32)
    if gain.max() > _MAX_CAST * gain.min():  # the palm region is not the skin of the rest frame
        return np.zeros((h, w), bool)
    balanced: np.ndarray = cv2.transform(small, np.diag(gain))  # saturating, rounded
    q = balanced >> _SHIFT
    bits = 8 - _SHIFT
    index = (q[..., 0].astype(np.int32) << 2 * bits) | (q[..., 1].astype(np.int32) << bits) | q[..., 2]
    inside = skin._table[index]
    m8 = cv2.morphologyEx(inside.view(np.uint8), cv2.MORPH_OPEN, _OPEN_KERNEL)
    _, labels = cv2.connectedComponents(m8)
    touching = np.unique(labels[palm & (m8 > 0)])
    touching = touching[touching > 0]
    if not len(touching):
        return np.zeros((h, w), bool)
    lut = np.zeros(labels.max() + 1, bool)
    lut[touching] = True
    return lut[labels]


def brightness_overlap(frame: np.ndarray, skin: SkinColour) -> float:
    """How far Otsu's threshold and the skin's colour agree on a frame.

    Parameters
    ----------
    frame : ndarray, shape (H, W, 3), uint8
    skin : SkinColour

    Returns
    -------
    float
        Intersection over union of :func:`~handsynth.render.binarize`'s mask
        (reduced to ``skin.work_size``, a pixel hand when at least half of it
        is) and :func:`skin_mask`'s; 1 when both are empty.  Near 1 on a dark
        background, low where the background is brighter than the hand.
    """
    import cv2

    from ._preprocess import binarize

    frame = _bgr(frame, "frame")
    by_colour = skin_mask(frame, skin)
    by_brightness = cv2.resize(binarize(frame).view(np.uint8), skin.work_size,
                               interpolation=cv2.INTER_AREA) > 0
    union = (by_colour | by_brightness).sum()
    return 1.0 if union == 0 else float((by_colour & by_brightness).sum() / union)
