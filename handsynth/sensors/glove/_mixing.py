"""Which representative motion the hand is doing: likelihood mixing.

Seed 004 section 2.2 (previous work of the same group): along each
representative motion p take n points; at each, the mean mu_pn and the
covariance Sigma_pn of the five readings over the calibration trials.  A
reading S has likelihood (eq. 4)

    L_pn = exp(-1/2 (S - mu_pn)^T Sigma_pn^-1 (S - mu_pn)),

motion p the best of its points (eq. 5), L_p = max_n L_pn, and the weights
(eq. 6) r_p = L_p / sum_p L_p.  The joint angles are the r-weighted mean of
every motion's estimate.

Here the n points are n equal bins of the time within each trial (scaled to
[0, 1]), the readings are standardised as in the regression, and a ridge is
added to each Sigma_pn (a few trials cannot fill a 5 x 5 covariance).  Eq. 6
is evaluated in the log domain, r = softmax(log L_p), which is the same
ratio but does not turn into 0/0 when a reading is far from every motion.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..._checks import check_integer
from ...errors import EstimationError, InvalidInputError
from ._fields import array_field

__all__ = ["MotionMixer", "fit_mixer"]

_CHUNK = 2048


@dataclass(frozen=True, eq=False)
class MotionMixer:
    """Per-motion point means and covariances of the standardised readings.

    Attributes
    ----------
    motions : tuple of str
    centre, scale : ndarray, shape (5,), counts
    means : ndarray, shape (P, n, 5)
    inv_covs : ndarray, shape (P, n, 5, 5)
    """

    motions: tuple[str, ...]
    centre: np.ndarray
    scale: np.ndarray
    means: np.ndarray
    inv_covs: np.ndarray

    def log_likelihood(self, sensors: np.ndarray) -> np.ndarray:
        """log L_p (eqs. 4-5), shape (N, P)."""
        z = (np.asarray(sensors, dtype=np.float64) - self.centre) / self.scale
        out = np.empty((len(z), len(self.motions)))
        for a in range(0, len(z), _CHUNK):      # bounded memory: (chunk, P, n, 5) at a time
            d = z[a:a + _CHUNK, None, None, :] - self.means[None]
            m = np.einsum("xpni,pnij,xpnj->xpn", d, self.inv_covs, d)  # Mahalanobis^2
            out[a:a + _CHUNK] = (-0.5 * m).max(axis=2)
        return out

    def weights(self, sensors: np.ndarray) -> np.ndarray:
        """r_p of eq. 6, shape (N, P), rows summing to 1 (NaN rows stay NaN)."""
        ll = self.log_likelihood(sensors)
        ll = ll - ll.max(axis=1, keepdims=True)
        w = np.exp(ll)
        return w / w.sum(axis=1, keepdims=True)

    def to_dict(self) -> dict:
        return {"motions": list(self.motions), "centre": self.centre.tolist(),
                "scale": self.scale.tolist(), "means": self.means.tolist(),
                "inv_covs": self.inv_covs.tolist()}

    @classmethod
    def from_dict(cls, d: dict) -> MotionMixer:
        motions = tuple(str(m) for m in d["motions"])
        means = array_field(d, "means", (len(motions), None, 5))
        scale = array_field(d, "scale", (5,))
        if not (scale > 0).all():
            i = int(np.argmin(scale > 0))
            raise InvalidInputError(f"field 'scale' must be positive (the readings' spread), got "
                                    f"{float(scale[i])!r} at index {i}")
        return cls(motions=motions, centre=array_field(d, "centre", (5,)), scale=scale, means=means,
                   inv_covs=array_field(d, "inv_covs", (len(motions), means.shape[1], 5, 5)))


def fit_mixer(sensors: np.ndarray, motion: np.ndarray, phase: np.ndarray, *,
              motions, centre: np.ndarray, scale: np.ndarray, n_points: int = 20,
              ridge: float = 0.01) -> MotionMixer:
    """Fit the point statistics of eq. 4 from calibration samples.

    Parameters
    ----------
    sensors : ndarray, shape (N, 5), counts
    motion : ndarray, shape (N,), str
        Motion label per sample.
    phase : ndarray, shape (N,), float in [0, 1]
        Time within the sample's trial, scaled.
    motions : sequence of str, keyword-only
        Representative motions, in the order of the weights.
    centre, scale : ndarray, shape (5,), keyword-only
        Standardisation of the readings.
    n_points : int, keyword-only
        Points n along each motion.
    ridge : float, keyword-only
        Added to the diagonal of each covariance (standardised units squared).

    Raises
    ------
    InvalidInputError
        `n_points` not an integer >= 1.
    EstimationError
        A motion without samples, or a bin with fewer than 2 samples.
    """
    check_integer(n_points, "n_points", minimum=1)
    z = (np.asarray(sensors, dtype=np.float64) - centre) / scale
    motions = tuple(motions)
    means = np.empty((len(motions), n_points, 5))
    inv = np.empty((len(motions), n_points, 5, 5))
    bins = np.minimum((np.asarray(phase) * n_points).astype(int), n_points - 1)
    for p, m in enumerate(motions):
        sel = np.asarray(motion) == m
        if not sel.any():
            raise EstimationError(f"no calibration samples of motion {m!r}")
        for k in range(n_points):
            zz = z[sel & (bins == k)]
            if len(zz) < 2:
                raise EstimationError(
                    f"motion {m!r}: point {k} of {n_points} has {len(zz)} calibration "
                    "samples; record more or lower n_points (--points)")
            means[p, k] = zz.mean(axis=0)
            inv[p, k] = np.linalg.inv(np.cov(zz, rowvar=False) + ridge * np.eye(5))
    return MotionMixer(motions=motions, centre=np.asarray(centre, dtype=np.float64),
                       scale=np.asarray(scale, dtype=np.float64), means=means, inv_covs=inv)
