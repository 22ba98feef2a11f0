import numpy as np

from handsynth.models import JOINT_NAMES
from handsynth.sensors.imu import (
    GRASP_POSES,
    POINTS,
    classify_grasp,
    fingertip_positions,
    joint_angles,
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
