import numpy as np
import pytest

from handsynth.errors import InvalidInputError
from handsynth.models import JOINT_LIMITS_DEG, JOINT_NAMES
from handsynth.sensors.imu import (
    GRASP_POSES,
    POINTS,
    angles_beyond_range,
    bone_lengths_mm,
    classify_grasp,
    fingertip_positions,
    hand_attitude,
    joint_angles,
    simulate_imu,
    truth_chain_model,
    truth_hand_attitude,
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


def _true_bones_mm(keypoints, names) -> dict[str, np.ndarray]:
    """Each BVH bone's true length, mm, from (..., P, 3) keypoints (m) named by `names`."""
    from handsynth.models import BVH_BONE_STARTS

    return {bone: 1e3 * np.linalg.norm(keypoints[..., names.index(bone), :]
                                       - keypoints[..., names.index(start), :], axis=-1)
            for bone, start in BVH_BONE_STARTS.items()}


def test_bone_lengths_of_exact_links_are_the_hands(ideal_rec):
    model = truth_chain_model(ideal_rec)
    got = bone_lengths_mm(fingertip_positions(ideal_rec.truth.quat, ideal_rec.sensors, model))
    true = _true_bones_mm(ideal_rec.truth.keypoints, POINTS)
    assert sorted(got) == sorted(true)
    for bone, lengths in true.items():
        assert got[bone] == pytest.approx(float(np.median(lengths)), abs=1e-6), bone
    # only the ring and little MCPs, across the hand's ulnar CM joint, change with the pose
    moving = {b for b, v in true.items() if np.ptp(v) > 1e-6}
    assert moving <= {"ring_mcp", "little_mcp"}


@pytest.mark.slow
def test_bone_lengths_measured_by_a_calibration_of_a_short_hand():
    """A calibration of a hand with short fingers and a narrow palm measures its bones far
    nearer than the standard hand's are (skin motion, mounting errors, noise)."""
    import warnings

    from handsynth.models import KEYPOINT_SITES, HandModel, HandShape
    from handsynth.sensors.imu import (
        ImuHand,
        ImuPlacement,
        SkinMotion,
        calibrate,
        calibration_motion,
        free_motion,
    )

    shape = HandShape(length=0.9, palm=0.93, thumb=1.08)
    rng = np.random.default_rng(3)
    placement = ImuPlacement(tilts_deg={s: tuple(rng.normal(0, 4, 3)) for s in ImuHand().sensors})
    skin = SkinMotion(2.0, 4.0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the simulated disturbance and still-start notes
        cal = calibrate(simulate_imu(calibration_motion(acc_poses=True),
                                     hand=ImuHand(shape, placement=placement, tip_sensors=True),
                                     skin=skin, seed=21, device_seed=22))
        rec = simulate_imu(free_motion(6.0, seed=23), hand=ImuHand(shape, placement=placement),
                           skin=skin, seed=24, device_seed=22)
    res = cal.track(rec)
    got = bone_lengths_mm(res["chains"])
    true = {b: float(np.median(v))
            for b, v in _true_bones_mm(rec.truth.keypoints, POINTS).items()}
    standard = _true_bones_mm(HandModel(HandShape(), forearm=False).keypoints(),
                              list(KEYPOINT_SITES))  # the open hand
    err = np.array([got[b] - true[b] for b in true])
    err_std = np.array([standard[b] - true[b] for b in true])
    assert np.abs(err).max() < 5.0, str({b: round(float(e), 1) for b, e in zip(true, err)})
    assert np.abs(err).mean() < 0.6 * np.abs(err_std).mean(), (np.abs(err).mean(),
                                                                np.abs(err_std).mean())


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


def _within_range(n=200, seed=0):
    rng = np.random.default_rng(seed)
    lo, hi = JOINT_LIMITS_DEG[:, 0], JOINT_LIMITS_DEG[:, 1]
    return lo + (hi - lo) * rng.random((n, len(JOINT_NAMES)))


def test_angles_within_the_range_of_motion_say_nothing():
    angles = _within_range()
    angles[:, 0] = np.nan  # a thumb CMC not read
    assert angles_beyond_range(angles) is None
    # a hypermobile joint 25 deg past its range: within the margin
    angles[:, JOINT_NAMES.index("index_pip_flex")] = -30.0
    assert angles_beyond_range(angles) is None
    assert angles_beyond_range(np.empty((0, 20))) is None


def test_angles_beyond_the_range_name_the_joints_and_the_sensor_they_share():
    angles = _within_range()
    pip, dip = JOINT_NAMES.index("index_pip_flex"), JOINT_NAMES.index("index_dip_flex")
    angles[:100, pip] = -170.0       # half the samples
    angles[:, dip] = -175.0
    msg = angles_beyond_range(angles)
    assert msg.startswith("2 joint angles read more than 30 deg beyond the hand's range of motion: "
                          "index_pip_flex in 50 % of the samples (-170 deg; range -5 to 100); "
                          "index_dip_flex in 100 % of the samples (-175 deg; range -10 to 90)")
    # index_middle is a sensor of both joints (PIP: proximal-middle, DIP: middle-distal)
    assert "Most likely sensor index_middle (a sensor of 2 of those 2 joints)" in msg
    # one joint: either of its two sensors
    one = _within_range()
    one[:, pip] = 150.0
    assert "Most likely sensor index_proximal or index_middle turned" in angles_beyond_range(one)
    # a flexion and an abduction of one joint count as one joint
    cmc = _within_range()
    cmc[:, 0], cmc[:, 1] = 120.0, -136.0
    assert "sensor hand_radial or thumb_metacarpal" in angles_beyond_range(cmc)
    # fewer samples than min_share: nothing said
    few = _within_range()
    few[:5, pip] = -170.0
    assert angles_beyond_range(few) is None
    assert "index_pip_flex in 2 %" in angles_beyond_range(few, min_share=0.02)


@pytest.mark.parametrize(("kwargs", "message"), [
    ({"angles": np.zeros((10, 19))}, r"angles must have shape \(N, 20\).*got \(10, 19\)"),
    ({"angles": np.zeros(20)}, r"got \(20,\)"),
    ({"angles": np.zeros((3, 20)), "margin_deg": -1}, "margin_deg must be a finite number >= 0"),
    ({"angles": np.zeros((3, 20)), "min_share": 0}, "min_share must be a finite number > 0"),
    ({"angles": np.zeros((3, 20)), "min_share": "5 %"}, "min_share"),
])
def test_angles_beyond_range_refuses_bad_arguments(kwargs, message):
    with pytest.raises(InvalidInputError, match=message):
        angles_beyond_range(**kwargs)


def test_truth_attitudes_give_the_true_hand_attitude(imu_hand, ideal_rec):
    """The hand sensor's true attitude turned by its true link frame is the palm's."""
    from handsynth.sensors.imu._quat import quat_to_mat

    frames = truth_link_frames(ideal_rec, truth_chain_model(ideal_rec), imu_hand)
    got = quat_to_mat(hand_attitude(ideal_rec.truth.quat, ideal_rec.sensors, frames))
    np.testing.assert_allclose(got, truth_hand_attitude(ideal_rec, imu_hand), atol=1e-6)


@pytest.mark.parametrize("side", ["right", "left"])
def test_hand_attitude_is_the_hand_frames(worn, side):
    import warnings

    from handsynth.sensors.imu import ImuHand, calibrate, calibration_motion, free_motion
    from handsynth.sensors.imu._quat import quat_to_mat

    cal, rec = worn
    hand = ImuHand(side=side)
    if side == "left":
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # the simulated disturbance and still-start notes
            cal = calibrate(simulate_imu(calibration_motion(),
                                         hand=ImuHand(side="left", tip_sensors=True), seed=1,
                                         device_seed=2), sensor_calibration=False, side="left")
            rec = simulate_imu(free_motion(12.0, seed=3), hand=hand, seed=4, device_seed=2)
    res = cal.track(rec)
    est = quat_to_mat(hand_attitude(res["quat"], cal.sensors, cal.frames))
    true = truth_hand_attitude(rec, hand)

    def angle(a, b):
        cos = (np.einsum("nij,nij->n", a, b) - 1.0) / 2.0
        return np.degrees(np.arccos(np.clip(cos, -1.0, 1.0)))

    err = angle(est, true)
    held = angle(np.broadcast_to(est[:1], est.shape), true)  # the first attitude held
    # 1.6-2.0 deg, nearly constant: the link frame's axes as the calibration found them
    rms = np.sqrt(np.mean(err ** 2))
    assert rms < 3.0 and rms < 0.3 * np.sqrt(np.mean(held ** 2)), rms
    with pytest.raises(InvalidInputError, match="hand_radial"):
        keep = [i for i, name in enumerate(cal.sensors) if name != "hand_radial"]
        hand_attitude(res["quat"][keep], [cal.sensors[i] for i in keep], cal.frames)
