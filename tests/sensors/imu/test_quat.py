import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from handsynth.sensors.imu._quat import (
    angle_deg,
    euler_zyx_to_quat,
    heading_inclination_deg,
    mat_to_quat,
    qexp,
    qmul,
    quat_from_acc_mag,
    quat_to_mat,
)


def test_matrix_round_trip_and_product():
    r = Rotation.random(6, random_state=0)
    q = mat_to_quat(r.as_matrix())
    assert np.allclose(quat_to_mat(q), r.as_matrix())
    q2 = mat_to_quat(r[::-1].as_matrix())
    assert np.allclose(quat_to_mat(qmul(q, q2)), (r * r[::-1]).as_matrix())


def test_euler_zyx_matches_eq_2_7():
    phi, theta, psi = 0.3, -0.4, 1.2
    ref = Rotation.from_euler("ZYX", [psi, theta, phi]).as_matrix()
    assert np.allclose(quat_to_mat(euler_zyx_to_quat(phi, theta, psi)), ref)


def test_attitude_from_gravity_and_compass():
    r = Rotation.random(5, random_state=1).as_matrix()
    g, m = np.array([0, 0, 9.81]), np.array([30.7, 0, -35.6])
    acc, mag = np.einsum("nji,j->ni", r, g), np.einsum("nji,j->ni", r, m)
    assert angle_deg(quat_from_acc_mag(acc, mag), mat_to_quat(r)).max() < 1e-4


def test_heading_and_inclination_split():
    q = mat_to_quat(Rotation.random(3, random_state=2).as_matrix())
    h, i = heading_inclination_deg(qmul(qexp([0, 0, np.radians(7)]), q), q)
    assert np.allclose(h, 7.0) and np.allclose(i, 0.0, atol=1e-4)
    h, i = heading_inclination_deg(qmul(qexp([np.radians(5), 0, 0]), q), q)
    assert np.allclose(h, 0.0, atol=1e-4) and i == pytest.approx(np.full(3, 5.0))
