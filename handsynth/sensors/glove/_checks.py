"""Checks of glove readings: NaN rows, dead sensors, saturated sensors, readings off the
calibration's range."""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np

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
        Rows with a NaN reading.
    dead : tuple of int
        Sensors (0-4, thumb to little) that never change.
    saturated : ndarray, shape (N, 5), bool
        Readings at 0 or at full scale.
    """

    nan_rows: np.ndarray
    dead: tuple[int, ...]
    saturated: np.ndarray

    @property
    def saturated_sensors(self) -> tuple[int, ...]:
        n = max(len(self.saturated), 1)
        share = self.saturated.sum(axis=0) / n
        return tuple(int(k) for k in np.flatnonzero(share > SATURATION_SHARE))


def check_sensors(sensors: np.ndarray, *, adc_max: float, where: str,
                  warn: bool = True) -> SensorCheck:
    """Find NaN rows, dead and saturated sensors in readings (N, 5).

    Parameters
    ----------
    sensors : ndarray, shape (N, 5), counts
    adc_max : float, keyword-only
        Full scale; readings at 0 or `adc_max` are saturated.
    where : str, keyword-only
        Name of the data in messages (a file name, "calibration", ...).
    warn : bool, keyword-only
        Issue a :class:`GloveWarning` for each finding.

    Returns
    -------
    SensorCheck
    """
    s = np.asarray(sensors, dtype=np.float64)
    nan_rows = np.flatnonzero(np.isnan(s).any(axis=1))
    good = s[~np.isnan(s).any(axis=1)]
    dead = []
    if len(good) >= DEAD_MIN_SAMPLES:
        dead = [k for k in range(5) if np.ptp(good[:, k]) == 0]
    saturated = (s <= 0) | (s >= adc_max)
    check = SensorCheck(nan_rows=nan_rows, dead=tuple(dead), saturated=saturated)
    if warn:
        if nan_rows.size:
            first = ", ".join(str(int(r)) for r in nan_rows[:5])
            warnings.warn(f"{where}: {nan_rows.size} of {len(s)} rows have a NaN reading "
                          f"(first rows {first}); their angles are NaN", GloveWarning,
                          stacklevel=3)
        for k in dead:
            warnings.warn(f"{where}: {SENSOR_NAMES[k]} is dead: it reads {good[0, k]:g} "
                          f"counts in all {len(good)} valid samples", GloveWarning,
                          stacklevel=3)
        for k in check.saturated_sensors:
            n_sat = int(saturated[:, k].sum())
            ends = sorted({0.0 if v <= 0 else float(adc_max) for v in s[saturated[:, k], k]})
            warnings.warn(f"{where}: {SENSOR_NAMES[k]} is saturated (at "
                          f"{' and '.join(f'{e:g}' for e in ends)} counts) in {n_sat} of "
                          f"{len(s)} samples ({100 * n_sat / max(len(s), 1):.1f} %)",
                          GloveWarning, stacklevel=3)
    return check


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
    with np.errstate(invalid="ignore"):
        off = (s < low - margin) | (s > high + margin)
    valid = max(int((~np.isnan(s).any(axis=1)).sum()), 1)
    share = off.sum(axis=0) / valid
    bad = tuple(int(k) for k in np.flatnonzero(share > OFF_RANGE_SHARE))
    for k in bad:
        warnings.warn(f"{where}: {100 * share[k]:.0f} % of the {SENSOR_NAMES[k]} readings lie "
                      f"off the calibration's range {low[k]:g}-{high[k]:g} counts (read there "
                      "as its end): the same glove, full scale (--adc-max) and wearing? A new "
                      "wearing needs a range calibration (--range)", GloveWarning,
                      stacklevel=stacklevel)
    return bad
