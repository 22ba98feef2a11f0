"""Fitting the measurement corrections on photos of model hands of known shape."""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from .._checks import check_options
from ..errors import InvalidInputError
from ..models import HandShape, model_measurements
from ._options import (
    _RATIOS,
    NO_CALIBRATION,
    NO_SHAPE_CORRECTION,
    MeasureCalibration,
    MeasureOptions,
    ShapeCorrection,
    _positive,
)
from ._photo import measure_photo
from ._render import render_measurement_photo

__all__ = ["calibrate_on_model", "fit_shape_correction"]


def _scales(mm_per_px) -> list[float]:
    """`mm_per_px` (one number or a sequence of them) as a list of positive finite floats.

    Raises
    ------
    InvalidInputError
        An empty sequence, or an item that is not a positive finite number
        (a text such as ``"0.25"`` included), named by its position.
    """
    if np.ndim(mm_per_px) == 0 and not isinstance(mm_per_px, (list, tuple)):
        return [_positive(mm_per_px, "mm_per_px")]
    items = list(np.asarray(mm_per_px, dtype=object).ravel())
    if not items:
        raise InvalidInputError("mm_per_px must be one or more positive numbers, got none")
    return [_positive(v, f"mm_per_px[{i}]") for i, v in enumerate(items)]


def calibrate_on_model(shape=None, *, mm_per_px=(0.2, 0.25, 0.3, 0.4, 0.5),
                       angles=None) -> MeasureCalibration:
    """Read the :class:`MeasureCalibration` off photos of the model hand of known shape.

    Renders `shape` (the standard hand by default) with
    :func:`render_measurement_photo` at each scale, measures it without
    calibration and compares with the model's true values
    (:func:`model_measurements` and the rendered keypoints): the wrist
    offset is the error of ``P_height``, the thumb-axis shift is the
    distance of the true CMC joint from the silhouette's thumb axis over the
    thumb's breadth, and the thumb factors are true over measured widths and
    lengths after those two corrections.  The values are averaged over the
    scales (the wrist's narrowest section moves by up to 0.5 mm with the
    pixel grid).

    Parameters
    ----------
    shape : HandShape, optional
    mm_per_px : float or sequence of float, keyword-only
        Scale(s) of the photos, mm per pixel.
    angles : array_like, shape (20,), optional
        Pose of the photo, :data:`MEASURE_POSE` by default.

    Returns
    -------
    MeasureCalibration

    Raises
    ------
    InvalidInputError
        A scale that is not a positive finite number (a text included).
    """
    scales = _scales(mm_per_px)
    truth = model_measurements(shape)
    found = []
    for scale in scales:
        photo = render_measurement_photo(shape, angles, mm_per_px=float(scale))
        raw = measure_photo(photo.image, mm_per_px=float(scale),
                            options=MeasureOptions(calibration=NO_CALIBRATION))
        wrist = (truth.P_height - raw.measurements.P_height
                 if raw.wrist_rule == "narrowest" else 0.0)
        thumb, index = raw.fingers[0], raw.fingers[1]
        normal = np.array([-thumb.axis[1], thumb.axis[0]])
        if float((index.joints_px[0] - thumb.joints_px[-1]) @ normal) < 0:
            normal = -normal
        off_px = float((photo.keypoints_px[1] - thumb.joints_px[-1]) @ normal)
        shift = off_px * float(scale) / thumb.breadth_mm
        step = MeasureCalibration(wrist_offset_mm=wrist, thumb_axis_shift=shift)
        m = measure_photo(photo.image, mm_per_px=float(scale),
                          options=MeasureOptions(calibration=step)).measurements
        found.append([wrist, shift, truth.W[0] / m.W[0], truth.W[1] / m.W[1],
                      (truth.L[0] + truth.L[1]) / (m.L[0] + m.L[1])])
    wrist, shift, w1, w2, length = np.mean(found, axis=0)
    return MeasureCalibration(wrist_offset_mm=float(wrist), thumb_axis_shift=float(shift),
                              thumb_width_factors=(float(w1), float(w2)),
                              thumb_length_factor=float(length))


def fit_shape_correction(shapes, *, mm_per_px=(0.15, 0.25, 0.4), seed: int = 0,
                         options: MeasureOptions | None = None) -> ShapeCorrection:
    """Fit the :class:`ShapeCorrection` on photos of model hands of known shape.

    Each shape is rendered (:func:`render_measurement_photo`, a random
    rotation per photo) and measured at every scale with `options` but no
    shape correction; the 4 x 5 matrix is the least-squares fit of the true
    ratios on the measured ratios (formulas (1)-(4), no normalisation) and 1.

    Parameters
    ----------
    shapes : sequence of HandShape
        At least 10 hands of known shape, spread over the ratios the
        correction should serve.
    mm_per_px : float or sequence of float, keyword-only
        Scales of the photos, mm per pixel.
    seed : int, keyword-only
        Seed of the photos' rotations.
    options : MeasureOptions, keyword-only, optional
        Measurement options (their `shape_correction` is ignored).

    Returns
    -------
    ShapeCorrection

    Raises
    ------
    InvalidInputError
        Fewer than 10 shapes, or something that is not a HandShape; a scale
        that is not a positive finite number (a text included).
    """
    shapes = list(shapes)
    if len(shapes) < 10 or not all(isinstance(s, HandShape) for s in shapes):
        raise InvalidInputError(
            f"shapes must be at least 10 HandShape objects, got {len(shapes)} items")
    opts = replace(check_options(options, MeasureOptions), shape_correction=NO_SHAPE_CORRECTION)
    scales = _scales(mm_per_px)
    rng = np.random.default_rng(seed)
    x, y = [], []
    for shape in shapes:
        for scale in scales:
            photo = render_measurement_photo(shape, mm_per_px=scale,
                                             roll_deg=float(rng.uniform(-180.0, 180.0)))
            found = measure_photo(photo.image, mm_per_px=scale, options=opts).shape
            x.append([getattr(found, n) for n in _RATIOS] + [1.0])
            y.append([getattr(shape, n) for n in _RATIOS])
    coef, *_ = np.linalg.lstsq(np.array(x), np.array(y), rcond=None)
    return ShapeCorrection(coefficients=tuple(tuple(float(v) for v in row) for row in coef.T))


# -- test photos ----------------------------------------------------------------------
