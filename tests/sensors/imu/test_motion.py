import numpy as np
import pytest

from handsynth.errors import InvalidInputError
from handsynth.sensors.imu import (
    MODEL_JOINTS,
    calibration_motion,
    free_motion,
    grasp_motion,
)


@pytest.mark.parametrize("make", [
    lambda: free_motion(8.0, seed=1),
    lambda: free_motion(8.0, seed=2, elbow="moving", speed=1.5),
    lambda: grasp_motion(("power_sphere",)),
])
def test_derivatives_are_consistent(make):
    m = make()
    dt = 1 / m.rate_hz
    num_v = np.gradient(m.q, dt, axis=0)
    num_a = np.gradient(m.qd, dt, axis=0)
    scale_v = np.abs(m.qd).max(axis=0) + 1e-9
    scale_a = np.abs(m.qdd).max(axis=0) + 1e-9
    assert np.all(np.abs(num_v - m.qd)[2:-2].max(axis=0) <= 0.02 * scale_v + 1e-6)
    assert np.all(np.abs(num_a - m.qdd)[2:-2].max(axis=0) <= 0.06 * scale_a + 1e-6)


def test_static_start_and_alignment_rotation():
    m = free_motion(8.0, seed=1)
    assert m.segments[0] == ("static", 0, 200)
    assert np.allclose(m.qd[:200], 0)
    align = m.qd[200:400, MODEL_JOINTS.index("elbow_flex")]
    assert np.abs(align).max() > 50  # deg/s


def test_elbow_fixed_or_moving():
    fixed = free_motion(8.0, seed=1)
    moving = free_motion(8.0, seed=1, elbow="moving")
    assert np.allclose(fixed.q[:, :3], 0)
    assert np.abs(moving.q[:, :3]).max() > 0.005


def test_calibration_rotates_one_joint_at_a_time():
    m = calibration_motion(cycles=2)
    for label, a, b in m.segments[1:]:
        moving = np.nonzero(np.abs(m.qd[a:b]).max(axis=0) > 1e-6)[0]
        assert [MODEL_JOINTS[j] for j in moving] == [label]


def test_bad_options_raise():
    with pytest.raises(InvalidInputError, match="elbow"):
        free_motion(8.0, elbow="loose")
    with pytest.raises(InvalidInputError, match="grasp 'fist2'"):
        grasp_motion(("fist2",))


def test_grasp_motion_names_an_elbow_it_does_not_know():
    # before, any value but "moving" silently meant a fixed elbow
    from handsynth.sensors.imu import grasp_motion

    with pytest.raises(InvalidInputError, match=r"^elbow must be 'fixed' or 'moving', got 'Moving'$"):
        grasp_motion(elbow="Moving")
