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

from ...errors import InvalidInputError
from ..common import rotvec_to_matrix

__all__ = ["LIBERTY", "LIBERTY_RESOLUTION", "NO_NOISE", "SensorNoise"]


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
            v = getattr(self, name)
            if not (np.isfinite(v) and v >= 0):
                raise InvalidInputError(f"{name} must be finite and >= 0, got {v!r}")

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
