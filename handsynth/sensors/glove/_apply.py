"""Joint angles of a glove recording with a calibration file, read, checked and written
(what ``handsynth glove apply`` does)."""

from __future__ import annotations

import numpy as np

from ..._checks import check_path_names
from ..._io import check_output, same_file
from ...errors import EstimationError, InvalidInputError
from ._calibrate import load_calibration, range_readings
from ._checks import check_sensors, refuse_unreadable
from ._estimators import GloveEstimator, RangeNormalizer
from ._recording import read_glove_csv, write_angles_csv

__all__ = ["apply_calibration"]


def apply_calibration(calibration, readings, out, *, model: str = "model4",
                      motion: str | None = None, range_csv=None,
                      adc_max: float = 4095.0) -> np.ndarray:
    """Estimate the joint angles of a glove recording with a calibration file.

    Reads the calibration (:func:`load_calibration`) and the readings
    (:func:`read_glove_csv`), checks the readings (:func:`check_sensors`),
    maps them onto the calibration's with the range holds of `range_csv` when
    given (:class:`RangeNormalizer`), estimates with the estimator `model`
    and writes the angles (:func:`write_angles_csv`).  The output's name is
    checked before anything is read, and the file appears whole or not at
    all.

    Parameters
    ----------
    calibration : str or os.PathLike
        Calibration file (JSON) written by :func:`save_calibration`.
    readings : str or os.PathLike
        Glove CSV with the readings, counts (time, motion and trial columns
        optional; joint columns ignored).
    out : str or os.PathLike
        Angles CSV to write: ``time_s`` (s; ``sample``, the row index from 0,
        when `readings` has no time column) and the 20 canonical joint
        columns (deg), one row per row of `readings` (``nan`` where a reading
        is missing).  Never one of the input files.
    model : str, keyword-only
        Name of the estimator in the calibration file (``"model1"`` ..
        ``"model4"``, ``"pooled_model4"``, ``"synergy"``, ``"model4+synergy"``,
        ``"constant"``).
    motion : str, keyword-only, optional
        The representative motion when it is known; None mixes over the
        calibrated motions (seed 004 eqs. 4-6).
    range_csv : str or os.PathLike, keyword-only, optional
        Glove CSV with this wearing's open-hand and fist holds (motions
        ``range_open``, ``range_fist``), counts; the readings are mapped onto
        the calibration's holds first.  May be `readings` itself.
    adc_max : float, keyword-only
        Full scale of the readings of `readings` and `range_csv`, counts.

    Returns
    -------
    ndarray, shape (N, 20), float64, deg
        The angles written, canonical order (N rows of `readings`).

    Raises
    ------
    OutputError
        `out` cannot be written or names an input (checked first).
    InvalidInputError
        A file name that is empty; the calibration file is unreadable or
        malformed, holds no estimator `model`, or has no range holds while
        `range_csv` is given; `range_csv` has no ``range_open`` and
        ``range_fist`` rows; `motion` was not calibrated.
    RecordingError
        `readings` or `range_csv` cannot be read (file, line and column
        named); `adc_max` is not a positive number of counts; no row of
        `readings` has five readings, or every reading is saturated or out of
        the converter's range; a hold of a sensor in `range_csv` is mostly
        saturated.
    EstimationError
        The range holds cannot be used (a sensor reads the same open and
        closed, or most sensors go the other way); the file is named.

    Warns
    -----
    GloveWarning
        Rows with a NaN reading, dead, saturated or out-of-range sensors
        (:func:`check_sensors`), range holds partly saturated, readings mostly
        off the calibration's range (:func:`check_reading_range`, once per
        sensor).
    """
    check_path_names((("calibration", calibration), ("readings", readings), ("out", out),
                      ("range_csv", range_csv)))
    check_output(out, what="angles file", inputs=[calibration, readings, range_csv])
    cal, est = load_estimator(calibration, model)
    rec = read_glove_csv(readings, kind=cal["kind"], adc_max=adc_max)
    sensors = rec.sensors
    check = check_sensors(sensors, adc_max=adc_max, where=str(readings), lines=rec.lines)
    refuse_unreadable(sensors, check, adc_max=adc_max, where=str(readings))
    if range_csv is not None:
        # the holds are often in the readings' own file: read once, warned about once
        held = rec if same_file(range_csv, readings) else None
        sensors = range_normalizer(cal, calibration, range_csv, adc_max=adc_max,
                                   held=held).apply(sensors)
    angles = est.predict(sensors, motion=motion)  # warns of readings off the calibration's range
    # a file without a time column gets the row index, not that index written as seconds
    timed = rec.meta.get("time_column", True)
    write_angles_csv(out, angles, time_s=rec.time_s if timed else None)
    return angles


def load_estimator(calibration, model: str) -> tuple[dict, GloveEstimator]:
    """The calibration file's contents (:func:`load_calibration`) and its estimator `model`.

    Raises
    ------
    InvalidInputError
        The file is unreadable or malformed, or holds no estimator `model`.
    """
    cal = load_calibration(calibration)
    est = cal["estimators"].get(model)
    if est is None:
        raise InvalidInputError(f"{calibration}: no estimator {model!r}; it holds "
                                f"{', '.join(cal['estimators'])}")
    return cal, est


def range_normalizer(cal: dict, calibration, range_csv, *, adc_max: float,
                     held=None) -> RangeNormalizer:
    """The map of this wearing's open-hand and fist holds (`range_csv`, or `held` read
    from it already) onto the calibration's (:class:`RangeNormalizer`).

    Raises
    ------
    InvalidInputError
        The calibration had no range holds; `range_csv` has no ``range_open`` and
        ``range_fist`` rows.
    RecordingError, EstimationError
        As :func:`apply_calibration` says.
    """
    if cal["range_reference"] is None:
        raise InvalidInputError(f"{calibration}: the calibration had no range_open/"
                                "range_fist holds, so range_csv (--range) cannot be used")
    if held is None:
        held = read_glove_csv(range_csv, adc_max=adc_max)
    src = range_readings(held, where=str(range_csv))
    if src is None:
        raise InvalidInputError(f"{range_csv}: needs rows with motion 'range_open' "
                                "and rows with motion 'range_fist'")
    tgt = cal["range_reference"]
    try:
        return RangeNormalizer(src[0], src[1], tgt[0], tgt[1])
    except EstimationError as exc:
        raise EstimationError(f"{range_csv}: {exc}") from None

