"""One IMU's orientation with gated corrections (beyond the thesis, after its Filter 4).

The thesis' Filter 1 trusts each sample's accelerometer and compass (seed
003 Table 4.3), so every linear acceleration tilts it and every magnetic
disturbance turns it; its Filter 4 avoids that with the link model, which a
single sensor does not have.  This filter keeps the thesis' idea of
observations that are trusted only under conditions, and applies it to one
sensor.  The orientation is the product of two parts: the gyro's strapdown
integration ``q_gyr`` (sensor to a frame that turns only with the gyro's
errors) and a slowly varying correction ``q_cor`` (that frame to the world):

1. **Prediction**: the gyro, less the bias estimate, integrated as a
   rotation vector (eq. 5.10) into ``q_gyr``.
2. **Inclination**: the accelerometer, turned by ``q_gyr``, is low-passed
   by two first-order stages in series, each with time constant
   ``acc_lowpass_s`` (a critically damped second-order low-pass).  In that
   frame a linear acceleration is the second derivative of a position that
   stays bounded while gravity stays put, so the low-passed vector is gravity
   even while the sensor moves.  One stage would leave an error in
   proportion to the velocity (the first integral of the acceleration); two
   leave one in proportion to the displacement.  Turned by ``q_cor`` into the
   world, the vector is pulled toward the vertical by a first-order
   correction of ``q_cor`` with time constant ``acc_tau_s`` -- only while its
   length is within ``acc_tol_mps2`` of gravity and the angular speed below
   ``rate_gate_dps`` (the thesis' switch, seed 003 section 4.3.2, at 400
   deg/s for its per-sample observation; after the low-pass a centripetal
   acceleration averages out as well, so by default the gate stands only at
   the gyro's full scale).
3. **Heading**: the compass's horizontal direction in the world is pulled
   toward the one seen over the static start (its mean, as for the initial
   attitude) with time constant ``mag_tau_s`` -- only while the field's
   strength is within ``mag_tol`` (relative) and its dip within
   ``dip_tol_deg`` of the start's (a magnet or steel nearby changes both; the
   thesis suspends its H3 on the strength alone).
   **A field fixed to the sensor** (a magnet or steel on the strap, a
   phone's speaker): it adds a constant ``h`` in the sensor's frame, so the
   field in the world turns with the sensor and the gates above close for as
   long as it stays.  While they are closed and the sensor turns (faster
   than ``iron_rate_dps``), ``h`` is learnt by gradient steps (time constant
   ``iron_tau_s``) that keep the corrected field ``m - h`` at the start's
   strength and its vertical part at the start's; the corrected field then
   passes through the same gates, but only once the turns have spread the
   two constraints' directions over all three axes (the smallest eigenvalue
   of their mean outer product, decayed over ``iron_span_s``, above
   ``iron_span_min``): a sensor turning about one axis leaves ``h``
   undetermined along it and keeps the compass off.  After ``iron_reset_s``
   of a field that passes the gates as read, ``h`` is forgotten.
4. **Gyro bias**: while the sensor rests (angular speed below
   ``rest_dps`` and the accelerometer within ``acc_tol_mps2`` of gravity
   for ``rest_s``), the bias follows the gyro with time constant
   ``bias_tau_s``.

On BROAD (docs/imu.md) the filter erred by 5.37 deg with each sample's
accelerometer trusted through the gates and the reference field read from
the first sample, 2.91 deg with one low-pass stage and the mean reference,
2.37 deg with two stages and this release's time constants, and 2.04 deg
with the field fixed to the sensor learnt as well (vqf 2.15).

:func:`gated_orientation` runs a compiled loop (numba); its plain Python
version (``fast=False``) is the reference the tests compare it with.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numba import njit

from ..._checks import check_options
from ...errors import InvalidInputError
from ._attitude import StaticStart, _n, check_run_input, gyro_bias, initial_attitude
from ._model import GRAVITY_MPS2
from ._quat_numba import _qexp, _qmat, _qmul
from ._recording import ImuRecording

__all__ = ["GatedFilter", "GatedOptions", "gated_orientation"]


@dataclass(frozen=True)
class GatedOptions:
    """Options of :class:`GatedFilter` (frozen: a typo raises).

    Parameters
    ----------
    acc_tau_s, mag_tau_s, bias_tau_s : float
        Time constants of the inclination, heading and gyro-bias corrections, s.
    acc_lowpass_s : float
        Time constant of each of the two stages of the accelerometer's
        low-pass in the gyro's strapdown frame, s.  The defaults were chosen
        on simulated data only (BROAD was run once, after the choice), by
        the rule: within 0.005 deg of the best figure on the
        simulator's tuning configuration (four 15- and 30-s free motions,
        every sensor of the hand, calibrated sensors; best 0.607 deg), the
        best on one free sensor turning fast with its gyro scale
        uncalibrated (``scripts/study_imu_single.py``, eight 150-s
        recordings).  Chosen: 1 / 1 / 30 s for the low-pass stages,
        inclination and heading and no angular-speed gate: 0.612 and 8.36
        deg (one low-pass stage of 3 s, inclination 5 s and the 400-deg/s
        gate, the previous defaults: 0.608 and 10.23; heading 20 s: 0.626
        and 7.21).
    acc_tol_mps2 : float
        Largest difference of the low-passed accelerometer's length from
        gravity at which it is trusted, and of each sample's at which the
        sensor may rest, m/s^2.
    rate_gate_dps : float
        Angular speed above which the accelerometer is not trusted, deg/s
        (seed 003 section 4.3.2, Table 4.3: 400 for the per-sample observation; by
        default 2000, the MPU-9250's full scale: on the hand configuration
        the gate changed nothing, on the free sensor it cost 0.3 deg).
    mag_tol : float
        Largest relative change of the field's strength at which the compass
        is trusted.
    dip_tol_deg : float
        Largest change of the field's dip at which the compass is trusted, deg.
    rest_dps, rest_s : float
        Rest detection for the bias: angular speed below `rest_dps` (deg/s)
        for `rest_s` seconds.
    iron_tau_s : float
        Time constant of the learning of a field fixed to the sensor, s (0:
        not learnt; module docstring).  Chosen on simulated data
        (``scripts/study_imu_single.py --iron``): among the settings that
        make no heading on the hand worse by more than 0.1 deg (a field of 27
        uT fixed to one sensor of the hand from 10 s of a 60-s free motion;
        a finger, the back of the hand and the forearm, two speeds), the best
        mean over the free-sensor recordings and six more with such a field
        for 30-60 s.  0.5 s with ``iron_span_min`` 0.02 came from a first
        pass over four settings: 7.37 deg against 8.27 without learning.  The
        full grid's best by that rule is 0.25 s with 0.01 (7.35 deg), one
        step from a setting that turns the forearm's heading by 4.4 deg; the
        first choice, farther from that edge, was kept.
    iron_rate_dps, iron_reset_s, iron_span_s, iron_span_min : float
        Learning only while turning faster than `iron_rate_dps` (deg/s);
        forgetting after `iron_reset_s` (s) of a clean field; the decay (s)
        and the threshold (< 1/3) of the turns' spread.  Set once, not
        searched except `iron_span_min`.
    """

    acc_tau_s: float = 1.0
    acc_lowpass_s: float = 1.0
    mag_tau_s: float = 30.0
    bias_tau_s: float = 3.0
    acc_tol_mps2: float = 1.0
    rate_gate_dps: float = 2000.0
    mag_tol: float = 0.1
    dip_tol_deg: float = 5.0
    rest_dps: float = 2.0
    rest_s: float = 1.0
    iron_tau_s: float = 0.5
    iron_rate_dps: float = 30.0
    iron_reset_s: float = 2.0
    iron_span_s: float = 10.0
    iron_span_min: float = 0.02

    def __post_init__(self) -> None:
        for name, value in self.__dict__.items():
            if name == "iron_tau_s" and value == 0:
                continue
            if not (isinstance(value, (int, float)) and not isinstance(value, bool)
                    and math.isfinite(value) and value > 0):
                raise InvalidInputError(f"GatedOptions.{name} must be a positive number, "
                                        f"got {value!r}")
        if self.iron_span_min >= 1 / 3:
            raise InvalidInputError(f"GatedOptions.iron_span_min must be < 1/3 (the smallest "
                                    f"eigenvalue of an isotropic spread), got {self.iron_span_min!r}")


@njit(cache=True)
def _field_passes(m_w, f_ref, dip_ref, mag_tol, dip_tol):
    """Whether a world-frame field has the start's strength and dip, within the tolerances."""
    f = math.sqrt(m_w[0] ** 2 + m_w[1] ** 2 + m_w[2] ** 2)
    if not (f > 0 and abs(f / f_ref - 1.0) < mag_tol):
        return False
    return abs(math.atan2(m_w[2], math.hypot(m_w[0], m_w[1])) - dip_ref) < dip_tol


def _kernel(q0, gyr, acc, mag, mag0, b0, dt, g, acc_k, lp_k, mag_k, bias_k, acc_tol, rate_gate,
            mag_tol, dip_tol, rest_rate, rest_n, iron_k, iron_rate, reset_n, info_k,
            info_min):
    """The filter's loop for one sensor: sensor-to-world quaternions (N, 4).

    `mag0` is the mean field over the static start (sensor frame).  Plain
    Python on numpy arrays, compiled as it is by numba (module docstring).
    """
    n = gyr.shape[0]
    out = np.empty((n, 4))
    q_gyr = np.array([1.0, 0.0, 0.0, 0.0])
    q_cor = q0.copy()
    b = b0.copy()
    # the field at the start, in the world: strength, dip, horizontal direction
    m_ref = _qmat(q0) @ mag0
    f_ref = math.sqrt(m_ref[0] ** 2 + m_ref[1] ** 2 + m_ref[2] ** 2)
    dip_ref = math.atan2(m_ref[2], math.hypot(m_ref[0], m_ref[1]))
    psi_ref = math.atan2(m_ref[1], m_ref[0])
    h = np.zeros(3)           # a field fixed to the sensor since the start, uT
    info = np.zeros((3, 3))   # how well the turns so far determine h (decayed)
    calm = 0
    a_lp1 = acc[0].copy()     # first stage of the low-pass
    a_lp = acc[0].copy()      # second stage
    still = 0
    out[0] = q0
    for i in range(1, n):
        w = gyr[i] - b
        q_gyr = _qmul(q_gyr, _qexp(w * dt))                          # eq. 5.10
        q_gyr = q_gyr / math.sqrt(q_gyr[0] ** 2 + q_gyr[1] ** 2 + q_gyr[2] ** 2 + q_gyr[3] ** 2)
        a_lp1 = a_lp1 + lp_k * (_qmat(q_gyr) @ acc[i] - a_lp1)
        a_lp = a_lp + lp_k * (a_lp1 - a_lp)
        speed = math.sqrt(w[0] ** 2 + w[1] ** 2 + w[2] ** 2)
        if speed < rate_gate:
            a_w = _qmat(q_cor) @ a_lp
            a_len = math.sqrt(a_w[0] ** 2 + a_w[1] ** 2 + a_w[2] ** 2)
            if a_len > 0 and abs(a_len - g) < acc_tol:
                a_w = a_w / a_len
                # rotation taking the measured up toward the world's up (0, 0, 1)
                axis = np.array([a_w[1], -a_w[0], 0.0])
                s = math.sqrt(axis[0] ** 2 + axis[1] ** 2)
                if s > 1e-12:
                    angle = math.atan2(s, a_w[2]) * acc_k
                    q_cor = _qmul(_qexp(axis / s * angle), q_cor)
        r_now = _qmat(_qmul(q_cor, q_gyr))
        m_w = r_now @ mag[i]
        ok = _field_passes(m_w, f_ref, dip_ref, mag_tol, dip_tol)
        calm = calm + 1 if ok else 0
        if iron_k > 0:
            if calm >= reset_n:
                h[:] = 0.0
                info[:] = 0.0
            elif not ok:
                m_c = mag[i] - h
                m_w = r_now @ m_c
                f = math.sqrt(m_w[0] ** 2 + m_w[1] ** 2 + m_w[2] ** 2)
                if f > 0:
                    if speed > iron_rate:
                        u = m_c / f
                        v = r_now[2]
                        h = h + iron_k * ((f - f_ref) * u + (m_w[2] - m_ref[2]) * v)
                        info = info + info_k * (0.5 * (np.outer(u, u) + np.outer(v, v)) - info)
                    ok = (_field_passes(m_w, f_ref, dip_ref, mag_tol, dip_tol)
                          and np.linalg.eigvalsh(info)[0] > info_min)
        if ok:
            err = math.atan2(m_w[1], m_w[0]) - psi_ref
            err = (err + math.pi) % (2 * math.pi) - math.pi
            q_cor = _qmul(_qexp(np.array([0.0, 0.0, -err * mag_k])), q_cor)
        q_cor = q_cor / math.sqrt(q_cor[0] ** 2 + q_cor[1] ** 2 + q_cor[2] ** 2 + q_cor[3] ** 2)
        a_raw = math.sqrt(acc[i, 0] ** 2 + acc[i, 1] ** 2 + acc[i, 2] ** 2)
        if abs(a_raw - g) < acc_tol and speed < rest_rate:
            still += 1
        else:
            still = 0
        if still >= rest_n:
            b = b + bias_k * (gyr[i] - b)
        out[i] = _qmul(q_cor, q_gyr)
    return out


#: The compiled loop; ``_kernel`` itself is the plain reference (it calls the
#: compiled helpers, which run from Python as they are).
_kernel_fast = njit(cache=True)(_kernel)


def gated_orientation(rec: ImuRecording, options: GatedOptions | None = None, *,
                      static: StaticStart | None = None, fast: bool = True) -> np.ndarray:
    """Each sensor's orientation by the gated filter (module docstring).

    Parameters
    ----------
    rec : ImuRecording
    options : GatedOptions, optional
    static : StaticStart, keyword-only, optional
        The still stretch at the start (initial attitude and gyro bias).
    fast : bool, keyword-only
        Run the compiled loop; False runs the plain Python reference.

    Returns
    -------
    ndarray, shape (S, N, 4)
        Sensor-to-world quaternions (w, x, y, z).
    """
    o = check_options(options, GatedOptions)
    static = check_options(static, StaticStart, name="static")
    check_run_input(rec, static)
    dt = 1.0 / rec.rate_hz
    q0 = initial_attitude(rec, static)
    b0 = gyro_bias(rec, static)
    mag = rec.mag
    if mag is None:  # 6-axis sensors: a zero field, which the field gate never passes (no
        mag = np.zeros_like(rec.gyr)  # heading correction, no iron learnt)
    mag0 = mag[:, : _n(rec, static.static_s)].mean(axis=1)
    kernel = _kernel_fast if fast else _kernel
    out = np.empty((len(rec.sensors), rec.n, 4))
    for s in range(len(rec.sensors)):
        out[s] = kernel(np.ascontiguousarray(q0[s], np.float64),
                        np.ascontiguousarray(rec.gyr[s], np.float64),
                        np.ascontiguousarray(rec.acc[s], np.float64),
                        np.ascontiguousarray(mag[s], np.float64),
                        np.ascontiguousarray(mag0[s], np.float64),
                        np.ascontiguousarray(b0[s], np.float64), dt, GRAVITY_MPS2,
                        min(dt / o.acc_tau_s, 1.0), min(dt / o.acc_lowpass_s, 1.0),
                        min(dt / o.mag_tau_s, 1.0),
                        min(dt / o.bias_tau_s, 1.0), o.acc_tol_mps2,
                        math.radians(o.rate_gate_dps), o.mag_tol, math.radians(o.dip_tol_deg),
                        math.radians(o.rest_dps), max(1, int(round(o.rest_s * rec.rate_hz))),
                        min(dt / o.iron_tau_s, 1.0) if o.iron_tau_s else 0.0,
                        math.radians(o.iron_rate_dps), max(1, int(round(o.iron_reset_s * rec.rate_hz))),
                        min(dt / o.iron_span_s, 1.0), o.iron_span_min)
    return out


@dataclass(frozen=True)
class GatedFilter:
    """The gated single-IMU filter as an orientation estimator (module docstring)."""

    options: GatedOptions = field(default_factory=GatedOptions)
    static: StaticStart = field(default_factory=StaticStart)
    name: str = "gated"

    def run(self, rec: ImuRecording) -> np.ndarray:
        return gated_orientation(rec, self.options, static=self.static)
