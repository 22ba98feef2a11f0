"""Jitter-free angles over time: the One Euro filter (beyond the paper).

A frame-by-frame estimator answers each frame on its own, so its angles
jitter while the hand is still (a camera's outline flickers by a pixel from
frame to frame) and a fixed low-pass filter that steadies them makes fast
motions lag.  The One Euro filter of Casiez, Roussel & Vogel, "1€ Filter: a
simple speed-based low-pass filter for noisy input in interactive systems",
Proc. CHI 2012, pp. 2527-2530, adapts its cut-off to the speed: for each
angle, with ``dt`` the frame interval,

    alpha(f_c) = 1 / (1 + 1 / (2 pi f_c dt))
    dx_hat_i = alpha(f_d) (x_i - x_hat_{i-1}) / dt + (1 - alpha(f_d)) dx_hat_{i-1}
    f_c = f_min + beta |dx_hat_i|
    x_hat_i = alpha(f_c) x_i + (1 - alpha(f_c)) x_hat_{i-1}

so that a still hand is filtered at ``f_min`` (strongly) and a moving one at
a cut-off that grows with its speed (little lag).

:class:`OneEuroFilter` filters a stream of angle vectors;
:func:`one_euro` is the plain reference over a whole array (tests hold the
two equal); :class:`SmoothedEstimator` wraps any
:class:`~handsynth.estimate.PoseEstimator`.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from .._checks import check_number, check_options, short_repr
from ..errors import InvalidInputError
from ._lookup import PoseEstimate

__all__ = ["OneEuroFilter", "OneEuroOptions", "OneEuroState", "SmoothedEstimator", "one_euro"]


@dataclass(frozen=True)
class OneEuroOptions:
    """Constants of the One Euro filter.

    The defaults were chosen on continuous motions with holds of three
    held-out model hands whose frames had their outline flickering
    (``python scripts/study_camera.py --cache DIR holds``; docs/camera_estimator.md, "Jitter"):
    among minimum cut-offs 0.3-2 Hz and speed coefficients 0.01-0.1 Hz per
    deg/s, the steadiest holds for at most 0.05 deg more flexion error, a
    tie (within 0.01 deg/frame^2: 0.3 and 0.5 Hz at 0.05) going to the higher
    cut-off, which lags less on slow motions.

    Parameters
    ----------
    min_cutoff_hz : float
        Cut-off frequency while the angle is still, Hz (> 0).
    beta : float
        Growth of the cut-off with the angle's speed, Hz per deg/s (>= 0).
    derivative_cutoff_hz : float
        Cut-off of the speed estimate, Hz (> 0).
    """

    min_cutoff_hz: float = 0.5
    beta: float = 0.05
    derivative_cutoff_hz: float = 1.0

    def __post_init__(self) -> None:
        for name in ("min_cutoff_hz", "beta", "derivative_cutoff_hz"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not np.isfinite(v):
                raise InvalidInputError(f"OneEuroOptions.{name} must be a number, got {v!r}")
        if self.min_cutoff_hz <= 0 or self.derivative_cutoff_hz <= 0 or self.beta < 0:
            raise InvalidInputError(
                "OneEuroOptions needs min_cutoff_hz > 0, derivative_cutoff_hz > 0 and beta >= 0, "
                f"got {self.min_cutoff_hz!r}, {self.derivative_cutoff_hz!r} and {self.beta!r}")


@dataclass
class OneEuroState:
    """Running state of a :class:`OneEuroFilter` (None before the first sample).

    Attributes
    ----------
    value : ndarray, shape (J,), or None
        The last filtered value.
    speed : ndarray, shape (J,), or None
        The last filtered speed, units per second.
    """

    value: np.ndarray | None = None
    speed: np.ndarray | None = None


def _alpha(cutoff_hz, dt_s: float):
    return 1.0 / (1.0 + 1.0 / (2.0 * np.pi * cutoff_hz * dt_s))


def _check_rate(rate_hz) -> float:
    return check_number(rate_hz, "rate_hz", above=0)


class OneEuroFilter:
    """The One Euro filter over a stream of equally spaced vectors (module docstring).

    Parameters
    ----------
    rate_hz : float
        Samples per second (a camera's frame rate).
    options : OneEuroOptions, keyword-only, optional

    Attributes
    ----------
    state : OneEuroState
    """

    def __init__(self, rate_hz: float, *, options: OneEuroOptions | None = None) -> None:
        self.rate_hz = _check_rate(rate_hz)
        self.options = check_options(options, OneEuroOptions)
        self.state = OneEuroState()

    def reset(self) -> None:
        """Forget the past: the next sample is passed through unchanged."""
        self.state = OneEuroState()

    def __call__(self, x) -> np.ndarray:
        """The filtered value of sample `x` (shape (J,)).

        A sample with a non-finite value (a frame without a hand) is returned
        as it is and resets the filter.
        """
        x = np.asarray(x, dtype=np.float64)
        st, o = self.state, self.options
        if not np.all(np.isfinite(x)):
            self.reset()
            return x.copy()
        if st.value is None or st.speed is None or st.value.shape != x.shape:
            st.value, st.speed = x.copy(), np.zeros_like(x)
            return x.copy()
        dt = 1.0 / self.rate_hz
        ad = _alpha(o.derivative_cutoff_hz, dt)
        st.speed = ad * (x - st.value) / dt + (1.0 - ad) * st.speed
        a = _alpha(o.min_cutoff_hz + o.beta * np.abs(st.speed), dt)
        st.value = a * x + (1.0 - a) * st.value
        return st.value.copy()


def one_euro(x, *, rate_hz: float, options: OneEuroOptions | None = None) -> np.ndarray:
    """The One Euro filter over a whole array, sample by sample (the plain reference).

    Parameters
    ----------
    x : ndarray, shape (N, J)
        Equally spaced samples, finite.
    rate_hz : float, keyword-only
    options : OneEuroOptions, keyword-only, optional

    Returns
    -------
    ndarray, shape (N, J), float64

    Raises
    ------
    InvalidInputError
        `x` not a finite (N, J) array of numbers, bad `rate_hz` or `options`.
    """
    try:
        x = np.asarray(x, dtype=np.float64)
    except (TypeError, ValueError):
        raise InvalidInputError(f"x must be a finite (N, J) array of numbers, got "
                                f"{type(x).__name__} {short_repr(x)}") from None
    if x.ndim != 2 or not np.all(np.isfinite(x)):
        raise InvalidInputError(f"x must be a finite (N, J) array, got shape {x.shape}")
    o = check_options(options, OneEuroOptions)
    dt = 1.0 / _check_rate(rate_hz)
    out = x.copy()
    if len(x) == 0:
        return out
    speed = np.zeros(x.shape[1])
    for i in range(1, len(x)):
        for j in range(x.shape[1]):
            ad = _alpha(o.derivative_cutoff_hz, dt)
            speed[j] = ad * (x[i, j] - out[i - 1, j]) / dt + (1 - ad) * speed[j]
            a = _alpha(o.min_cutoff_hz + o.beta * abs(speed[j]), dt)
            out[i, j] = a * x[i, j] + (1 - a) * out[i - 1, j]
    return out


class SmoothedEstimator:
    """Any pose estimator with its angles passed through a :class:`OneEuroFilter`.

    Implements :class:`~handsynth.estimate.PoseEstimator`.  It keeps the
    filter's state between frames, so one instance serves one stream.

    Parameters
    ----------
    estimator : PoseEstimator
    rate_hz : float, keyword-only
        The stream's frame rate.
    options : OneEuroOptions, keyword-only, optional
    """

    def __init__(self, estimator, *, rate_hz: float,
                 options: OneEuroOptions | None = None) -> None:
        if not callable(getattr(estimator, "estimate", None)):
            raise InvalidInputError(f"estimator {estimator!r} has no estimate(frame) method")
        self.estimator = estimator
        self.filter = OneEuroFilter(rate_hz, options=options)

    def calibrated(self, rest_frame: np.ndarray) -> SmoothedEstimator:
        """A copy around the estimator calibrated to `rest_frame`, with a fresh filter."""
        inner = getattr(self.estimator, "calibrated", None)
        if not callable(inner):
            raise InvalidInputError(f"{type(self.estimator).__name__} cannot be calibrated")
        return SmoothedEstimator(inner(rest_frame), rate_hz=self.filter.rate_hz,
                                 options=self.filter.options)

    def estimate(self, frame: np.ndarray) -> PoseEstimate:
        """The wrapped estimator's answer with its angles filtered over time."""
        got = self.estimator.estimate(frame)
        return dataclasses.replace(got, angles=self.filter(got.angles))
