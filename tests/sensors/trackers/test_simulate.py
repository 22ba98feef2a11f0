import numpy as np
import pytest

from handsynth.errors import InvalidInputError, RecordingError
from handsynth.sensors.common import rotation_error
from handsynth.sensors.trackers import (
    NO_NOISE,
    FingerJoint,
    FlexionMotion,
    HingeJoint,
    Recording,
    SensorMount,
    SensorNoise,
    simulate_recording,
)


def _exact(model, **kw):
    return simulate_recording(
        "index_dip", model=model, noise=NO_NOISE, geometry_source="table",
        motion=FlexionMotion(duration_s=4.0, **kw), seed=0,
    )


def test_truth_is_fixed_in_lower_frame_and_maps_to_world():
    rec = _exact(FingerJoint())
    t = rec.truth
    # the lower-sensor coordinates of the centre never move (bone slides on upper)
    assert np.ptp(t.centre_sensor[:, 1], axis=0).max() < 1e-12
    # the upper-sensor coordinates do move, by about the slide (2.5 mm at 90 deg)
    assert 1e-3 < np.ptp(t.centre_sensor[:, 0], axis=0).max() < 3e-3
    for s in (0, 1):
        world = np.einsum("nij,nj->ni", rec.rotations[:, s], t.centre_sensor[:, s])
        np.testing.assert_allclose(world + rec.positions[:, s], t.centre_world, atol=1e-12)


def test_hinge_centre_fixed_in_both_frames():
    rec = _exact(HingeJoint(), wobble_deg=0.0)
    for s in (0, 1):
        assert np.ptp(rec.truth.centre_sensor[:, s], axis=0).max() < 1e-12
        np.testing.assert_allclose(rec.truth.reference_centre[s], rec.truth.centre_sensor[0, s], atol=1e-12)


def test_rate_duration_and_mount_geometry():
    rec = simulate_recording(motion=FlexionMotion(duration_s=2.0, rate_hz=120.0),
                             noise=NO_NOISE, geometry_source="table",
                             upper_mount=SensorMount(height_mm=9.0, pitch_deg=0.0))
    assert rec.n_frames == 240 and rec.rate_hz == pytest.approx(120.0)
    # upper sensor 9 mm above the bone: centre is 9 mm below it in its frame
    assert rec.truth.reference_centre[0][2] == pytest.approx(-9e-3)
    assert rotation_error(rec.rotations).max() < 1e-9


def test_noise_level_matches_liberty_figure():
    kw = dict(model="hinge", motion=FlexionMotion(duration_s=10.0), geometry_source="table", seed=5)
    clean = simulate_recording(noise=NO_NOISE, **kw)
    noisy = simulate_recording(noise=SensorNoise(position_sd_mm=0.76), **kw)
    sd = (noisy.positions - clean.positions).std() * 1e3
    assert sd == pytest.approx(0.76, rel=0.05)


def test_bad_options_name_the_argument():
    with pytest.raises(InvalidInputError, match="model"):
        simulate_recording(model="wooden")
    with pytest.raises(InvalidInputError, match="joint"):
        simulate_recording("index_knuckle")
    with pytest.raises(InvalidInputError, match="flexion_range_deg"):
        FlexionMotion(flexion_range_deg=(50, 10))
    with pytest.raises(InvalidInputError, match="position_sd_mm"):
        SensorNoise(position_sd_mm=-1)
    with pytest.raises(TypeError):
        FlexionMotion(wobble=3.0)  # typo of wobble_deg


def test_recording_rejects_bad_arrays(finger_rec):
    n = 20
    good = dict(times=np.arange(n) / 240, positions=np.zeros((n, 2, 3)),
                rotations=np.broadcast_to(np.eye(3), (n, 2, 3, 3)))
    Recording(**good)
    pos = good["positions"].copy()
    pos[7, 1, 0] = np.nan
    with pytest.raises(RecordingError, match=r"NaN.*\[7\]"):
        Recording(**{**good, "positions": pos})
    rot = np.array(good["rotations"])
    rot[3, 0] *= 1.1
    with pytest.raises(RecordingError, match="not rotations.*index \\(3, 0\\)"):
        Recording(**{**good, "rotations": rot})
    with pytest.raises(RecordingError, match="increase"):
        Recording(**{**good, "times": np.zeros(n)})
    with pytest.raises(RecordingError, match="shape"):
        Recording(**{**good, "positions": np.zeros((n, 3))})
    assert not finger_rec.positions.flags.writeable


def test_geometry_from_mujoco_hand_matches_its_keypoints():
    from handsynth import models
    from handsynth.sensors.trackers import joint_geometry

    hand = models.HandModel(models.HandShape())
    hand.set_pose(np.zeros(20))
    kp = np.asarray(hand.keypoints())
    g = joint_geometry("index_dip", hand=hand)
    assert g.source == "model"
    # index: keypoints 5..8 = MCP, PIP, DIP, tip
    assert g.upper_length == pytest.approx(np.linalg.norm(kp[7] - kp[6]), abs=1e-6)
    assert g.lower_length == pytest.approx(np.linalg.norm(kp[8] - kp[7]), abs=1e-6)
    np.testing.assert_allclose(g.upper_rotation.T @ g.upper_rotation, np.eye(3), atol=1e-12)
    assert g.upper_rotation[2, 2] > 0.99  # segment +z is the hand's dorsal +z
    rec = simulate_recording("index_dip", hand=hand, noise=NO_NOISE,
                             motion=FlexionMotion(duration_s=2.0), seed=0)
    np.testing.assert_allclose(rec.truth.centre_world[0], kp[7], atol=1e-9)


@pytest.mark.parametrize("joint", ["index_pip", "index_dip", "middle_pip", "ring_dip",
                                   "little_pip", "thumb_ip"])
def test_table_geometry_is_the_hand_models_buchholz_table_1(joint):
    # one source: the table's phalanges are the model's coefficients times its hand length
    from handsynth.models import HAND_LENGTH_MM, SEGMENT_COEFFICIENTS
    from handsynth.sensors.trackers import joint_geometry

    finger, j = joint.split("_")
    i_up = {"pip": 1, "dip": 2, "ip": 1}[j]  # index into (metacarpal, proximal, ...)
    coeff = SEGMENT_COEFFICIENTS[finger]
    g = joint_geometry(joint, source="table")
    assert g.source == "table"
    assert g.upper_length == pytest.approx(coeff[i_up] * HAND_LENGTH_MM / 1e3, abs=1e-12)
    assert g.lower_length == pytest.approx(coeff[i_up + 1] * HAND_LENGTH_MM / 1e3, abs=1e-12)
    if j == "dip":  # the upper segment starts one proximal phalanx beyond the MCP
        mcp = joint_geometry(f"{finger}_pip", source="table").upper_origin
        assert g.upper_origin[1] - mcp[1] == pytest.approx(coeff[1] * HAND_LENGTH_MM / 1e3, abs=1e-12)


@pytest.mark.parametrize("joint", ["index_pip", "ring_pip", "little_dip", "thumb_ip"])
def test_table_geometry_is_a_right_hand_as_the_model_is(joint):
    # the simulated hand is a right hand: each finger on the side the model's right hand has it
    # (the index and thumb at -x, the ring and little fingers at +x), never mirrored
    from handsynth.models import HandModel, HandShape
    from handsynth.sensors.trackers import joint_geometry

    hand = HandModel(HandShape(), side="right")
    hand.set_pose(np.zeros(20))
    kp = np.asarray(hand.keypoints())
    finger = joint.split("_")[0]
    base = kp[1 + 4 * ("thumb", "index", "middle", "ring", "little").index(finger)]
    table = joint_geometry(joint, source="table").upper_origin
    model = joint_geometry(joint, hand=hand).upper_origin
    assert np.sign(table[0]) == np.sign(base[0]) == np.sign(model[0])
    assert abs(table[0] - model[0]) < 0.025  # a rough placement, on the model's side
