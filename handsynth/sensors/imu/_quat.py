"""Unit quaternions (w, x, y, z), sensor-to-world, vectorised over leading axes.

Conventions of seed 003 chapter 5: q = cos(b/2) + n sin(b/2) (eq. 5.7),
the Hamilton product of eq. 5.9 and the rotation matrix of eq. 5.11.  The
world frame is z up, x magnetic north (eq. 2.8's g = [0, 0, g]).
"""

from __future__ import annotations

import warnings

import numpy as np

from ...errors import InvalidInputError
from ._recording import check_unique_names

__all__ = [
    "angle_deg",
    "check_quats",
    "euler_zyx_to_quat",
    "heading_inclination_deg",
    "mat_to_quat",
    "qconj",
    "qexp",
    "qmul",
    "qnormalize",
    "qrot",
    "qrotinv",
    "quat_from_acc_mag",
    "quat_to_mat",
]


def qmul(a, b):
    """Hamilton product a * b (seed 003 eq. 5.9)."""
    w1, x1, y1, z1 = np.moveaxis(np.asarray(a), -1, 0)
    w2, x2, y2, z2 = np.moveaxis(np.asarray(b), -1, 0)
    return np.stack([w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2, w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2,
                     w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2, w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2],
                    axis=-1)


def check_quats(quats, sensors, *, name: str = "quats") -> np.ndarray:
    """Sensor attitudes of `sensors` as unit quaternions, float64, shape (S, N, 4).

    Norms within 0.1 % of 1 (rounding, a float32 copy) are normalised
    silently, within 1 % with a warning; NaN samples (a gap) pass through.
    The result may be `quats` itself (unit float64 quaternions): copy it
    before changing it.

    Parameters
    ----------
    quats : array_like, shape (S, N, 4)
    sensors : sequence of str, length S
        The sensor of each row, each named once.
    name : str, keyword-only
        The argument's name, for messages.

    Raises
    ------
    InvalidInputError
        Another shape (an (N, S, 4) array named as such), repeated sensor
        names, infinite values, or a quaternion whose norm departs from 1 by
        more than 1 %.
    """
    sensors = tuple(sensors)
    check_unique_names(sensors, error=InvalidInputError)
    try:
        q = np.asarray(quats, dtype=np.float64)
    except (TypeError, ValueError):
        raise InvalidInputError(f"{name} must be an array of quaternions, got "
                                f"{type(quats).__name__}") from None
    s = len(sensors)
    if q.ndim != 3 or q.shape[0] != s or q.shape[2] != 4:
        hint = (" ((N, S, 4) given? use quats.transpose(1, 0, 2))"
                if q.ndim == 3 and q.shape[1] == s and q.shape[2] == 4 else "")
        raise InvalidInputError(f"{name} must have shape (S, N, 4) with S = len(sensors) = {s}, "
                                f"got {q.shape}{hint}")
    norm = np.sqrt(np.einsum("sni,sni->sn", q, q))
    dev = np.abs(norm - 1.0)
    off = dev > 1e-3                                                     # NaN compares False
    if off.any():
        k, i = np.unravel_index(int(np.argmax(np.where(off, dev, 0.0))), dev.shape)
        if not dev[k, i] <= 0.01:
            raise InvalidInputError(
                f"{name} must be unit quaternions: sensor {sensors[k]!r} sample {i} has norm "
                f"{norm[k, i]:.6g} ({int(np.count_nonzero(dev > 0.01))} quaternion(s) more "
                "than 1 % from 1)")
        warnings.warn(f"{name}: {int(off.sum())} quaternion(s) of norm 0.1-1 % from 1 "
                      "normalised", UserWarning, stacklevel=3)
    if np.any(dev > 1e-12):                     # unit quaternions are returned as given
        q = np.where((dev > 1e-12)[..., None], q / norm[..., None], q)
    return q


def qconj(q):
    q = np.asarray(q)
    return q * np.array([1.0, -1.0, -1.0, -1.0])


def qnormalize(q):
    q = np.asarray(q, dtype=float)
    return q / np.linalg.norm(q, axis=-1, keepdims=True)


def quat_to_mat(q):
    """Rotation matrix G_R_S of eq. 5.11, shape (..., 3, 3)."""
    q = np.asarray(q)
    w, x, y, z = q[..., 0], q[..., 1], q[..., 2], q[..., 3]
    r = np.empty(q.shape[:-1] + (3, 3), dtype=np.result_type(q.dtype, np.float64))
    r[..., 0, 0] = 1 - 2 * (y * y + z * z)
    r[..., 0, 1] = 2 * (x * y - w * z)
    r[..., 0, 2] = 2 * (x * z + w * y)
    r[..., 1, 0] = 2 * (x * y + w * z)
    r[..., 1, 1] = 1 - 2 * (x * x + z * z)
    r[..., 1, 2] = 2 * (y * z - w * x)
    r[..., 2, 0] = 2 * (x * z - w * y)
    r[..., 2, 1] = 2 * (y * z + w * x)
    r[..., 2, 2] = 1 - 2 * (x * x + y * y)
    return r


def mat_to_quat(r):
    """Quaternion (w >= 0) of rotation matrices, shape (..., 4)."""
    r = np.asarray(r, dtype=float)
    from scipy.spatial.transform import Rotation

    flat = Rotation.from_matrix(r.reshape(-1, 3, 3)).as_quat()  # x, y, z, w
    q = np.concatenate([flat[:, 3:], flat[:, :3]], axis=1)
    q *= np.where(q[:, :1] < 0, -1.0, 1.0)
    return q.reshape(*r.shape[:-2], 4)


def qrot(q, v):
    """Rotate sensor-frame vectors `v` into the world: G_R_S v."""
    return np.einsum("...ij,...j->...i", quat_to_mat(q), v)


def qrotinv(q, v):
    """World vectors into the sensor frame: G_R_S^T v."""
    return np.einsum("...ji,...j->...i", quat_to_mat(q), v)


def qexp(rotvec):
    """Quaternion of rotation vectors (rad), shape (..., 4): cos(b/2) + n sin(b/2) (eq. 5.7)."""
    rv = np.asarray(rotvec, dtype=float)
    ang = np.linalg.norm(rv, axis=-1, keepdims=True)
    half = 0.5 * ang
    # sin(a/2)/a with its limit 1/2 at a -> 0
    k = np.where(ang > 1e-9, np.sin(half) / np.where(ang > 1e-9, ang, 1.0), 0.5 - ang**2 / 48)
    return np.concatenate([np.cos(half), k * rv], axis=-1)


def euler_zyx_to_quat(phi, theta, psi):
    """q of G_R_S = R_z(psi) R_y(theta) R_x(phi) (eqs. 2.7 and 5.8), radians."""
    cp, sp = np.cos(np.asarray(phi) / 2), np.sin(np.asarray(phi) / 2)
    ct, st = np.cos(np.asarray(theta) / 2), np.sin(np.asarray(theta) / 2)
    cs, ss = np.cos(np.asarray(psi) / 2), np.sin(np.asarray(psi) / 2)
    return np.stack([cp * ct * cs + sp * st * ss, sp * ct * cs - cp * st * ss,
                     cp * st * cs + sp * ct * ss, cp * ct * ss - sp * st * cs], axis=-1)


def quat_from_acc_mag(acc, mag, *, heading_offset_rad=0.0):
    """Attitude from gravity and the tilt-compensated compass (eqs. 2.9-2.11, 5.8).

    Parameters
    ----------
    acc : array_like, shape (..., 3)
        Accelerometer (any units; only the direction is used).
    mag : array_like, shape (..., 3)
        Magnetometer (any units).
    heading_offset_rad : float or array_like, keyword-only
        Added to the compass azimuth psi (the correction psi_cor of eq. 4.22).

    Returns
    -------
    ndarray, shape (..., 4)
    """
    acc = np.asarray(acc, dtype=float)
    mag = np.asarray(mag, dtype=float)
    ax, ay, az = np.moveaxis(acc, -1, 0)
    phi = np.arctan2(ay, az)                                     # eq. 2.9
    theta = -np.arctan2(ax, np.hypot(ay, az))
    mx, my, mz = np.moveaxis(mag, -1, 0)
    # eq. 2.10: H m = R_y(theta) R_x(phi) S m
    cph, sph, cth, sth = np.cos(phi), np.sin(phi), np.cos(theta), np.sin(theta)
    my1 = cph * my - sph * mz
    mz1 = sph * my + cph * mz
    hx = cth * mx + sth * mz1
    hy = my1
    psi = -np.arctan2(hy, hx) + heading_offset_rad             # eq. 2.11
    return euler_zyx_to_quat(phi, theta, psi)


def angle_deg(q1, q2):
    """Angle of the rotation between two orientations, degrees, shape (...)."""
    d = np.abs(np.sum(np.asarray(q1) * np.asarray(q2), axis=-1))
    return np.degrees(2 * np.arccos(np.clip(d, 0.0, 1.0)))


def heading_rad(q_to, q_from):
    """The turn about the world's vertical from attitude `q_from` to attitude `q_to`, rad.

    The twist about z of the world-frame rotation ``q_to q_from^*`` (the tilt
    between the two left aside); shape (...) of the (..., 4) unit quaternions
    (sensor to world).  ``qmul(qexp([0, 0, heading_rad(a, b)]), b)`` has
    `a`'s heading.
    """
    d = qmul(q_to, qconj(q_from))
    return 2.0 * np.arctan2(d[..., 3], d[..., 0])


def heading_inclination_deg(q_est, q_true):
    """Split the error of sensor-to-world estimates into heading and inclination.

    The error e = q_true^-1... taken in the world frame, e = q_est q_true^*,
    is decomposed as a rotation about the vertical (heading) times the rest
    (inclination), as in the BROAD benchmark (Laidig et al., Data 6(7):72,
    2021).  Returns two arrays of degrees.
    """
    e = qmul(q_est, qconj(q_true))
    w, z = e[..., 0], e[..., 3]
    heading = np.degrees(2 * np.arctan2(np.abs(z), np.abs(w)))
    heading = np.where(heading > 180, 360 - heading, heading)
    hq = np.stack([w, 0 * w, 0 * w, z], -1) / np.maximum(np.hypot(w, z), 1e-12)[..., None]
    incl = qmul(qconj(hq), e)
    return heading, angle_deg(incl, np.array([1.0, 0, 0, 0]))
