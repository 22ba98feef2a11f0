"""Choosing the database from hand measurements (SPEC.md section 1, "Choosing the database").

The user's hand is measured on a picture of the open, flat hand (dorsal or
palmar side, fingers together): 14 segment lengths, 14 segment widths and
four palm values (:class:`handsynth.models.HandMeasurements`, where they are
defined).  The same values are measured on the *standard model*
(:func:`model_measurements` of ``HandShape()``), the user's values are
normalised so that the palm widths are equal, and formulas (1)-(4) give four
ratios; each ratio picks the nearest level of its row of
:data:`handsynth.models.GRID_LEVELS` and the four levels name the database.

Normalisation
-------------
The paper (seed 001) normalises the user's values so that ``P''_width =
P'_width`` (``normalize="palm_width"``, the default), because its photos
have no scale.  handsynth's :class:`~handsynth.models.HandShape` ratios are
absolute (``palm`` scales only the palm's breadth), so for measurements in
true millimetres ``normalize="none"`` recovers the ratios of a model hand
exactly, while the paper's normalisation returns ``length / palm``,
``width / palm``, ``palm`` and ``thumb / palm``.  Both are offered; the
choice is a field of :class:`SelectionOptions`.
"""
from __future__ import annotations

from dataclasses import dataclass, field

from .._checks import check_instance, check_options
from ..errors import InvalidShapeError
from ..models import NORMALIZATIONS as _NORMALIZE
from ..models import HandMeasurements, HandShape, formula_ratios, model_measurements

__all__ = ["Selection", "SelectionOptions", "select_shape", "shape_ratios"]


@dataclass(frozen=True)
class SelectionOptions:
    """Options of :func:`select_shape`.

    Parameters
    ----------
    normalize : {"palm_width", "none"}
        ``"palm_width"`` scales the user's values so that ``P_width`` equals
        the standard model's (the paper); ``"none"`` uses them as measured.
    standard : HandShape
        The shape whose model provides ``L'``, ``W'``, ``P'`` and ``T'``.
    """

    normalize: str = "palm_width"
    standard: HandShape = field(default_factory=HandShape)

    def __post_init__(self) -> None:
        if self.normalize not in _NORMALIZE:
            raise InvalidShapeError(
                f"SelectionOptions.normalize must be one of {_NORMALIZE}, got {self.normalize!r}"
            )
        check_instance(self.standard, HandShape, name="SelectionOptions.standard",
                       error=InvalidShapeError)


@dataclass(frozen=True)
class Selection:
    """Result of :func:`select_shape`.

    Attributes
    ----------
    ratios : HandShape
        The continuous ratios of formulas (1)-(4) (may lie off the grid).
    shape : HandShape
        The grid shape: nearest level per ratio; names the database.
    """

    ratios: HandShape
    shape: HandShape

    @property
    def name(self) -> str:
        """File stem of the chosen database (``<shape.name>``)."""
        return self.shape.name


def shape_ratios(user: HandMeasurements, standard: HandMeasurements, *,
                 normalize: str = "palm_width") -> HandShape:
    """Formulas (1)-(4) of SPEC.md section 1: the user's ratios to the standard model.

    The formulas are :func:`handsynth.models.formula_ratios`; here they
    become a :class:`HandShape`, which refuses ratios outside [0.5, 2].

    Parameters
    ----------
    user, standard : HandMeasurements
        The user's hand and the standard model, mm.
    normalize : {"palm_width", "none"}, keyword-only

    Returns
    -------
    HandShape
        The four continuous ratios.

    Raises
    ------
    InvalidShapeError
        A ratio outside [0.5, 2] (not a human hand measured consistently).
    """
    if normalize not in _NORMALIZE:
        raise InvalidShapeError(f"normalize must be one of {_NORMALIZE}, got {normalize!r}")
    return HandShape(**formula_ratios(user, standard, normalize=normalize))


def select_shape(measurements: HandMeasurements, *,
                 options: SelectionOptions | None = None) -> Selection:
    """Choose the database for a measured hand (SPEC.md section 1, formulas (1)-(4)).

    Parameters
    ----------
    measurements : HandMeasurements
        The user's hand, mm.
    options : SelectionOptions, keyword-only, optional

    Returns
    -------
    Selection
        Continuous ratios and the nearest grid shape (nearest level of
        :data:`~handsynth.models.GRID_LEVELS` per ratio).

    Examples
    --------
    >>> sel = select_shape(model_measurements(HandShape(width=1.08)))
    >>> sel.shape.name
    'L1.000_W1.100_P1.000_T1.000'
    """
    if not isinstance(measurements, HandMeasurements):
        raise InvalidShapeError(
            f"measurements must be HandMeasurements, got {type(measurements).__name__}"
        )
    opts = check_options(options, SelectionOptions)
    try:
        ratios = shape_ratios(measurements, model_measurements(opts.standard),
                              normalize=opts.normalize)
    except InvalidShapeError:
        measurements.check_consistent()  # names the values behind a ratio out of range
        raise
    return Selection(ratios=ratios, shape=ratios.nearest_grid())
