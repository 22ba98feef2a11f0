"""Options of :func:`measure_photo` and the corrections found on the model hand."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .._checks import check_number, is_number
from ..errors import InvalidInputError
from ..models import HandShape

__all__ = [
    "MODEL_CALIBRATION",
    "MODEL_SHAPE_CORRECTION",
    "NO_CALIBRATION",
    "NO_SHAPE_CORRECTION",
    "MeasureCalibration",
    "MeasureOptions",
    "ShapeCorrection",
]

_NORMALIZE = ("none", "palm_width")


def _positive(value, name: str) -> float:
    """`value` as a positive finite ``float``; a text, a bool or an array is refused by name.

    ``"12"`` and ``"12mm"`` are refused although ``float()`` reads the first:
    a scale or a size must be given as a number, never as a text that reads
    as one (:func:`handsynth._checks.check_number`).
    """
    return check_number(value, name, above=0.0)


@dataclass(frozen=True)
class MeasureCalibration:
    """Corrections for what a silhouette cannot show, found on the standard model.

    A silhouette shows no joints.  The finger joints are placed by geometry
    (see :func:`measure_photo`); four things are left that only a hand of
    known shape can tell, and :func:`calibrate_on_model` reads them off a
    photo of the standard model measured the same way (SPEC.md section 1:
    "measure the same on the standard model").

    Parameters
    ----------
    wrist_offset_mm : float
        How far the wrist line (the palm's lower edge) lies below the
        narrowest section between palm and forearm, mm.
    thumb_axis_shift : float
        How far the thumb's bone axis lies from the midline of its
        silhouette, toward the index finger, as a fraction of the thumb's
        breadth (the thumb is seen from its side and is not symmetric).
    thumb_width_factors : tuple of 2 float
        Breadth of the thumb's proximal and distal phalanx over their
        breadth in a top view (the thumb is turned about 50 deg).
    thumb_length_factor : float
        Length of the thumb's phalanges over their length in the photo.

    Raises
    ------
    InvalidInputError
        A value that is not finite, or a factor that is not in (0.5, 2).
    """

    wrist_offset_mm: float = 0.0
    thumb_axis_shift: float = 0.0
    thumb_width_factors: tuple[float, float] = (1.0, 1.0)
    thumb_length_factor: float = 1.0

    def __post_init__(self) -> None:
        for name in ("wrist_offset_mm", "thumb_axis_shift"):
            object.__setattr__(self, name, check_number(getattr(self, name),
                                                        f"MeasureCalibration.{name}"))
        factors = self.thumb_width_factors
        if isinstance(factors, (str, bytes)) or not hasattr(factors, "__len__") \
                or len(factors) != 2 or not all(is_number(v) for v in factors):
            raise InvalidInputError("MeasureCalibration.thumb_width_factors must be 2 numbers, "
                                    f"got {factors!r}")
        wf = tuple(check_number(v, f"MeasureCalibration.thumb_width_factors[{i}]", above=0.5,
                                below=2.0) for i, v in enumerate(factors))
        object.__setattr__(self, "thumb_width_factors", wf)
        object.__setattr__(self, "thumb_length_factor",
                           check_number(self.thumb_length_factor,
                                        "MeasureCalibration.thumb_length_factor", above=0.5,
                                        below=2.0))


#: No correction: the raw silhouette measurements.
NO_CALIBRATION = MeasureCalibration()

#: Corrections read off the standard model in :data:`MEASURE_POSE` by
#: :func:`calibrate_on_model` (mean over 0.2 to 0.5 mm/px; a test checks
#: they still agree with the model).
MODEL_CALIBRATION = MeasureCalibration(
    wrist_offset_mm=1.215, thumb_axis_shift=-0.0948, thumb_width_factors=(1.106, 1.175),
    thumb_length_factor=1.040)


_RATIOS = tuple(HandShape().as_dict())  # length, width, palm, thumb


@dataclass(frozen=True)
class ShapeCorrection:
    """Linear map from a photo's measured ratios to the model shape that made it.

    Formulas (1)-(4) on silhouette measurements give ratios that track the
    model's but not one for one: the measured palm section includes flesh
    that the palm ratio does not scale, the phalanx lengths are split by
    fixed proportions, and the hidden thumb CMC moves with the other
    ratios.  On photos of model hands of known shape the measured ratios
    are close to an affine function of the true ones, so a 4 x 5 matrix
    fitted by least squares (:func:`fit_shape_correction`) maps them back:

    ``shape_k = sum_j coefficients[k][j] * measured_j + coefficients[k][4]``

    with ``j`` and ``k`` over ``length, width, palm, thumb`` and the
    measured ratios those of formulas (1)-(4) without normalisation.  On a
    human hand the map gives the model shape whose photo would measure the
    same, which is what a database built for the hand needs.

    Parameters
    ----------
    coefficients : 4 rows of 5 float
        Row ``k`` gives model ratio ``k`` (length, width, palm, thumb) from
        the four measured ratios and a constant.

    Raises
    ------
    InvalidInputError
        Not a 4 x 5 table of finite numbers.
    """

    coefficients: tuple[tuple[float, ...], ...] = (
        (1.0, 0.0, 0.0, 0.0, 0.0), (0.0, 1.0, 0.0, 0.0, 0.0),
        (0.0, 0.0, 1.0, 0.0, 0.0), (0.0, 0.0, 0.0, 1.0, 0.0))

    def __post_init__(self) -> None:
        try:
            c = np.array(self.coefficients, dtype=np.float64)
        except (TypeError, ValueError):
            c = np.full(0, np.nan)
        if c.shape != (4, 5) or not np.isfinite(c).all():
            raise InvalidInputError("ShapeCorrection.coefficients must be 4 rows of 5 finite "
                                    f"numbers, got {self.coefficients!r}")
        object.__setattr__(self, "coefficients",
                           tuple(tuple(float(v) for v in row) for row in c))

    def apply(self, measured):
        """The model shape for `measured` ratios.

        Parameters
        ----------
        measured : HandShape
            Ratios of formulas (1)-(4) without normalisation.

        Returns
        -------
        HandShape

        Raises
        ------
        InvalidShapeError
            The corrected ratios leave the range a :class:`HandShape` allows.
        """
        x = np.array([getattr(measured, n) for n in _RATIOS] + [1.0])
        y = np.array(self.coefficients) @ x
        return HandShape(**dict(zip(_RATIOS, (float(v) for v in y), strict=True)))


#: No correction: the model shape is the formulas' ratios.
NO_SHAPE_CORRECTION = ShapeCorrection()

#: Fitted by ``python scripts/fit_shape_correction.py`` (:func:`fit_shape_correction`
#: on 60 random model hands, ratio margin 0.75, seed 1000, photos at 0.15, 0.25
#: and 0.4 mm/px, random rotations); a test checks it on other hands.
MODEL_SHAPE_CORRECTION = ShapeCorrection(coefficients=(
    (1.05103, 0.00743, -0.00322, 0.00414, -0.05849),
    (-0.01915, 1.02642, -0.00099, -0.00134, -0.00433),
    (-0.00596, 0.01008, 1.11099, -0.00027, -0.11239),
    (0.05386, 0.01759, -0.45083, 0.99661, 0.38388),
))


@dataclass(frozen=True)
class MeasureOptions:
    """Options of :func:`measure_photo`.

    Parameters
    ----------
    tip_arc_mm : float
        Arc length followed along the outline on each side of a point to
        decide whether it is a fingertip.
    max_finger_width_mm : float
        Widest finger accepted (also the widest chord of a fingertip).
    min_tip_depth_mm : float
        How far a fingertip must stand out beyond the chord of its arcs.
    min_hand_area_mm2 : float
        Smallest hand silhouette accepted (an adult hand with wrist is about
        10,000 to 20,000 mm^2); smaller means no hand or a wrong scale.
    normalize : {"none", "palm_width"}
        Normalisation of formulas (1)-(4) used to select the database (see
        :class:`~handsynth.estimate.SelectionOptions`).  The photo has a
        scale, so ``"none"`` (true millimetres) is the default.
    calibration : MeasureCalibration
        Corrections found on the standard model (:data:`MODEL_CALIBRATION`);
        :data:`NO_CALIBRATION` gives the raw silhouette measurements.
    shape_correction : ShapeCorrection
        Map from the measured ratios to the model shape
        (:attr:`PhotoMeasurement.shape`), fitted on model hands of known
        shape (:data:`MODEL_SHAPE_CORRECTION`); :data:`NO_SHAPE_CORRECTION`
        keeps the formulas' ratios.
    """

    tip_arc_mm: float = 22.0
    max_finger_width_mm: float = 32.0
    min_tip_depth_mm: float = 10.0
    min_hand_area_mm2: float = 6000.0
    normalize: str = "none"
    calibration: MeasureCalibration = MODEL_CALIBRATION
    shape_correction: ShapeCorrection = MODEL_SHAPE_CORRECTION

    def __post_init__(self) -> None:
        for name in ("tip_arc_mm", "max_finger_width_mm", "min_tip_depth_mm",
                     "min_hand_area_mm2"):
            value = _positive(getattr(self, name), f"MeasureOptions.{name}")
            object.__setattr__(self, name, value)
        if self.normalize not in _NORMALIZE:
            raise InvalidInputError(
                f"MeasureOptions.normalize must be one of {_NORMALIZE}, got {self.normalize!r}")
        if not isinstance(self.calibration, MeasureCalibration):
            raise InvalidInputError("MeasureOptions.calibration must be a MeasureCalibration, "
                                    f"got {type(self.calibration).__name__}")
        if not isinstance(self.shape_correction, ShapeCorrection):
            raise InvalidInputError("MeasureOptions.shape_correction must be a ShapeCorrection, "
                                    f"got {type(self.shape_correction).__name__}")
