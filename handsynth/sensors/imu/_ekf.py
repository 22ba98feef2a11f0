"""The thesis' multi-sensor EKF ("Filter 2", "Filter 3", "Filter 4"), quaternion form.

State (seed 003 section 4.3.1, 4.4.1): the attitude of every sensor and the
elbow's acceleration (eq. 4.38: a random value each step, F = 0).  The
attitudes are quaternions (the quaternion form of chapter 5, eqs. 5.8-5.11);
the filter runs on their small-angle errors in the world frame (a
multiplicative EKF, so the 3N + 3 state has no quaternion norm constraint),
which changes the parameterisation, not the observation models.

Prediction: eq. 5.10 with the bias-corrected gyro.  Observations, all in
terms of the link model of chapter 3 (sensor-to-joint vectors P, link
vectors V):

- H1 (eqs. 4.25-4.28, 4.37): each sensor's accelerometer minus its own
  rotational acceleration about its proximal joint is the specific force at
  that joint, which is gravity plus the elbow acceleration plus the
  rotational accelerations of every proximal link at its distal joint,
  rotated into the sensor frame;
- H2 (eqs. 4.29-4.32, 4.37): the two sensors on either side of a joint see
  the same specific force at the joint (both directions; the root link
  against gravity plus elbow acceleration);
- H3 (eqs. 4.33-4.35): the tilt-compensated compass's horizontal component,
  turned by -psi_cor, points along world x with its static magnitude.

Filter 2 uses H1 and H3, Filter 3 adds H2, Filter 4 switches the weights
of H1 and H2 by each sensor's angular speed (|w| >= 400 deg/s puts H2
first; Table 4.3).  The thesis ran one EKF per finger chain and averaged
the shared sensors; here the whole tree is one EKF (shared sensors appear
once).  The Kalman update (eqs. 4.7-4.8) is computed in its information
form, P+ = (P-^-1 + H^T V^-1 H)^-1, which is the same update for a diagonal
V and needs only (3N + 3)-square inversions.  The magnetometer observation
of a sensor is skipped while its field strength departs more than
`mag_gate` from the static value (a magnetic disturbance; not in the
thesis).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..._checks import check_instance, check_number, is_number
from ...errors import InvalidInputError
from ._attitude import (
    StaticStart,
    azimuth_correction,
    check_run_input,
    gyro_bias,
    initial_attitude,
)
from ._layout import LINKS
from ._model import GRAVITY_MPS2
from ._quat import qexp, qmul, qnormalize, quat_to_mat
from ._recording import ImuRecording
from ._vectors import ChainModel

__all__ = ["FILTER4B", "ChainEKF", "ChainEKFOptions", "FilterStart", "fast_turns", "observed_field",
           "sensor_tree"]


@dataclass(frozen=True)
class ChainEKFOptions:
    """Options of :class:`ChainEKF` (frozen: a typo raises).

    The defaults were chosen on the tuning configuration only (datasheet
    noise, standard hand, exact mounting; two 20-s free motions, elbow fixed
    and moving) from acc_sd in {1, 3}, mag_sd in {10, 30}, gyro_noise in
    {0.003, 0.01}; the evaluation uses another configuration.
    ``elbow_acc_sd``, ``demoted`` and ``mag_gate`` were not among the
    settings searched: their defaults are assumptions, not tuned; the
    held-out configuration (docs/imu.md, "Figures") scores them with the
    rest.

    Parameters
    ----------
    use_h2 : bool
        Include the joint-agreement observation H2 (Filters 3 and 4).
    switch_dps : float or None
        Angular speed at which H2 takes priority over H1 (Filter 4: 400,
        seed 003 section 4.3.2, Table 4.3; SPEC.md section 3, "|w| >= 400 deg/s");
        None keeps both at their base weights (Filters 2, 3).
    gyro_noise : float
        Process noise, rad/s.
    elbow_acc_sd : float
        s.d. of the elbow acceleration per step, m/s^2 (the process noise
        w of eq. 4.38).  Default 3 m/s^2: an assumption; the thesis states
        no value for w.
    acc_sd : float
        Observation noise of H1/H2 rows, m/s^2.
    demoted : float
        Factor on the s.d. of the observation model that is not first.
        Default 3: an assumption; the thesis says only that H2 takes
        priority above the switch (section 4.3.2, Table 4.3), not by how
        much.
    mag_sd : float
        Observation noise of H3 rows, uT.
    mag_gate : float
        Relative field-strength change that suspends H3 for a sensor.
        Default 0.1 (10 %): an assumption (the gate is not in the thesis):
        five times the 2 % disagreement above which the magnetometer
        calibration warns of a disturbed pose, and below the change of about
        12 % that the held-out configuration's magnet makes to the field's
        strength at full strength (docs/imu.md, "Figures").
    filled_rate : float
        Process noise of a sensor's attitude, rad/s, over the samples filled
        in for it (:attr:`ImuRecording.filled`, set by :func:`bridge_lost`),
        added to `gyro_noise`: its attitude loosens while its readings are
        made up, and the readings after the gap pull it back (not in the
        thesis).  Default 1 rad/s: chosen on the tuning configuration
        (``python scripts/study_imu_held.py``).
    bias_tau_s : float or None
        Time constant (s) of a gyro bias learnt from the filter's own
        corrections (not in the thesis): each step's correction of a sensor's
        attitude, turned into the sensor's frame and divided by the time
        constant, is taken off its gyro bias (an integral feedback; a bias
        error b turns the predicted attitude by b dt a step, which the
        corrections take back).  None: the static start's bias only, as in
        the thesis.
    """

    use_h2: bool = True
    switch_dps: float | None = 400.0
    gyro_noise: float = 0.01
    elbow_acc_sd: float = 3.0
    acc_sd: float = 1.0
    demoted: float = 3.0
    mag_sd: float = 30.0
    mag_gate: float = 0.1
    filled_rate: float = 1.0
    bias_tau_s: float | None = None

    def __post_init__(self) -> None:
        if not isinstance(self.use_h2, (bool, np.bool_)):
            raise InvalidInputError(f"ChainEKFOptions.use_h2 must be True or False, got "
                                    f"{self.use_h2!r}")
        for k in ("gyro_noise", "elbow_acc_sd", "acc_sd", "demoted", "mag_sd", "mag_gate",
                  "filled_rate"):
            check_number(getattr(self, k), f"ChainEKFOptions.{k}", above=0)
        for k in ("switch_dps", "bias_tau_s"):
            v = getattr(self, k)
            if v is not None and not (is_number(v) and np.isfinite(v) and v > 0):
                raise InvalidInputError(f"ChainEKFOptions.{k} must be a finite number > 0 or "
                                        f"None, got {v!r}")


#: ``filter4b``: Filter 4 that also learns each gyro's bias from its own
#: corrections (:attr:`ChainEKFOptions.bias_tau_s`, not in the thesis), the
#: time constant chosen on the tuning configuration with gyro biases drifting
#: during 120-s recordings (``python scripts/study_imu_drift.py``; docs/imu.md,
#: "A gyro bias that drifts").
FILTER4B = ChainEKFOptions(bias_tau_s=3.0)


@dataclass(frozen=True, eq=False)
class FilterStart:
    """What Filter 4 takes from a recording's static start (:meth:`ChainEKF.prepare`).

    Attributes
    ----------
    tree : _Tree
        The sensors' link tree.
    gyro_bias : ndarray, shape (S, 3), rad/s
        Each gyro's mean over the static start (seed 003 section 4.2.4).
    q0 : ndarray, shape (S, 4)
        Initial attitudes (eqs. 2.9-2.11, 4.22).
    covariance : ndarray, shape (3S + 3, 3S + 3)
        The first covariance: attitudes 1e-4 rad^2, the elbow's acceleration (eq. 4.38).
    mh, fnorm0 : ndarray, shape (S,)
        The static compass's horizontal magnitude (eq. 4.33), uT, and its field strength.
    rz : ndarray, shape (S, 2, 3)
        The azimuth corrections as rows of a rotation (eq. 4.35).
    """

    tree: _Tree
    gyro_bias: np.ndarray
    q0: np.ndarray
    covariance: np.ndarray
    mh: np.ndarray
    fnorm0: np.ndarray
    rz: np.ndarray


def sensor_tree(sensors) -> tuple[list[int], list[tuple[str, str]]]:
    """Parent sensor index (-1 for the forearm roots) and (proximal, distal) link of each.

    Parameters
    ----------
    sensors : iterable of str
        Sensor names, each the measuring sensor of a link of :data:`LINKS`
        (no fingertip sensors).

    Returns
    -------
    parent : list of int, length S
        Index in `sensors` of the sensor whose link ends at this sensor's
        proximal point (the first such in :data:`LINKS` order, e.g.
        ``forearm_3`` before ``forearm_1`` for ``hand_radial``); -1 where
        none of `sensors` is (the forearm sensors, or any sensor whose parent
        is absent).
    link : list of (str, str), length S
        The (proximal, distal) points of the sensor's first link in
        :data:`LINKS` (``hand_radial`` and ``hand_ulnar`` measure several).

    Raises
    ------
    InvalidInputError
        A sensor that measures no link of :data:`LINKS`.
    """
    sensors = tuple(sensors)
    parent, link = [], []
    for s in sensors:
        own = next((lk for lk in LINKS if lk[0] == s), None)
        if own is None:
            raise InvalidInputError(f"sensor {s!r} is not part of the link model")
        prox = own[1]
        par = next((lk[0] for lk in LINKS if lk[2] == prox and lk[0] in sensors), None)
        parent.append(-1 if par is None else sensors.index(par))
        link.append((own[1], own[2]))
    return parent, link


def _skew(v):
    z = np.zeros(v.shape[:-1])
    x, y, w = v[..., 0], v[..., 1], v[..., 2]
    return np.stack([np.stack([z, -w, y], -1), np.stack([w, z, -x], -1),
                     np.stack([-y, x, z], -1)], -2)


@dataclass(frozen=True)
class _Tree:
    """Constants of the link model for one recording's sensors."""

    parent: np.ndarray        # (S,) int, -1 for roots
    order: np.ndarray         # (S,) topological order
    anc: np.ndarray           # (S, D) ancestors, -1 padded
    via: np.ndarray           # (S, D) child of each ancestor on the path to the sensor
    own: np.ndarray           # (S, 3) P_j
    vpar: np.ndarray          # (S, 3) parent's link vector to the child's proximal joint
    ppar: np.ndarray          # (S, 3) parent's vector from that joint to the parent sensor
    children: np.ndarray      # sensors with a parent
    roots: np.ndarray         # sensors without


def _tree(names, model: ChainModel) -> _Tree:
    parent, link = sensor_tree(names)
    s_n = len(names)
    own = np.array([model.own[s] for s in names], dtype=float)
    vpar = np.zeros((s_n, 3))
    for j, p in enumerate(parent):
        if p >= 0:
            vpar[j] = model.links[(names[p], link[p][0], link[j][0])]
    ppar = np.zeros((s_n, 3))
    for j, p in enumerate(parent):
        if p >= 0:
            ppar[j] = own[p] - vpar[j]                                      # eq. 4.31
    depth = 8
    anc = -np.ones((s_n, depth), dtype=np.int64)
    via = -np.ones((s_n, depth), dtype=np.int64)
    for j in range(s_n):
        for d, k in enumerate(_ancestors(j, parent)):
            anc[j, d] = k
            via[j, d] = _child_on_path(j, k, parent)
    par = np.array(parent, dtype=np.int64)
    return _Tree(par, np.array(_topological(parent), dtype=np.int64), anc, via, own, vpar, ppar,
                 np.nonzero(par >= 0)[0], np.nonzero(par < 0)[0])


def observe(tree: _Tree, r, w, dw, a, mag, *, mh, fnorm0, rz, fast, options: ChainEKFOptions):
    """Observation vector, prediction, Jacobian and s.d. at one sample (reference version).

    Parameters
    ----------
    tree : _Tree
    r : ndarray, shape (S, 3, 3)
        Predicted sensor-to-world rotations.
    w, dw, a, mag : ndarray, shape (S, 3)
        Gyro (rad/s), angular acceleration (rad/s^2), accelerometer (m/s^2),
        magnetometer (uT) at this sample.
    mh, fnorm0 : ndarray, shape (S,)
        Static horizontal field (eq. 4.33) and field strength per sensor.
    rz : ndarray, shape (S, 2, 3)
        First two rows of R_z0(-psi_cor) (eq. 4.35).
    fast : ndarray of bool, shape (S,)
        |w| above the Filter 4 switch.

    Returns
    -------
    z, hx, sd : ndarray, shape (M,)
    h : ndarray, shape (M, 3 S + 3)
        Jacobian with respect to world-frame attitude errors and the elbow
        acceleration (last three columns).
    """
    o = options
    s_n = r.shape[0]
    nx = 3 * s_n + 3
    ie = slice(3 * s_n, nx)
    g = np.array([0.0, 0.0, GRAVITY_MPS2])
    par = np.maximum(tree.parent, 0)
    ar_own = np.cross(dw, tree.own) + np.cross(w, np.cross(w, tree.own))      # eq. 4.27
    a_joint = a - ar_own
    wp, dwp = w[par], dw[par]
    c_par = np.cross(dwp, tree.vpar) + np.cross(wp, np.cross(wp, tree.vpar))  # eq. 4.28
    cw = np.einsum("sij,sj->si", r[par], c_par)
    f = np.empty((s_n, 3))
    for j in tree.order:                                                    # eqs. 4.25, 4.37
        f[j] = g if tree.parent[j] < 0 else f[tree.parent[j]] + cw[j]
    rt = r.transpose(0, 2, 1)
    rows_z, rows_h, rows_hx, rows_sd = [], [], [], []

    def add(zv, hv, jac, sdv):
        rows_z.append(zv)
        rows_hx.append(hv)
        rows_h.append(jac)
        rows_sd.append(np.full(len(zv), sdv))

    for j in range(s_n):                                                    # H1, eq. 4.26
        jac = np.zeros((3, nx))
        jac[:, 3 * j:3 * j + 3] = rt[j] @ _skew(f[j])
        for k, c in zip(tree.anc[j], tree.via[j]):
            if k < 0:
                break
            jac[:, 3 * k:3 * k + 3] -= rt[j] @ _skew(cw[c])
        jac[:, ie] = rt[j]
        add(a_joint[j], rt[j] @ f[j], jac, o.acc_sd * (o.demoted if fast[j] else 1.0))
    if o.use_h2:
        ar_bar = np.cross(dwp, tree.ppar) + np.cross(wp, np.cross(wp, tree.ppar))  # eq. 4.30
        m_par = a[par] - ar_bar
        for j in tree.children:                                             # eqs. 4.29, 4.32
            p = tree.parent[j]
            sdv = o.acc_sd * ((1.0 if fast[j] else o.demoted) if o.switch_dps else 1.0)
            u = r[p] @ m_par[j]
            jac = np.zeros((3, nx))
            jac[:, 3 * j:3 * j + 3] = rt[j] @ _skew(u)
            jac[:, 3 * p:3 * p + 3] = -rt[j] @ _skew(u)
            add(a_joint[j], rt[j] @ u, jac, sdv)
            v = r[j] @ a_joint[j]
            jac = np.zeros((3, nx))
            jac[:, 3 * p:3 * p + 3] = rt[p] @ _skew(v)
            jac[:, 3 * j:3 * j + 3] = -rt[p] @ _skew(v)
            add(m_par[j], rt[p] @ v, jac, sdv)
        for j in tree.roots:
            sdv = o.acc_sd * ((1.0 if fast[j] else o.demoted) if o.switch_dps else 1.0)
            jac = np.zeros((3, nx))
            jac[:, 3 * j:3 * j + 3] = rt[j] @ _skew(g)
            jac[:, ie] = rt[j]
            add(a_joint[j], rt[j] @ g, jac, sdv)
            v = r[j] @ a_joint[j]
            jac = np.zeros((3, nx))
            jac[:, 3 * j:3 * j + 3] = -_skew(v)
            jac[:, ie] = -np.eye(3)
            add(g, v, jac, sdv)
    mw = np.einsum("sij,sj->si", r, mag)                                    # H3, eq. 4.34
    ok = np.abs(np.linalg.norm(mag, axis=-1) / fnorm0 - 1.0) < o.mag_gate
    for j in range(s_n):
        jac = np.zeros((2, nx))
        jac[:, 3 * j:3 * j + 3] = -rz[j] @ _skew(mw[j])
        add(np.array([mh[j], 0.0]), rz[j] @ mw[j], jac, o.mag_sd if ok[j] else 1e6)
    return (np.concatenate(rows_z), np.concatenate(rows_hx), np.concatenate(rows_h),
            np.concatenate(rows_sd))


@dataclass(frozen=True)
class ChainEKF:
    """Multi-sensor EKF of the thesis on a link model (an :class:`OrientationEstimator`).

    Parameters
    ----------
    model : ChainModel
        Sensor-to-joint vectors and link vectors (from :func:`chain_model`).
    options : ChainEKFOptions, keyword-only
    static : StaticStart, keyword-only
    name : str, keyword-only
    fast : bool, keyword-only
        Run the compiled loop (numba); False runs the plain reference loop
        with :func:`observe` (the same arithmetic, tested equal).
    """

    model: ChainModel
    options: ChainEKFOptions = field(default_factory=ChainEKFOptions)
    static: StaticStart = field(default_factory=StaticStart)
    name: str = "filter4"
    fast: bool = True

    def __post_init__(self) -> None:
        check_instance(self.model, ChainModel, name="ChainEKF.model")
        check_instance(self.options, ChainEKFOptions, name="ChainEKF.options")
        if not isinstance(self.fast, (bool, np.bool_)):
            raise InvalidInputError(f"ChainEKF.fast must be True or False, got {self.fast!r}")

    def run(self, rec: ImuRecording) -> np.ndarray:
        from threadpoolctl import threadpool_limits

        check_run_input(rec, self.static)
        # the matrices are small (3S + 3 square): BLAS threads only contend
        with threadpool_limits(limits=1):
            return self._run(rec)

    def prepare(self, rec: ImuRecording) -> FilterStart:
        """What the filter takes from the static start (and the common rotation) of `rec`.

        `rec` holds at least the static start (and the common rotation, if any); the
        filter's arithmetic after it depends on no later sample but the next one (the gyro's
        derivative), so :class:`ImuStream` runs the same filter on samples as they come.
        """
        s_n = len(rec.sensors)
        n0 = max(1, int(self.static.static_s * rec.rate_hz))
        q = initial_attitude(rec, self.static)
        cor = azimuth_correction(rec, self.static)
        mag = observed_field(rec)
        m_static = np.einsum("sij,sj->si", quat_to_mat(q), mag[:, :n0].mean(axis=1))
        fnorm0 = np.linalg.norm(mag[:, :n0].mean(axis=1), axis=-1)
        fnorm0[fnorm0 == 0] = 1.0
        rz = np.zeros((s_n, 2, 3))                                          # eq. 4.35
        c, s_ = np.cos(-cor), np.sin(-cor)
        rz[:, 0, 0], rz[:, 0, 1], rz[:, 1, 0], rz[:, 1, 1] = c, -s_, s_, c
        p_cov = np.eye(3 * s_n + 3) * 1e-4
        p_cov[-3:, -3:] = np.eye(3) * self.options.elbow_acc_sd**2
        return FilterStart(tree=_tree(rec.sensors, self.model), gyro_bias=gyro_bias(rec, self.static),
                           q0=q, covariance=p_cov,
                           mh=np.hypot(m_static[:, 0], m_static[:, 1]),           # eq. 4.33
                           fnorm0=fnorm0, rz=rz)

    def _run(self, rec: ImuRecording) -> np.ndarray:
        o = self.options
        s_n, n = len(rec.sensors), rec.n
        dt = 1.0 / rec.rate_hz
        start = self.prepare(rec)
        tree, mh, fnorm0, rz = start.tree, start.mh, start.fnorm0, start.rz
        gyr = rec.gyr - start.gyro_bias[:, None]
        dgyr = np.gradient(gyr, dt, axis=1)
        q, p_cov = start.q0, start.covariance
        mag = observed_field(rec)
        filled = np.zeros((s_n, n), bool) if rec.filled is None else rec.filled
        fast_w = fast_turns(gyr, o)
        bias = np.zeros((s_n, 3))                          # learnt beyond the static start's
        if self.fast:
            from ._ekf_numba import run_fast

            return run_fast(tree, q, (p_cov, bias), gyr, dgyr, rec.acc, mag, dt, mh, fnorm0, rz,
                            fast_w, filled, o)[0]
        qn = (o.gyro_noise * dt) ** 2
        qn_filled = qn + (o.filled_rate * dt) ** 2
        out = np.empty((s_n, n, 4))
        out[:, 0] = q
        for i in range(1, n):
            w = 0.5 * (gyr[:, i] + gyr[:, i - 1]) - bias
            q = qnormalize(qmul(q, qexp(w * dt)))                           # eq. 5.10
            idx = np.arange(3 * s_n)
            p_cov[idx, idx] += np.where(np.repeat(filled[:, i], 3), qn_filled, qn)
            p_cov[-3:, :] = 0.0
            p_cov[:, -3:] = 0.0
            p_cov[-3:, -3:] = np.eye(3) * o.elbow_acc_sd**2                 # eq. 4.38
            r = quat_to_mat(q)
            z, hx, h, sd = observe(tree, r, gyr[:, i] - bias, dgyr[:, i], rec.acc[:, i],
                                   mag[:, i], mh=mh, fnorm0=fnorm0, rz=rz, fast=fast_w[:, i],
                                   options=o)
            vinv = 1.0 / sd**2                                              # eqs. 4.7-4.8
            info = np.linalg.inv(p_cov) + (h.T * vinv) @ h
            p_cov = np.linalg.inv(info)
            p_cov = 0.5 * (p_cov + p_cov.T)
            dx = p_cov @ (h.T @ (vinv * (z - hx)))
            q = qnormalize(qmul(qexp(dx[:3 * s_n].reshape(s_n, 3)), q))
            if o.bias_tau_s is not None:
                bias -= np.einsum("sji,sj->si", r, dx[:3 * s_n].reshape(s_n, 3)) / o.bias_tau_s
            out[:, i] = q
        return out


def observed_field(rec: ImuRecording) -> np.ndarray:
    """The magnetometer readings H3 observes, (S, N, 3) uT: for 6-axis sensors a zero field,
    which the field-strength gate never passes, so that H3 observes nothing (its rows carry
    zero weight)."""
    return np.zeros_like(rec.gyr) if rec.mag is None else rec.mag


def fast_turns(gyr: np.ndarray, options: ChainEKFOptions) -> np.ndarray:
    """Samples at or above Filter 4's angular-speed switch (Table 4.3), shape (S, N), bool.

    `gyr` (S, N, 3), rad/s, the static start's bias removed.
    """
    return np.degrees(np.linalg.norm(gyr, axis=-1)) >= (options.switch_dps or np.inf)


def _ancestors(j: int, parent) -> list[int]:
    out = []
    while parent[j] >= 0:
        j = parent[j]
        out.append(j)
    return out


def _child_on_path(j: int, k: int, parent) -> int:
    """The child of ancestor k on the path down to j."""
    c = j
    while parent[c] != k:
        c = parent[c]
    return c


def _topological(parent) -> list[int]:
    order: list[int] = []
    done = set()
    while len(order) < len(parent):
        for j, p in enumerate(parent):
            if j not in done and (p < 0 or p in done):
                order.append(j)
                done.add(j)
    return order
