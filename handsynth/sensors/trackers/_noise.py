"""Measurement error of a 6-DOF magnetic tracker.

Figures (Polhemus, *LIBERTY* data sheet, "Specifications"):

* static accuracy: 0.03 in = **0.76 mm RMS** for the X, Y or Z position and
  **0.15 deg RMS** for sensor orientation;
* resolution at 30 cm range: **0.0038 mm** position and **0.0012 deg**
  orientation (0.00015 in, 0.0012 deg).

The patent's sensors are 10-15 cm from a wrist-mounted TX-1 transmitter
(JP2010-88628, para. 0096), inside the data sheet's calibrated range.

:data:`LIBERTY` applies the *accuracy* figures as independent per-axis errors
on every frame.  This is deliberately pessimistic: the data sheet's accuracy
is mostly a slowly varying field distortion, and frame-to-frame jitter is at
the resolution level (:data:`LIBERTY_RESOLUTION`).  ``correlation_time_s``
turns the white error into a first-order Gauss-Markov process of the same
RMS, a model of that slowly varying distortion.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..common import rotvec_to_matrix
from ._checks import check_integer, check_number

__all__ = ["DISTORTED_FIELD", "LIBERTY", "LIBERTY_RESOLUTION", "NO_NOISE", "FieldDistortion", "SensorNoise"]


@dataclass(frozen=True, kw_only=True)
class SensorNoise:
    """Per-axis random error added to simulated sensor poses.

    Parameters
    ----------
    position_sd_mm : float
        RMS error of each position coordinate, millimetres.
    orientation_sd_deg : float
        RMS of each component of the orientation error (a small rotation
        vector applied in the sensor frame), degrees.
    correlation_time_s : float
        0 for white error; otherwise the time constant of a first-order
        Gauss-Markov process with the same RMS, seconds.
    """

    position_sd_mm: float = 0.0
    orientation_sd_deg: float = 0.0
    correlation_time_s: float = 0.0

    def __post_init__(self) -> None:
        for name in ("position_sd_mm", "orientation_sd_deg", "correlation_time_s"):
            check_number(getattr(self, name), name, minimum=0.0)

    def _process(self, rng: np.random.Generator, times: np.ndarray, shape) -> np.ndarray:
        """Unit-variance white or Gauss-Markov samples, ``(n,) + shape``."""
        n = times.shape[0]
        w = rng.standard_normal((n,) + tuple(shape))
        if self.correlation_time_s == 0 or n < 2:
            return w
        # exact discretisation of an Ornstein-Uhlenbeck process, unit variance
        a = np.exp(-np.diff(times) / self.correlation_time_s)
        out = np.empty_like(w)
        out[0] = w[0]
        for i in range(1, n):
            out[i] = a[i - 1] * out[i - 1] + np.sqrt(1.0 - a[i - 1] ** 2) * w[i]
        return out

    def apply(
        self,
        positions: np.ndarray,
        rotations: np.ndarray,
        times: np.ndarray,
        *,
        rng: np.random.Generator,
    ) -> tuple[np.ndarray, np.ndarray]:
        """Return noisy copies of sensor poses.

        Parameters
        ----------
        positions : (n, k, 3) ndarray of float64
            Metres.
        rotations : (n, k, 3, 3) ndarray of float64
            Sensor to transmitter.
        times : (n,) ndarray of float64
            Seconds (used by the correlated model).
        rng : numpy.random.Generator

        Returns
        -------
        positions, rotations : ndarrays of the input shapes
        """
        k = positions.shape[1]
        dp = self._process(rng, times, (k, 3)) * (self.position_sd_mm * 1e-3)
        dr = self._process(rng, times, (k, 3)) * np.deg2rad(self.orientation_sd_deg)
        return positions + dp, rotations @ rotvec_to_matrix(dr)


#: Liberty static accuracy applied as white per-frame error (pessimistic).
LIBERTY = SensorNoise(position_sd_mm=0.76, orientation_sd_deg=0.15)
#: Liberty resolution at 30 cm: the frame-to-frame jitter floor.
LIBERTY_RESOLUTION = SensorNoise(position_sd_mm=0.0038, orientation_sd_deg=0.0012)
#: Exact poses.
NO_NOISE = SensorNoise()


@dataclass(frozen=True, kw_only=True)
class FieldDistortion:
    """Smooth field distortion, slow drift and small white jitter.

    A second error model, independent of :class:`SensorNoise`: the Liberty
    data sheet's static accuracy (0.76 mm, 0.15 deg RMS, see module
    docstring) is applied as a *spatially smooth* distortion of the field,
    the same for both sensors at the same place (a sum of `n_waves` plane
    waves of wavelength `wavelength_mm` with random directions, phases and
    amplitudes), plus a linear drift of each sensor's reading over the trial
    and white jitter.  Wavelength, drift and jitter are modelling choices,
    not data-sheet figures: the jitter is about ten times the data sheet's
    resolution, the drift a fraction of a millimetre per trial.

    Parameters
    ----------
    position_rms_mm, orientation_rms_deg : float
        RMS of each component of the distortion over space.
    wavelength_mm : float
        Spatial wavelength of the distortion (> 0).
    drift_mm, drift_deg : float
        Drift of each sensor reached at the end of the trial (random
        direction per sensor).
    white_mm, white_deg : float
        Per-frame white jitter, RMS per component.
    n_waves : int
        Number of plane waves in the distortion field.
    """

    position_rms_mm: float = 0.76
    orientation_rms_deg: float = 0.15
    wavelength_mm: float = 150.0
    drift_mm: float = 0.3
    drift_deg: float = 0.1
    white_mm: float = 0.04
    white_deg: float = 0.01
    n_waves: int = 6

    def __post_init__(self) -> None:
        for name in ("position_rms_mm", "orientation_rms_deg", "drift_mm", "drift_deg",
                     "white_mm", "white_deg"):
            check_number(getattr(self, name), name, minimum=0.0)
        check_number(self.wavelength_mm, "wavelength_mm", above=0.0)
        check_integer(self.n_waves, "n_waves", minimum=1)

    def _field(self, rng: np.random.Generator, rms: float):
        """A random smooth vector field ``f(p)`` of per-component RMS `rms`."""
        k = rng.standard_normal((self.n_waves, 3))
        k *= 2 * np.pi / (self.wavelength_mm * 1e-3) / np.linalg.norm(k, axis=1, keepdims=True)
        phase = rng.uniform(0, 2 * np.pi, self.n_waves)
        amp = rng.standard_normal((self.n_waves, 3)) * rms / np.sqrt(self.n_waves / 2)

        def f(p: np.ndarray) -> np.ndarray:
            return np.sin(p @ k.T + phase) @ amp

        return f

    def apply(
        self,
        positions: np.ndarray,
        rotations: np.ndarray,
        times: np.ndarray,
        *,
        rng: np.random.Generator,
    ) -> tuple[np.ndarray, np.ndarray]:
        """Return distorted copies of sensor poses; see :meth:`SensorNoise.apply`."""
        n, k = positions.shape[:2]
        fp = self._field(rng, self.position_rms_mm * 1e-3)
        fr = self._field(rng, np.deg2rad(self.orientation_rms_deg))
        span = max(float(times[-1] - times[0]), 1e-9)
        ramp = ((times - times[0]) / span)[:, None, None]

        def drift(total: float) -> np.ndarray:
            d = rng.standard_normal((k, 3))
            return ramp * (total * d / np.linalg.norm(d, axis=1, keepdims=True))

        dp = fp(positions) + drift(self.drift_mm * 1e-3)
        dp += rng.standard_normal((n, k, 3)) * (self.white_mm * 1e-3)
        dr = fr(positions) + drift(np.deg2rad(self.drift_deg))
        dr += rng.standard_normal((n, k, 3)) * np.deg2rad(self.white_deg)
        # the field's orientation error is a rotation in the transmitter frame
        return positions + dp, rotvec_to_matrix(dr) @ rotations


#: The independent error model of the second evaluation configuration.
DISTORTED_FIELD = FieldDistortion()
