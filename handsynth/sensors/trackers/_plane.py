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

__all__ = ["foot_of_perpendicular", "plane_coordinates", "plane_normal", "plane_point"]


def _points(p1, p2, p3) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    p1, p2, p3 = (np.asarray(p, dtype=np.float64) for p in (p1, p2, p3))
    for name, p in (("p1", p1), ("p2", p2), ("p3", p3)):
        if p.shape != (3,) or not np.isfinite(p).all():
            raise InvalidInputError(f"{name}: expected 3 finite numbers, got {p!r}")
    return p1, p2, p3


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
        If the three points are (nearly) collinear.
    """
    p1, p2, p3 = _points(p1, p2, p3)
    abc = np.cross(p2 - p1, p3 - p1)  # eq. 5
    norm = np.linalg.norm(abc)
    scale = max(np.linalg.norm(p2 - p1) * np.linalg.norm(p3 - p1), np.finfo(float).tiny)
    if norm <= 1e-9 * scale:
        raise InvalidInputError("p1, p2, p3 are collinear and do not define a plane")
    n = abc / norm
    return n, float(-n @ p1)  # eq. 6


def foot_of_perpendicular(p1, p2, p3, v) -> np.ndarray:
    """Foot of the perpendicular from `v` to the plane (eqs. 7-9).

    ``l = -(a x_v + b y_v + c z_v + d) / sqrt(a^2 + b^2 + c^2)`` (eq. 7),
    ``VP = l n`` (eq. 8), ``OP = OV + l n`` (eq. 9).

    Returns
    -------
    (3,) ndarray of float64
    """
    n, d = plane_normal(p1, p2, p3)
    v = np.asarray(v, dtype=np.float64)
    l = -(n @ v + d)  # eq. 7 with the unit normal
    return v + l * n  # eqs. 8-9


def plane_point(p1, p2, p3, s, t) -> np.ndarray:
    """Point of parameters ``(s, t)`` (eq. 4); broadcasts over `s`, `t`."""
    p1, p2, p3 = _points(p1, p2, p3)
    s = np.asarray(s, dtype=np.float64)[..., None]
    t = np.asarray(t, dtype=np.float64)[..., None]
    return p1 + s * (p2 - p1) + t * (p3 - p1)


def plane_coordinates(p1, p2, p3, point) -> tuple[float, float]:
    """Parameters ``(s, t)`` of a point of the plane (inverse of eq. 4)."""
    p1, p2, p3 = _points(p1, p2, p3)
    basis = np.column_stack([p2 - p1, p3 - p1])
    (s, t), *_ = np.linalg.lstsq(basis, np.asarray(point, dtype=np.float64) - p1, rcond=None)
    return float(s), float(t)
