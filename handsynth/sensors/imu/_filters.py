"""Orientation estimators sharing one interface, and the external baselines.

Every estimator is an :class:`OrientationEstimator`: ``run(rec)`` returns the
sensor-to-world quaternions (w, x, y, z) of every sensor, shape (S, N, 4),
world frame z up, x magnetic north.  All start from the same preprocessing:
gyro bias from the static start (seed 003 section 4.2.4) and, for the
estimators of the thesis, the initial attitude of eqs. 2.9-2.11 with the
azimuth alignment of eqs. 4.18-4.22.

- :class:`RawIntegration`: gyro integration only (quaternion update, eq. 5.10).
- :class:`Filter1`: Kalman filter whose observation is the attitude from
  accelerometer and compass at every sample (seed 003 Table 4.3, "Filter 1").
- :class:`VQFEstimator`: VQF (Laidig & Seel, Information Fusion 91:187-204,
  2023), the ``vqf`` package, 9D.
- :class:`MadgwickEstimator`, :class:`MahonyEstimator`, :class:`AhrsEKFEstimator`:
  the ``ahrs`` package's filters (MARG versions).
- :class:`ConstantEstimator`: the initial attitude held for ever, the trivial
  baseline every figure stands beside.

The multi-sensor EKF of the thesis ("Filter 4") is in :mod:`._ekf`.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Protocol, runtime_checkable

import numpy as np

from ..._checks import check_number
from ...errors import EstimationError, InvalidInputError
from ._attitude import StaticStart, check_run_input, gyro_bias, initial_attitude
from ._quat import heading_rad, qexp, qmul, qnormalize, quat_from_acc_mag
from ._quat_numba import _chain
from ._recording import ImuRecording

__all__ = [
    "AhrsEKFEstimator",
    "ConstantEstimator",
    "Filter1",
    "Filter1Options",
    "MadgwickEstimator",
    "MahonyEstimator",
    "OrientationEstimator",
    "RawIntegration",
    "VQFEstimator",
    "integrate_gyro",
]

# q_world<-enu: the ENU frame (x east, y north) turned -90 deg about z into
# ours (x north, y west)
_Q_NWU_FROM_ENU = np.array([np.cos(-np.pi / 4), 0.0, 0.0, np.sin(-np.pi / 4)])


@runtime_checkable
class OrientationEstimator(Protocol):
    """What every orientation estimator provides."""

    name: str

    def run(self, rec: ImuRecording) -> np.ndarray:
        """Sensor-to-world quaternions, shape (S, N, 4), float64."""
        ...


def integrate_gyro(q0: np.ndarray, gyr: np.ndarray, rate_hz: float) -> np.ndarray:
    """Integrate body-frame angular velocity from `q0` (eq. 5.10).

    Eq. 5.10 is the first-order form of q_i = q_{i-1} * exp(w dt / 2); the
    exact exponential is used (it equals eq. 5.10 to O(dt^2) and keeps
    |q| = 1).

    Parameters
    ----------
    q0 : ndarray, shape (S, 4)
    gyr : ndarray, shape (S, N, 3), rad/s
    rate_hz : float

    Returns
    -------
    ndarray, shape (S, N, 4)
        q[:, 0] = q0; q[:, i] uses gyr[:, i] (mean of samples i-1 and i).

    Raises
    ------
    InvalidInputError
        `rate_hz` not a finite number > 0; `gyr` not (S, N, 3) or `q0` not
        (S, 4) unit quaternions; non-finite values.
    """
    dt = 1.0 / _check_rate(rate_hz)
    gyr = _float_array(gyr, "gyr")
    if gyr.ndim != 3 or gyr.shape[2] != 3:
        raise InvalidInputError(f"gyr must have shape (S, N, 3), got {gyr.shape}")
    s = gyr.shape[0]
    q0 = _float_array(q0, "q0")
    if q0.shape != (s, 4):
        raise InvalidInputError(f"q0 must have shape (S, 4) with S = {s} (gyr's), got {q0.shape}")
    if not (np.all(np.isfinite(gyr)) and np.all(np.isfinite(q0))):
        raise InvalidInputError("gyr and q0 must be finite (NaN or infinite values given)")
    norm = np.linalg.norm(q0, axis=-1)
    if np.any(np.abs(norm - 1.0) > 0.01):
        raise InvalidInputError(f"q0 must be unit quaternions, got norms {norm.min():.4g} "
                                f"to {norm.max():.4g}")
    w = np.empty_like(gyr)
    w[:, 0] = 0.0
    w[:, 1:] = 0.5 * (gyr[:, 1:] + gyr[:, :-1])
    dq = qexp(w * dt)
    return qnormalize(_chain(q0 / norm[:, None], dq))


def _chain_reference(q0: np.ndarray, dq: np.ndarray) -> np.ndarray:
    """Plain version of the compiled ``_chain``: q[:, i] = q[:, i-1] * dq[:, i]."""
    out = np.empty(dq.shape)
    q = q0
    for i in range(dq.shape[1]):
        if i:
            q = qmul(q, dq[:, i])
        out[:, i] = q
    return out


@dataclass(frozen=True)
class ConstantEstimator:
    """The initial attitude (eqs. 2.9-2.11, 4.22) held constant: the trivial baseline."""

    static: StaticStart = field(default_factory=StaticStart)
    name: str = "constant"

    def run(self, rec: ImuRecording) -> np.ndarray:
        check_run_input(rec, self.static)
        q0 = initial_attitude(rec, self.static)
        return np.repeat(q0[:, None], rec.n, axis=1)


@dataclass(frozen=True)
class RawIntegration:
    """Gyro integration from the initial attitude, static bias removed ("Raw")."""

    static: StaticStart = field(default_factory=StaticStart)
    name: str = "raw"

    def run(self, rec: ImuRecording) -> np.ndarray:
        check_run_input(rec, self.static)
        q0 = initial_attitude(rec, self.static)
        return integrate_gyro(q0, rec.gyr - gyro_bias(rec, self.static)[:, None], rec.rate_hz)


@dataclass(frozen=True)
class Filter1Options:
    """Options of :class:`Filter1` (frozen: a typo raises).

    Parameters
    ----------
    gyro_noise : float
        Angular-rate noise of the process model, rad/s per sample.
    obs_noise : float
        s.d. of the accelerometer/compass attitude observation (quaternion
        units, about half the angle in rad).
    """

    gyro_noise: float = 0.01
    obs_noise: float = 0.05

    def __post_init__(self) -> None:
        for name in ("gyro_noise", "obs_noise"):
            _check_positive(f"Filter1Options.{name}", getattr(self, name))


@dataclass(frozen=True)
class Filter1:
    """Kalman filter with the accelerometer+compass attitude as observation.

    State: the quaternion (the thesis used Euler angles; its chapter 5 gives
    the quaternion form, eqs. 5.8-5.11).  Prediction: eq. 5.10 with the
    gyro.  Observation: the attitude of eqs. 2.9-2.11 (+ psi_cor of
    eq. 4.22) from the current accelerometer and magnetometer, H = I
    (seed 003 Table 4.3, Filter 1).  Kalman update eqs. 4.6-4.8, then
    normalisation.
    """

    options: Filter1Options = field(default_factory=Filter1Options)
    static: StaticStart = field(default_factory=StaticStart)
    name: str = "filter1"

    def run(self, rec: ImuRecording) -> np.ndarray:
        from ._attitude import azimuth_correction

        check_run_input(rec, self.static)
        if rec.mag is None:
            raise EstimationError(
                "filter1 observes each sensor's compass attitude, and a recording of 6-axis "
                "sensors has no magnetometer: use filter4, gated, raw or vqf")
        o = self.options
        s, n = len(rec.sensors), rec.n
        dt = 1.0 / rec.rate_hz
        cor = azimuth_correction(rec, self.static)
        q = initial_attitude(rec, self.static)
        gyr = rec.gyr - gyro_bias(rec, self.static)[:, None]
        z_all = quat_from_acc_mag(rec.acc, rec.mag, heading_offset_rad=cor[:, None])
        p = np.repeat(np.eye(4)[None] * 1e-4, s, axis=0)
        r = o.obs_noise**2 * np.eye(4)
        out = np.empty((s, n, 4))
        out[:, 0] = q
        for i in range(1, n):
            w = 0.5 * (gyr[:, i] + gyr[:, i - 1])
            f = _omega_matrix(w * dt)                              # eq. 5.10
            q = np.einsum("sij,sj->si", f, q)
            xi = _xi(q) * (0.5 * dt)
            qn = (o.gyro_noise**2) * np.einsum("sik,sjk->sij", xi, xi) / dt * dt
            p = f @ p @ f.transpose(0, 2, 1) + qn + 1e-10 * np.eye(4)      # eq. 4.6
            z = z_all[:, i]
            z = z * np.sign(np.sum(z * q, axis=-1, keepdims=True) + 1e-12)
            k = p @ np.linalg.inv(p + r)                           # eq. 4.7, H = I
            q = q + np.einsum("sij,sj->si", k, z - q)              # eq. 4.8
            p = (np.eye(4) - k) @ p
            q = qnormalize(q)
            out[:, i] = q
        return out


def _omega_matrix(rv):
    """I + Omega(w dt)/2 of eq. 5.10, shape (S, 4, 4)."""
    x, y, z = (0.5 * rv[:, k] for k in range(3))
    one = np.ones_like(x)
    return np.stack([
        np.stack([one, -x, -y, -z], -1), np.stack([x, one, z, -y], -1),
        np.stack([y, -z, one, x], -1), np.stack([z, y, -x, one], -1)], -2)


def _xi(q):
    """dq/dw (4 x 3) of q * [0, w] for body rates."""
    w, x, y, z = (q[:, k] for k in range(4))
    return np.stack([np.stack([-x, -y, -z], -1), np.stack([w, -z, y], -1),
                     np.stack([z, w, -x], -1), np.stack([-y, x, w], -1)], -2)


def _prepared(rec: ImuRecording, static: StaticStart):
    return rec.gyr - gyro_bias(rec, static)[:, None]


@dataclass(frozen=True)
class VQFEstimator:
    """VQF, 9D (magnetometer on), default parameters of the ``vqf`` package.

    6D (no magnetometer) for a recording of 6-axis sensors: each sensor's
    heading then drifts on its own, from the heading the common rotation gives
    it (:func:`initial_attitude`), which its 6D output is turned to at the
    first sample.

    By default the package's offline variant (``offlineVQF``): it is acausal,
    estimating the gyro bias from the whole recording, past and future, so
    it cannot run live.  ``online=True`` runs the causal filter (``VQF``'s
    ``updateBatch``), the one a live system can use: the fair baseline for
    the causal filters here (Filter 4, gated, Madgwick).
    """

    static: StaticStart = field(default_factory=StaticStart)
    name: str = "vqf"
    online: bool = False

    def __post_init__(self) -> None:
        if not isinstance(self.online, (bool, np.bool_)):
            raise InvalidInputError(f"VQFEstimator.online must be True or False, got "
                                    f"{self.online!r}")

    def run(self, rec: ImuRecording) -> np.ndarray:
        from vqf import VQF, offlineVQF

        check_run_input(rec, self.static)
        gyr = _prepared(rec, self.static)
        out = np.empty((len(rec.sensors), rec.n, 4))
        ts = 1.0 / rec.rate_hz
        mag = rec.mag
        q0 = initial_attitude(rec, self.static) if mag is None else None
        for k in range(len(rec.sensors)):
            args = (np.ascontiguousarray(gyr[k]), np.ascontiguousarray(rec.acc[k]),
                    None if mag is None else np.ascontiguousarray(mag[k]))
            res = VQF(ts).updateBatch(*args) if self.online else offlineVQF(*args, ts)
            out[k] = qmul(_Q_NWU_FROM_ENU, res["quat9D" if q0 is None else "quat6D"])
            if q0 is not None:  # 6D: its own heading turned to the common rotation's at the start
                turn = heading_rad(q0[k], out[k, 0])
                out[k] = qmul(qexp(np.array([0.0, 0.0, turn])), out[k])
        return out


@dataclass(frozen=True)
class _AhrsBase:
    static: StaticStart = field(default_factory=StaticStart)
    name: str = "ahrs"

    def _filter(self, gyr, acc, mag, rate, q0):  # pragma: no cover - overridden
        raise NotImplementedError

    def run(self, rec: ImuRecording) -> np.ndarray:
        check_run_input(rec, self.static)
        if rec.mag is None:
            raise EstimationError(
                f"{self.name} is run here as a 9-axis baseline, and a recording of 6-axis "
                "sensors has no magnetometer: use filter4, gated, raw or vqf")
        gyr = _prepared(rec, self.static)
        q0 = initial_attitude(rec, self.static, align=False)
        out = np.empty((len(rec.sensors), rec.n, 4))
        for k in range(len(rec.sensors)):
            q = self._filter(gyr[k], rec.acc[k], rec.mag[k], rec.rate_hz, q0[k])
            if not np.all(np.isfinite(q)):
                raise EstimationError(f"{self.name} diverged on sensor {rec.sensors[k]!r}")
            out[k] = qnormalize(q)
        return out


@dataclass(frozen=True)
class MadgwickEstimator(_AhrsBase):
    """Madgwick's MARG filter (``ahrs.filters.Madgwick``, gain 0.041 default)."""

    gain: float = 0.041
    name: str = "madgwick"

    def __post_init__(self) -> None:
        _check_positive("MadgwickEstimator.gain", self.gain)

    def _filter(self, gyr, acc, mag, rate, q0):
        from ahrs.filters import Madgwick

        return Madgwick(gyr=gyr, acc=acc, mag=mag, frequency=rate, gain=self.gain, q0=q0).Q


@dataclass(frozen=True)
class MahonyEstimator(_AhrsBase):
    """Mahony's complementary filter (``ahrs.filters.Mahony``, defaults)."""

    name: str = "mahony"

    def _filter(self, gyr, acc, mag, rate, q0):
        from ahrs.filters import Mahony

        q0_enu = qmul(np.array([_Q_NWU_FROM_ENU[0], 0, 0, -_Q_NWU_FROM_ENU[3]]), q0)
        q = Mahony(gyr=gyr, acc=acc, mag=mag, frequency=rate, q0=q0_enu).Q
        return qmul(_Q_NWU_FROM_ENU, q)


@dataclass(frozen=True)
class AhrsEKFEstimator(_AhrsBase):
    """The ``ahrs`` package's quaternion EKF (default noises).

    Run in its NED frame, which expects the accelerometer as the gravity
    direction (minus the specific force) and the local dip angle; its output
    is turned into our frame by 180 deg about x.  (Its ENU mode drifted by
    tens of degrees on static noisy data in our checks.)
    """

    name: str = "ahrs_ekf"

    def _filter(self, gyr, acc, mag, rate, q0):
        from ahrs.filters import EKF

        from ._quat import qrot

        n0 = max(1, int(self.static.static_s * rate))
        m_world = qrot(q0, mag[:n0].mean(axis=0))
        dip = float(np.degrees(np.arctan2(-m_world[2], np.hypot(m_world[0], m_world[1]))))
        q0_ned = qmul(_Q_X180, q0)
        q = EKF(gyr=gyr, acc=-acc, mag=mag, frequency=rate, frame="NED", magnetic_ref=dip,
                q0=q0_ned).Q
        return qmul(_Q_X180, q)


_Q_X180 = np.array([0.0, 1.0, 0.0, 0.0])


def _check_rate(rate_hz) -> float:
    """`rate_hz` as a float; InvalidInputError naming it unless a finite number > 0."""
    _check_positive("rate_hz", rate_hz)
    return float(rate_hz)


def _check_positive(name: str, value) -> None:
    """Refuse `value` unless it is a finite real number > 0 (not a bool), naming `name`."""
    check_number(value, name, above=0)


def _float_array(value, name: str) -> np.ndarray:
    """`value` as a float64 array in C order; InvalidInputError naming `name` if not numbers."""
    try:
        return np.ascontiguousarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise InvalidInputError(f"{name} must be an array of numbers, got "
                                f"{type(value).__name__}") from None
