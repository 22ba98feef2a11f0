"""Measuring a hand on a top-down photo, for choosing its database (SPEC.md section 1).

:func:`measure_photo` finds the values of :class:`handsynth.models.HandMeasurements`
on a photo of the open hand and chooses the database shape with
:func:`handsynth.estimate.select_shape`; :class:`MeasureOptions` holds the
scale, the normalisation and the corrections that a silhouette cannot show
(:class:`MeasureCalibration`, :class:`ShapeCorrection`), fitted on rendered
model hands by :func:`calibrate_on_model` and :func:`fit_shape_correction`
from :func:`render_measurement_photo`.
"""

from ._fit import calibrate_on_model, fit_shape_correction
from ._options import (
    MODEL_CALIBRATION,
    MODEL_SHAPE_CORRECTION,
    NO_CALIBRATION,
    NO_SHAPE_CORRECTION,
    MeasureCalibration,
    MeasureOptions,
    ShapeCorrection,
)
from ._photo import (
    MAX_MM_PER_PX,
    MAX_REFERENCE_WIDTH_MM,
    FingerFit,
    PhotoMeasurement,
    annotate_measurement,
    measure_photo,
    write_measurement_file,
)
from ._render import MEASURE_POSE, RenderedPhoto, render_measurement_photo

__all__ = [
    "MAX_MM_PER_PX",
    "MAX_REFERENCE_WIDTH_MM",
    "MEASURE_POSE",
    "MODEL_CALIBRATION",
    "MODEL_SHAPE_CORRECTION",
    "NO_CALIBRATION",
    "NO_SHAPE_CORRECTION",
    "FingerFit",
    "MeasureCalibration",
    "MeasureOptions",
    "PhotoMeasurement",
    "RenderedPhoto",
    "ShapeCorrection",
    "annotate_measurement",
    "calibrate_on_model",
    "fit_shape_correction",
    "measure_photo",
    "render_measurement_photo",
    "write_measurement_file",
]
