"""The hand a command is about: ``--shape NAME`` or ``--measurements FILE``."""

from __future__ import annotations

from ..errors import InvalidInputError, InvalidShapeError


def shape_option(name: str, flag: str):
    """The hand of a hand-shape option: ``standard`` or a name such as L1.000_W1.000_P1.000_T1.000.

    Raises
    ------
    InvalidShapeError
        A name of another form or outside the supported ratios, naming `flag`.
    """
    from ..models import HandShape

    if name.strip().lower() == "standard":
        return HandShape()
    try:
        return HandShape.from_name(name.strip())
    except InvalidShapeError as exc:
        raise InvalidShapeError(f"{flag} {name!r}: {exc}") from None


def _read_measurements(path):
    """The measurements of ``--measurements`` FILE, every error naming the option and the file."""
    from ..models import HandMeasurements

    try:
        return HandMeasurements.from_file(path)
    except InvalidInputError as exc:
        raise about_measurements(exc, path) from None


def hand_options(shape_name, measurements):
    """The hand of ``--shape`` NAME or ``--measurements`` FILE (at most one of them):
    ``(HandShape or None, HandMeasurements or None)``."""
    if shape_name is not None and measurements is not None:
        raise InvalidInputError("give --shape or --measurements, not both")
    return (None if shape_name is None else shape_option(shape_name, "--shape"),
            None if measurements is None else _read_measurements(measurements))


def about_measurements(exc: InvalidInputError, path) -> InvalidInputError:
    """`exc` (an error about the measurements of `path`) with the option and the file named."""
    text = str(exc)
    where = "--measurements" if str(path) in text else f"--measurements {str(path)!r}"
    return type(exc)(f"{where}: {text}")


def hand_shape(shape_name, measurements):
    """The hand of ``--shape`` NAME or ``--measurements`` FILE, the standard hand by default.

    Measurements are matched to the nearest hand of the supported ratios (as the keypoints
    of ``estimate --keypoints`` are).
    """
    from ..estimate import SelectionOptions, select_shape
    from ..models import HandShape

    shape, meas = hand_options(shape_name, measurements)
    if meas is not None:
        try:  # values that give no hand of the supported ratios (centimetres read as mm)
            ratios = select_shape(meas, options=SelectionOptions(normalize="none")).ratios
            shape = HandShape.from_name(ratios.name)
        except InvalidInputError as exc:
            raise about_measurements(exc, measurements) from None
    return HandShape() if shape is None else shape
