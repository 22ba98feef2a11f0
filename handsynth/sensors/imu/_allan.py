"""Allan variance of static recordings and the thesis' Kalman denoising.

Allan variance (seed 003 eqs. 4.1-4.3, the overlapping estimator of IEEE Std
952-1997): for averaging time tau = m dt,

    sigma^2(tau) = 1 / (2 (N - 2m)) sum_k (wbar_{k+m}(tau) - wbar_k(tau))^2,

computed from the integrated signal theta (N + 1 values, theta_0 = 0) so
that wbar_k = (theta_{k+m} - theta_k) / tau; the sum has N + 1 - 2m terms
and is divided by that count (eq. 4.3 counts N - 2m for N phase values).
Noise coefficients: eq. 4.4, sigma^2 = Q^2/tau + K^2 tau / 3,
extended by the flat bias-instability term (2 ln 2 / pi) B^2, fitted with
non-negative least squares in relative error.  Q is the angle (velocity)
random walk, K the rate random walk.

Denoising (seed 003 section 4.2.3, after Xue et al., Micromachines 6:266,
2015): state X = [w, b] with w' = n_w, b' = w_b, observation z = w + b + n
(eqs. 4.9-4.12, Phi = 0, H = [1, 1]); process noise W = diag(q_w, K^2),
observation noise Q^2 / dt; the discretisation of eq. 4.13 (Van Loan) with
Phi = 0 is F = I, W_d = W dt; the Kalman recursion (eqs. 4.6-4.8) run to
steady state gives K_inf; the continuous filter X' = K (z - H X), K =
K_inf / dt, is discretised exactly (eqs. 4.15-4.17) and its first state is
the denoised signal.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.linalg import expm
from scipy.optimize import nnls

from ..._checks import check_number
from ...errors import InvalidInputError

__all__ = [
    "KalmanDenoiser",
    "NoiseCoefficients",
    "allan_deviation",
    "log_taus",
    "noise_coefficients",
]


def _check_rate(rate_hz) -> float:
    return check_number(rate_hz, "rate_hz", above=0)


def log_taus(n: int, rate_hz: float, *, per_decade: int = 8) -> np.ndarray:
    """Log-spaced averaging times from one sample to N/4 samples, seconds."""
    rate_hz = _check_rate(rate_hz)
    m_max = max(1, n // 4)
    m = np.unique(np.round(np.logspace(0, np.log10(m_max), int(per_decade * np.log10(m_max)) + 2)))
    return m.astype(int) / rate_hz


def allan_deviation(x, rate_hz: float, taus=None) -> tuple[np.ndarray, np.ndarray]:
    """Overlapping Allan deviation of rate samples (eqs. 4.1-4.3).

    Parameters
    ----------
    x : array_like, shape (N,) or (N, C)
        Rate samples (e.g. rad/s), C channels.
    rate_hz : float
    taus : array_like of float, optional
        Averaging times, s, finite and > 0, each rounded to a whole number m
        of samples with 1 <= m < N/2 (times that round to the same m give
        one value); log-spaced by default.

    Returns
    -------
    taus : ndarray, shape (T,)
    adev : ndarray, shape (T,) or (T, C)
        Same units as `x`.

    Raises
    ------
    InvalidInputError
        `x` not (N,) or (N, C) finite numbers with N >= 4, `rate_hz` not a
        finite number > 0, a tau that is not finite, not > 0, shorter than
        half a sample or not under N/2 samples.
    """
    x = np.asarray(x, dtype=float)
    if x.ndim not in (1, 2) or x.shape[0] < 4:
        raise InvalidInputError(f"x must have shape (N,) or (N, C) with N >= 4, got {x.shape}")
    if not np.all(np.isfinite(x)):
        raise InvalidInputError("x contains NaN or infinite values")
    rate_hz = _check_rate(rate_hz)
    n = x.shape[0]
    dt = 1.0 / rate_hz
    if taus is None:
        taus = log_taus(n, rate_hz)
    else:
        try:
            taus = np.asarray(taus, dtype=float).ravel()
        except (TypeError, ValueError):
            raise InvalidInputError(f"taus must be numbers (seconds), got {taus!r}") from None
        if taus.size == 0:
            raise InvalidInputError("taus is empty")
        bad = taus[~(np.isfinite(taus) & (taus > 0))]
        if bad.size:
            raise InvalidInputError(f"taus must be finite and > 0 s, got {bad[0]!r} "
                                    f"({bad.size} such)")
    m_all = np.round(taus * rate_hz)
    out_of_range = taus[(m_all < 1) | (m_all >= n / 2)]
    if out_of_range.size:
        raise InvalidInputError(
            f"taus must lie between one sample and half the recording "
            f"({1 / rate_hz:.4g}-{(np.ceil(n / 2) - 1) / rate_hz:.4g} s for {n} samples at "
            f"{rate_hz:g} Hz), got {out_of_range[0]:.4g} s ({out_of_range.size} such)")
    m = np.unique(m_all.astype(int))
    theta = np.concatenate([np.zeros((1,) + x.shape[1:]), np.cumsum(x, axis=0) * dt])
    out = np.empty((m.size,) + x.shape[1:])
    for i, mi in enumerate(m):
        tau = mi * dt
        d = theta[2 * mi:] - 2 * theta[mi:-mi] + theta[: -2 * mi]
        out[i] = np.sqrt(np.sum(d**2, axis=0) / (2.0 * tau**2 * d.shape[0]))
    return m * dt, out


@dataclass(frozen=True)
class NoiseCoefficients:
    """Allan noise coefficients of one channel.

    Attributes
    ----------
    random_walk : float
        Q: angle random walk (gyro) or velocity random walk (accelerometer),
        units/sqrt(Hz) = sigma(tau = 1 s) on the -1/2 slope.
    rate_random_walk : float
        K: units/sqrt(s), sigma(tau = 3 s) on the +1/2 slope.
    bias_instability : float
        B: units (the flat part is 0.664 B).
    """

    random_walk: float
    rate_random_walk: float
    bias_instability: float


def noise_coefficients(taus, adev) -> NoiseCoefficients:
    """Fit Q, B and K of eq. 4.4 (plus the flat term) to an Allan deviation.

    Parameters
    ----------
    taus : array_like, shape (T,)
    adev : array_like, shape (T,)

    Returns
    -------
    NoiseCoefficients

    Raises
    ------
    InvalidInputError
        `taus` and `adev` not 1-D numbers of equal length >= 3, or a value
        of either that is not finite and > 0.
    """
    try:
        taus = np.asarray(taus, dtype=float)
        adev = np.asarray(adev, dtype=float)
    except (TypeError, ValueError):
        raise InvalidInputError("taus and adev must be arrays of numbers") from None
    if adev.shape != taus.shape or taus.ndim != 1 or taus.size < 3:
        raise InvalidInputError(f"taus and adev must be 1-D of equal length >= 3, got "
                                f"{taus.shape} and {adev.shape}")
    for name, v in (("taus", taus), ("adev", adev)):
        bad = np.flatnonzero(~(np.isfinite(v) & (v > 0)))
        if bad.size:
            raise InvalidInputError(f"{name} must be finite and > 0, got {v[bad[0]]!r} at index "
                                    f"{bad[0]} ({bad.size} such)")
    var = adev**2
    a = np.column_stack([1.0 / taus, np.full_like(taus, 2 * np.log(2) / np.pi), taus / 3.0])
    coef, _ = nnls(a / var[:, None], np.ones_like(var))
    q2, b2, k2 = coef
    return NoiseCoefficients(float(np.sqrt(q2)), float(np.sqrt(k2)), float(np.sqrt(b2)))


@dataclass(frozen=True)
class KalmanDenoiser:
    """The thesis' Kalman denoising of gyro or accelerometer output (eqs. 4.9-4.17).

    Parameters
    ----------
    random_walk : float
        Q from the Allan fit (units/sqrt(Hz)).
    rate_random_walk : float
        K from the Allan fit (units/sqrt(s)).
    q_signal : float
        q_w (gyro) or q_a (accelerometer), the variance rate of the signal's
        own random walk (units^2/s): large values follow motion closely.
        The thesis chose 0.5 for its gyros and 1e4 for its accelerometers
        by comparison with motion capture (section 4.2.4); their units are not
        stated, so the default here is 0.5 (rad/s)^2/s.
    rate_hz : float
        Sampling rate, Hz; default 100 Hz, the thesis' IMU rate (SPEC.md
        section 3, "20 MPU-9250 IMUs ..., 100 Hz").
    """

    random_walk: float
    rate_random_walk: float
    q_signal: float = 0.5
    rate_hz: float = 100.0

    def __post_init__(self) -> None:
        for k in ("random_walk", "rate_random_walk", "q_signal", "rate_hz"):
            check_number(getattr(self, k), f"KalmanDenoiser.{k}", above=0)

    def steady_state_gain(self) -> np.ndarray:
        """K_inf of the static filter, shape (2,) (eqs. 4.11-4.14, 4.6-4.8)."""
        dt = 1.0 / self.rate_hz
        wd = np.diag([self.q_signal, self.rate_random_walk**2]) * dt      # eq. 4.13, Phi = 0
        vd = self.random_walk**2 / dt
        h = np.array([[1.0, 1.0]])
        p = np.eye(2) * vd
        k = np.zeros((2, 1))
        for _ in range(100000):
            pm = p + wd                                                    # eq. 4.6
            k_new = pm @ h.T / (h @ pm @ h.T + vd)                         # eq. 4.7
            p = (np.eye(2) - k_new @ h) @ pm                               # eq. 4.8
            if np.allclose(k_new, k, rtol=1e-10, atol=1e-14):
                break
            k = k_new
        return k_new[:, 0]

    def transition(self) -> tuple[np.ndarray, np.ndarray]:
        """(A, B) with X_{i+1} = A X_i + B z_{i+1} (eqs. 4.15-4.17)."""
        dt = 1.0 / self.rate_hz
        kc = self.steady_state_gain()[:, None] / dt
        m = kc @ np.array([[1.0, 1.0]])
        # exact: A = exp(-m dt), B = int_0^dt exp(-m s) ds K (augmented exponential)
        aug = np.zeros((4, 4))
        aug[:2, :2] = -m
        aug[:2, 2:] = np.eye(2)
        e = expm(aug * dt)
        return e[:2, :2], e[:2, 2:] @ kc[:, 0]

    def apply(self, z) -> np.ndarray:
        """Denoise samples along axis 0, shape (N, ...) -> same shape.

        The state starts at X_0 = [z_0, 0] (signal at the first sample, no bias).

        Raises
        ------
        InvalidInputError
            No samples, or values that are not finite numbers.
        """
        try:
            z = np.asarray(z, dtype=float)
        except (TypeError, ValueError):
            raise InvalidInputError(f"z must be an array of numbers, got {type(z).__name__}") from None
        if z.ndim == 0 or z.shape[0] == 0:
            raise InvalidInputError(f"z needs at least one sample along axis 0, got shape {z.shape}")
        if not np.all(np.isfinite(z)):
            raise InvalidInputError("z contains NaN or infinite values")
        a, b = self.transition()
        x0 = z[0].copy()
        x1 = np.zeros_like(x0)
        out = np.empty_like(z)
        out[0] = x0
        for i in range(1, z.shape[0]):
            x0, x1 = a[0, 0] * x0 + a[0, 1] * x1 + b[0] * z[i], a[1, 0] * x0 + a[1, 1] * x1 + b[1] * z[i]
            out[i] = x0
        return out
