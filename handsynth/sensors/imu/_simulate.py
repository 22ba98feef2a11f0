"""Simulate the 20-IMU system: MuJoCo's ideal sensors plus the noise model."""

from __future__ import annotations

import zlib
from dataclasses import dataclass

import numpy as np

from ..._checks import check_instance, check_number
from ...errors import InvalidInputError
from ...models import HandShape
from ._layout import FLEX_JOINT, POINTS
from ._model import MODEL_JOINTS, ImuHand, ImuPlacement
from ._motion import Motion
from ._noise import MPU9250_DATASHEET, ImuNoise, apply_axis_noise, draw_fixed_errors
from ._recording import ImuRecording, ImuTruth

__all__ = ["SkinMotion", "simulate_imu"]


@dataclass(frozen=True)
class SkinMotion:
    """Sensor motion on the skin, following the segment's proximal flexion.

    Per 90 deg of the flexion joint at the segment's proximal end the sensor
    slides `slide_mm` along the segment and tilts `tilt_deg` about the
    flexion axis (skin stretches over a flexing joint; seed 003 section 2.4.2
    measured up to 25 % strain on the back of the hand near the wrist).  The
    sensor feels that motion: its gyro reads the tilt rate on top of the
    segment's rotation, its accelerometer the sliding's relative and
    Coriolis accelerations.
    """

    slide_mm: float = 2.0
    tilt_deg: float = 4.0

    def __post_init__(self) -> None:
        for k in ("slide_mm", "tilt_deg"):
            check_number(getattr(self, k), f"SkinMotion.{k}", minimum=0)


def _quat_mul(a, b):
    w1, x1, y1, z1 = np.moveaxis(a, -1, 0)
    w2, x2, y2, z2 = np.moveaxis(b, -1, 0)
    return np.stack([w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2, w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2,
                     w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2, w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2],
                    axis=-1)


def simulate_imu(motion: Motion, *, shape: HandShape | None = None, side: str = "right",
                 placement: ImuPlacement | None = None, noise: ImuNoise | None = MPU9250_DATASHEET,
                 skin: SkinMotion | None = None, seed: int = 0,
                 device_seed: int | None = None, hand: ImuHand | None = None) -> ImuRecording:
    """Run `motion` on the IMU hand and return what the 20 IMUs measure.

    Parameters
    ----------
    motion : Motion
    shape, side, placement : keyword-only
        The hand and where its sensors sit (ignored when `hand` is given).
    noise : ImuNoise or None, keyword-only
        None gives MuJoCo's ideal signals.
    skin : SkinMotion or None, keyword-only
    seed : int, keyword-only
        Seed of every random term of this recording.
    device_seed : int or None, keyword-only
        Seed of the physical sensors: each sensor's accelerometer and gyro
        scale/cross-axis matrices and turn-on biases are drawn from it and
        the sensor's name, so recordings with the same `device_seed` (a
        calibration and later tracking) share them, whichever sensors they
        hold.  None draws them from `seed` (new sensors every recording).
        The magnetometer's hard iron, soft iron and axis rotation belong to
        the physical sensor too (drawn from `device_seed` when given); its
        hard iron also changes by ``hard_iron_repeatability_ut`` at every
        recording.
    hand : ImuHand, keyword-only
        A compiled hand to reuse.

    Returns
    -------
    ImuRecording
        With :class:`ImuTruth`.
    """
    check_instance(motion, Motion, name="motion")
    if skin is not None:
        check_instance(skin, SkinMotion, name="skin")
    if noise is not None:
        check_instance(noise, ImuNoise, name="noise")
    hand = (ImuHand(shape, side=side, placement=placement) if hand is None
            else check_instance(hand, ImuHand, name="hand"))
    for dist in noise.disturbances if noise is not None else ():
        lacking = [x for x in dist.sensors if x not in hand.sensors]
        if lacking:
            raise InvalidInputError(f"MagDisturbance.sensors names {', '.join(map(repr, lacking))}, "
                                    "not on this hand (tip sensors need ImuHand(tip_sensors=True))")
    m, d = hand.model, hand.data
    import mujoco

    names = hand.sensors
    s_n, n = len(names), motion.n
    site_ids = hand.site_ids
    site_pos0 = m.site_pos[site_ids].copy()
    site_quat0 = m.site_quat[site_ids].copy()
    sameframe0 = m.site_sameframe[site_ids].copy()
    if skin is not None:
        m.site_sameframe[site_ids] = 0  # let MuJoCo use the moved site frames
    flex_col = np.array([MODEL_JOINTS.index(FLEX_JOINT[s]) for s in names])
    point_sites = [m.site(p).id if p not in ("elbow", "ulnar_cm") else -1 for p in POINTS]
    point_bodies = {"elbow": m.body("forearm").id, "ulnar_cm": m.body("palm_ulnar").id}
    body_of_site = m.site_bodyid[site_ids]

    acc_adr = np.array([hand.sensor_adr[(s, "acc")] for s in names])
    gyr_adr = np.array([hand.sensor_adr[(s, "gyr")] for s in names])
    mag_adr = np.array([hand.sensor_adr[(s, "mag")] for s in names])
    acc = np.empty((s_n, n, 3))
    gyr = np.empty((s_n, n, 3))
    mag = np.empty((s_n, n, 3))
    quat = np.empty((s_n, n, 4))
    spos = np.empty((s_n, n, 3))
    pts = np.empty((n, len(POINTS), 3))
    bq = np.empty(4)
    off3 = np.arange(3)
    try:
        for i in range(n):
            if skin is not None:
                f = motion.q[i, flex_col] / 90.0
                m.site_pos[site_ids] = site_pos0
                m.site_pos[site_ids, 1] += 1e-3 * skin.slide_mm * f
                half = np.radians(skin.tilt_deg * f) / 2
                dq = np.stack([np.cos(half), -np.sin(half), 0 * half, 0 * half], axis=-1)
                m.site_quat[site_ids] = _quat_mul(site_quat0, dq)
            hand.set_state(motion.q[i], motion.qd[i], motion.qdd[i])
            sd = d.sensordata
            acc[:, i] = sd[acc_adr[:, None] + off3]
            gyr[:, i] = sd[gyr_adr[:, None] + off3]
            mag[:, i] = sd[mag_adr[:, None] + off3]
            if skin is not None:
                _add_skin_kinematics(acc[:, i], gyr[:, i], d, site_ids, body_of_site, skin,
                                     motion.qd[i, flex_col] / 90.0, motion.qdd[i, flex_col] / 90.0)
            spos[:, i] = d.site_xpos[site_ids]
            for k, b in enumerate(body_of_site):
                mujoco.mju_mulQuat(bq, d.xquat[b], site_quat0[k])
                quat[k, i] = bq
            for k, p in enumerate(POINTS):
                pts[i, k] = d.site_xpos[point_sites[k]] if point_sites[k] >= 0 \
                    else d.xpos[point_bodies[p]]
        # true sensor-to-point vectors at the zero pose, nominal mounting
        m.site_pos[site_ids] = site_pos0
        m.site_quat[site_ids] = site_quat0
        hand.set_state(np.zeros(len(MODEL_JOINTS)))
        vectors = {}
        pts0 = {p: (d.site_xpos[point_sites[k]] if point_sites[k] >= 0
                    else d.xpos[point_bodies[p]]).copy() for k, p in enumerate(POINTS)}
        for k, sensor in enumerate(names):
            r = d.site_xmat[site_ids[k]].reshape(3, 3)
            for p in POINTS:
                vectors[(sensor, p)] = r.T @ (d.site_xpos[site_ids[k]] - pts0[p])
    finally:
        m.site_pos[site_ids] = site_pos0
        m.site_quat[site_ids] = site_quat0
        m.site_sameframe[site_ids] = sameframe0
    if noise is not None:
        rng = np.random.default_rng(seed)
        fixed_acc = fixed_gyr = None
        if device_seed is not None:
            fixed_acc, fixed_gyr = _fixed_errors(noise, names, device_seed)
        acc = apply_axis_noise(acc, noise.accel, motion.rate_hz, rng, fixed=fixed_acc)
        gyr = apply_axis_noise(gyr, noise.gyro, motion.rate_hz, rng, fixed=fixed_gyr)
        mag = _mag_noise(mag, quat, noise, motion.rate_hz, rng, names, device_seed)
    truth = ImuTruth(quat=quat, sensor_pos=spos, keypoints=pts, elbow=pts[:, 0].copy(),
                     angles=motion.q.copy(), joint_vectors=vectors, segments=motion.segments)
    return ImuRecording(motion.rate_hz, names, acc, gyr, mag, truth)


def _add_skin_kinematics(acc, gyr, d, site_ids, body_of_site, skin: SkinMotion, fd, fdd) -> None:
    """Add what MuJoCo leaves out of a sensor that moves on its body (in place).

    MuJoCo's sensors treat the (moved) site as fixed on its body.  A sensor
    sliding along the body's y axis by ``s(t)`` and tilting about its own x
    axis by ``-tilt(t)`` also feels the relative acceleration and the
    Coriolis term, ``R_S^T (s'' y_B + 2 w x s' y_B)``, and turns at the body's
    rate plus ``-tilt'`` about x.  `fd`, `fdd`: rate and acceleration of the
    flexion angle in units of 90 deg (1/s, 1/s^2), shape (S,).
    """
    r_site = d.site_xmat[site_ids].reshape(-1, 3, 3)
    y_body = d.xmat[body_of_site].reshape(-1, 3, 3)[:, :, 1]
    w_world = np.einsum("sij,sj->si", r_site, gyr)
    v_rel = 1e-3 * skin.slide_mm * fd[:, None] * y_body
    a_rel = 1e-3 * skin.slide_mm * fdd[:, None] * y_body + 2 * np.cross(w_world, v_rel)
    acc += np.einsum("sji,sj->si", r_site, a_rel)
    gyr[:, 0] -= np.radians(skin.tilt_deg) * fd


def _device_rng(device_seed: int, name: str, *stream: int) -> np.random.Generator:
    """The generator of one physical sensor's fixed errors (order-independent).

    `stream` keeps the magnetometer's draws apart from the accelerometer's
    and gyro's."""
    return np.random.default_rng([int(device_seed), zlib.crc32(name.encode()), *stream])


def _fixed_errors(noise: ImuNoise, names, device_seed: int):
    """Per-sensor accelerometer and gyro fixed errors, one generator per sensor name."""
    acc, gyr = [], []
    for name in names:
        rng = _device_rng(device_seed, name)
        acc.append(draw_fixed_errors(noise.accel, 1, rng))
        gyr.append(draw_fixed_errors(noise.gyro, 1, rng))
    return ((np.concatenate([a[0] for a in acc]), np.concatenate([a[1] for a in acc])),
            (np.concatenate([g[0] for g in gyr]), np.concatenate([g[1] for g in gyr])))


def _rot_from_quat(q):
    w, x, y, z = np.moveaxis(q, -1, 0)
    return np.stack([
        np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)], -1),
        np.stack([2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)], -1),
        np.stack([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)], -1),
    ], -2)


def _mag_fixed(mn, s: int, rng) -> tuple[np.ndarray, np.ndarray]:
    """Axis rotation times soft iron (S, 3, 3) and hard iron (S, 3) of S magnetometers."""
    ang = np.radians(rng.normal(0.0, mn.azimuth_sd_deg, s))
    c, si = np.cos(ang), np.sin(ang)
    rz = np.zeros((s, 3, 3))
    rz[:, 0, 0], rz[:, 0, 1], rz[:, 1, 0], rz[:, 1, 1], rz[:, 2, 2] = c, -si, si, c, 1.0
    soft = rng.normal(0.0, mn.soft_iron, (s, 3, 3))
    soft = np.eye(3) + 0.5 * (soft + soft.transpose(0, 2, 1))
    return soft @ rz, rng.normal(0.0, mn.hard_iron_ut, (s, 3))


def _mag_noise(mag, quat, noise: ImuNoise, rate_hz: float, rng, names,
               device_seed: int | None = None) -> np.ndarray:
    mn = noise.mag
    s, n, _ = mag.shape
    t = np.arange(n) / rate_hz
    for dist in noise.disturbances:
        ramp_in = np.clip((t - dist.start_s) / 0.5, 0, 1)
        ramp_out = np.clip((dist.end_s - t) / 0.5, 0, 1)
        w = np.minimum(ramp_in, ramp_out)
        if not w.any():
            continue
        r = _rot_from_quat(quat)  # sensor -> world (nominal mount; fine for the extra field)
        extra = np.einsum("snji,j->sni", r, np.asarray(dist.field_ut, float)) * w[None, :, None]
        mask = np.array([not dist.sensors or name in dist.sensors for name in names])
        mag = mag + extra * mask[:, None, None]
    if device_seed is None:
        matrix, hard = _mag_fixed(mn, s, rng)
    else:
        per = [_mag_fixed(mn, 1, _device_rng(device_seed, name, 1)) for name in names]
        matrix = np.concatenate([p[0] for p in per])
        hard = np.concatenate([p[1] for p in per])
    y = np.einsum("sij,snj->sni", matrix, mag)
    y += (hard + rng.normal(0.0, mn.hard_iron_repeatability_ut, (s, 3)))[:, None, :]
    y += rng.normal(0.0, mn.white_ut, y.shape)
    y = np.clip(y, -mn.full_scale_ut, mn.full_scale_ut)
    if mn.lsb_ut > 0:
        y = np.round(y / mn.lsb_ut) * mn.lsb_ut
    return y
