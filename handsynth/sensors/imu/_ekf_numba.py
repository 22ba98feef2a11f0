"""Compiled (numba) observation of the chain EKF; tested against :func:`._ekf.observe`."""

from __future__ import annotations

import numpy as np
from numba import njit

from ._model import GRAVITY_MPS2
from ._quat_numba import _qexp, _qmat, _qmul

__all__ = ["observe_fast"]


@njit(cache=True)
def _cross(a, b):
    return np.array([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2],
                     a[0] * b[1] - a[1] * b[0]])


@njit(cache=True)
def _skew(v):
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])


@njit(cache=True)
def _kernel(parent, order, anc, via, own, vpar, ppar, children, roots, r, w, dw, a, mag,
            mh, fnorm0, rz, fast, use_h2, switch, acc_sd, demoted, mag_sd, mag_gate):
    s_n = r.shape[0]
    nx = 3 * s_n + 3
    ny = 3 * s_n + (6 * (children.size + roots.size) if use_h2 else 0) + 2 * s_n
    z = np.zeros(ny)
    hx = np.zeros(ny)
    sd = np.zeros(ny)
    h = np.zeros((ny, nx))
    g = np.array([0.0, 0.0, GRAVITY_MPS2])
    a_joint = np.empty((s_n, 3))
    cw = np.zeros((s_n, 3))
    m_par = np.zeros((s_n, 3))
    for j in range(s_n):
        p = parent[j] if parent[j] >= 0 else 0
        ar = _cross(dw[j], own[j]) + _cross(w[j], _cross(w[j], own[j]))
        a_joint[j] = a[j] - ar
        c = _cross(dw[p], vpar[j]) + _cross(w[p], _cross(w[p], vpar[j]))
        cw[j] = r[p] @ c
        arb = _cross(dw[p], ppar[j]) + _cross(w[p], _cross(w[p], ppar[j]))
        m_par[j] = a[p] - arb
    f = np.zeros((s_n, 3))
    for jj in range(s_n):
        j = order[jj]
        if parent[j] < 0:
            f[j] = g
        else:
            f[j] = f[parent[j]] + cw[j]
    row = 0
    for j in range(s_n):
        rt = r[j].T
        z[row:row + 3] = a_joint[j]
        hx[row:row + 3] = rt @ f[j]
        h[row:row + 3, 3 * j:3 * j + 3] += rt @ _skew(f[j])
        for d in range(anc.shape[1]):
            k = anc[j, d]
            if k < 0:
                break
            h[row:row + 3, 3 * k:3 * k + 3] -= rt @ _skew(cw[via[j, d]])
        h[row:row + 3, 3 * s_n:] = rt
        sd[row:row + 3] = acc_sd * (demoted if fast[j] else 1.0)
        row += 3
    if use_h2:
        for jj in range(children.size):
            j = children[jj]
            p = parent[j]
            sdv = acc_sd * ((1.0 if fast[j] else demoted) if switch else 1.0)
            u = r[p] @ m_par[j]
            rtj = r[j].T
            z[row:row + 3] = a_joint[j]
            hx[row:row + 3] = rtj @ u
            su = rtj @ _skew(u)
            h[row:row + 3, 3 * j:3 * j + 3] += su
            h[row:row + 3, 3 * p:3 * p + 3] -= su
            sd[row:row + 3] = sdv
            row += 3
            v = r[j] @ a_joint[j]
            rtp = r[p].T
            z[row:row + 3] = m_par[j]
            hx[row:row + 3] = rtp @ v
            sv = rtp @ _skew(v)
            h[row:row + 3, 3 * p:3 * p + 3] += sv
            h[row:row + 3, 3 * j:3 * j + 3] -= sv
            sd[row:row + 3] = sdv
            row += 3
        for jj in range(roots.size):
            j = roots[jj]
            sdv = acc_sd * ((1.0 if fast[j] else demoted) if switch else 1.0)
            rtj = r[j].T
            z[row:row + 3] = a_joint[j]
            hx[row:row + 3] = rtj @ g
            h[row:row + 3, 3 * j:3 * j + 3] += rtj @ _skew(g)
            h[row:row + 3, 3 * s_n:] = rtj
            sd[row:row + 3] = sdv
            row += 3
            v = r[j] @ a_joint[j]
            z[row:row + 3] = g
            hx[row:row + 3] = v
            h[row:row + 3, 3 * j:3 * j + 3] -= _skew(v)
            for k in range(3):
                h[row + k, 3 * s_n + k] = -1.0
            sd[row:row + 3] = sdv
            row += 3
    for j in range(s_n):
        mw = r[j] @ mag[j]
        z[row] = mh[j]
        z[row + 1] = 0.0
        hx[row:row + 2] = rz[j] @ mw
        h[row:row + 2, 3 * j:3 * j + 3] = -(rz[j] @ _skew(mw))
        ok = abs(np.sqrt(np.sum(mag[j] ** 2)) / fnorm0[j] - 1.0) < mag_gate
        sd[row:row + 2] = mag_sd if ok else 1e6
        row += 2
    return z, hx, h, sd


def observe_fast(tree, r, w, dw, a, mag, mh, fnorm0, rz, fast, options):
    """Same result as :func:`._ekf.observe`, compiled."""
    o = options
    return _kernel(tree.parent, tree.order, tree.anc, tree.via, tree.own, tree.vpar, tree.ppar,
                   tree.children, tree.roots, np.ascontiguousarray(r), np.ascontiguousarray(w),
                   np.ascontiguousarray(dw), np.ascontiguousarray(a), np.ascontiguousarray(mag),
                   mh, fnorm0, rz, np.ascontiguousarray(fast), o.use_h2,
                   o.switch_dps is not None, o.acc_sd, o.demoted, o.mag_sd, o.mag_gate)


@njit(cache=True)
def _loop(q0, p0, bias0, gyr, dgyr, acc, mag, dt, parent, order, anc, via, own, vpar, ppar,
          children, roots, mh, fnorm0, rz, fast, use_h2, switch, acc_sd, demoted, mag_sd,
          mag_gate, qn, qn_filled, filled, elbow_var, bias_tau):
    s_n, n = gyr.shape[0], gyr.shape[1]
    out = np.empty((s_n, n, 4))
    q = q0.copy()
    out[:, 0] = q
    bias = bias0.copy()
    w_i = np.empty((s_n, 3))
    p = p0.copy()
    r = np.empty((s_n, 3, 3))
    for i in range(1, n):
        for j in range(s_n):                                   # eq. 5.10
            w = (0.5 * (gyr[j, i] + gyr[j, i - 1]) - bias[j]) * dt
            w_i[j] = gyr[j, i] - bias[j]
            qj = _qmul(q[j], _qexp(w))
            q[j] = qj / np.sqrt(np.sum(qj * qj))
            r[j] = _qmat(q[j])
        for k in range(3 * s_n):
            p[k, k] += qn_filled if filled[k // 3, i] else qn
        p[3 * s_n:, :] = 0.0
        p[:, 3 * s_n:] = 0.0
        for k in range(3):
            p[3 * s_n + k, 3 * s_n + k] = elbow_var              # eq. 4.38
        z, hx, h, sd = _kernel(parent, order, anc, via, own, vpar, ppar, children, roots, r,
                               w_i, np.ascontiguousarray(dgyr[:, i]),
                               np.ascontiguousarray(acc[:, i]), np.ascontiguousarray(mag[:, i]),
                               mh, fnorm0, rz, fast[:, i], use_h2, switch, acc_sd, demoted,
                               mag_sd, mag_gate)
        vinv = 1.0 / (sd * sd)                                 # eqs. 4.7-4.8, information form
        hv = h.T * vinv
        info = np.linalg.inv(p) + hv @ h
        p = np.linalg.inv(info)
        p = 0.5 * (p + p.T)
        dx = p @ (hv @ (z - hx))
        for j in range(s_n):
            qj = _qmul(_qexp(dx[3 * j:3 * j + 3]), q[j])
            q[j] = qj / np.sqrt(np.sum(qj * qj))
            if bias_tau > 0.0:
                bias[j] -= (r[j].T @ dx[3 * j:3 * j + 3]) / bias_tau
        out[:, i] = q
    return out, p, bias


def run_fast(tree, q0, state, gyr, dgyr, acc, mag, dt, mh, fnorm0, rz, fast, filled, options):
    """The whole filter loop compiled; the same arithmetic as :meth:`ChainEKF._run` with ``fast=False``.

    Sample 0 of the arrays is the one `q0` and `state`, ``(covariance, learnt gyro bias)``,
    belong to.  Returns the quaternions (S, N, 4) and the state after the last sample.
    """
    o = options
    p0, bias0 = state
    out, p, bias = _loop(
        np.ascontiguousarray(q0), np.ascontiguousarray(p0), np.ascontiguousarray(bias0),
        np.ascontiguousarray(gyr), np.ascontiguousarray(dgyr), np.ascontiguousarray(acc),
        np.ascontiguousarray(mag), dt, tree.parent, tree.order, tree.anc, tree.via, tree.own,
        tree.vpar, tree.ppar, tree.children, tree.roots, mh, fnorm0, rz,
        np.ascontiguousarray(fast), o.use_h2, o.switch_dps is not None, o.acc_sd, o.demoted,
        o.mag_sd, o.mag_gate, (o.gyro_noise * dt) ** 2,
        (o.gyro_noise * dt) ** 2 + (o.filled_rate * dt) ** 2, np.ascontiguousarray(filled),
        o.elbow_acc_sd**2, o.bias_tau_s or 0.0)
    return out, (p, bias)
