"""Sensor axes read in another convention: a gyro's or a magnetometer's against the accelerometer's.

A logger that writes one gyro axis with the other sign, or two axes exchanged, leaves every
reading plausible and every attitude wrong; an MPU-9250's magnetometer (the AK8963) has axes
of its own.  The directions of two fields fixed in the world tell: where the sensor moves
little its accelerometer reads gravity, and its magnetometer reads the Earth's field always;
the gyro, integrated over a few seconds, must carry both from one moment to the next.
:func:`gyro_axes_errors` integrates the gyro read in each of the 48 signed permutations of
its axes and measures how far gravity's carried direction lands from the one read;
:func:`mag_axes_errors` does the same for the magnetometer's direction read in each
permutation of its axes, the gyro as read.
"""

from __future__ import annotations

import itertools

import numpy as np

from ...errors import InvalidInputError
from ._model import GRAVITY_MPS2

__all__ = ["REVERSED", "SIGNED_PERMUTATIONS", "axes_label", "gyro_axes_errors", "mag_axes_errors",
           "moving_mean", "parse_axes"]

#: Signed permutations of the three axes, the identity first: ``(perm, signs)`` reads
#: ``v[:, perm] * signs`` for the axes ``v``.
SIGNED_PERMUTATIONS = tuple(
    (perm, np.array(signs)) for perm in itertools.permutations(range(3))
    for signs in itertools.product((1.0, -1.0), repeat=3))

#: Rate the gyro is integrated at, Hz (block means of faster recordings); the window
#: gravity's direction is carried over, s; the moving mean that gives gravity's direction,
#: s; the share of 1 g by which that mean may differ from 1 g where the sensor counts as
#: moving little; the most windows judged per sensor (those whose gravity direction tilts
#: most); the least tilt within a window that is judged, deg.
_RATE_HZ = 50.0
_WINDOW_S = 2.0
_MEAN_S = 0.25
_QUASI_TOL = 0.05
_MAX_WINDOWS = 32
_MIN_TILT_DEG = 5.0
#: The least a window of the gyro turns, deg, for the magnetometer's direction in it to be
#: judged.
_MIN_TURN_DEG = 5.0

#: The permutations as matrices: ``v @ P.T`` reads ``v[:, perm] * signs``.
_MATRICES = np.stack([np.eye(3)[list(perm)] * signs[:, None]
                      for perm, signs in SIGNED_PERMUTATIONS])
#: The index of (-x, -y, -z): a direction reversed in every reading keeps every angle
#: between readings, so it cannot be told from the axes as read.
REVERSED = next(j for j, (perm, signs) in enumerate(SIGNED_PERMUTATIONS)
                if perm == (0, 1, 2) and (signs < 0).all())
#: The index of each permutation's reverse (every sign changed).
_NEGATED = tuple(next(i for i, q in enumerate(_MATRICES) if np.array_equal(q, -p))
                 for p in _MATRICES)


def axes_label(perm, signs) -> str:
    """The axes a signed permutation reads, as ``"y, x, -z"``."""
    return ", ".join(("-" if sg < 0 else "") + "xyz"[i] for i, sg in zip(perm, signs))


def parse_axes(text, *, name: str = "axes") -> tuple[tuple[int, ...], np.ndarray]:
    """The signed permutation a text such as ``"y,x,-z"`` names (:func:`axes_label`'s inverse).

    Parameters
    ----------
    text : str
        Three axes, each ``x``, ``y`` or ``z`` once, with ``-`` for the other sign,
        separated by commas (spaces and enclosing parentheses allowed, as a warning
        prints them: ``"(y, x, -z)"``).
    name : str, keyword-only
        The argument, for the message.

    Returns
    -------
    perm : tuple of int
    signs : ndarray, shape (3,), float
        Axes ``v`` read so are ``v[..., perm] * signs``.

    Raises
    ------
    InvalidInputError
        Not three axes naming x, y and z once each.
    """
    from ...errors import InvalidInputError

    parts = str(text).strip().strip("()").split(",") if isinstance(text, str) else []
    parts = [p.strip().lower() for p in parts]
    ok = len(parts) == 3 and all(p.lstrip("-") in ("x", "y", "z") and p.count("-") <= 1
                                 and not p.endswith("-") for p in parts)
    perm = tuple("xyz".index(p.lstrip("-")) for p in parts) if ok else ()
    if not ok or sorted(perm) != [0, 1, 2]:
        raise InvalidInputError(f"{name} must name the axes x, y and z once each, with - for the "
                                f"other sign, as 'y,x,-z'; got {text!r}")
    return perm, np.array([-1.0 if p.startswith("-") else 1.0 for p in parts])


def gyro_axes_errors(acc: np.ndarray, gyr: np.ndarray, rate_hz: float, *,
                     static_n: int, keep: np.ndarray | None = None
                     ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """How far each signed permutation of the gyro's axes carries gravity's direction off.

    The gyro, its mean over the still start taken off, is integrated over windows of
    2 s from the first moment in each where the accelerometer's 0.25-s mean is within
    5 % of 1 g; at every later such moment of the window the direction carried
    (that first direction turned by the integrated rotation) is compared with the one
    read.  Windows whose directions read tilt by less than 5 deg tell nothing and are
    left out; of the rest, the 32 that tilt most are judged.

    Parameters
    ----------
    acc, gyr : ndarray, shape (S, N, 3), float
        Accelerometer (m/s^2) and gyro (rad/s) readings of `S` sensors.
    rate_hz : float
        Sampling rate, Hz.
    static_n : int, keyword-only
        Samples of the still start (the gyro's bias).
    keep : ndarray, shape (N,), bool, keyword-only, optional
        Samples where the accelerometer may be read as gravity's direction; the others
        (a calibration's fast oscillations about one joint, whose tangential acceleration
        swings the direction read against the turn) are integrated over but not read.
        Every sample by default.

    Returns
    -------
    sq_err : ndarray, shape (S, 48), float
        Sum of the squared angles, rad^2, between carried and read directions, per
        sensor and permutation (:data:`SIGNED_PERMUTATIONS`' order; the identity first).
    count : ndarray, shape (S,), int
        Directions compared per sensor (0: nothing judged).
    sq_fixed : ndarray, shape (S,), float
        The same sum for a direction that stays put in the sensor (each direction read
        compared with the first, not carried): how far the directions read move at all.
    """
    s_n = acc.shape[0]
    if keep is not None:
        keep = np.asarray(keep)
        if keep.dtype != bool or keep.shape != acc.shape[1:2]:
            raise InvalidInputError(f"keep must be a bool array of shape ({acc.shape[1]},), one "
                                    f"flag per sample, got {keep.dtype} of shape {keep.shape}")
    (acc_b, gyr_b), rate = _block_means(acc, gyr, rate_hz=rate_hz)
    gyr_b -= _bias(gyr, static_n)
    nb = acc_b.shape[1]
    w = max(1, int(round(_MEAN_S * rate)))
    big_l = max(2, int(round(_WINDOW_S * rate)))
    m = nb // big_l
    sq_err = np.zeros((s_n, len(SIGNED_PERMUTATIONS)))
    count = np.zeros(s_n, int)
    if m == 0 or nb < w:
        return sq_err, count, np.zeros(s_n)
    mean = np.full_like(acc_b, np.nan)
    mean[:, w // 2:w // 2 + nb - w + 1] = moving_mean(acc_b, w)
    norm = np.linalg.norm(mean, axis=-1)
    quasi = np.abs(norm - GRAVITY_MPS2) < _QUASI_TOL * GRAVITY_MPS2  # NaN compares False
    if keep is not None:  # every sample of every block of the mean's window kept
        b = int(round(rate_hz / rate))
        dropped = np.concatenate([[0], np.cumsum(~keep[:nb * b].reshape(nb, b).all(axis=1))])
        whole = np.zeros(nb, bool)
        whole[w // 2:w // 2 + nb - w + 1] = dropped[w:] == dropped[:-w]
        quasi &= whole
    up = mean / np.where(quasi, norm, 1.0)[..., None]
    quasi = quasi[:, :m * big_l].reshape(s_n, m, big_l)
    up = up[:, :m * big_l].reshape(s_n, m, big_l, 3)
    om = gyr_b[:, :m * big_l].reshape(s_n, m, big_l, 3)
    # the windows to judge: the most tilted, per sensor
    first = np.argmax(quasi, axis=2)  # (S, m); 0 where none is quasi-static (masked below)
    ref = np.take_along_axis(up, first[..., None, None], axis=2)[:, :, 0]
    cos = np.einsum("smli,smi->sml", up, ref)
    tilt = np.where(quasi, np.degrees(np.arccos(np.clip(cos, -1.0, 1.0))), 0.0).max(axis=2)
    k = min(m, _MAX_WINDOWS)
    pick = np.argsort(-tilt, axis=1)[:, :k]  # (S, k)
    judged = np.take_along_axis(tilt, pick, axis=1) >= _MIN_TILT_DEG

    def take(a):
        return np.take_along_axis(a, pick.reshape(s_n, k, *([1] * (a.ndim - 2))), axis=1)

    quasi, up, om, first = take(quasi) & judged[..., None], take(up), take(om), take(first)
    # The gyro read as P (a signed permutation) is sigma Q with Q = sigma P a rotation,
    # sigma = det P; integrating Q (sigma w) gives Q R_sigma Q^T, where R_sigma integrates
    # sigma w.  So two integrations serve all 48, and the angle between carried and read
    # directions is the one between R_sigma Q^T v at the two moments.
    rot = _integrate(np.stack([om, -om]), rate)
    later = quasi & (np.arange(big_l) > first[..., None])  # (S, k, L)
    count += later.sum(axis=(1, 2))
    start = np.take_along_axis(up, first[..., None, None], axis=2)
    d = np.clip(np.einsum("smli,smli->sml", up, start), -1.0, 1.0)
    sq_fixed = np.where(later, np.arccos(d) ** 2, 0.0).sum(axis=(1, 2))
    for j, p_mat in enumerate(_MATRICES):
        sigma = round(float(np.linalg.det(p_mat)))
        carried = np.einsum("smlij,smlj->smli", rot[(1 - sigma) // 2], up @ (sigma * p_mat))
        ref = np.take_along_axis(carried, first[..., None, None], axis=2)
        d = np.clip(np.einsum("smli,smli->sml", carried, ref), -1.0, 1.0)
        sq_err[:, j] = np.where(later, np.arccos(d) ** 2, 0.0).sum(axis=(1, 2))
    return sq_err, count, sq_fixed


def mag_axes_errors(gyr: np.ndarray, mag: np.ndarray, rate_hz: float, *,
                    static_n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """How far the gyro carries the magnetometer's direction, read in each permutation.

    The gyro, its mean over the still start taken off, is integrated over windows of 2 s;
    at every moment of a window the magnetometer's direction, read in one of the 48 signed
    permutations of its axes, is carried back to the window's start and compared with the
    direction read there.  The Earth's field is fixed in the world, so the axes as read
    carry it exactly but for noise, iron and disturbances; no accelerometer is needed, so
    the hand's accelerations do not matter.  Of the windows whose gyro turns 5 deg or more,
    the 32 that turn most are judged.  The gyro's own axes are taken as read (judge them
    first, :func:`gyro_axes_errors`).

    Parameters
    ----------
    gyr, mag : ndarray, shape (S, N, 3), float
        Gyro (rad/s) and magnetometer (any unit) readings of `S` sensors.
    rate_hz, static_n
        As for :func:`gyro_axes_errors`.

    Returns
    -------
    sq_err : ndarray, shape (S, 48), float
        Sum of the squared angles, rad^2, per sensor and permutation
        (:data:`SIGNED_PERMUTATIONS`' order; the identity first, its reverse,
        :data:`REVERSED`, alike by construction).
    count : ndarray, shape (S,), int
        Directions compared per sensor (0: nothing judged).
    sq_fixed : ndarray, shape (S,), float
        The same sum for a field that turns with the sensor (each direction read compared
        with the window's first, not carried): a magnetometer that reads a magnet fixed to
        the sensor, or one that is stuck, fits this better than any reading of its axes.
    """
    s_n = gyr.shape[0]
    (gyr_b, mag_b), rate = _block_means(gyr, mag, rate_hz=rate_hz)
    gyr_b -= _bias(gyr, static_n)
    big_l = max(2, int(round(_WINDOW_S * rate)))
    m = gyr_b.shape[1] // big_l
    sq_err = np.zeros((s_n, len(SIGNED_PERMUTATIONS)))
    count = np.zeros(s_n, int)
    if m == 0:
        return sq_err, count, np.zeros(s_n)
    om = gyr_b[:, :m * big_l].reshape(s_n, m, big_l, 3)
    field = mag_b[:, :m * big_l].reshape(s_n, m, big_l, 3)
    norm = np.linalg.norm(field, axis=-1, keepdims=True)
    field = field / np.where(norm > 0, norm, 1.0)
    turn = np.degrees(np.linalg.norm(om, axis=-1).sum(axis=2) / rate)  # (S, m)
    k = min(m, _MAX_WINDOWS)
    pick = np.argsort(-turn, axis=1)[:, :k]
    judged = (np.take_along_axis(turn, pick, axis=1) >= _MIN_TURN_DEG)[..., None] \
        & (np.take_along_axis(norm[..., 0], pick[..., None], axis=1) > 0)
    om = np.take_along_axis(om, pick[..., None, None], axis=1)
    field = np.take_along_axis(field, pick[..., None, None], axis=1)
    rot = _integrate(om, rate)  # (S, k, L, 3, 3)
    later = judged & (np.arange(big_l) > 0)
    count += later.sum(axis=(1, 2))
    d = np.clip(np.einsum("smli,smi->sml", field, field[:, :, 0]), -1.0, 1.0)
    sq_fixed = np.where(later, np.arccos(d) ** 2, 0.0).sum(axis=(1, 2))
    for j, p_mat in enumerate(_MATRICES):
        if _NEGATED[j] < j:  # a reading and its reverse keep the same angles
            sq_err[:, j] = sq_err[:, _NEGATED[j]]
            continue
        carried = np.einsum("smlij,smlj->smli", rot, field @ p_mat.T)
        d = np.clip(np.einsum("smli,smi->sml", carried, carried[:, :, 0]), -1.0, 1.0)
        sq_err[:, j] = np.where(later, np.arccos(d) ** 2, 0.0).sum(axis=(1, 2))
    return sq_err, count, sq_fixed


def moving_mean(a: np.ndarray, w: int) -> np.ndarray:
    """Means of `w` consecutive samples of (S, N, 3) `a`, shape (S, N - w + 1, 3)."""
    c = np.concatenate([np.zeros((a.shape[0], 1, 3)), np.cumsum(a, axis=1)], axis=1)
    return (c[:, w:] - c[:, :-w]) / w


def _bias(gyr: np.ndarray, static_n: int) -> np.ndarray:
    """The gyro's mean over the still start, shape (S, 1, 3) (taken off the block means: no
    copy of a long recording is made)."""
    return gyr[:, :max(1, static_n)].mean(axis=1, keepdims=True)


def _block_means(*arrays: np.ndarray, rate_hz: float) -> tuple[list[np.ndarray], float]:
    """(S, N, 3) arrays as means of blocks of samples, at about :data:`_RATE_HZ`, and that rate."""
    b = max(1, int(round(rate_hz / _RATE_HZ)))
    s_n, n, _ = arrays[0].shape
    nb = n // b
    return [a[:, :nb * b].reshape(s_n, nb, b, 3).mean(axis=2) for a in arrays], rate_hz / b


def _integrate(om: np.ndarray, rate: float) -> np.ndarray:
    """Rotation matrices from each window's start, shape (..., L, 3, 3), of (..., L, 3) rates."""
    from ._quat import qexp, qmul, quat_to_mat  # _quat reads _recording, which reads this module

    q = np.zeros((*om.shape[:-2], 4))
    q[..., 0] = 1.0
    rot = np.empty((*om.shape, 3))
    step = qexp(om / rate)
    for l in range(om.shape[-2]):
        rot[..., l, :, :] = quat_to_mat(q)
        q = qmul(q, step[..., l, :])
    return rot
