import numpy as np

from handsynth.models import JOINT_NAMES
from handsynth.sensors.imu import (
    GRASP_POSES,
    POINTS,
    classify_grasp,
    fingertip_positions,
    joint_angles,
    simulate_imu,
    truth_chain_model,
    truth_link_frames,
)


def test_truth_attitudes_give_the_true_finger_angles(imu_hand, ideal_rec):
    model = truth_chain_model(ideal_rec)
    frames = truth_link_frames(ideal_rec, model, imu_hand)
    angles, extra = joint_angles(ideal_rec.truth.quat, ideal_rec.sensors, frames)
    true = ideal_rec.truth.angles[:, 9:]
    # index, middle and little lie in the palm's wrist-flexion frame: exact;
    # the ring finger's MCP angles mix by its 2 deg yaw (abduction offset)
    for name in ("index_pip_flex", "index_dip_flex", "middle_mcp_flex", "middle_mcp_abd",
                 "little_pip_flex", "thumb_ip_flex"):
        j = JOINT_NAMES.index(name)
        assert np.abs(angles[:, j] - true[:, j]).max() < 0.05, name
    assert np.isnan(angles[:, 0]).all() and extra["thumb_cmc_euler"].shape == (ideal_rec.n, 3)


def test_fingertips_by_chaining_exact_links(ideal_rec):
    model = truth_chain_model(ideal_rec)
    tips = fingertip_positions(ideal_rec.truth.quat, ideal_rec.sensors, model)
    kp = ideal_rec.truth.keypoints
    for f in ("thumb", "index", "little"):
        true = kp[:, POINTS.index(f"{f}_tip")] - kp[:, POINTS.index("elbow")]
        assert np.abs(tips[f] - true).max() < 1e-6


def test_grasp_classifier_recovers_perturbed_postures():
    rng = np.random.default_rng(0)
    names = [g for g in GRASP_POSES if g != "open"]
    rows = np.stack([GRASP_POSES[g] + rng.normal(0, 4.0, 20) for g in names])
    rows[:, :2] = np.nan  # the thumb CMC is not measured
    assert classify_grasp(rows, {g: GRASP_POSES[g] for g in names}) == names


def test_thumb_cmc_axes_learnt_from_the_calibration_give_its_canonical_angles(imu_hand,
                                                                             ideal_rec):
    from handsynth.sensors.imu import calibration_motion, thumb_cmc_model

    cal = simulate_imu(calibration_motion(), hand=imu_hand, noise=None)
    model = truth_chain_model(cal)
    frames = truth_link_frames(cal, model, imu_hand)
    cmc = thumb_cmc_model(cal, frames)
    assert np.allclose(np.linalg.norm(cmc.axes, axis=1), 1.0)
    angles, _ = joint_angles(ideal_rec.truth.quat, ideal_rec.sensors, frames, cmc=cmc)
    true = ideal_rec.truth.angles[:, 9:11]
    err = angles[:, :2] - true
    rmse = np.sqrt(np.mean(err**2, axis=0))
    const = np.sqrt(np.mean(true**2, axis=0))  # the zero pose held
    assert np.all(rmse < 1.5) and np.all(rmse < 0.2 * const), (rmse, const)
    # the flexion and abduction rotations are told apart (not one axis twice)
    assert abs(cmc.axes[0] @ cmc.axes[1]) < 0.5
