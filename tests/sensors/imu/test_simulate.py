import numpy as np
import pytest

from handsynth.errors import InvalidInputError
from handsynth.sensors.imu import (
    GRAVITY_MPS2,
    SENSOR_NAMES,
    SkinMotion,
    free_motion,
    simulate_imu,
)
from handsynth.sensors.imu._quat import angle_deg, quat_to_mat


def test_gyro_matches_orientation_change(ideal_rec):
    r = quat_to_mat(ideal_rec.truth.quat)
    dt = 1 / ideal_rec.rate_hz
    for k in (0, 10, 16, 19):
        for i in (500, 900):
            d = r[k, i].T @ r[k, i + 1]
            w = np.array([d[2, 1] - d[1, 2], d[0, 2] - d[2, 0], d[1, 0] - d[0, 1]]) / 2 / dt
            mean = 0.5 * (ideal_rec.gyr[k, i] + ideal_rec.gyr[k, i + 1])
            assert np.allclose(w, mean, atol=2e-3 + 2e-3 * np.linalg.norm(mean))


def test_accelerometer_is_specific_force(ideal_rec):
    r = quat_to_mat(ideal_rec.truth.quat)
    for k in (3, 16, 19):
        p = ideal_rec.truth.sensor_pos[k]
        for i in (600, 1000):
            a = (p[i + 1] - 2 * p[i] + p[i - 1]) * ideal_rec.rate_hz**2
            expect = r[k, i].T @ (a + [0, 0, GRAVITY_MPS2])
            assert np.allclose(ideal_rec.acc[k, i], expect, atol=0.05)


def test_noise_differs_from_ideal_by_the_datasheet_density(free_rec, ideal_rec):
    still = slice(20, 190)  # static start
    d = free_rec.gyr[:, still] - ideal_rec.gyr[:, still]
    per_sample = np.degrees(d - d.mean(axis=1, keepdims=True)).std()
    # 0.01 deg/s/sqrt(Hz) at 100 Hz -> 0.1 deg/s per sample, plus 0.061 deg/s LSB
    assert 0.08 < per_sample < 0.13


def test_skin_motion_moves_sensor_but_not_truth(imu_hand):
    m = free_motion(6.0, seed=3)
    a = simulate_imu(m, hand=imu_hand, noise=None)
    b = simulate_imu(m, hand=imu_hand, noise=None, skin=SkinMotion(slide_mm=3, tilt_deg=6))
    assert np.allclose(a.truth.quat, b.truth.quat)
    k = SENSOR_NAMES.index("index_middle")
    assert np.abs(a.truth.sensor_pos[k] - b.truth.sensor_pos[k]).max() > 1e-3
    assert np.abs(a.gyr[k] - b.gyr[k]).max() > 1e-3
    # the model's sites are restored afterwards
    c = simulate_imu(m, hand=imu_hand, noise=None)
    assert np.allclose(a.acc, c.acc)


def test_joint_vectors_are_exact(imu_hand, ideal_rec):
    v = ideal_rec.truth.joint_vectors
    k = SENSOR_NAMES.index("index_middle")
    pts = ideal_rec.truth.keypoints
    from handsynth.sensors.imu import POINTS

    r = quat_to_mat(ideal_rec.truth.quat[k])
    for i in (0, 700):
        rel = ideal_rec.truth.sensor_pos[k, i] - pts[i, POINTS.index("index_pip")]
        assert np.allclose(r[i] @ v[("index_middle", "index_pip")], rel, atol=1e-9)


def test_seed_reproducible(imu_hand):
    m = free_motion(6.0, seed=3)
    a = simulate_imu(m, hand=imu_hand, seed=1)
    b = simulate_imu(m, hand=imu_hand, seed=1)
    c = simulate_imu(m, hand=imu_hand, seed=2)
    assert np.array_equal(a.gyr, b.gyr) and not np.array_equal(a.gyr, c.gyr)
    assert angle_deg(a.truth.quat, c.truth.quat).max() < 1e-4


def test_device_seed_keeps_each_sensors_fixed_errors(imu_hand):
    """Same physical sensors in two recordings: same scale errors and turn-on bias, new noise."""
    import dataclasses

    from handsynth.sensors.imu import MPU9250_DATASHEET, static_motion

    quiet = dataclasses.replace(MPU9250_DATASHEET, gyro=dataclasses.replace(
        MPU9250_DATASHEET.gyro, white=0.0, rate_random_walk=0.0, bias_instability=0.0, lsb=0.0),
        accel=dataclasses.replace(MPU9250_DATASHEET.accel, white=0.0, rate_random_walk=0.0,
                                  bias_instability=0.0, lsb=0.0))
    m = static_motion(0.2)
    ideal = simulate_imu(m, hand=imu_hand, noise=None)
    a = simulate_imu(m, hand=imu_hand, noise=quiet, seed=1, device_seed=7)
    b = simulate_imu(m, hand=imu_hand, noise=quiet, seed=2, device_seed=7)
    c = simulate_imu(m, hand=imu_hand, noise=quiet, seed=1, device_seed=8)
    assert np.allclose(a.acc, b.acc) and np.allclose(a.gyr, b.gyr)
    assert np.abs(a.acc - c.acc).max() > 1e-3                     # other sensors
    assert np.abs(a.acc - ideal.acc).max() > 1e-3                 # the errors are there
    assert not np.allclose(a.mag, b.mag)                          # magnetometer: per recording
    # fixed by sensor name, not by position in the recording
    from handsynth.sensors.imu import ImuHand

    tips = simulate_imu(static_motion(0.2), hand=ImuHand(tip_sensors=True), noise=quiet, seed=3,
                        device_seed=7)
    k = tips.sensors.index("index_distal")
    assert np.allclose(tips.acc[k], a.acc[a.sensors.index("index_distal")])


def test_bias_repeatability_changes_the_bias_between_recordings(imu_hand):
    import dataclasses

    from handsynth.sensors.imu import MPU9250_DATASHEET, AxisNoise, static_motion

    acc = AxisNoise(0.0, 0.0, 0.0, turn_on_bias=0.2, bias_repeatability=0.05)
    noise = dataclasses.replace(MPU9250_DATASHEET, accel=acc)
    m = static_motion(0.2)
    d = [simulate_imu(m, hand=imu_hand, noise=noise, seed=s, device_seed=1).acc[:, 0]
         for s in range(6)]
    change = np.std(np.array(d), axis=0)                          # over recordings, per axis
    assert 0.02 < float(np.sqrt(np.mean(change**2))) < 0.08


def test_skin_motion_is_felt_by_the_sensor(imu_hand):
    """With skin motion the gyro and accelerometer follow the sensor's actual motion."""
    from handsynth.sensors.imu import FLEX_JOINT, MODEL_JOINTS

    skin = SkinMotion(slide_mm=3.0, tilt_deg=8.0)
    rec = simulate_imu(free_motion(6.0, seed=4, speed=2.0), hand=imu_hand, noise=None, skin=skin)
    dt = 1 / rec.rate_hz
    for name in ("index_middle", "little_proximal", "thumb_distal"):
        k = rec.sensors.index(name)
        flex = rec.truth.angles[:, MODEL_JOINTS.index(FLEX_JOINT[name])]
        a = -np.radians(skin.tilt_deg * flex / 90.0)            # tilt about the sensor's x axis
        rx = np.zeros((rec.n, 3, 3))
        rx[:, 0, 0], rx[:, 1, 1], rx[:, 2, 2] = 1.0, np.cos(a), np.cos(a)
        rx[:, 1, 2], rx[:, 2, 1] = -np.sin(a), np.sin(a)
        r = quat_to_mat(rec.truth.quat[k]) @ rx                    # actual sensor -> world
        p = rec.truth.sensor_pos[k]
        gyr_err, acc_err, tilt_rate = [], [], []
        for i in range(450, 590, 7):
            dr = r[i].T @ r[i + 1]
            w = np.array([dr[2, 1] - dr[1, 2], dr[0, 2] - dr[2, 0], dr[1, 0] - dr[0, 1]]) / 2 / dt
            gyr_err.append(np.linalg.norm(w - 0.5 * (rec.gyr[k, i] + rec.gyr[k, i + 1])))
            tilt_rate.append(abs(a[i + 1] - a[i]) / dt)
            acc = r[i].T @ ((p[i + 1] - 2 * p[i] + p[i - 1]) / dt**2 + [0, 0, GRAVITY_MPS2])
            acc_err.append(np.linalg.norm(acc - rec.acc[k, i]))
        # the tilt rate alone is far above what is left
        assert np.max(gyr_err) < 0.02 < 0.2 * np.max(tilt_rate), (name, max(gyr_err))
        assert np.max(acc_err) < 0.05, (name, max(acc_err))


def test_a_drifting_bias_changes_steadily_and_leaves_the_other_draws_alone():
    from handsynth.sensors.imu import AxisNoise, apply_axis_noise

    base = AxisNoise(white=1e-3, rate_random_walk=1e-5, bias_instability=1e-4, turn_on_bias=1e-2)
    drifting = AxisNoise(white=1e-3, rate_random_walk=1e-5, bias_instability=1e-4, turn_on_bias=1e-2,
                         bias_drift_rate=2e-3)
    x = np.zeros((400, 1000, 3))  # 400 sensors, 10 s at 100 Hz
    a = apply_axis_noise(x, base, 100.0, np.random.default_rng(3))
    b = apply_axis_noise(x, drifting, 100.0, np.random.default_rng(3))
    change = b - a  # the same draws but the drift's, which come last
    np.testing.assert_allclose(change[:, 0], 0.0, atol=1e-12)
    slope = change[:, -1] / 9.99
    np.testing.assert_allclose(change[:, 500], slope * 5.0, rtol=1e-9, atol=1e-12)
    assert np.std(slope) == pytest.approx(2e-3, rel=0.1)
    with pytest.raises(InvalidInputError, match="bias_drift_rate"):
        AxisNoise(white=1e-3, rate_random_walk=0.0, bias_instability=0.0, bias_drift_rate=-1.0)
