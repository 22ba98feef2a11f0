"""What a recording determines about the joint centre.

A point fixed in both sensors satisfies, in the upper sensor's frame and for
every frame ``i`` (O'Brien et al. 2000; :class:`~handsynth.sensors.trackers.
OBrienEstimator`)::

    c_U - Q(i) c_L = d(i)

with ``Q(i)`` the lower sensor's orientation and ``d(i)`` its origin in the
upper frame.  The normal matrix of this least-squares problem, divided by the
number of frames, is ``M = [[I, -Qm], [-Qm^T, I]]`` with ``Qm`` the mean of
the ``Q(i)``.  With ``Qm = U diag(s) V^T`` its eigenvalues are ``1 - s_k`` and
``1 + s_k``; the eigenvector of ``1 - s_k`` is ``(u_k, v_k) / sqrt(2)``: the
centre moving rigidly along ``u_k`` (upper frame) = ``v_k`` (lower frame).
``1 - s_k`` is about half the mean squared angle through which the motion
turns the direction ``u_k``, so ``spread_k = sqrt(2 (1 - s_k))`` is that
angle (RMS, radians) -- the *turn* of ``u_k``, whatever the joint.  The
joint axis is the direction that turns least; flexion about it turns the
two directions across it by about the RMS flexion angle:

* a hinge has one turn near zero, its axis: only the axis is determined,
  a point can slide along it;
* a joint that barely moved has all three near zero: nothing is determined.

The expected error of the centre along ``u_k`` is the least-squares standard
error ``2 sigma / sqrt(n_eff (1 - s_k))`` (two standard errors), with
``sigma`` the RMS per coordinate of the residual ``c_U - Q c_L - d`` and
``n_eff`` the number of effectively independent frames, ``n`` divided by the
integrated autocorrelation time of the residual (summed up to its first zero
crossing), so that drift and slowly varying field distortion, which do not
average out over frames, are not counted as independent samples.

The decision thresholds are options of every estimator (see
:class:`~handsynth.sensors.trackers.OBrienEstimator`): the centre is refused
when its expected error across the axis exceeds ``refuse_error_mm``, a
warning gives the expected error above ``warn_error_mm``, and a motion whose
expected error *along* the best axis exceeds ``axis_error_mm`` is reported as
single-axis: the axis and the point of it nearest the two sensors.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ...errors import InvalidInputError
from ._checks import check_array, check_integer

__all__ = ["Determinability", "assess_determinability", "linear_centre"]


def _autocorrelation_time(z: np.ndarray) -> float:
    """Integrated autocorrelation time of the columns of `z` (mean, >= 1)."""
    n = z.shape[0]
    z = z - z.mean(axis=0)
    f = np.fft.rfft(z, 2 * n, axis=0)
    ac = np.fft.irfft(f * np.conj(f), axis=0)[:n]
    taus = []
    for j in range(z.shape[1]):
        a = ac[:, j]
        if a[0] <= 0:
            continue
        a = a / a[0]
        neg = np.flatnonzero(a < 0)
        k = int(neg[0]) if neg.size else n
        taus.append(1.0 + 2.0 * float(a[1:k].sum()))
    return max(1.0, float(np.mean(taus))) if taus else 1.0


@dataclass(frozen=True)
class Determinability:
    """How well the frames used determine the joint centre.

    Attributes
    ----------
    spread_deg : (3,) ndarray of float64
        RMS angle through which the relative motion turns each of the three
        principal directions, ascending, degrees (element 0: the joint axis).
    directions_upper, directions_lower : (3, 3) ndarray of float64
        Row ``k``: the unit direction of ``spread_deg[k]`` in the upper and
        lower sensor frame.  Row 0 is the best joint axis.
    residual_mm : float
        RMS per coordinate of the least-squares residual, millimetres.
    n_effective : float
        Effectively independent frames (see module docstring).
    expected_error_mm : (3,) ndarray of float64
        Two standard errors of the centre along each direction, millimetres.
    """

    spread_deg: np.ndarray
    directions_upper: np.ndarray
    directions_lower: np.ndarray
    residual_mm: float
    n_effective: float
    expected_error_mm: np.ndarray

    @property
    def axis_upper(self) -> np.ndarray:
        """Direction that turns least (the joint axis), upper frame."""
        return self.directions_upper[0]

    @property
    def axis_lower(self) -> np.ndarray:
        """The same direction in the lower frame."""
        return self.directions_lower[0]

    def to_dict(self) -> dict:
        """JSON-serialisable summary."""
        return {
            "turn_deg": np.round(self.spread_deg, 3).tolist(),
            "axis_upper": np.round(self.axis_upper, 5).tolist(),
            "axis_lower": np.round(self.axis_lower, 5).tolist(),
            "residual_mm": round(float(self.residual_mm), 4),
            "n_effective": round(float(self.n_effective), 1),
            "expected_error_mm": np.round(self.expected_error_mm, 3).tolist(),
        }


def _normal_system(
    q: np.ndarray, d: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    n = q.shape[0]
    qm = q.mean(axis=0)
    u, s, vt = np.linalg.svd(qm)
    b = np.concatenate([d.mean(axis=0), -np.einsum("nji,nj->i", q, d) / n])
    return u, s, vt, b


def _sensor_midpoint(q: np.ndarray, d: np.ndarray) -> np.ndarray:
    """Midpoint of the two sensors' mean positions, in both frames, (6,) m."""
    lower_in_lower = -np.einsum("nji,nj->ni", q, d).mean(axis=0)  # upper origin, lower frame
    return 0.5 * np.concatenate([d.mean(axis=0), lower_in_lower])


def _check_relative(q: object, d: object) -> tuple[np.ndarray, np.ndarray]:
    """`q` and `d` as finite ``(n, 3, 3)`` and ``(n, 3)`` arrays of one length."""
    q = check_array(q, "q", (None, 3, 3), rows="frames")
    d = check_array(d, "d", (None, 3), rows="frames")
    if d.shape[0] != q.shape[0]:
        raise InvalidInputError(
            f"d: expected one row per frame of q, shape ({q.shape[0]}, 3), got {d.shape}"
        )
    return q, d


def linear_centre(
    q: np.ndarray, d: np.ndarray, *, free_directions: int = 0
) -> tuple[np.ndarray, np.ndarray]:
    """Least-squares point fixed in both frames, with undetermined directions fixed.

    Parameters
    ----------
    q : (n, 3, 3) ndarray of float64
        Lower sensor orientation in the upper frame.
    d : (n, 3) ndarray of float64
        Lower sensor origin in the upper frame, metres.
    free_directions : int
        How many of the weakest directions (0 to 3; the estimators use 0, or
        1 for a single-axis motion) the data do not determine; along them
        the centre is put at the point nearest the midpoint of the two
        sensors.

    Returns
    -------
    centre_upper, centre_lower : (3,) ndarray of float64
        Metres.

    Raises
    ------
    InvalidInputError
        If `q` or `d` has the wrong shape or holds NaN or inf, or
        `free_directions` is not an integer from 0 to 3.
    """
    q, d = _check_relative(q, d)
    free = check_integer(free_directions, "free_directions", minimum=0, maximum=3)
    return _linear_centre(q, d, free)


#: ``1 - s_k`` below which no rotation turns direction k at all (a spread of about
#: 1e-4 deg; a finger flexed by 1 deg gives 1e-4).
_UNTURNED = 1e-12


def _linear_centre(q: np.ndarray, d: np.ndarray, free_directions: int) -> tuple[
        np.ndarray, np.ndarray]:
    """:func:`linear_centre` of checked arrays."""
    u, s, vt, b = _normal_system(q, d)
    x = np.zeros(6)
    m = _sensor_midpoint(q, d)
    for k in range(3):  # eigenvalue 1 - s_k, vector (u_k, v_k)/sqrt2; 1 + s_k, (u_k, -v_k)/sqrt2
        plus = np.concatenate([u[:, k], -vt[k]]) / np.sqrt(2)
        x += (plus @ b) / (1.0 + s[k]) * plus
        minus = np.concatenate([u[:, k], vt[k]]) / np.sqrt(2)
        # a direction no rotation turns at all (rotations identical to rounding, as in a
        # pure translation) is as free as the weakest ones: dividing by its 1 - s_k of
        # 1e-16 or 0 overflowed (1e300 in the residual, an overflow warning on the terminal)
        if k < free_directions or 1.0 - s[k] < _UNTURNED:
            x += (minus @ m) * minus
        else:
            x += (minus @ b) / max(1.0 - s[k], 1e-300) * minus
    return x[:3], x[3:]


def _fit_residual(q: np.ndarray, d: np.ndarray) -> np.ndarray:
    """Residual vectors ``c_U - Q c_L - d`` (m) of the linear centre with the
    weakest direction fixed, ``(n, 3)``."""
    cu, cl = _linear_centre(q, d, 1)
    return cu - np.einsum("nij,j->ni", q, cl) - d


def assess_determinability(q: np.ndarray, d: np.ndarray) -> Determinability:
    """Spread of the relative rotations and the expected error of the centre.

    Parameters
    ----------
    q : (n, 3, 3) ndarray of float64
        Lower sensor orientation in the upper frame.
    d : (n, 3) ndarray of float64
        Lower sensor origin in the upper frame, metres.

    Returns
    -------
    Determinability

    Raises
    ------
    InvalidInputError
        If `q` or `d` has the wrong shape or holds NaN or inf.
    """
    q, d = _check_relative(q, d)
    u, s, vt, _ = _normal_system(q, d)
    lam = np.clip(1.0 - s, 0.0, None)
    # a direction no rotation turns (1 - s of rounding, 1e-16) determines nothing: its
    # expected error is infinite, not 6e7 mm
    lam[lam < _UNTURNED] = 0.0
    # residual of the fit with the weakest direction fixed: its scale does
    # not depend on how badly that direction is determined
    res = _fit_residual(q, d)
    sigma = float(np.sqrt((res**2).mean()))
    n_eff = q.shape[0] / _autocorrelation_time(res)
    with np.errstate(divide="ignore"):
        expected = np.where(lam > 0, 2.0 * sigma / np.sqrt(n_eff * lam), np.inf) * 1e3
    # s is descending, so lam is ascending: direction 0 is the least spread
    return Determinability(
        spread_deg=np.rad2deg(np.sqrt(2.0 * lam)),
        directions_upper=u.T.copy(),
        directions_lower=vt.copy(),
        residual_mm=sigma * 1e3,
        n_effective=float(n_eff),
        expected_error_mm=expected,
    )
