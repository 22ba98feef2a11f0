"""Measuring a hand on a top-down photo (SPEC.md section 1, "Choosing the database").

The paper measures the user's open hand on a photo by hand, about 2 minutes
with the photo; :func:`measure_photo` finds the same values (``L1..L14``,
``W1..W14``, ``P_width``, ``P_height``, ``T_width``, ``T_height``; see
:mod:`handsynth.models.HandMeasurements`) on the silhouette in a fraction of a
second and applies formulas (1)-(4) (:func:`select_shape`).

The photo
---------
One open hand lying flat on a plain background, fingers spread, the thumb
flat and spread away from the index finger, taken from straight above
(dorsal or palmar side, left or right hand, any rotation).  A forearm may
leave the picture at the border; nothing else of the hand may touch it.  A
scale is required: ``mm_per_px`` at the plane of the hand, or a reference
object of known size lying beside the hand (see :func:`measure_photo`).
Colour photos work on any background unlike skin in colour; grey photos
need a background much darker than the hand's shaded edges (at most a
quarter of the hand's grey level: black cloth) or lighter than its brightest
parts (white paper), and are refused otherwise ("a colour photo is
needed"): on a mid-grey background the shaded rim of the hand would be
taken for background and every breadth would come out too small.  A flatbed
scanner gives an orthographic picture with a known scale (25.4 / dpi mm per
pixel); a camera should be far away (perspective scales parts nearer the
lens up, see the accuracy below).

Method
------
1. *Silhouette*: distance of every pixel's colour to the background colour
   (median of the picture's border; CIELAB with lightness weighted 0.35 for
   colour, grey level for grey photos), Otsu's threshold (0.7 of it in a
   thin band around the object, for dimly lit rims), 3x3 opening and
   closing.  The largest object, holes filled, is the hand; the second
   largest is the reference object.
2. *Fingertips and valleys*: outline points where the outline, followed
   22 mm each way, forms a narrow convex protrusion (chord at most 32 mm,
   apex at least 10 mm and half the chord beyond it).  The five tips split
   the outline; the longest arc runs round the wrist, and of the two end
   digits the thumb is the one farther from its neighbour.  A valley is the
   outline point between neighbouring tips farthest from their chord.
3. *Finger axes*: the line through the midpoints of 15 sections across the
   digit between its base (the valleys) and its tip, fitted three times
   (total least squares); the fingertip is where the axis leaves the
   silhouette (sub-pixel).
4. *MCP joints* (not visible on a silhouette): each finger of a spread hand
   turns about its MCP joint, so its axis passes through it.  The standard
   hand's knuckle layout (:func:`~handsynth.models.standard_layout_mm`:
   MCP spacing a quarter of the hand breadth, heights from the metacarpal
   lengths of Buchholz et al. 1992), scaled across by the palm ratio, is
   rotated and moved onto the fan of axes (least squares, with weak priors
   4 +- 8 mm below the valleys for nearly parallel fingers).
5. *Hand frame and wrist*: origin at the middle MCP; the hand axis runs from
   the middle of the wrist section to it.  The wrist is the narrowest section
   across the hand 40-160 mm below the knuckles (the middle of the stretch
   within 1 mm of the narrowest breadth, sections every 0.05 mm), or the
   silhouette's end when no forearm is in the picture.
6. *Thumb CMC* (hidden under the thenar): on the thumb's axis where it is
   ``T_width`` from the middle finger's axis; ``T_width`` is the standard
   hand's (23.5 mm, 0.28 hand breadths) scaled by the palm ratio, so it is
   not measured independently.  The thumb's MCP joint lies one metacarpal
   (0.251 hand lengths, Buchholz et al. 1992) further along.
7. *Phalanx lengths*: a silhouette shows no creases (rendered hands have
   none), so each digit's length from its MCP joint to its tip is split in
   the proportions of Buchholz et al. (1992) Table 1: the split is
   proportional, and ``r_length`` of formula (1) is in effect the mean
   ratio of the five digit lengths.
8. *Breadths*: median of five sections across the axis within +-10 % of
   each phalanx around its middle.
9. *Palm*: ``P_width`` is the section across the hand midway between the CMC
   and the mean MCP height; the palm ratio of steps 4 and 6 is ``P_width``
   over the standard hand's, iterated with steps 4-6 until it settles.
   ``P_height`` runs from the wrist to the middle MCP, ``T_height`` from the
   wrist to the CMC, along the hand axis.
10. *Calibration*: four things a silhouette cannot show are read off the
    standard model measured the same way (SPEC.md: "measure the same on the
    standard model"; :class:`MeasureCalibration`, :func:`calibrate_on_model`):
    the wrist line lies 1.2 mm below the narrowest section, the thumb's bone
    axis lies 0.095 thumb breadths off its silhouette's midline, and the
    thumb, seen from its side and 12 deg out of the palm's plane, shows 0.90
    and 0.85 of its phalanges' breadth and 0.96 of their length.  On a human
    hand these corrections are the model's, not the person's.
11. *Formulas (1)-(4)* with ``normalize="none"`` (the photo has a scale, so
    the values are true millimetres).
12. *Model shape* (:attr:`PhotoMeasurement.shape`): the formulas' ratios
    mapped by a linear :class:`ShapeCorrection` fitted on photos of model
    hands of known shape (:func:`fit_shape_correction`), for a database
    built for the hand itself.  On 30 hands it was not fitted on, the RMS
    error of (length, width, palm, thumb) falls from (.003, .003, .0045,
    .019) to (.0014, .0012, .0015, .0048) at 0.25 mm/px and from (.0056,
    .0037, .0059, .020) to (.0042, .0022, .0036, .0071) at 0.5 mm/px
    (``scripts/fit_shape_correction.py``).

Accuracy on rendered hands of known shape
-----------------------------------------
Of the formulas' ratios (``selection``; the model shape's is in step 12).
Photos of the model hand in :data:`MEASURE_POSE` from
:func:`render_measurement_photo` (orthographic, exact scale), each at a
random rotation; off-grid shapes drawn uniformly from length and palm
0.93-1.07, width and thumb 0.86-1.14; error = measured - true ratio (half a
level step is 0.025 for length and palm, 0.05 for width and thumb):

====================  ========  =======================  =======================
photos                selected  mean abs error           max abs error
                      =nearest  length width palm thumb  length width palm thumb
====================  ========  =======================  =======================
81 grid, 0.25 mm/px   81/81     .002  .002  .004  .015   .006  .007  .010  .036
60 off, 0.25 mm/px    52/60     .003  .002  .005  .016   .006  .006  .011  .039
81 grid, 0.5 mm/px    81/81     .003  .002  .005  .017   .010  .010  .013  .042
60 off, 0.5 mm/px     54/60     .004  .003  .005  .015   .012  .008  .011  .036
====================  ========  =======================  =======================

Every off-grid miss is a shape near a level boundary: within 0.01 of it for
length and palm, within 0.03 for the thumb, the least precise ratio (its CMC
joint is hidden).  Per ratio at 0.25 mm/px: length 58/60, width 60/60,
palm 58/60, thumb 56/60.
With the scene's perspective "top" camera (450 mm up, fovy 40 deg) the
scale at the joints' plane leaves errors of about -0.015 (length), -0.02
(width) and +0.03 (thumb): parts nearer the lens look larger.  Blur (2 px)
and JPEG (quality 60) move the width ratio by up to +0.01.  A thumb raised
off the table (the ``spread`` pose) or a fist is refused, not measured.
Time per photo (one core of a shared, busy machine): 0.1-0.3 s at 600 x 600
pixels, 0.2-0.6 s at 1200 x 1200; the first call adds about 1 s of imports.
"""

from __future__ import annotations

import itertools
import math
import os
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .._checks import check_instance, check_number, check_options, check_path
from .._io import write_text
from ..errors import InvalidInputError
from ..estimate import Selection, SelectionOptions, select_shape, shape_ratios
from ..models import HandMeasurements, HandShape, model_measurements
from ._options import MeasureCalibration, MeasureOptions

__all__ = [
    "MAX_MM_PER_PX",
    "MAX_REFERENCE_WIDTH_MM",
    "FingerFit",
    "PhotoMeasurement",
    "annotate_measurement",
    "measure_photo",
    "write_measurement_file",
]

#: Largest scale accepted, mm per pixel (a photo of a hand has about 0.05 to 1; far
#: beyond that is a scale in other units, refused by the hand's area).
MAX_MM_PER_PX = 1000.0
#: Longest reference object accepted, mm.
MAX_REFERENCE_WIDTH_MM = 10_000.0

_FINGER_ORDER = ("thumb", "index", "middle", "ring", "little")
_LIGHTNESS_WEIGHT = 0.35
_RIM_FRACTION = 0.004   # rim band around the object, fraction of the picture's side
_RIM_THRESHOLD = 0.7    # fraction of Otsu's threshold enough within the rim band
_WRIST_BAND_MM = 1.0    # the wrist: middle of the sections within this of the narrowest
# largest silhouette taken for a hand (a hand with 300 mm of forearm is about
# 50,000 mm^2): more means a wrong scale, e.g. mm_per_px given per cm or inch
_MAX_HAND_AREA_MM2 = 250_000.0
# a grey photo needs a background at most this fraction of the hand's (median)
# grey level: the shaded rim of a hand is about half as bright as its back; or,
# for a hand darker than the background, the gap between the background and the
# hand's brightest parts (99th percentile) at least this fraction of the gap
# between the background and the hand's median (found on rendered hands: 0.46-0.49
# where a large part of the hand is missed, 0.78-0.86 where nothing is)
_GREY_DARK_BACKGROUND = 0.25
_GREY_LIGHT_GAP = 0.65
_LARGE_HAND_AREA_MM2 = 60_000.0  # above this a failure to find the fingers hints at the scale


# -- segmentation -----------------------------------------------------------------


def _foreground(image: np.ndarray) -> np.ndarray:
    """Foreground mask (H, W) bool of a plain-background photo (colour distance + Otsu)."""
    import cv2

    from ..render import check_frame

    img = check_frame(image)
    if img.dtype == bool:
        return img.copy()
    if img.ndim == 2:
        pix = img.astype(np.float32)[..., None]
    else:
        # CIELAB with the lightness weighted down: a background lit unevenly
        # changes mostly in lightness, skin differs from it in colour as well
        pix = cv2.cvtColor(img, cv2.COLOR_BGR2LAB).astype(np.float32)
        pix[..., 0] *= _LIGHTNESS_WEIGHT
    border = np.concatenate([pix[:2].reshape(-1, pix.shape[2]), pix[-2:].reshape(-1, pix.shape[2]),
                             pix[:, :2].reshape(-1, pix.shape[2]),
                             pix[:, -2:].reshape(-1, pix.shape[2])])
    background = np.median(border, axis=0)
    dist = np.sqrt(((pix - background) ** 2).sum(axis=2))
    top = float(dist.max())
    if top < 12.0:
        raise InvalidInputError(
            "no hand found: the photo is plain (every pixel is within "
            f"{top:.0f} grey levels of the background colour)")
    scaled = np.round(dist * (255.0 / top)).astype(np.uint8)
    otsu, strong = cv2.threshold(scaled, 0, 255, cv2.THRESH_BINARY + cv2.THRESH_OTSU)
    # a dimly lit rim (skin turning away from the light) may fall under Otsu's
    # threshold: within a thin band around the object 0.7 of it is enough
    # (less would take in the halo of a blurred or JPEG-compressed edge),
    # unless the background itself varies that much (its 90th
    # percentile on the border: a forearm may cover a little of the border)
    border_dist = np.sqrt(((border - background) ** 2).sum(axis=1)) * (255.0 / top)
    weak_t = max(_RIM_THRESHOLD * otsu, 2.0 * float(np.percentile(border_dist, 90)) + 2.0)
    r = max(1, round(_RIM_FRACTION * min(img.shape[:2])))
    band = cv2.dilate(strong, cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (2 * r + 1, 2 * r + 1)))
    out = np.where((scaled > weak_t) & (band > 0), 255, strong).astype(np.uint8)
    kernel = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (3, 3))
    opened = cv2.morphologyEx(out, cv2.MORPH_OPEN, kernel)
    closed = cv2.morphologyEx(opened, cv2.MORPH_CLOSE, kernel)
    mask = closed > 0
    grey = img if img.ndim == 2 else _grey_or_none(img)
    if grey is not None:
        _check_grey_contrast(grey, mask)
    return mask


def _grey_or_none(img: np.ndarray) -> np.ndarray | None:
    """The grey level of a BGR picture whose three channels are equal (a grey photo), else None."""
    b, g, r = (img[..., k].astype(np.int16) for k in range(3))
    if int(np.abs(b - g).max()) <= 2 and int(np.abs(g - r).max()) <= 2:
        return img[..., 1]
    return None


def _check_grey_contrast(grey: np.ndarray, mask: np.ndarray) -> None:
    """Refuse a grey photo whose background is not much darker or lighter than the hand.

    Without colour only the grey level separates the hand from the
    background, and a hand's edges are shaded: seen from above the skin
    turning away from the light is about half as bright as the back of the
    hand.  On a background within that range the shaded rim is taken for
    background, every breadth comes out 1-3 mm too small and the fingers
    too long (or fingertips are lost), with nothing to show for it.
    """
    if not mask.any():
        return
    border = np.concatenate([grey[:2].ravel(), grey[-2:].ravel(),
                             grey[:, :2].ravel(), grey[:, -2:].ravel()]).astype(np.float64)
    background = float(np.median(border))
    hand, brightest = (float(v) for v in np.percentile(grey[mask], [50.0, 99.0]))
    if hand > background:
        # the shaded rim, about half the hand's level, must stay well above the background
        ok = background <= _GREY_DARK_BACKGROUND * hand
        need = f"darker than grey level {_GREY_DARK_BACKGROUND * hand:.0f}"
    else:
        # the hand's brightest parts must stay nearer the hand's level than the background's
        # (when they come close to it, the part of the hand found is the darker part only)
        ok = background - brightest >= _GREY_LIGHT_GAP * (background - hand)
        need = "much lighter than the hand's brightest parts"
    if not ok:
        raise InvalidInputError(
            f"a colour photo is needed: in this grey photo the background (grey level "
            f"{background:.0f}) is too close to the hand's (median {hand:.0f}) to tell the "
            "hand's shaded edges from it, so its breadths would come out too small; take "
            f"the photo in colour, or in grey on a plain background {need}")


def _hand_and_reference(mask: np.ndarray, want_reference: bool):
    """Split the foreground into the hand (largest blob) and the reference (second largest)."""
    import cv2

    n, labels, stats, _ = cv2.connectedComponentsWithStats(mask.astype(np.uint8), connectivity=8)
    areas = stats[1:, cv2.CC_STAT_AREA].astype(np.int64)
    if n <= 1:
        raise InvalidInputError("no hand found: the photo has no foreground object")
    order = np.argsort(areas)[::-1]
    big = areas[order[0]]
    blobs = [int(i) + 1 for i in order if areas[i] >= 0.01 * big]
    if len(blobs) >= 2 and areas[blobs[1] - 1] >= 0.5 * big:
        raise InvalidInputError(
            f"two hand-sized blobs in the photo ({big} and {areas[blobs[1] - 1]} pixels): "
            "photograph one hand alone on a plain background")
    hand = _fill_holes(labels == blobs[0])
    ref = None
    if want_reference:
        if len(blobs) < 2:
            raise InvalidInputError(
                "reference_width_mm was given but the photo holds no reference object: "
                "put an object of known width (e.g. a card) beside the hand, apart from it")
        if len(blobs) >= 3 and areas[blobs[2] - 1] >= 0.5 * areas[blobs[1] - 1]:
            raise InvalidInputError(
                "the reference object is ambiguous: the second- and third-largest objects "
                f"are of similar size ({areas[blobs[1] - 1]} and {areas[blobs[2] - 1]} pixels)")
        ref = _fill_holes(labels == blobs[1])
    return hand, ref


def _fill_holes(blob: np.ndarray) -> np.ndarray:
    """The blob with its holes filled (outer contour drawn filled)."""
    import cv2

    contours, _ = cv2.findContours(blob.astype(np.uint8), cv2.RETR_EXTERNAL,
                                   cv2.CHAIN_APPROX_NONE)
    out = np.zeros(blob.shape, np.uint8)
    cv2.drawContours(out, contours, -1, 1, thickness=cv2.FILLED)
    return out > 0


def _reference_scale(ref: np.ndarray, width_mm: float) -> tuple[float, np.ndarray]:
    """mm per pixel from the reference blob (its longer min-area-rectangle side is `width_mm`).

    Returns the scale and the rectangle's corners (4, 2) px.
    """
    import cv2

    contours, _ = cv2.findContours(ref.astype(np.uint8), cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_NONE)
    pts = max(contours, key=len).reshape(-1, 2).astype(np.float32)
    if ((pts[:, 0] <= 0) | (pts[:, 1] <= 0) | (pts[:, 0] >= ref.shape[1] - 1)
            | (pts[:, 1] >= ref.shape[0] - 1)).any():
        raise InvalidInputError(
            "the reference object (the second-largest object) touches the picture's border: "
            "it must lie wholly inside the photo")
    (cx, cy), (w, h), ang = cv2.minAreaRect(pts)
    corners = cv2.boxPoints(((cx, cy), (w, h), ang))
    # the rectangle runs through the outermost pixel centres: the object is one pixel longer
    side_px = max(w, h) + 1.0
    return width_mm / side_px, np.asarray(corners, np.float64)


# -- contour ------------------------------------------------------------------------


def _outer_contour(hand: np.ndarray) -> np.ndarray:
    """Outer contour (N, 2) float (x, y) of the hand blob, resampled to 1-pixel steps."""
    import cv2

    contours, _ = cv2.findContours(hand.astype(np.uint8), cv2.RETR_EXTERNAL,
                                   cv2.CHAIN_APPROX_NONE)
    p = max(contours, key=len).reshape(-1, 2).astype(np.float64)
    closed = np.vstack([p, p[:1]])
    cum = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(closed, axis=0).T))])
    n = max(round(cum[-1]), 8)
    s = np.arange(n) * (cum[-1] / n)
    return np.stack([np.interp(s, cum, closed[:, 0]), np.interp(s, cum, closed[:, 1])], axis=1)


def _ray_edges(score: np.ndarray, origins: np.ndarray, dirs: np.ndarray,
               max_px: float) -> np.ndarray:
    """Distance (R,) px from each origin along its direction to the first exit from the blob.

    `score` is the blob as float (1 inside, 0 outside); the exit is where the
    bilinear interpolation of `score` falls below 0.5 (the pixel boundary on
    a binary mask).  NaN where no exit is found within `max_px` or the origin
    is outside.
    """
    from scipy.ndimage import map_coordinates

    origins = np.atleast_2d(origins)
    dirs = np.broadcast_to(np.atleast_2d(dirs), origins.shape)
    steps = np.arange(0.0, max_px + 0.5, 0.5)
    pts = origins[:, None, :] + dirs[:, None, :] * steps[None, :, None]
    vals = map_coordinates(score, [pts[..., 1].ravel(), pts[..., 0].ravel()], order=1,
                           mode="constant", cval=0.0).reshape(pts.shape[:2])
    out = vals < 0.5
    first = out.argmax(axis=1)
    ok = out.any(axis=1) & (first > 0)
    r = np.arange(len(origins))
    i = np.where(ok, first, 1)
    v0, v1 = vals[r, i - 1], vals[r, i]
    frac = np.clip((v0 - 0.5) / np.maximum(v0 - v1, 1e-9), 0.0, 1.0)
    return np.where(ok, steps[i - 1] + 0.5 * frac, np.nan)


def _fingertips(contour: np.ndarray, shape_hw: tuple[int, int], px_per_mm: float,
                *, arc_mm: float, max_width_mm: float, min_depth_mm: float):
    """Indices of fingertip candidates on the contour, and their protrusion depth in mm.

    A contour point is a fingertip candidate where the contour, followed
    `arc_mm` both ways, forms a narrow convex protrusion: the chord between
    the two end points is at most `max_width_mm` and the point lies at least
    `min_depth_mm`, and at least half the chord, beyond the chord's midpoint.
    Windows touching the image border are skipped (a forearm cut by the
    border is not a finger).  Each run of candidates gives one tip, its
    deepest point.
    """
    from scipy.ndimage import gaussian_filter1d, maximum_filter1d

    n = len(contour)
    k = max(3, round(arc_mm * px_per_mm))
    if 2 * k + 1 >= n:
        return np.zeros(0, np.intp), np.zeros(0)
    sm = gaussian_filter1d(contour, sigma=max(1.0, px_per_mm), axis=0, mode="wrap")
    a, b = np.roll(sm, k, axis=0), np.roll(sm, -k, axis=0)
    chord = np.hypot(*(b - a).T) / px_per_mm
    depth = np.hypot(*(sm - 0.5 * (a + b)).T) / px_per_mm
    x, y = contour.T
    area2 = float(np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y))
    da, db = sm - a, b - sm
    turn = da[:, 0] * db[:, 1] - da[:, 1] * db[:, 0]
    convex = np.sign(turn) == np.sign(area2)
    h, w = shape_hw
    on_border = (x < 1.0) | (y < 1.0) | (x > w - 2.0) | (y > h - 2.0)
    near_border = maximum_filter1d(on_border.astype(np.uint8), size=2 * k + 1, mode="wrap") > 0
    # a finger stands out at least half its width beyond the chord (a square corner: 0.35)
    cand = (convex & ~near_border & (chord <= max_width_mm) & (depth >= min_depth_mm)
            & (depth >= 0.5 * chord))
    if not cand.any():
        return np.zeros(0, np.intp), np.zeros(0)
    if cand.all():
        return np.array([int(np.argmax(depth))]), depth[[int(np.argmax(depth))]]
    start = int(np.flatnonzero(~cand)[0])  # walk the circle from a non-candidate
    tips: list[int] = []
    run: list[int] = []
    for j in range(start, start + n + 1):
        i = j % n
        if cand[i] and j < start + n:
            run.append(i)
        elif run:
            tips.append(run[int(np.argmax(depth[run]))])
            run = []
    rows = np.array(sorted(tips), np.intp)
    return rows, depth[rows]


def _arc(n: int, i0: int, i1: int, step: int) -> np.ndarray:
    """Contour indices from `i0` to `i1` inclusive walking by `step` (+1 or -1) around n points."""
    length = ((i1 - i0) * step) % n
    return (i0 + step * np.arange(length + 1)) % n


def _order_fingers(contour: np.ndarray, tips: np.ndarray):
    """Tips in the order thumb..little, the four valleys between them, and the walking step.

    The five tips split the closed contour into five arcs; the longest runs
    round the palm and wrist, so the fingers follow each other along the
    other four.  Of the two end fingers the thumb is the one farther from
    its neighbour's tip.  A valley is the contour point between two
    neighbouring tips farthest from the chord joining them.
    """
    n = len(contour)
    gaps = (np.roll(tips, -1) - tips) % n
    j = int(np.argmax(gaps))
    seq = np.roll(tips, -(j + 1))
    step = 1
    p = contour[seq]
    if np.hypot(*(p[4] - p[3])) > np.hypot(*(p[0] - p[1])):
        seq, step = seq[::-1], -1
    valleys = []
    for t0, t1 in itertools.pairwise(seq):
        idx = _arc(n, int(t0), int(t1), step)
        a, b = contour[t0], contour[t1]
        d = b - a
        dist = np.abs(d[0] * (contour[idx, 1] - a[1]) - d[1] * (contour[idx, 0] - a[0]))
        valleys.append(int(idx[np.argmax(dist)]))
    return seq, np.array(valleys, np.intp), step


def _side_point(contour: np.ndarray, tip: int, step: int, distance_px: float) -> int:
    """First contour index from `tip` (walking by `step`) at least `distance_px` from the tip."""
    n = len(contour)
    idx = (tip + step * np.arange(1, n)) % n
    d = np.hypot(*(contour[idx] - contour[tip]).T)
    hit = np.flatnonzero(d >= distance_px)
    return int(idx[hit[0]]) if len(hit) else int(idx[-1])


@dataclass(frozen=True)
class _Axis:
    """A finger's fitted axis: point `c` (2,) px, unit direction `u` toward the tip."""

    c: np.ndarray
    u: np.ndarray
    s_tip: float       # fingertip along u from c, px
    s_base: float      # base line (valleys) along u from c, px
    rms_px: float      # RMS distance of the section midpoints from the axis
    n_sections: int
    width_px: float    # median breadth of the sections

    def shifted(self, d_px: float) -> _Axis:
        """The same axis moved by `d_px` along its normal."""
        return _Axis(c=self.c + d_px * self.normal, u=self.u, s_tip=self.s_tip,
                     s_base=self.s_base, rms_px=self.rms_px, n_sections=self.n_sections,
                     width_px=self.width_px)

    @property
    def normal(self) -> np.ndarray:
        return np.array([-self.u[1], self.u[0]])

    def at(self, s) -> np.ndarray:
        return self.c + np.multiply.outer(np.asarray(s, float), self.u)

    def along(self, p) -> np.ndarray:
        return (np.asarray(p, float) - self.c) @ self.u

    def widths(self, score: np.ndarray, s, max_px: float) -> np.ndarray:
        """Widths (px) of the blob across the axis at positions `s` (px along u)."""
        q = self.at(np.atleast_1d(s))
        nrm = self.normal
        e1 = _ray_edges(score, q, nrm, max_px)
        e2 = _ray_edges(score, q, -nrm, max_px)
        return e1 + e2


def _fit_axis(score: np.ndarray, tip: np.ndarray, base_a: np.ndarray, base_b: np.ndarray,
              max_width_px: float, *, t_range: tuple[float, float] = (0.15, 0.85),
              n_sections: int = 15) -> _Axis:
    """Fit a digit's axis: the line through the midpoints of sections across it.

    `n_sections` sections perpendicular to the current axis, spread over
    `t_range` of the way from the base (midpoint of `base_a`, `base_b`, px)
    to the `tip` (px); the line through their midpoints (total least
    squares) is the new axis; three rounds.  Sections wider than
    `max_width_px` (into a neighbour) are dropped.
    """
    m = 0.5 * (base_a + base_b)
    u = tip - m
    u = u / np.hypot(*u)
    c = m
    centres = np.zeros((0, 2))
    widths = np.full(1, np.nan)
    for _ in range(3):
        length = float((tip - c) @ u)
        s = np.linspace(*t_range, n_sections) * length
        q = c + np.multiply.outer(s, u)
        nrm = np.array([-u[1], u[0]])
        e1 = _ray_edges(score, q, nrm, max_width_px)
        e2 = _ray_edges(score, q, -nrm, max_width_px)
        ok = np.isfinite(e1) & np.isfinite(e2) & (e1 + e2 < max_width_px)
        if ok.sum() < 3:
            break
        centres = q[ok] + nrm * (0.5 * (e1[ok] - e2[ok]))[:, None]
        widths = (e1 + e2)[ok]
        mean = centres.mean(axis=0)
        _, _, vt = np.linalg.svd(centres - mean)
        v = vt[0] if vt[0] @ u > 0 else -vt[0]
        u = v
        c = mean + u * float((m - mean) @ u)
    resid = (centres - c) @ np.array([-u[1], u[0]]) if len(centres) else np.zeros(1)
    # the fingertip on the axis: march from 10 px inside the apex along the axis
    start = c + u * (float((tip - c) @ u) - 10.0)
    e = _ray_edges(score, start, u, 10.0 + max_width_px)[0]
    s_tip = float((tip - c) @ u) if not np.isfinite(e) else float((start - c) @ u) + float(e)
    s_base = float(0.5 * ((base_a - c) @ u + (base_b - c) @ u))
    return _Axis(c=c, u=u, s_tip=s_tip, s_base=s_base,
                 rms_px=float(np.sqrt(np.mean(resid ** 2))), n_sections=len(centres),
                 width_px=float(np.median(widths)))


# -- knuckles, wrist, thumb base ------------------------------------------------------


@dataclass(frozen=True)
class _HandFrame:
    """The hand frame in the picture: origin at the middle MCP, unit axes in pixels."""

    origin: np.ndarray   # (2,) px, the middle-finger MCP joint
    u: np.ndarray        # (2,) hand +y: wrist -> fingers
    n: np.ndarray        # (2,) hand +x: toward the little finger

    def to_hand(self, p, px_per_mm: float) -> np.ndarray:
        """(x, y) mm in the hand frame (origin at the middle MCP) of picture points (..., 2)."""
        d = np.asarray(p, float) - self.origin
        return np.stack([d @ self.n, d @ self.u], axis=-1) / px_per_mm

    def to_px(self, xy_mm, px_per_mm: float) -> np.ndarray:
        xy = np.asarray(xy_mm, float) * px_per_mm
        return (self.origin + np.multiply.outer(xy[..., 0], self.n)
                + np.multiply.outer(xy[..., 1], self.u))


def _knuckle_template_mm() -> np.ndarray:
    """MCP joint centres (4, 2) of index..little, (across, along) mm from the middle MCP.

    The standard hand's layout (:func:`handsynth.models.standard_layout_mm`:
    spacing of a quarter hand breadth, heights from the metacarpal lengths of
    Buchholz et al. 1992).
    """
    from ..models import standard_layout_mm

    mcp = standard_layout_mm().mcp
    mid = mcp["middle"]
    return np.array([[mcp[f][0] - mid[0], mcp[f][1] - mid[1]] for f in _FINGER_ORDER[1:]])


def _fit_knuckles(axes: list[_Axis], palm_ratio: float | None, px_per_mm: float,
                  prior_s: np.ndarray, prior_sd_px: float, side: float,
                  hand_y: np.ndarray | None = None):
    """Place the MCP joints on the four finger axes with the knuckle template.

    Finds the positions ``s_f`` along the finger axes, the template's
    rotation and its translation that bring the axis points ``c_f + s_f u_f``
    closest (least squares) to the template's knuckles: in a spread hand
    each finger turns about its MCP joint, so the fan of axes fixes where the
    joints lie once their spacing is known.  Weak priors (standard deviation
    `prior_sd_px`) pull ``s_f`` toward `prior_s` (the web between the
    fingers) so that nearly parallel fingers still give an answer.  For a
    given rotation the problem is linear; the rotation is searched (or
    taken from `hand_y`).  With ``palm_ratio=None`` the template's across-hand
    scale is a further unknown.

    Returns
    -------
    s : ndarray (4,)
        MCP positions along the axes, px.
    frame : _HandFrame
    palm_ratio : float
        The template's across-hand scale (the one given, or the fitted one).
    rms_mm : float
        RMS distance of the knuckles from the template.
    sd_mm : ndarray (4,)
        Standard deviation of each ``s_f`` for a 0.5-pixel axis noise.
    """
    from scipy.optimize import minimize_scalar

    tm = _knuckle_template_mm() * px_per_mm      # (4, 2) px: x across, y along
    c = np.array([a.c for a in axes])
    u = np.array([a.u for a in axes])
    phi0 = math.atan2(u[1, 1], u[1, 0])
    free = palm_ratio is None

    def frame_axes(phi):
        uh = np.array([math.cos(phi), math.sin(phi)])
        return uh, side * np.array([-uh[1], uh[0]])

    def solve(phi):
        uh, nh = frame_axes(phi)
        # unknowns z = (s_1..s_4, tx, ty[, palm ratio]); rows: x, y of each knuckle, then priors
        a = np.zeros((12, 7 if free else 6))
        b = np.zeros(12)
        for f in range(4):
            across = tm[f, 0] * nh
            for k in range(2):
                r = 2 * f + k
                a[r, f] = u[f, k]
                a[r, 4 + k] = -1.0
                if free:
                    a[r, 6] = -across[k]
                    b[r] = tm[f, 1] * uh[k] - c[f, k]
                else:
                    b[r] = palm_ratio * across[k] + tm[f, 1] * uh[k] - c[f, k]
            a[8 + f, f] = 1.0 / prior_sd_px
            b[8 + f] = prior_s[f] / prior_sd_px
        z, *_ = np.linalg.lstsq(a, b, rcond=None)
        r = a @ z - b
        return z, a, float(np.sum(r ** 2))

    if hand_y is None:
        # coarse search (the cost has several minima), then refine the best
        grid = phi0 + np.radians(np.arange(-30.0, 30.5, 1.0))
        best = float(grid[int(np.argmin([solve(p)[2] for p in grid]))])
        step = math.radians(1.0)
        phi = minimize_scalar(lambda p: solve(p)[2], bounds=(best - step, best + step),
                              method="bounded", options={"xatol": 1e-7}).x
    else:
        phi = math.atan2(hand_y[1], hand_y[0])
    z, a, _ = solve(phi)
    uh, nh = frame_axes(phi)
    ratio = float(z[6]) if palm_ratio is None else float(palm_ratio)  # None: fitted (free)
    knuckles = c + z[:4, None] * u
    template = z[4:6] + ratio * tm[:, :1] * nh + tm[:, 1:] * uh
    rms_mm = float(np.sqrt(np.mean(np.sum((knuckles - template) ** 2, axis=1)))) / px_per_mm
    cov = np.linalg.pinv(a.T @ a) * 0.25
    sd_mm = np.sqrt(np.maximum(np.diag(cov)[:4], 0.0)) / px_per_mm
    return z[:4], _HandFrame(origin=z[4:6], u=uh, n=nh), ratio, rms_mm, sd_mm


def _section_widths(score: np.ndarray, frame: _HandFrame, ys_mm: np.ndarray, px_per_mm: float,
                    max_mm: float):
    """Breadth of the blob across the hand at hand heights `ys_mm` (through the hand axis).

    Returns (widths_mm, left_px, right_px) with NaN where the axis point is
    outside the blob or no edge is found.
    """
    q = frame.to_px(np.stack([np.zeros_like(ys_mm), ys_mm], axis=-1), px_per_mm)
    e1 = _ray_edges(score, q, frame.n, max_mm * px_per_mm)
    e2 = _ray_edges(score, q, -frame.n, max_mm * px_per_mm)
    return (e1 + e2) / px_per_mm, q - frame.n * e2[:, None], q + frame.n * e1[:, None]


def _find_wrist(score: np.ndarray, frame: _HandFrame, px_per_mm: float, shape_hw):
    """The palm's lower edge: the narrowest section below the palm, or the blob's end.

    Sections across the hand are taken every 0.5 mm from 40 mm to 160 mm
    below the middle MCP.  Where the blob goes on (a forearm), the wrist is
    the narrowest section; where it ends first (no forearm in the picture),
    the end is the palm's lower edge.  Sections touching the picture's
    border end the search (a forearm leaving the picture).

    Returns (y_mm, left_px, right_px, rule) with y relative to the middle MCP.
    """
    h, w = shape_hw
    ys = -np.arange(40.0, 160.0, 0.5)
    widths, left, right = _section_widths(score, frame, ys, px_per_mm, 150.0)
    found = np.isfinite(widths)

    def inside(p):
        return (p[:, 0] > 1.0) & (p[:, 1] > 1.0) & (p[:, 0] < w - 2.0) & (p[:, 1] < h - 2.0)

    at_border = found & ~(inside(np.nan_to_num(left)) & inside(np.nan_to_num(right)))
    stops = np.flatnonzero(~found | at_border)
    last = int(stops[0]) if len(stops) else len(ys)
    if last < 10:
        raise InvalidInputError(
            "cannot find the wrist: the palm below the knuckles is cut off by the picture's "
            "border or missing; the whole palm and the wrist must be in the photo")
    from scipy.ndimage import median_filter

    prof = median_filter(widths[:last], size=5, mode="nearest")
    k = int(np.argmin(prof))
    if k >= last - 6:
        if last < len(ys) and not found[last]:
            # the blob ends without narrowing first: its end is the palm's lower edge
            y_end = float(ys[last - 1]) - 0.25
            mid = frame.to_px(np.array([0.0, y_end]), px_per_mm)
            return y_end, mid - frame.n, mid + frame.n, "end"
        raise InvalidInputError(
            "cannot find the wrist: the hand keeps narrowing up to the picture's border; "
            "the wrist and the start of the forearm must be in the photo")
    # refine: sections every 0.05 mm within 3 mm of the coarse minimum; the wrist is
    # the middle of the stretch within _WRIST_BAND_MM of the narrowest (steadier
    # than the narrowest section itself, which wanders along a flat bottom)
    fine = ys[k] + np.arange(-3.0, 3.0001, 0.05)
    fw, fl, fr = _section_widths(score, frame, fine, px_per_mm, 150.0)
    fw = np.where(np.isfinite(fw), fw, np.inf)
    near = np.flatnonzero(fw <= fw.min() + _WRIST_BAND_MM)
    runs = np.split(near, np.flatnonzero(np.diff(near) > 1) + 1)
    run = next(r for r in runs if int(np.argmin(fw)) in r)
    j = round(0.5 * (run[0] + run[-1]))
    return float(fine[j]), fl[j], fr[j], "narrowest"


# -- results --------------------------------------------------------------------------


@dataclass(frozen=True, eq=False)
class FingerFit:
    """One digit as measured on the photo.

    Attributes
    ----------
    name : str
        ``"thumb"``, ``"index"``, ``"middle"``, ``"ring"`` or ``"little"``.
    joints_px : ndarray, shape (4, 2), float64
        (x, y) pixels of the base joint, the two joints above it and the
        tip: MCP, PIP, DIP, tip for a finger; CMC, MCP, IP, tip for the thumb.
    axis : ndarray, shape (2,), float64
        Unit direction of the fitted axis in the picture, base to tip.
    segment_lengths_mm : tuple of float
        Joint-to-joint lengths of the phalanges (2 for the thumb, 3 for a
        finger), mm.
    widths_mm : tuple of float
        Breadth at the middle of each phalanx, mm.
    breadth_mm : float
        Median breadth of the cross-sections used for the axis, mm.
    rms_px : float
        RMS distance of the cross-section midpoints from the fitted axis.
    n_sections : int
        Cross-sections used for the axis.
    """

    name: str
    joints_px: np.ndarray
    axis: np.ndarray
    segment_lengths_mm: tuple[float, ...]
    widths_mm: tuple[float, ...]
    breadth_mm: float
    rms_px: float
    n_sections: int

    def as_dict(self) -> dict:
        """JSON-ready form."""
        return {"name": self.name, "joints_px": np.round(self.joints_px, 2).tolist(),
                "axis": np.round(self.axis, 5).tolist(),
                "segment_lengths_mm": [round(v, 3) for v in self.segment_lengths_mm],
                "widths_mm": [round(v, 3) for v in self.widths_mm],
                "breadth_mm": round(self.breadth_mm, 3), "rms_px": round(self.rms_px, 3),
                "n_sections": self.n_sections}


@dataclass(frozen=True, eq=False)
class PhotoMeasurement:
    """What :func:`measure_photo` found on a photo.

    Attributes
    ----------
    measurements : HandMeasurements
        ``L1..L14``, ``W1..W14``, ``P_width``, ``P_height``, ``T_width``,
        ``T_height`` in mm (definitions in :mod:`handsynth.models.HandMeasurements`).
    selection : Selection
        Formulas (1)-(4) applied to `measurements`: continuous ratios and the
        grid shape that names the database.
    shape : HandShape
        The model shape of the hand: the formulas' ratios without
        normalisation mapped by :attr:`MeasureOptions.shape_correction`.
        Build a database for exactly this shape
        (:meth:`PoseLookup.personal <handsynth.estimate.PoseLookup.personal>`)
        rather than use the nearest grid shape.
    mm_per_px : float
        Scale used (given, or from the reference object).
    scale_source : {"mm_per_px", "reference"}
    reference_px : ndarray, shape (4, 2), or None
        Corners of the reference object's minimum-area rectangle.
    fingers : tuple of FingerFit
        Thumb, index, middle, ring, little.
    valleys_px : ndarray, shape (4, 2)
        The outline's deepest points between neighbouring digits (thumb-index
        first).
    hand_origin_px, hand_y, hand_x : ndarray, shape (2,)
        The hand frame in the picture: the middle MCP joint, the unit
        direction wrist to fingers and the unit direction toward the little
        finger.
    wrist_px : ndarray, shape (2, 2)
        Ends of the wrist section (the palm's lower edge).
    wrist_rule : {"narrowest", "end"}
        The wrist is the narrowest section above the forearm, or the end of
        the silhouette when no forearm is in the picture.
    palm_width_px : ndarray, shape (2, 2)
        Ends of the ``P_width`` section.
    cmc_px : ndarray, shape (2,)
        Estimated thumb CMC joint.
    knuckle_rms_mm : float
        RMS misfit of the knuckle template on the finger axes.
    knuckle_sd_mm : ndarray, shape (4,)
        How well the finger spread fixes each MCP joint along its finger
        (standard deviation for 0.5-pixel axis noise).
    mask : ndarray, shape (H, W), bool
        The hand silhouette.
    warnings : tuple of str
    """

    measurements: HandMeasurements
    selection: Selection
    shape: HandShape
    mm_per_px: float
    scale_source: str
    reference_px: np.ndarray | None
    fingers: tuple[FingerFit, ...]
    valleys_px: np.ndarray
    hand_origin_px: np.ndarray
    hand_y: np.ndarray
    hand_x: np.ndarray
    wrist_px: np.ndarray
    wrist_rule: str
    palm_width_px: np.ndarray
    cmc_px: np.ndarray
    knuckle_rms_mm: float
    knuckle_sd_mm: np.ndarray
    mask: np.ndarray = field(repr=False)
    warnings: tuple[str, ...] = ()

    def as_dict(self) -> dict:
        """JSON-ready form: the file format, ``selection``, ``shape`` and ``diagnostics``."""
        out = self.measurements.as_dict()
        r = self.selection.ratios
        out["selection"] = {
            "ratios": {"length": r.length, "width": r.width, "palm": r.palm, "thumb": r.thumb},
            "shape": self.selection.name,
        }
        out["shape"] = {"ratios": self.shape.as_dict(), "name": self.shape.name}
        out["diagnostics"] = {
            "mm_per_px": self.mm_per_px,
            "scale_source": self.scale_source,
            "reference_px": None if self.reference_px is None
            else np.round(self.reference_px, 2).tolist(),
            "fingers": [f.as_dict() for f in self.fingers],
            "valleys_px": np.round(self.valleys_px, 2).tolist(),
            "hand_origin_px": np.round(self.hand_origin_px, 2).tolist(),
            "hand_y": np.round(self.hand_y, 5).tolist(),
            "hand_x": np.round(self.hand_x, 5).tolist(),
            "wrist_px": np.round(self.wrist_px, 2).tolist(),
            "wrist_rule": self.wrist_rule,
            "palm_width_px": np.round(self.palm_width_px, 2).tolist(),
            "cmc_px": np.round(self.cmc_px, 2).tolist(),
            "knuckle_rms_mm": round(self.knuckle_rms_mm, 3),
            "knuckle_sd_mm": np.round(self.knuckle_sd_mm, 3).tolist(),
            "warnings": list(self.warnings),
        }
        return out


# -- the measurement ------------------------------------------------------------------

#: Web-to-MCP offsets (mm) of index..little used as the weak prior of the
#: knuckle fit: on the standard model the MCP joints lie 2-6 mm below the
#: outline's valleys.
_PRIOR_WEB_TO_MCP_MM = 4.0
_PRIOR_SD_MM = 8.0


def _bases(contour: np.ndarray, seq: np.ndarray, valleys: np.ndarray, step: int):
    """For each digit (thumb..little): tip index and the two base points of its outline."""
    out = []
    for k in range(5):
        tip = int(seq[k])
        if k in (2, 3):                       # middle, ring: the valleys on both sides
            out.append((tip, int(valleys[k - 1]), int(valleys[k])))
            continue
        # thumb, index: the valley on the ulnar side; little: on the radial side.
        # The other base point is the outline point as far from the tip.
        v = {0: 0, 1: 1, 4: 3}[k]
        walk = step if k == 4 else -step
        d = float(np.hypot(*(contour[tip] - contour[valleys[v]])))
        out.append((tip, int(valleys[v]), _side_point(contour, tip, walk, d)))
    return out


def _axis_x_cross(axis: _Axis, frame: _HandFrame, x_mm: float, px_per_mm: float) -> float:
    """Position along `axis` (px) where it crosses the hand-frame line x = `x_mm`."""
    xc = float((axis.c - frame.origin) @ frame.n) / px_per_mm
    dx = float(axis.u @ frame.n)
    if abs(dx) < 0.2:
        raise InvalidInputError(
            "cannot place the thumb's base: the thumb lies almost parallel to the fingers; "
            "spread the thumb away from the index finger")
    return (x_mm - xc) * px_per_mm / dx


def _find_digits(con: np.ndarray, shape_hw, px_per_mm: float, opts: MeasureOptions,
                 touches_border: bool, warnings: list[str], area_mm2: float = 0.0):
    """Five fingertips on the outline, in the order thumb..little, and the valleys between them."""
    tips, depth = _fingertips(con, shape_hw, px_per_mm, arc_mm=opts.tip_arc_mm,
                              max_width_mm=opts.max_finger_width_mm,
                              min_depth_mm=opts.min_tip_depth_mm)
    if len(tips) < 5:
        if area_mm2 > _LARGE_HAND_AREA_MM2:
            # fingers drawn too large for a finger at this scale are no fingertips
            hint = (f" (the hand covers {area_mm2:.0f} mm^2 at {1.0 / px_per_mm:.4g} mm/px, "
                    "more than most hands with forearm: check the scale)")
        elif touches_border:
            hint = " (the hand touches the picture's border, which may cut off a finger)"
        else:
            hint = ""
        raise InvalidInputError(
            f"found {len(tips)} fingertip(s), expected 5{hint}: photograph one open hand, "
            "fingers spread apart, lying flat, from straight above")
    if len(tips) > 5:
        warnings.append(f"{len(tips)} fingertip candidates; kept the 5 that stand out most")
        tips = tips[np.sort(np.argsort(depth)[::-1][:5])]
    return _order_fingers(con, tips)


def _digit_axes(score, con, seq, valleys, step, max_width_px: float,
                cal: MeasureCalibration) -> list[_Axis]:
    """Fitted axes of thumb..little; the thumb's moved onto its bone axis (calibration)."""
    axes = []
    for k, (tip, a, b) in enumerate(_bases(con, seq, valleys, step)):
        # the thumb's base region is its metacarpal, wider and half hidden: fit further out
        t_range = (0.3, 0.85) if k == 0 else (0.15, 0.85)
        axes.append(_fit_axis(score, con[tip], con[a], con[b], max_width_px, t_range=t_range))
    toward_index = 1.0 if float((axes[1].c - axes[0].c) @ axes[0].normal) > 0 else -1.0
    axes[0] = axes[0].shifted(toward_index * cal.thumb_axis_shift * axes[0].width_px)
    return axes


@dataclass(frozen=True, eq=False)
class _Palm:
    """The hand frame and the palm's landmarks (hand-frame mm relative to the middle MCP)."""

    frame: _HandFrame
    s_mcp: np.ndarray        # (4,) MCP positions along the finger axes, px
    s_cmc: float             # CMC position along the thumb axis, px
    x_cmc: float
    y_cmc: float
    y_wrist: float
    y_width: float           # height of the P_width section
    width_mm: float          # P_width
    wrist_px: np.ndarray
    wrist_rule: str
    width_px: np.ndarray
    cmc_px: np.ndarray
    knuckle_rms_mm: float
    knuckle_sd_mm: np.ndarray


def _fit_palm(score: np.ndarray, axes: list[_Axis], px_per_mm: float,
              std: HandMeasurements, *, wrist_offset_mm: float) -> _Palm:
    """Knuckles, hand frame, wrist, thumb CMC and palm width, iterated to agreement.

    The knuckle template's across-hand scale is the palm ratio: first
    fitted with the knuckles, then taken from the measured ``P_width`` (at
    the height midway between the CMC and the MCP joints) until it settles.
    """
    from ..models import standard_layout_mm

    lay = standard_layout_mm()
    thumb, fingers = axes[0], axes[1:]
    h, w = score.shape
    n0 = np.array([-fingers[1].u[1], fingers[1].u[0]])
    side = 1.0 if float((fingers[3].c - fingers[0].c) @ n0) > 0 else -1.0
    prior = np.array([a.s_base for a in fingers]) - _PRIOR_WEB_TO_MCP_MM * px_per_mm
    ratio, hand_y = None, None  # first pass: the knuckle fit also finds the palm's scale
    last = None
    for it in range(10):
        s_mcp, frame, ratio, rms, sd = _fit_knuckles(
            fingers, ratio, px_per_mm, prior, _PRIOR_SD_MM * px_per_mm, side, hand_y)
        y_wrist, w_left, w_right, rule = _find_wrist(score, frame, px_per_mm, (h, w))
        if rule == "narrowest":
            y_wrist -= wrist_offset_mm
        if it < 2:
            # the hand axis runs from the middle of the wrist to the middle MCP joint
            # (then held, so that the remaining loop only settles the palm's scale)
            axis = frame.origin - 0.5 * (np.asarray(w_left) + np.asarray(w_right))
            hand_y = axis / np.hypot(*axis)
        x_cmc = (lay.thumb_cmc[0] - lay.mcp["middle"][0]) * ratio
        s_cmc = _axis_x_cross(thumb, frame, x_cmc, px_per_mm)
        cmc_px = thumb.at(s_cmc)
        knuckles = np.array([a.at(s) for a, s in zip(fingers, s_mcp)])
        y_cmc = float(frame.to_hand(cmc_px, px_per_mm)[1])
        y_mid = 0.5 * (y_cmc + float(frame.to_hand(knuckles, px_per_mm)[:, 1].mean()))
        pw, p_left, p_right = _section_widths(score, frame, np.array([y_mid]), px_per_mm, 150.0)
        if not np.isfinite(pw[0]):
            raise InvalidInputError("cannot measure the palm's width: the section across the "
                                    "palm leaves the silhouette")
        new_ratio = float(pw[0]) / std.P_width
        state = np.array([new_ratio, y_wrist, y_cmc])
        done = it >= 2 and np.all(np.abs(state - last) < [2e-4, 0.02, 0.02])
        ratio, last = new_ratio, state
        if done:
            break
    return _Palm(frame=frame, s_mcp=s_mcp, s_cmc=s_cmc, x_cmc=x_cmc, y_cmc=y_cmc,
                 y_wrist=y_wrist, y_width=y_mid, width_mm=float(pw[0]),
                 wrist_px=np.array([w_left, w_right], float).reshape(2, 2), wrist_rule=rule,
                 width_px=np.array([p_left[0], p_right[0]]), cmc_px=np.asarray(cmc_px, float),
                 knuckle_rms_mm=rms, knuckle_sd_mm=sd)


def _measure_digits(score: np.ndarray, axes: list[_Axis], palm: _Palm, mm_per_px: float,
                    opts: MeasureOptions) -> list[FingerFit]:
    """Joints, phalanx lengths and mid-phalanx breadths of each digit.

    Fingers: from the MCP joint to the tip, split in the proportions of
    Buchholz et al. (1992) Table 1 (:data:`SEGMENT_COEFFICIENTS`).  Thumb:
    the MCP joint lies one metacarpal (0.251 hand lengths, Buchholz) beyond
    the CMC joint; the rest is split likewise.  Breadths are the median of
    five sections across the axis within +-10 % of the phalanx around its
    middle.
    """
    from ..models import SEGMENT_COEFFICIENTS

    px = 1.0 / mm_per_px
    cal = opts.calibration
    max_w_px = opts.max_finger_width_mm * px
    # hand length: wrist line to the middle fingertip
    hand_length_mm = float(axes[2].s_tip - palm.s_mcp[1]) * mm_per_px - palm.y_wrist
    digits = []
    for k, name in enumerate(_FINGER_ORDER):
        ax = axes[k]
        coef = np.asarray(SEGMENT_COEFFICIENTS[name][1:], float)
        if k == 0:
            s0 = palm.s_cmc + SEGMENT_COEFFICIENTS["thumb"][0] * hand_length_mm * px
            joints_s = [palm.s_cmc]
        else:
            s0 = float(palm.s_mcp[k - 1])
            joints_s = []
        total = ax.s_tip - s0
        if total <= 0:
            raise InvalidInputError(f"the {name}'s base joint lies beyond its tip: the {name} "
                                    "must lie flat, straight and fully visible")
        cuts = s0 + total * np.concatenate([[0.0], np.cumsum(coef) / coef.sum()])
        joints_s += list(cuts)
        seg_w = []
        for a_s, b_s in itertools.pairwise(cuts):
            at = 0.5 * (a_s + b_s) + (b_s - a_s) * np.linspace(-0.1, 0.1, 5)
            ws = ax.widths(score, at, max_w_px)
            ws = ws[np.isfinite(ws) & (ws < max_w_px)]
            if len(ws) == 0:
                what = ("the thumb is hidden or held against the palm: lay it flat on the "
                        "table, spread away from the index finger" if k == 0 else
                        "it touches a neighbouring finger: spread the fingers apart")
                raise InvalidInputError(f"cannot measure the {name}'s breadth: {what}")
            seg_w.append(float(np.median(ws)) * mm_per_px)
        seg_l = [float(v) for v in np.diff(cuts) * mm_per_px]
        if k == 0:
            seg_w = [v * f for v, f in zip(seg_w, cal.thumb_width_factors)]
            seg_l = [v * cal.thumb_length_factor for v in seg_l]
        digits.append(FingerFit(
            name=name, joints_px=ax.at(np.array(joints_s[-4:])), axis=ax.u.copy(),
            segment_lengths_mm=tuple(seg_l), widths_mm=tuple(seg_w),
            breadth_mm=ax.width_px * mm_per_px, rms_px=ax.rms_px, n_sections=ax.n_sections))
    return digits


#: Accepted range of a measured phalanx length or breadth over the standard hand's.
_PLAUSIBLE = (0.6, 1.6)


def _check_plausible(lengths, widths, std: HandMeasurements) -> None:
    """Refuse phalanx lengths and breadths far from any adult hand's (a hidden or raised digit)."""
    from ..models import SEGMENTS

    lo, hi = _PLAUSIBLE
    for kind, values, ref in (("L", lengths, std.L), ("W", widths, std.W)):
        for i, (v, r) in enumerate(zip(values, ref)):
            if not lo <= v / r <= hi:
                finger, seg = SEGMENTS[i]
                what = "length" if kind == "L" else "breadth"
                raise InvalidInputError(
                    f"implausible measurement: {kind}{i + 1} ({finger} {seg} phalanx {what}) = "
                    f"{v:.1f} mm, {v / r:.2f} times the standard hand's; the {finger} must lie "
                    "flat, straight and fully visible (and the scale must be right)")


def measure_photo(image, *, mm_per_px: float | None = None,
                  reference_width_mm: float | None = None,
                  options: MeasureOptions | None = None) -> PhotoMeasurement:
    """Measure a hand on a top-down photo and choose its database (formulas (1)-(4)).

    Parameters
    ----------
    image : ndarray, shape (H, W) or (H, W, 3), or str or os.PathLike
        uint8 grey or BGR photo of one open hand, fingers spread, lying flat
        on a plain background, seen from straight above; or a bool
        silhouette; or the path of such a photo's image file (read with
        OpenCV as :func:`handsynth.render.read_image` reads it: 16-bit pixels
        keep their top 8 bits, an alpha channel is dropped).  A forearm may
        leave the picture at the border; nothing else of the hand may touch
        it.
    mm_per_px : float, keyword-only
        Scale at the plane of the hand, mm per pixel: a number (not a text
        such as ``"0.25"``) in (0, :data:`MAX_MM_PER_PX`].
    reference_width_mm : float, keyword-only
        Instead of `mm_per_px`: the length in mm of the longer side of a
        reference object lying beside the hand on the same plane (e.g. 85.60
        for an ISO/IEC 7810 ID-1 card), in (0, :data:`MAX_REFERENCE_WIDTH_MM`].  The reference object is the
        second-largest object in the photo; it must not touch the hand.
    options : MeasureOptions, keyword-only, optional

    Returns
    -------
    PhotoMeasurement

    Raises
    ------
    InvalidInputError
        No scale or two scales, or a scale that is not a positive finite
        number within its bound (a text or a bool included; named with the
        value received); an image that is not a uint8 grey/BGR image
        or bool mask, or a path that is not a readable image file (named);
        no hand; two hand-sized objects; a missing or
        ambiguous reference object; a hand touching the border; fewer than
        five separated fingers.  The message names the problem.
    """
    opts = check_options(options, MeasureOptions)
    if (mm_per_px is None) == (reference_width_mm is None):
        raise InvalidInputError(
            "give the photo's scale: exactly one of mm_per_px (mm per pixel at the hand) or "
            f"reference_width_mm (a reference object's width); got mm_per_px={mm_per_px!r}, "
            f"reference_width_mm={reference_width_mm!r}")
    # the scale given is checked before the photo's analysis; the upper bounds are far
    # beyond any photo of a hand and only keep the arithmetic finite
    ref_mm: float | None = None
    scale: float = 0.0
    if reference_width_mm is not None:
        ref_mm = check_number(reference_width_mm, "reference_width_mm", above=0.0,
                              maximum=MAX_REFERENCE_WIDTH_MM)
    else:
        scale = check_number(mm_per_px, "mm_per_px", above=0.0, maximum=MAX_MM_PER_PX)
    if isinstance(image, (str, os.PathLike)):
        from ..render import read_image

        image = read_image(image, what="photo")
    hand, ref = _hand_and_reference(_foreground(image), ref_mm is not None)
    reference_px = None
    if ref is not None and ref_mm is not None:
        scale, reference_px = _reference_scale(ref, ref_mm)
        scale_source = "reference"
    else:
        scale_source = "mm_per_px"
    mm_per_px = scale
    px = 1.0 / mm_per_px
    area_mm2 = float(hand.sum()) * mm_per_px ** 2
    if area_mm2 < opts.min_hand_area_mm2:
        raise InvalidInputError(
            f"no hand found: the largest object covers {area_mm2:.0f} mm^2 at "
            f"{mm_per_px:.4g} mm/px, less than a hand ({opts.min_hand_area_mm2:.0f} mm^2); "
            "check the scale and that the background is plain")
    if area_mm2 > _MAX_HAND_AREA_MM2:
        raise InvalidInputError(
            f"no hand found: the largest object covers {area_mm2:.0f} mm^2 at "
            f"{mm_per_px:.4g} mm/px, more than a hand with its forearm "
            f"({_MAX_HAND_AREA_MM2:.0f} mm^2); check the scale (mm per pixel at the hand)")
    warnings: list[str] = []
    con = _outer_contour(hand)
    h, w = hand.shape
    on_border = ((con[:, 0] < 1.0) | (con[:, 1] < 1.0) | (con[:, 0] > w - 2.0)
                 | (con[:, 1] > h - 2.0))
    seq, valleys, step = _find_digits(con, hand.shape, px, opts, on_border.any(), warnings,
                                      area_mm2)
    score = hand.astype(np.float32)
    axes = _digit_axes(score, con, seq, valleys, step, opts.max_finger_width_mm * px,
                       opts.calibration)
    std = model_measurements()
    palm = _fit_palm(score, axes, px, std, wrist_offset_mm=opts.calibration.wrist_offset_mm)
    if float(palm.frame.to_hand(con[valleys[0]], px)[1]) > palm.y_width:
        warnings.append("the thumb web lies above the palm-width section: P_width may "
                        "include part of the thumb")
    if on_border.any():
        y_border = palm.frame.to_hand(con[on_border], px)[:, 1]
        if float(y_border.max()) > palm.y_wrist:
            p = con[on_border][int(np.argmax(y_border))]
            raise InvalidInputError(
                f"the hand touches the picture's border at pixel ({p[0]:.0f}, {p[1]:.0f}): "
                "only the forearm may leave the photo; move the camera back or the hand in")
    if float(palm.knuckle_sd_mm.max()) > 3.0:
        warnings.append(
            f"the fingers are hardly spread: MCP joints located to "
            f"+-{palm.knuckle_sd_mm.max():.1f} mm only (spread the fingers wider)")
    digits = _measure_digits(score, axes, palm, mm_per_px, opts)
    lengths = [v for d in digits for v in d.segment_lengths_mm]
    widths = [v for d in digits for v in d.widths_mm]
    _check_plausible(lengths, widths, std)
    meas = HandMeasurements(
        L=tuple(lengths), W=tuple(widths), P_width=palm.width_mm, P_height=-palm.y_wrist,
        T_width=abs(palm.x_cmc), T_height=palm.y_cmc - palm.y_wrist)
    selection = select_shape(meas, options=SelectionOptions(normalize=opts.normalize))
    raw = shape_ratios(meas, std, normalize="none")
    try:
        shape = opts.shape_correction.apply(raw)
    except InvalidInputError as exc:
        raise InvalidInputError(f"the hand's measured ratios {raw.as_dict()} give no usable "
                                f"model shape: {exc}") from None
    return PhotoMeasurement(
        measurements=meas, selection=selection, shape=shape, mm_per_px=float(mm_per_px),
        scale_source=scale_source, reference_px=reference_px, fingers=tuple(digits),
        valleys_px=con[valleys].copy(), hand_origin_px=palm.frame.origin.copy(),
        hand_y=palm.frame.u.copy(), hand_x=palm.frame.n.copy(), wrist_px=palm.wrist_px,
        wrist_rule=palm.wrist_rule, palm_width_px=palm.width_px, cmc_px=palm.cmc_px,
        knuckle_rms_mm=palm.knuckle_rms_mm, knuckle_sd_mm=palm.knuckle_sd_mm, mask=hand,
        warnings=tuple(warnings))


def write_measurement_file(path, measurements: HandMeasurements, *, inputs=()) -> Path:
    """Write `measurements` to ``.json`` or ``.csv`` (read back by ``HandMeasurements.from_file``).

    The file appears complete or not at all (written to a temporary name,
    then renamed).

    Parameters
    ----------
    path : str or os.PathLike
        Ends in ``.json`` or ``.csv``.
    measurements : HandMeasurements
    inputs : iterable of path-like, keyword-only
        Files the caller read (the photo); `path` must be none of them.

    Returns
    -------
    Path

    Raises
    ------
    InvalidInputError
        Another suffix, `path` not a file name, or `measurements` not a
        :class:`HandMeasurements`.
    OutputError
        The file cannot be written (missing folder, full disk...) or is one
        of `inputs`.
    """
    import json

    path = check_path(path, "path")
    check_instance(measurements, HandMeasurements, name="measurements")
    suffix = path.suffix.lower()
    if suffix == ".json":
        text = json.dumps(measurements.as_dict(), indent=1) + "\n"
    elif suffix == ".csv":
        rows = ["name,value_mm"]
        rows += [f"L{i},{v:.4f}" for i, v in enumerate(measurements.L, 1)]
        rows += [f"W{i},{v:.4f}" for i, v in enumerate(measurements.W, 1)]
        rows += [f"{n},{getattr(measurements, n):.4f}"
                 for n in ("P_width", "P_height", "T_width", "T_height")]
        text = "\n".join(rows) + "\n"
    else:
        raise InvalidInputError(f"measurement file must end in .json or .csv, got {str(path)!r}")
    return write_text(path, text, what="measurement file", inputs=inputs)


def annotate_measurement(image, result: PhotoMeasurement) -> np.ndarray:
    """Draw what :func:`measure_photo` found onto a copy of the photo.

    Drawn: the hand's outline (yellow), each digit's fitted axis from its
    base joint to its tip with the joints (cyan line, red dots), the
    valleys (magenta), the knuckle line through the MCP joints (white), the
    thumb's CMC joint (orange), the wrist and ``P_width`` sections (green),
    the reference object (blue) and, top left, the ratios of formulas
    (1)-(4) and the selected database.

    Parameters
    ----------
    image : ndarray, shape (H, W) or (H, W, 3)
        The photo that was measured (uint8 grey or BGR, or a bool mask).
    result : PhotoMeasurement

    Returns
    -------
    ndarray, shape (H, W, 3), uint8
        BGR picture.
    """
    import cv2

    from ..render import check_frame

    img = check_frame(image)
    if img.shape[:2] != result.mask.shape:
        raise InvalidInputError(
            f"image of shape {img.shape} is not the measured photo of shape {result.mask.shape}")
    if img.dtype == bool:
        img = img.astype(np.uint8) * 255
    out = cv2.cvtColor(img, cv2.COLOR_GRAY2BGR) if img.ndim == 2 else img.copy()
    h, w = out.shape[:2]
    t = max(1, round(min(h, w) / 500))
    r = 2 * t + 1

    def pt(p):
        return round(float(p[0])), round(float(p[1]))

    contours, _ = cv2.findContours(result.mask.astype(np.uint8), cv2.RETR_EXTERNAL,
                                   cv2.CHAIN_APPROX_NONE)
    cv2.drawContours(out, contours, -1, (0, 220, 255), t)
    if result.reference_px is not None:
        cv2.polylines(out, [np.round(result.reference_px).astype(np.int32)], True, (255, 80, 0), t)
    for a, b in (result.wrist_px, result.palm_width_px):
        cv2.line(out, pt(a), pt(b), (0, 200, 0), t)
    wrist_mid = result.wrist_px.mean(axis=0)
    cv2.line(out, pt(wrist_mid), pt(result.hand_origin_px), (255, 255, 255), t)
    knuckles = [f.joints_px[0] for f in result.fingers[1:]]
    cv2.polylines(out, [np.round(knuckles).astype(np.int32)], False, (255, 255, 255), t)
    for f in result.fingers:
        cv2.line(out, pt(f.joints_px[0]), pt(f.joints_px[-1]), (255, 255, 0), t)
        for j in f.joints_px:
            cv2.circle(out, pt(j), r, (0, 0, 255), -1)
    cv2.circle(out, pt(result.cmc_px), r + t, (0, 140, 255), -1)
    for v in result.valleys_px:
        cv2.circle(out, pt(v), r, (255, 0, 255), -1)
    q = result.selection.ratios
    lines = [f"length {q.length:.3f}  width {q.width:.3f}",
             f"palm {q.palm:.3f}  thumb {q.thumb:.3f}",
             f"database {result.selection.name}",
             f"{result.mm_per_px:.4g} mm/px ({result.scale_source})"]
    scale = max(0.4, min(h, w) / 1400)
    for i, text in enumerate(lines):
        org = (8 * t, int((i + 1) * 30 * scale) + 4 * t)
        cv2.putText(out, text, org, cv2.FONT_HERSHEY_SIMPLEX, scale, (0, 0, 0), 3 * t, cv2.LINE_AA)
        cv2.putText(out, text, org, cv2.FONT_HERSHEY_SIMPLEX, scale, (255, 255, 255), t,
                    cv2.LINE_AA)
    return out
