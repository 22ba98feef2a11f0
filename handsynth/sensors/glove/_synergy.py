"""Postural synergies (PCA of joint angles) and reconstruction from few sensors.

Santello, Flanders & Soechting, "Postural hand synergies for tool use",
J. Neurosci. 18:10105-10115 (1998): two principal components explained
more than 80 % of the variance of grasp postures.  Reconstructing all
joints from a few measured ones through such synergies is the approach of
Bianchi, Salaris & Bicchi, "Synergy-based hand pose sensing", Int. J.
Robotics Research 32(4):396-406 (2013); Jarque-Bou et al. (2021) study
kinematic synergies of grasps recorded with CyberGloves.  Issue 19 names the
three as anchors; every figure handsynth reports is measured here, none is
taken from them.

The reconstruction is the minimum-variance estimate of Bianchi et al.: the
synergies give a Gaussian prior on the 20 angles, theta ~ N(mu, Sigma) with
Sigma = V diag(lambda) V^T + sigma_res^2 I (k components, residual variance
sigma_res^2 of the rest); a glove gives b = A theta + e, the bend of each
sensor (A: the sensor's nominal joint weights); then

    theta_hat = mu + Sigma A^T (A Sigma A^T + R)^-1 (b - A mu),

with R the variance of the bend error.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..._checks import check_integer
from ...errors import EstimationError, InvalidInputError
from ...models import JOINT_NAMES
from ._fields import array_field, number_field

__all__ = ["Synergies", "fit_synergies"]

#: Largest |joint angle| (deg) a posture can hold: beyond, a value is corrupt (and the
#: covariance would overflow).
_MAX_ANGLE_DEG = 720.0


@dataclass(frozen=True, eq=False)
class Synergies:
    """Principal components of joint-angle postures.

    Attributes
    ----------
    mean : ndarray, shape (20,), deg
    components : ndarray, shape (k, 20)
        Unit row vectors, largest variance first.
    variances : ndarray, shape (k,), deg^2
    residual_variance : float, deg^2
        Mean variance per joint left after k components.
    explained : ndarray, shape (k,)
        Share of the total variance of each component.
    source : str
    """

    mean: np.ndarray
    components: np.ndarray
    variances: np.ndarray
    residual_variance: float
    explained: np.ndarray
    source: str = ""

    @property
    def k(self) -> int:
        return self.components.shape[0]

    def covariance(self) -> np.ndarray:
        """Prior covariance V diag(lambda) V^T + sigma_res^2 I, shape (20, 20)."""
        v = self.components
        return (v.T * self.variances) @ v + self.residual_variance * np.eye(v.shape[1])

    def reconstruct(self, bend: np.ndarray, weights: np.ndarray,
                    bend_variance: np.ndarray) -> np.ndarray:
        """Minimum-variance angles (N, 20) from bends (N, M) = weights (M, 20) @ theta.

        Parameters
        ----------
        bend : ndarray, shape (N, M), deg
        weights : ndarray, shape (M, 20)
        bend_variance : ndarray, shape (M,), deg^2
        """
        sig = self.covariance()
        a = np.asarray(weights, dtype=np.float64)
        gain = sig @ a.T @ np.linalg.inv(a @ sig @ a.T + np.diag(bend_variance))
        return self.mean + (np.asarray(bend) - a @ self.mean) @ gain.T

    def to_dict(self) -> dict:
        return {"mean": self.mean.tolist(), "components": self.components.tolist(),
                "variances": self.variances.tolist(),
                "residual_variance": self.residual_variance,
                "explained": self.explained.tolist(), "source": self.source}

    @classmethod
    def from_dict(cls, d: dict) -> Synergies:
        components = array_field(d, "components", (None, len(JOINT_NAMES)))
        k = len(components)
        return cls(mean=array_field(d, "mean", (len(JOINT_NAMES),)), components=components,
                   variances=array_field(d, "variances", (k,)),
                   residual_variance=number_field(d, "residual_variance"),
                   explained=array_field(d, "explained", (k,)),
                   source=str(d.get("source", "")))


def fit_synergies(postures: np.ndarray, *, k: int = 2, source: str = "") -> Synergies:
    """PCA of `postures` (N, 20) deg keeping `k` components.

    Parameters
    ----------
    postures : array_like, shape (N, 20), deg
        Joint angles, canonical order; rows with a NaN or infinite value are
        left out.
    k : int, keyword-only
        Components kept, 1 to 20.
    source : str, keyword-only
        What the postures are, stored as ``Synergies.source``.

    Returns
    -------
    Synergies
        Mean and sample covariance (``numpy.cov``, N - 1) of the finite rows;
        the residual variance is floored at 1e-6 deg^2.

    Raises
    ------
    InvalidInputError
        `postures` not of shape (N, 20), `k` not an integer in 1..20, or an
        angle beyond +-720 deg (`source` named).
    EstimationError
        Fewer than k + 2 finite postures (`source` named), or postures that hardly vary (a
        total variance under 1 deg^2: nothing to find synergies in).
    """
    p = np.asarray(postures, dtype=np.float64)
    if p.ndim != 2 or p.shape[1] != len(JOINT_NAMES):
        raise InvalidInputError(f"postures must have shape (N, 20), got {p.shape}")
    where = f"{source}: " if source else ""
    p = p[np.isfinite(p).all(axis=1)]
    check_integer(k, "k", minimum=1, maximum=20)
    if len(p) < k + 2:
        raise EstimationError(f"{where}{len(p)} finite postures cannot give {k} synergies "
                              f"(at least {k + 2} are needed)")
    if np.abs(p).max() > _MAX_ANGLE_DEG:
        row, col = np.unravel_index(int(np.argmax(np.abs(p))), p.shape)
        raise InvalidInputError(f"{where}{JOINT_NAMES[col]} is {p[row, col]:g} deg in a "
                                f"posture, beyond any joint angle (|angle| <= "
                                f"{_MAX_ANGLE_DEG:g} deg)")
    mean = p.mean(axis=0)
    var_all, vec = np.linalg.eigh(np.cov(p, rowvar=False))
    order = np.argsort(var_all)[::-1]
    var = np.clip(var_all[order], 0.0, None)
    vt = vec[:, order].T
    total = var.sum()
    if total < 1.0:
        raise EstimationError(f"{where}the {len(p)} postures hardly vary (total variance "
                              f"{total:.3g} deg^2 over the 20 joints): synergies need "
                              "postures of many grasps")
    resid = float(var[k:].sum() / len(JOINT_NAMES))
    return Synergies(mean=mean, components=vt[:k].copy(), variances=var[:k].copy(),
                     residual_variance=max(resid, 1e-6), explained=var[:k] / total,
                     source=source)
