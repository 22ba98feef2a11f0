"""Quaternion helpers compiled with numba, shared by the compiled filter loops.

Quaternions are (w, x, y, z); the same conventions as :mod:`._quat` (eqs.
5.9-5.11 of seed 003).  Called from Python they run as they are (slowly).
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__: list[str] = []


@njit(cache=True)
def _qmul(a, b):
    return np.array([a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3],
                     a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2],
                     a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1],
                     a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0]])


@njit(cache=True)
def _qexp(v):
    ang = np.sqrt(np.sum(v * v))
    if ang < 1e-12:
        return np.array([1.0, 0.5 * v[0], 0.5 * v[1], 0.5 * v[2]])
    s = np.sin(0.5 * ang) / ang
    return np.array([np.cos(0.5 * ang), s * v[0], s * v[1], s * v[2]])


@njit(cache=True)
def _qmat(q):
    w, x, y, z = q[0], q[1], q[2], q[3]
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


@njit(cache=True, nogil=True)
def _chain(q0, dq):
    """q[:, 0] = q0, q[:, i] = q[:, i-1] * dq[:, i] (eq. 5.9); shapes (S, 4), (S, N, 4)."""
    s, n = dq.shape[0], dq.shape[1]
    out = np.empty((s, n, 4))
    if n == 0:
        return out
    for k in range(s):
        a0, a1, a2, a3 = q0[k, 0], q0[k, 1], q0[k, 2], q0[k, 3]
        out[k, 0, 0], out[k, 0, 1], out[k, 0, 2], out[k, 0, 3] = a0, a1, a2, a3
        for i in range(1, n):
            b0, b1, b2, b3 = dq[k, i, 0], dq[k, i, 1], dq[k, i, 2], dq[k, i, 3]
            a0, a1, a2, a3 = (a0 * b0 - a1 * b1 - a2 * b2 - a3 * b3,
                              a0 * b1 + a1 * b0 + a2 * b3 - a3 * b2,
                              a0 * b2 - a1 * b3 + a2 * b0 + a3 * b1,
                              a0 * b3 + a1 * b2 - a2 * b1 + a3 * b0)
            out[k, i, 0], out[k, i, 1], out[k, i, 2], out[k, i, 3] = a0, a1, a2, a3
    return out
