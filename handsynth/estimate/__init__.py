"""Runtime pose lookup of the back-of-hand camera estimator (SPEC.md section 1).

* Database selection from hand measurements, formulas (1)-(4):
  :class:`HandMeasurements`, :func:`model_measurements`, :func:`shape_ratios`,
  :func:`select_shape`.
"""

from ._selection import (
    SEGMENTS,
    HandMeasurements,
    Selection,
    SelectionOptions,
    database_path,
    model_measurements,
    select_shape,
    shape_ratios,
)

__all__ = [
    "SEGMENTS",
    "HandMeasurements",
    "Selection",
    "SelectionOptions",
    "database_path",
    "model_measurements",
    "select_shape",
    "shape_ratios",
]
