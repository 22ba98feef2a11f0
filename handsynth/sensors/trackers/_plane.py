"""Plane geometry of the patent's constrained search (JP2010-88628, eqs. 3-9).

The search space for the joint centre is the plane through three points
``P1, P2, P3`` written in parametric form (eq. 4)::

    P(s, t) = P1 + s (P2 - P1) + t (P3 - P1)

with normal ``n = v21 x v31`` (eq. 5) and implicit form ``a x + b y + c z + d
= 0`` (eq. 3).  The Nelder-Mead start is the foot of the perpendicular from a
point ``V`` (eqs. 6-9).  The patent recovers ``(s, t)`` of a point in the
plane by solving two of the three component equations, choosing which by the
plane's orientation (para. 0071); :func:`plane_coordinates` solves all three
in the least-squares sense instead, which needs no case distinction.
"""

from __future__ import annotations

import numpy as np

from ...errors import InvalidInputError
from ._checks import check_vector3

__all__ = ["foot_of_perpendicular", "plane_coordinates", "plane_normal", "plane_point"]


def _points(p1, p2, p3) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    return check_vector3(p1, "p1"), check_vector3(p2, "p2"), check_vector3(p3, "p3")


def _plane(p1, p2, p3) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, float]:
    """Checked points, unit normal and offset; collinear points refused."""
    p1, p2, p3 = _points(p1, p2, p3)
    abc = np.cross(p2 - p1, p3 - p1)  # eq. 5
    norm = np.linalg.norm(abc)
    scale = max(np.linalg.norm(p2 - p1) * np.linalg.norm(p3 - p1), np.finfo(float).tiny)
    if norm <= 1e-9 * scale:
        raise InvalidInputError(
            f"p1, p2, p3 are collinear and do not define a plane, got "
            f"{p1.tolist()}, {p2.tolist()}, {p3.tolist()}"
        )
    n = abc / norm
    return p1, p2, p3, n, float(-n @ p1)  # eq. 6


def plane_normal(p1, p2, p3) -> tuple[np.ndarray, float]:
    """Unit normal and offset of the plane through three points.

    Parameters
    ----------
    p1, p2, p3 : (3,) array_like of float

    Returns
    -------
    n : (3,) ndarray of float64
        ``(a, b, c) / |(a, b, c)|`` with ``(a, b, c) = v21 x v31`` (eq. 5).
    d : float
        Offset of eq. 3 for the unit normal: ``d = -n . OP1`` (eq. 6).

    Raises
    ------
    InvalidInputError
        If a point is not 3 finite numbers, or the three are (nearly)
        collinear.
    """
    *_, n, d = _plane(p1, p2, p3)
    return n, d


def foot_of_perpendicular(p1, p2, p3, v) -> np.ndarray:
    """Foot of the perpendicular from `v` to the plane (eqs. 7-9).

    ``l = -(a x_v + b y_v + c z_v + d) / sqrt(a^2 + b^2 + c^2)`` (eq. 7),
    ``VP = l n`` (eq. 8), ``OP = OV + l n`` (eq. 9).

    Parameters
    ----------
    p1, p2, p3 : (3,) array_like of float
        Three points of the plane, not collinear; any length unit, the same
        for all four points.
    v : (3,) array_like of float
        The point projected, in the unit of the others.

    Returns
    -------
    (3,) ndarray of float64

    Raises
    ------
    InvalidInputError
        As :func:`plane_normal`, or if `v` is not 3 finite numbers.
    """
    n, d = plane_normal(p1, p2, p3)
    v = check_vector3(v, "v")
    l = -(n @ v + d)  # eq. 7 with the unit normal
    return v + l * n  # eqs. 8-9


def plane_point(p1, p2, p3, s, t) -> np.ndarray:
    """Point of parameters ``(s, t)`` (eq. 4); broadcasts over `s`, `t`.

    Parameters
    ----------
    p1, p2, p3 : (3,) array_like of float
        The plane's points (any length unit; not checked for collinearity
        here).
    s, t : array_like of float
        Parameters along ``P2 - P1`` and ``P3 - P1`` (dimensionless),
        broadcast against each other; not checked to be finite.

    Returns
    -------
    (..., 3) ndarray of float64
        ``...`` is the broadcast shape of `s` and `t`; the unit of the points.

    Raises
    ------
    InvalidInputError
        If a point is not 3 finite numbers.
    """
    p1, p2, p3 = _points(p1, p2, p3)
    s = np.asarray(s, dtype=np.float64)[..., None]
    t = np.asarray(t, dtype=np.float64)[..., None]
    return p1 + s * (p2 - p1) + t * (p3 - p1)


def plane_coordinates(p1, p2, p3, point) -> tuple[float, float]:
    """Parameters ``(s, t)`` of a point of the plane (inverse of eq. 4).

    A point off the plane gets the parameters of its foot of perpendicular.

    Raises
    ------
    InvalidInputError
        As :func:`plane_normal`, or if `point` is not 3 finite numbers.
    """
    p1, p2, p3, _n, _d = _plane(p1, p2, p3)
    point = check_vector3(point, "point")
    basis = np.column_stack([p2 - p1, p3 - p1])
    (s, t), *_ = np.linalg.lstsq(basis, point - p1, rcond=None)
    return float(s), float(t)
