"""Checks of glove readings: NaN rows, dead sensors, saturated sensors, readings out of the
converter's range (below 0, above full scale) or off the calibration's range."""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np

from ...errors import RecordingError
from ._models import GloveWarning
from ._sensors import SENSOR_NAMES

__all__ = ["SensorCheck", "check_reading_range", "check_sensors"]

#: A sensor that reads exactly the same value over at least this many
#: samples is dead (a live resistive sensor always shows a count or two of
#: noise; assumption).
DEAD_MIN_SAMPLES = 30
#: Share of samples at either end of the range above which a sensor is
#: reported as saturated.
SATURATION_SHARE = 0.01
#: Share of readings beyond the calibration's range (widened by a quarter of its span on
#: each side) above which readings are reported as not matching the calibration.
OFF_RANGE_SHARE = 0.05


@dataclass(frozen=True)
class SensorCheck:
    """What :func:`check_sensors` found.

    Attributes
    ----------
    nan_rows : ndarray of int
        Rows with a NaN reading (indices into the readings, from 0).
    dead : tuple of int
        Sensors (0-4, thumb to little) that never change, at a value inside the
        converter's range (a sensor stuck at 0 or at full scale is saturated).
    saturated : ndarray, shape (N, 5), bool
        Readings at exactly 0 or exactly full scale (the converter's ends).
    below : ndarray, shape (N, 5), bool
        Readings below the converter's range (negative), which no converter gives.
    above : ndarray, shape (N, 5), bool
        Readings above the full scale, which no converter with that full scale
        gives (another full scale, or another unit).
    """

    nan_rows: np.ndarray
    dead: tuple[int, ...]
    saturated: np.ndarray
    below: np.ndarray = None  # type: ignore[assignment]
    above: np.ndarray = None  # type: ignore[assignment]

    def __post_init__(self) -> None:
        shape = np.shape(self.saturated)
        for name in ("below", "above"):
            if getattr(self, name) is None:
                object.__setattr__(self, name, np.zeros(shape, dtype=bool))

    @property
    def off_scale(self) -> np.ndarray:
        """Readings that give no exact value, shape (N, 5), bool: saturated, below or
        above the converter's range."""
        return self.saturated | self.below | self.above

    @property
    def saturated_sensors(self) -> tuple[int, ...]:
        """Sensors saturated in more than :data:`SATURATION_SHARE` of the rows."""
        n = max(len(self.saturated), 1)
        share = self.saturated.sum(axis=0) / n
        return tuple(int(k) for k in np.flatnonzero(share > SATURATION_SHARE))

    @property
    def out_of_range_sensors(self) -> tuple[int, ...]:
        """Sensors with at least one reading below or above the converter's range."""
        return tuple(int(k) for k in np.flatnonzero((self.below | self.above).any(axis=0)))


def row_positions(rows, lines=None, *, limit: int = 5) -> str:
    """The first `limit` of `rows` in words, as file lines when `lines` is given.

    Parameters
    ----------
    rows : array_like of int
        Row indices, from 0.
    lines : array_like of int, optional
        File line of every row (1 = the file's first line); None for data not
        read from a file.
    limit : int, keyword-only
        How many to name.

    Returns
    -------
    str
        ``"first at lines 9, 52"`` (of the file) or ``"first at row indices 7, 50"``
        (from 0); ``"at line 9"`` for one row.
    """
    rows = np.asarray(rows, dtype=np.int64)
    first = "at" if len(rows) == 1 else "first at"
    plural = "" if len(rows) == 1 else "s"
    if lines is not None:
        return f"{first} line{plural} " + ", ".join(str(int(lines[r])) for r in rows[:limit])
    return f"{first} row ind{'ex' if len(rows) == 1 else 'ices'} " + ", ".join(
        str(int(r)) for r in rows[:limit])


def off_scale_words(sensors: np.ndarray, check: SensorCheck, k: int, *, adc_max: float,
                    rows: np.ndarray | None = None, unit: str = "") -> list[str]:
    """What is wrong with sensor `k`'s readings, one phrase per kind, each with its count.

    Parameters
    ----------
    sensors : ndarray, shape (N, 5), counts
        The readings `check` was made of.
    check : SensorCheck
    k : int
        The sensor, 0-4 (thumb to little).
    adc_max : float, keyword-only
        Full scale, counts.
    rows : ndarray, shape (N,), bool, keyword-only, optional
        Count only these rows (default all).
    unit : str, keyword-only
        Word after each count (``"row"``, made plural where the count is not 1);
        none by default.

    Returns
    -------
    list of str
        Such as ``"saturated (at 4095 counts) in 12"``, ``"below the converter's range
        (negative, down to -3 counts) in 2"``, ``"above the full scale 1 counts (up to
        1837) in 333"``; the caller adds ``" of N rows"`` (and :func:`scale_hint`).
    """
    sel = np.ones(len(sensors), dtype=bool) if rows is None else rows
    s = sensors[sel, k]

    def count(mask: np.ndarray) -> str:
        n = int(mask.sum())
        return f"{n} {unit}{'' if n == 1 else 's'}" if unit else str(n)

    out = []
    sat = check.saturated[sel, k]
    if sat.any():
        ends = sorted({0.0 if v <= 0 else float(adc_max) for v in s[sat]})
        # a sensor at 0 in every row may as well be unplugged as bent past its range
        what = "saturated or disconnected" if ends == [0.0] and sat.all() else "saturated"
        out.append(f"{what} (at {' and '.join(f'{e:g}' for e in ends)} counts) in "
                   f"{count(sat)}")
    below = check.below[sel, k]
    if below.any():
        out.append(f"below the converter's range (negative, down to {s[below].min():g} counts) "
                   f"in {count(below)}")
    above = check.above[sel, k]
    if above.any():
        out.append(f"above the full scale {adc_max:g} counts (up to {s[above].max():g}) in "
                   f"{count(above)}")
    return out


def scale_hint(check: SensorCheck, rows: np.ndarray | None = None) -> str:
    """``"; is the full scale (--adc-max) right?"`` when a reading lies above it, else ``""``.

    Parameters
    ----------
    check : SensorCheck
    rows : ndarray, shape (N,), bool, optional
        Look only at these rows (default all).
    """
    above = check.above if rows is None else check.above[rows]
    return "; is the full scale (--adc-max) right?" if above.any() else ""


def check_sensors(sensors: np.ndarray, *, adc_max: float, where: str,
                  warn: bool = True, lines=None) -> SensorCheck:
    """Find NaN rows, dead, saturated and out-of-range sensors in readings (N, 5).

    Parameters
    ----------
    sensors : ndarray, shape (N, 5), counts
    adc_max : float, keyword-only
        Full scale; readings at exactly 0 or `adc_max` are saturated, readings
        below 0 or above `adc_max` are out of the converter's range.
    where : str, keyword-only
        Name of the data in messages (a file name, "calibration", ...).
    warn : bool, keyword-only
        Issue a :class:`GloveWarning` for each finding.
    lines : array_like of int, shape (N,), keyword-only, optional
        File line of each row, to name rows by (``GloveRecording.lines``).

    Returns
    -------
    SensorCheck

    Warns
    -----
    GloveWarning
        (`warn`) rows with a NaN reading (counted in rows, named by file line
        where `lines` is given), each dead sensor, each sensor saturated in
        more than 1 % of the rows and each sensor with a reading out of the
        converter's range.

    Raises
    ------
    RecordingError
        `sensors` is not an array of numbers of shape (N, 5), naming `where`.
    """
    try:
        s = np.asarray(sensors, dtype=np.float64)
    except (TypeError, ValueError):
        s = None
    if s is None or s.ndim != 2 or s.shape[1] != 5:
        got = f"shape {s.shape}" if s is not None else type(sensors).__name__
        raise RecordingError(f"{where}: sensors must be readings of shape (N, 5), got {got}")
    nan = np.isnan(s)
    nan_rows = np.flatnonzero(nan.any(axis=1))
    good = s[~nan.any(axis=1)]
    with np.errstate(invalid="ignore"):
        saturated = (s == 0) | (s == adc_max)
        below = s < 0
        above = s > adc_max
    dead = []
    if len(good) >= DEAD_MIN_SAMPLES:
        dead = [k for k in range(5) if np.ptp(good[:, k]) == 0 and 0 < good[0, k] < adc_max]
    check = SensorCheck(nan_rows=nan_rows, dead=tuple(dead), saturated=saturated, below=below,
                        above=above)
    if warn:
        n = len(s)
        if nan_rows.size:
            warnings.warn(f"{where}: {nan_rows.size} of {n} rows have a NaN reading "
                          f"({row_positions(nan_rows, lines)}); their angles are NaN",
                          GloveWarning, stacklevel=3)
        for k in dead:
            warnings.warn(f"{where}: {SENSOR_NAMES[k]} is dead: it reads {good[0, k]:g} "
                          f"counts in all {len(good)} rows with five readings", GloveWarning,
                          stacklevel=3)
        for k in sorted(set(check.saturated_sensors) | set(check.out_of_range_sensors)):
            words = off_scale_words(s, check, k, adc_max=adc_max)
            n_off = int(check.off_scale[:, k].sum())
            hint = scale_hint(check) if check.above[:, k].any() else ""
            warnings.warn(f"{where}: {SENSOR_NAMES[k]} is {' and '.join(words)} of {n} rows "
                          f"({100 * n_off / max(n, 1):.1f} %){hint}", GloveWarning,
                          stacklevel=3)
    return check


def refuse_unreadable(sensors: np.ndarray, check: SensorCheck, *, adc_max: float,
                      where: str) -> None:
    """Refuse readings from which no angle can be estimated.

    Parameters
    ----------
    sensors : ndarray, shape (N, 5), counts
    check : SensorCheck
        Of `sensors`.
    adc_max : float, keyword-only
        Full scale, counts.
    where : str, keyword-only
        Name of the data in messages.

    Raises
    ------
    RecordingError
        No row has all five readings, or every reading of every sensor is
        saturated or out of the converter's range (each sensor named with its
        count of rows).
    """
    s = np.asarray(sensors, dtype=np.float64)
    valid = np.asarray(~np.isnan(s).any(axis=1), dtype=bool)
    if not valid.any():
        raise RecordingError(f"{where}: none of the {len(s)} rows has all five readings "
                             "(every row has an empty or NaN sensor cell)")
    if check.off_scale[valid].all():
        n = int(valid.sum())
        per = "; ".join(f"{SENSOR_NAMES[k]} "
                        + " and ".join(off_scale_words(s, check, k, adc_max=adc_max, rows=valid))
                        + f" of {n} rows" for k in range(5))
        raise RecordingError(f"{where}: every reading is saturated or out of the converter's "
                             f"range, so no angle can be estimated ({per}){scale_hint(check)}")


def check_reading_range(sensors: np.ndarray, low: np.ndarray, high: np.ndarray, *,
                        where: str, stacklevel: int = 2) -> tuple[int, ...]:
    """Warn about sensors whose readings mostly lie off the calibration's range.

    The models clamp readings to the range they were fitted on, so a glove
    read with another full scale (a 10-bit converter, volts) or another
    wearing without the range calibration gives a nearly constant answer
    without this check.

    Parameters
    ----------
    sensors : ndarray, shape (N, 5), counts
    low, high : ndarray, shape (5,), counts
        Lowest and highest reading of each sensor in the calibration.
    where : str, keyword-only
        Name of the data in messages.
    stacklevel : int, keyword-only
        Of the warnings, as for :func:`warnings.warn` (2: the caller's line).

    Returns
    -------
    tuple of int
        The sensors warned about (0-4, thumb to little).
    """
    s = np.asarray(sensors, dtype=np.float64)
    low, high = np.asarray(low, dtype=np.float64), np.asarray(high, dtype=np.float64)
    margin = 0.25 * (high - low)
    valid = max(int((~np.isnan(s).any(axis=1)).sum()), 1)

    def off_share(readings: np.ndarray, k: int) -> float:
        """Share of `readings` off sensor `k`'s calibrated range (widened by `margin`)."""
        with np.errstate(invalid="ignore"):
            return float(((readings < low[k] - margin[k])
                          | (readings > high[k] + margin[k])).sum() / valid)

    share = np.array([off_share(s[:, k], k) for k in range(s.shape[1])])
    bad = tuple(int(k) for k in np.flatnonzero(share > OFF_RANGE_SHARE))
    for k in bad:
        # two channels exchanged (cables plugged into each other's inputs): each one's
        # readings fit the other's range
        other = next((j for j in range(s.shape[1]) if j != k
                      and off_share(s[:, k], j) <= OFF_RANGE_SHARE
                      and off_share(s[:, j], k) <= OFF_RANGE_SHARE), None)
        swap = "" if other is None else (
            f"; its readings fit {SENSOR_NAMES[other]}'s range and {SENSOR_NAMES[other]}'s fit "
            "its: were the two channels exchanged?")
        warnings.warn(f"{where}: {100 * share[k]:.0f} % of the {SENSOR_NAMES[k]} readings lie "
                      f"off the calibration's range {low[k]:g}-{high[k]:g} counts (read there "
                      f"as its end){swap}: the same glove, full scale (--adc-max) and wearing? "
                      "A new wearing needs a range calibration (--range); a calibration "
                      "recording that bent the finger less than these readings does needs "
                      "recording again", GloveWarning,
                      stacklevel=stacklevel)
    return bad
