import numpy as np
import pytest

from handsynth.errors import InvalidInputError
from handsynth.sensors.imu import (
    MODEL_JOINTS,
    calibration_motion,
    free_motion,
    grasp_motion,
    pose_motion,
)


@pytest.mark.parametrize("make", [
    lambda: free_motion(8.0, seed=1),
    lambda: free_motion(8.0, seed=2, elbow="moving", speed=1.5),
    lambda: grasp_motion(("power_sphere",)),
    lambda: pose_motion(np.full((2, 20), 10.0), elbow="moving", seed=3),
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


def test_pose_motion_holds_each_pose_within_the_range():
    from handsynth.models import JOINT_LIMITS_DEG, JOINT_NAMES

    poses = np.array([np.full(20, 10.0), np.full(20, 30.0)])
    poses[1, JOINT_NAMES.index("index_mcp_abd")] = 35.0  # beyond its 20-deg range
    m = pose_motion(poses, names=["ten", "thirty"], move_s=0.5, hold_s=1.0)
    assert m.label == "poses" and [s for s, _, _ in m.segments] == ["static", "align", "ten",
                                                                   "thirty"]
    hand = [MODEL_JOINTS.index(n) for n in JOINT_NAMES]
    for (name, a, b), pose in zip(m.segments[2:], np.clip(poses, *JOINT_LIMITS_DEG.T)):
        np.testing.assert_allclose(m.q[a:b, hand], np.broadcast_to(pose, (b - a, 20)), atol=1e-9,
                                   err_msg=name)
    np.testing.assert_allclose(m.q[-1, hand], 0.0, atol=1e-9)  # released to the open hand


@pytest.mark.parametrize("kwargs, message", [
    ({"poses": np.zeros((0, 20))}, r"shape \(K, 20\)"),
    ({"poses": np.zeros((2, 19))}, r"shape \(K, 20\)"),
    ({"poses": np.full((1, 20), np.nan)}, "finite"),
    ({"poses": np.zeros((2, 20)), "names": ["a"]}, "name each of the 2 poses"),
    ({"poses": np.zeros((1, 20)), "elbow": "swaying"}, "elbow"),
])
def test_pose_motion_refuses_what_it_cannot_move_through(kwargs, message):
    with pytest.raises(InvalidInputError, match=message):
        pose_motion(**kwargs)
