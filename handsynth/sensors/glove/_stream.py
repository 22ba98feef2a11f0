"""Joint angles of a glove's readings as they come (what ``handsynth glove stream`` does).

:func:`apply_calibration` reads a whole recording.  A glove worn for VR or to drive a
robot hand sends one line of five readings at a time; :func:`stream_glove_csv` answers each
line as it comes with the same estimator, which reads every sample on its own (the
regressions, the mixing over motions of seed 004 eqs. 4-6 and the synergy baseline look at
no other sample), so the answers are :func:`apply_calibration`'s on the same lines.

What a whole recording allows and a stream does not: judging a sensor saturated or off its
range over the whole recording (:func:`check_sensors`).  Line by line, a reading that is
missing or outside the converter's range (0 to `adc_max`) gives a row of NaN, and a
reading at either end of the range is warned of, once per sensor.  A sensor that reads one
value for :data:`STUCK_LINES` lines while another sensor moves is warned of as dead (once
per sensor): a live sensor shows a count or two of noise, the assumption of
:func:`check_sensors`' dead sensor, which a stream cannot wait for the end to judge.
"""

from __future__ import annotations

import re
import warnings

import numpy as np

from ..._csv import row_numbers, stream_rows
from ...errors import RecordingError
from ._apply import load_estimator, range_normalizer
from ._models import GloveWarning
from ._recording import _check_adc_max, glove_columns
from ._sensors import SENSOR_NAMES

__all__ = ["STUCK_LINES", "stream_glove_csv"]

#: Lines a sensor must read one value for, while another sensor moves by
#: :data:`_MOVED_SHARE` of the converter's range, to be warned of as dead: under 2 s at
#: the 60 Hz of the seed's glove, and more than three times the 30 samples
#: :func:`check_sensors` asks of a whole recording's dead sensor.
STUCK_LINES = 100
#: ... and that motion, a share of `adc_max` (1 %: 41 counts at 12 bits, 10 at 10 bits).
_MOVED_SHARE = 0.01


def stream_glove_csv(lines, calibration, *, model: str = "model4", motion: str | None = None,
                     range_csv=None, adc_max: float = 4095.0, source: str = "stream"):
    """Joint angles of glove CSV lines as they come: a header, then one sample a line.

    Parameters
    ----------
    lines : iterable of str
        A glove CSV (:func:`read_glove_csv`'s columns: ``sensor_thumb`` ..
        ``sensor_little``, or a glove's own names read by their meaning; ``time_s`` or a
        time in milliseconds optional; other columns passed over), the header first;
        commas, or a spreadsheet's semicolons with decimal commas, or tabs, as the header
        has them.  Lines starting with ``#`` and blank lines are passed over.
    calibration : str or os.PathLike
        Calibration file (JSON) of ``handsynth glove calibrate``.
    model, motion, range_csv, adc_max
        As :func:`apply_calibration`'s.
    source : str, keyword-only
        The input's name, for messages.

    Yields
    ------
    time_s : float or None
        The line's time, s; None where the lines have no time column.
    angles : ndarray, shape (20,), float64, deg
        Canonical order; NaN where a reading is missing or beyond the converter's range.

    Raises
    ------
    InvalidInputError, RecordingError, EstimationError
        As :func:`apply_calibration` for the calibration, `model`, `motion` and
        `range_csv`; no header; a line whose number of cells is not the header's, or a
        sensor's or time's cell that is no number (naming the line and the column).

    Warns
    -----
    GloveWarning
        Once per sensor: a reading at either end of the converter's range (saturated); a
        sensor that reads one value for :data:`STUCK_LINES` lines while another moves
        (dead); the estimator's warnings (readings off the calibration's range), once each.
    """
    _check_adc_max(adc_max)
    cal, est = load_estimator(calibration, model)
    normalizer = None if range_csv is None else range_normalizer(cal, calibration, range_csv,
                                                                 adc_max=adc_max)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        est.predict(np.full((1, 5), np.nan), motion=motion)  # an unknown motion refused first
    header: list[str] | None = None
    where = np.zeros(5, int)
    time_col: int | None = None
    scale = 1.0
    said: set[str] = set()
    stuck = _StuckSensors(adc_max)
    for number, cells in stream_rows(lines):
        if header is None:
            header, col, ms_col = glove_columns(cells, path=source, line=number)
            where = np.array([col[name] for name in SENSOR_NAMES])
            time_col = col.get("time_s", ms_col)
            scale = 1.0 if "time_s" in col else 1e-3
            continue
        while len(cells) > len(header) and cells[-1] == "":  # a delimiter after each row
            cells.pop()
        if len(cells) != len(header):
            raise RecordingError(f"{source}, line {number}: {len(cells)} fields, header has "
                                 f"{len(header)}")
        readings = row_numbers(cells, where, header, source=source, line=number)
        t = None if time_col is None else \
            float(row_numbers(cells, time_col, header, source=source, line=number)) * scale
        for held, other, span in stuck.push(readings):
            _once(said, f"{SENSOR_NAMES[held]} stuck",
                  f"{source}, line {number}: {SENSOR_NAMES[held]} has read {readings[held]:g} for the "
                  f"last {STUCK_LINES} lines while {SENSOR_NAMES[other]} moved {span:g} counts: "
                  "dead or disconnected? Its joints are read as held there")
        outside = ~((readings >= 0) & (readings <= adc_max))
        for k in np.flatnonzero(((readings == 0) | (readings == adc_max)) & ~outside):
            _once(said, f"{SENSOR_NAMES[k]} saturated",
                  f"{source}, line {number}: {SENSOR_NAMES[k]} reads {readings[k]:g}, the end "
                  f"of the converter's range 0-{adc_max:g} (saturated); its joints are read as "
                  "at that end while it stays there")
        if outside.any():
            j = int(np.flatnonzero(outside)[0])
            _once(said, f"{SENSOR_NAMES[j]} outside",
                  f"{source}, line {number}: {SENSOR_NAMES[j]} reads {readings[j]:g}, outside "
                  f"the converter's range 0-{adc_max:g}: its line is read as missing (NaN)")
            yield t, np.full(20, np.nan)
            continue
        if normalizer is not None:
            readings = normalizer.apply(readings[None])[0]
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            angles = est.predict(readings[None], motion=motion)[0]
        for w in caught:
            _once(said, re.sub(r"[-+\d.]+", "", str(w.message)), str(w.message))
        yield t, angles
    if header is None:
        raise RecordingError(f"{source}: no header line ({', '.join(('time_s', *SENSOR_NAMES))})")


def _once(said: set, key: str, message: str) -> None:
    """Warn of `message` unless a message of the same `key` was warned of already."""
    if key not in said:
        said.add(key)
        warnings.warn(f"{message} (said once)", GloveWarning, stacklevel=4)


class _StuckSensors:
    """Each sensor's run of one value, and how far every sensor moved meanwhile."""

    def __init__(self, adc_max: float) -> None:
        self.adc_max = adc_max
        self.moved = _MOVED_SHARE * adc_max
        self.value = np.full(5, np.nan)
        self.run = np.zeros(5, int)
        self.low = np.full((5, 5), np.inf)    # [k, j]: sensor j's range during k's run
        self.high = np.full((5, 5), -np.inf)

    def push(self, readings: np.ndarray) -> list[tuple[int, int, float]]:
        """(sensor, the sensor that moved most, its span) of each sensor stuck now inside
        the converter's range (at either end it is saturated, warned of as such)."""
        same = readings == self.value
        self.run = np.where(same, self.run + 1, 1)
        self.value = readings.copy()
        self.low[~same], self.high[~same] = np.inf, -np.inf
        with np.errstate(invalid="ignore"):
            self.low = np.fmin(self.low, readings)
            self.high = np.fmax(self.high, readings)
        out = []
        inside = (readings > 0) & (readings < self.adc_max)
        for k in np.flatnonzero((self.run >= STUCK_LINES) & inside):
            span = self.high[k] - self.low[k]
            j = int(np.nanargmax(np.where(np.arange(5) == k, -np.inf, span)))
            if span[j] >= self.moved:
                out.append((int(k), j, float(span[j])))
        return out
