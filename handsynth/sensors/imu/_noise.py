"""MEMS noise of an MPU-9250-like IMU, parameterised as Allan-deviation figures.

MuJoCo's sensors are ideal; everything below is added here, per sensor and
axis, as the gyro model of seed 003 eq. 4.9 (Lam et al. 2003): output = true
+ bias + white noise, the bias a random walk (rate random walk, slope +1/2 of
the Allan deviation) plus a first-order Gauss-Markov bias instability (the
flat part) plus a constant turn-on bias.

Default figures (:data:`MPU9250_DATASHEET`)
-------------------------------------------
InvenSense, *MPU-9250 Product Specification*, PS-MPU-9250A-01 rev. 1.1 (2016):

- gyro rate noise spectral density 0.01 deg/s/sqrt(Hz) (Table "Gyroscope
  specifications"); full scale +/-2000 deg/s (16 bit, 0.061 deg/s per LSB);
  initial zero-rate output tolerance +/-5 deg/s (taken as 3 sigma after a
  static bias removal of the start: 0.3 deg/s residual s.d. is used, see
  ``turn_on_bias``); sensitivity tolerance +/-3 %, cross-axis +/-2 %;
- accelerometer noise power spectral density 300 ug/sqrt(Hz); full scale
  +/-16 g (0.49 mg per LSB); zero-g initial tolerance +/-80 mg, sensitivity
  +/-3 %, cross-axis +/-2 %;
- magnetometer (AK8963 die) full scale +/-4800 uT (section 2.3,
  "Magnetometer features"), 0.15 uT per LSB in 16-bit output (Asahi Kasei
  Microdevices, *AK8963 3-axis Electronic Compass*, MS1356-E-02, 2013/10,
  section 1 "Features": 0.15 uT/LSB typ.).

The datasheet gives no rate random walk and no bias instability.  Rate random
walk comes from the thesis' own Allan analysis of 20 MPU-9250s (seed 003
Table 4.1: gyro RRW 1.4-6.2e-4 deg/s^1.5, mean 2.3e-4; accelerometer RRW
1.1-8.7e-6 G/s^0.5, mean 4.6e-6).  Its Allan plots (Figs. 4.3-4.4) show only
the -1/2 and +1/2 slopes, so the bias instability is set below their
crossing (gyro 5e-4 deg/s, accelerometer 1e-5 G): an assumption, stated as
such; so is the correlation time of that bias instability (``bias_corr_s``,
100 s; see :class:`AxisNoise`).  The magnetometer's white noise 0.3 uT (two
LSB), its residual hard iron 1.0 uT and soft iron 0.02 after a calibration
and the hard iron's change between recordings 0.2 uT are assumptions, not
datasheet figures (see :class:`MagNoise`, field by field); the
between-sensor azimuth spread of 4.5 deg s.d. is the thesis' measured figure
(Table 4.2).  The held-out configuration (:data:`EVAL_NOISE`) sets other
values for every one of these assumed figures (larger noise and residuals,
40 s for the correlation time), so that no assumed figure the filters were
tuned with is the one they are scored with (docs/imu.md, "Figures").

How the tolerances become s.d.s: the sensitivity tolerance of +/-3 % is
taken as 3 sigma (``scale_error`` 0.01); the cross-axis terms' 0.005 and the
accelerometer's turn-on bias of 10 mg are assumptions below their tolerances
taken as 3 sigma (0.0067 and 27 mg), stated as such.

Scale/cross-axis matrices and turn-on biases belong to the physical sensor
(:func:`draw_fixed_errors`; ``device_seed`` of :func:`simulate_imu` keeps them
across recordings, so that a calibration can be carried to later
recordings); the bias also changes by ``bias_repeatability`` at every
recording.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from ..._checks import check_number, is_number
from ...errors import InvalidInputError
from ._model import GRAVITY_MPS2, SENSOR_NAMES, TIP_SENSORS

__all__ = [
    "EVAL_NOISE",
    "MPU9250_DATASHEET",
    "AxisNoise",
    "ImuNoise",
    "MagDisturbance",
    "MagNoise",
    "apply_axis_noise",
    "draw_fixed_errors",
]

_DEG = np.pi / 180.0


def _check_figure(name: str, value, *, positive: bool = False) -> None:
    """Refuse a noise figure that is not a finite number >= 0 (> 0 with `positive`)."""
    if positive:
        check_number(value, name, above=0)
    else:
        check_number(value, name, minimum=0)


@dataclass(frozen=True)
class AxisNoise:
    """Noise of one 3-axis inertial sensor, SI units (rad/s or m/s^2).

    Parameters
    ----------
    white : float
        Noise density N (Allan slope -1/2 coefficient, the value of the
        Allan deviation at tau = 1 s): rad/s/sqrt(Hz) or m/s^2/sqrt(Hz).
    rate_random_walk : float
        K (Allan slope +1/2 coefficient, seed 003 eq. 4.4): units/sqrt(s).
    bias_instability : float
        B (flat part of the Allan deviation, at 0.664 B): units.
    bias_corr_s : float
        Correlation time T_c (s) of the first-order Gauss-Markov process that
        models B.  Default 100 s: an assumption; neither the MPU-9250
        datasheet nor the thesis' Allan analysis (seed 003 Figs. 4.3-4.4,
        which show no flat part) gives a correlation time.  With it the
        term's Allan deviation peaks at tau = 1.89 T_c, about 190 s (IEEE Std
        952-1997, annex C; see :func:`apply_axis_noise`), which is of the
        order of the averaging time at which the default white noise and
        rate random walk cross, N sqrt(3) / K: about 75 s for the gyro and
        110 s for the accelerometer, where a bias instability would show.
        The held-out configuration (:data:`EVAL_NOISE`) uses 40 s.
    turn_on_bias : float
        s.d. of the constant bias per axis (units): a property of the
        physical sensor (see ``device_seed`` of :func:`simulate_imu`).
    bias_repeatability : float
        s.d. of the change of that bias from one recording (power-up) to the
        next, per axis (units); a calibration cannot remove it.
    bias_drift_rate : float
        s.d. of a steady change of the bias during a recording, per axis
        (units/s), drawn per recording: a sensor warming on the skin.  The
        MPU-9250 datasheet gives the gyro's zero-rate output a variation of
        +-30 deg/s over -40 to 85 C (PS-MPU-9250A-01, table 1), up to 0.24
        deg/s per C; how fast a sensor warms on a hand is an assumption.  0
        (the default) leaves every other draw as it was.
    scale_error, cross_axis : float
        s.d. of the scale-factor error and of the cross-axis terms (fractions).
    full_scale : float
        Saturation, units.
    lsb : float
        Quantisation step, units (0 for none).
    """

    white: float
    rate_random_walk: float
    bias_instability: float
    bias_corr_s: float = 100.0
    turn_on_bias: float = 0.0
    bias_repeatability: float = 0.0
    bias_drift_rate: float = 0.0
    scale_error: float = 0.0
    cross_axis: float = 0.0
    full_scale: float = np.inf
    lsb: float = 0.0

    def __post_init__(self) -> None:
        for k in ("white", "rate_random_walk", "bias_instability", "turn_on_bias",
                  "bias_repeatability", "bias_drift_rate", "scale_error", "cross_axis", "lsb"):
            v = getattr(self, k)
            if not (np.isfinite(v) and v >= 0):
                raise InvalidInputError(f"{k} must be finite and >= 0, got {v!r}")
        if not self.bias_corr_s > 0:
            raise InvalidInputError(f"bias_corr_s must be > 0, got {self.bias_corr_s!r}")
        if not self.full_scale > 0:
            raise InvalidInputError(f"full_scale must be > 0, got {self.full_scale!r}")

    def scaled(self, factor: float) -> AxisNoise:
        """The same sensor with every random term times `factor`."""
        return replace(self, white=self.white * factor,
                       rate_random_walk=self.rate_random_walk * factor,
                       bias_instability=self.bias_instability * factor,
                       turn_on_bias=self.turn_on_bias * factor,
                       bias_repeatability=self.bias_repeatability * factor,
                       bias_drift_rate=self.bias_drift_rate * factor)


@dataclass(frozen=True)
class MagNoise:
    """Magnetometer noise and calibration residuals, microtesla.

    The defaults of ``white_ut``, ``hard_iron_ut``, ``soft_iron`` and
    ``hard_iron_repeatability_ut`` are assumptions, not figures of the
    MPU-9250 product specification or the AK8963 datasheet.  They stand for
    a calibrated magnetometer: residuals small against the 47 uT field of
    ``EARTH_FIELD_UT``.  The held-out configuration (:data:`EVAL_NOISE`)
    scores the filters with other figures (0.5 uT, 2.0 uT, 0.04, 0.5 uT;
    docs/imu.md, "Figures").

    Parameters
    ----------
    white_ut : float
        White noise s.d. per sample.  Default 0.3 uT: an assumption, two
        quantisation steps of the AK8963 (0.15 uT/LSB, AK8963 datasheet
        MS1356-E-02, section 1).
    hard_iron_ut : float
        s.d. of the constant offset per axis.  Default 1.0 uT: an
        assumption for the residual after a calibration (about 2 % of the
        47 uT field).
    soft_iron : float
        s.d. of the symmetric soft-iron matrix entries around identity.
        Default 0.02: an assumption for the residual after a calibration
        (a 2 % scale or cross-axis error).
    azimuth_sd_deg : float
        s.d. of a per-sensor rotation of the magnetometer axes about the
        sensor z axis.  Default 4.5 deg: the thesis' measured between-sensor
        azimuth spread (seed 003 Table 4.2).
    hard_iron_repeatability_ut : float
        s.d. of the hard iron's change per axis between two recordings of
        the same physical sensor.  Default 0.2 uT: an assumption (no
        datasheet figure), a fifth of ``hard_iron_ut``.
    full_scale_ut, lsb_ut : float
        Saturation (> 0) and quantisation step (0 for none).  Defaults
        4800 uT (MPU-9250 product specification PS-MPU-9250A-01, section
        2.3) and 0.15 uT (AK8963 datasheet MS1356-E-02, section 1, 16-bit
        output).

    Every figure is a finite number >= 0 (InvalidInputError naming it).
    """

    white_ut: float = 0.3
    hard_iron_ut: float = 1.0
    soft_iron: float = 0.02
    azimuth_sd_deg: float = 4.5
    hard_iron_repeatability_ut: float = 0.2
    full_scale_ut: float = 4800.0
    lsb_ut: float = 0.15

    def __post_init__(self) -> None:
        for k in ("white_ut", "hard_iron_ut", "soft_iron", "azimuth_sd_deg",
                  "hard_iron_repeatability_ut", "lsb_ut"):
            _check_figure(f"MagNoise.{k}", getattr(self, k))
        _check_figure("MagNoise.full_scale_ut", self.full_scale_ut, positive=True)


@dataclass(frozen=True)
class MagDisturbance:
    """A local magnetic field (a magnet, a steel tool) for a while.

    Parameters
    ----------
    start_s, end_s : float
        Active time, with 0.5 s smooth onset and offset.
    field_ut : (3,) float
        Extra world-frame field at full strength, microtesla.
    sensors : tuple of str
        Affected sensors (empty: all), names of :data:`SENSOR_NAMES` or
        :data:`TIP_SENSORS`; :func:`simulate_imu` refuses a name its hand
        lacks.

    Raises
    ------
    InvalidInputError
        Times that are not finite or an end not after the start, a field
        that is not three finite numbers, unknown sensor names.
    """

    start_s: float
    end_s: float
    field_ut: tuple = (15.0, 10.0, -5.0)
    sensors: tuple = ()

    def __post_init__(self) -> None:
        for k in ("start_s", "end_s"):
            v = getattr(self, k)
            if not (is_number(v) and np.isfinite(v)):
                raise InvalidInputError(f"MagDisturbance.{k} must be a finite number of seconds, "
                                        f"got {v!r}")
        if not self.end_s > self.start_s:
            raise InvalidInputError(f"MagDisturbance is empty: end_s ({self.end_s!r}) must be after "
                                    f"start_s ({self.start_s!r})")
        try:
            f = np.asarray(self.field_ut, dtype=float)
        except (TypeError, ValueError):
            f = np.full(1, np.nan)
        if f.shape != (3,) or not np.all(np.isfinite(f)):
            raise InvalidInputError(f"MagDisturbance.field_ut must be three finite numbers (uT), "
                                    f"got {self.field_ut!r}")
        if isinstance(self.sensors, str) or not all(isinstance(x, str) for x in self.sensors):
            raise InvalidInputError(f"MagDisturbance.sensors must be a tuple of sensor names, "
                                    f"got {self.sensors!r}")
        object.__setattr__(self, "sensors", tuple(self.sensors))
        unknown = [x for x in self.sensors if x not in SENSOR_NAMES + TIP_SENSORS]
        if unknown:
            raise InvalidInputError(f"MagDisturbance.sensors: unknown sensor(s) "
                                    f"{', '.join(map(repr, unknown))}; expected names of "
                                    f"{', '.join(SENSOR_NAMES)}")


@dataclass(frozen=True)
class ImuNoise:
    """Noise of every IMU of the system (each sensor draws its own terms)."""

    gyro: AxisNoise
    accel: AxisNoise
    mag: MagNoise = field(default_factory=MagNoise)
    disturbances: tuple = ()
    label: str = ""

    def __post_init__(self) -> None:
        for k, kind in (("gyro", AxisNoise), ("accel", AxisNoise), ("mag", MagNoise)):
            v = getattr(self, k)
            if not isinstance(v, kind):
                raise InvalidInputError(f"ImuNoise.{k} must be a {kind.__name__}, got "
                                        f"{type(v).__name__}")
        if isinstance(self.disturbances, MagDisturbance) or not all(
                isinstance(d, MagDisturbance) for d in self.disturbances):
            raise InvalidInputError(f"ImuNoise.disturbances must be a tuple of MagDisturbance, "
                                    f"got {self.disturbances!r}")
        object.__setattr__(self, "disturbances", tuple(self.disturbances))


_G = GRAVITY_MPS2
#: Defaults from the MPU-9250 datasheet and the thesis' Table 4.1 (see module notes).
MPU9250_DATASHEET = ImuNoise(
    gyro=AxisNoise(white=0.01 * _DEG, rate_random_walk=2.3e-4 * _DEG,
                   bias_instability=5e-4 * _DEG, turn_on_bias=0.3 * _DEG,
                   scale_error=0.01, cross_axis=0.005, full_scale=2000 * _DEG,
                   lsb=2000 * _DEG / 32768),
    accel=AxisNoise(white=300e-6 * _G, rate_random_walk=4.6e-6 * _G,
                    bias_instability=1e-5 * _G, turn_on_bias=0.01 * _G,
                    scale_error=0.01, cross_axis=0.005, full_scale=16 * _G,
                    lsb=16 * _G / 32768),
    mag=MagNoise(),
    label="mpu9250-datasheet",
)

#: The held-out configuration for evaluation: other (worse) noise figures,
#: larger calibration residuals, a bias that changes between recordings
#: (run-to-run repeatability 0.1 deg/s and 5 mg: the datasheet gives no
#: figure, these are assumptions) and a magnet near the hand from 14 to 19 s.
#: Chosen here: figures other than the tuning configuration's, on which the
#: filters' options were chosen (docs/imu.md, "Figures": "Two simulator
#: configurations").
#: Sensor misalignment and skin motion are set in the simulation call.
EVAL_NOISE = ImuNoise(
    gyro=AxisNoise(white=0.015 * _DEG, rate_random_walk=6e-4 * _DEG,
                   bias_instability=2e-3 * _DEG, bias_corr_s=40.0, turn_on_bias=0.5 * _DEG,
                   bias_repeatability=0.1 * _DEG,
                   scale_error=0.02, cross_axis=0.01, full_scale=2000 * _DEG,
                   lsb=2000 * _DEG / 32768),
    accel=AxisNoise(white=400e-6 * _G, rate_random_walk=9e-6 * _G,
                    bias_instability=3e-5 * _G, bias_corr_s=40.0, turn_on_bias=0.02 * _G,
                    bias_repeatability=0.005 * _G,
                    scale_error=0.02, cross_axis=0.01, full_scale=16 * _G,
                    lsb=16 * _G / 32768),
    mag=MagNoise(white_ut=0.5, hard_iron_ut=2.0, soft_iron=0.04, azimuth_sd_deg=6.0,
                 hard_iron_repeatability_ut=0.5),
    disturbances=(MagDisturbance(14.0, 19.0, (12.0, -8.0, 6.0)),),
    label="eval-heldout",
)


def draw_fixed_errors(noise: AxisNoise, n_sensors: int, rng: np.random.Generator
                      ) -> tuple[np.ndarray, np.ndarray]:
    """Scale/cross-axis matrices and turn-on biases of `n_sensors` physical sensors.

    Parameters
    ----------
    noise : AxisNoise
        Its ``scale_error`` and ``cross_axis`` (s.d., fractions) and
        ``turn_on_bias`` (s.d., rad/s for a gyro, m/s^2 for an accelerometer)
        are used.
    n_sensors : int
        S, the number of sensors.
    rng : numpy.random.Generator
        Draws the matrices first, then the biases.

    Returns
    -------
    matrix : ndarray, shape (S, 3, 3), float64
        ``M`` of ``y = M x + ...``, dimensionless.
    bias : ndarray, shape (S, 3), float64
        Turn-on bias, the units of `noise`.
    """
    return _draw_matrix(noise, n_sensors, rng), rng.normal(0.0, noise.turn_on_bias, (n_sensors, 3))


def _draw_matrix(noise: AxisNoise, n_sensors: int, rng: np.random.Generator) -> np.ndarray:
    m = np.eye(3) + rng.normal(0.0, noise.cross_axis, (n_sensors, 3, 3)) * (1 - np.eye(3))
    return m + np.eye(3) * rng.normal(0.0, noise.scale_error, (n_sensors, 1, 3))


def apply_axis_noise(x: np.ndarray, noise: AxisNoise, rate_hz: float,
                     rng: np.random.Generator, *, fixed: tuple | None = None) -> np.ndarray:
    """Add the terms of `noise` to ideal 3-axis signals.

    Parameters
    ----------
    x : ndarray, shape (S, N, 3)
        Ideal signals of S sensors, SI units.
    noise : AxisNoise
    rate_hz : float
    rng : numpy.random.Generator
        Draws the terms of this recording.
    fixed : (matrix, bias), keyword-only
        The sensors' own scale/cross-axis matrices (S, 3, 3) and turn-on
        biases (S, 3) from :func:`draw_fixed_errors` (the same physical
        sensors in another recording); None draws them from `rng`.  Either
        way each recording adds a bias change of s.d. ``bias_repeatability``.

    Returns
    -------
    ndarray, shape (S, N, 3)
        Noisy, saturated and quantised signals.
    """
    s, _, _ = x.shape
    dt = 1.0 / rate_hz
    if fixed is None:
        m = _draw_matrix(noise, s, rng)
    else:
        m = np.asarray(fixed[0], float)
        if m.shape != (s, 3, 3) or np.shape(fixed[1]) != (s, 3):
            raise InvalidInputError(f"fixed errors must have shapes ({s}, 3, 3) and ({s}, 3), "
                                    f"got {m.shape} and {np.shape(fixed[1])}")
    y = np.einsum("sij,snj->sni", m, x)
    # white noise: density N -> per-sample s.d. N / sqrt(dt)
    y += rng.normal(0.0, noise.white / np.sqrt(dt), y.shape)
    # rate random walk: bias increments of s.d. K sqrt(dt)
    y += np.cumsum(rng.normal(0.0, noise.rate_random_walk * np.sqrt(dt), y.shape), axis=1)
    if noise.bias_instability > 0:
        # Gauss-Markov: peak Allan deviation 0.618 sigma at tau ~ 1.89 T_c,
        # matched to the flicker plateau 0.664 B (IEEE Std 952-1997, annex C)
        sigma = 0.664 * noise.bias_instability / 0.618
        phi = np.exp(-dt / noise.bias_corr_s)
        e = rng.normal(0.0, sigma * np.sqrt(1 - phi**2), y.shape)
        from scipy.signal import lfilter

        e[:, 0] = rng.normal(0.0, sigma, (s, 3))
        y += lfilter([1.0], [1.0, -phi], e, axis=1)
    if fixed is None:
        y += rng.normal(0.0, noise.turn_on_bias, (s, 1, 3))
    else:
        y += np.asarray(fixed[1], float)[:, None, :]
    if noise.bias_repeatability > 0:
        y += rng.normal(0.0, noise.bias_repeatability, (s, 1, 3))
    if noise.bias_drift_rate > 0:
        t_s = np.arange(y.shape[1]) * dt
        y += rng.normal(0.0, noise.bias_drift_rate, (s, 1, 3)) * t_s[None, :, None]
    y = np.clip(y, -noise.full_scale, noise.full_scale)
    if noise.lsb > 0:
        y = np.round(y / noise.lsb) * noise.lsb
    return y
