import numpy as np
import pytest

from handsynth.errors import InvalidInputError
from handsynth.models import KEYPOINT_SITES, HandModel
from handsynth.sensors.imu import (
    EARTH_FIELD_UT,
    GRAVITY_MPS2,
    MODEL_JOINTS,
    SENSOR_NAMES,
    ImuHand,
    ImuPlacement,
)


def test_twenty_sensors_with_three_channels(imu_hand):
    assert len(SENSOR_NAMES) == 20
    assert imu_hand.model.nsensor == 60


def test_static_zero_pose_reads_gravity_and_field(imu_hand):
    imu_hand.set_state(np.zeros(len(MODEL_JOINTS)))
    sd = imu_hand.data.sensordata
    for s in SENSOR_NAMES:
        a = sd[imu_hand.sensor_adr[(s, "acc")]:][:3]
        g = sd[imu_hand.sensor_adr[(s, "gyr")]:][:3]
        m = sd[imu_hand.sensor_adr[(s, "mag")]:][:3]
        assert np.linalg.norm(a) == pytest.approx(GRAVITY_MPS2)
        assert np.allclose(g, 0)
        assert np.linalg.norm(m) == pytest.approx(np.linalg.norm(EARTH_FIELD_UT))


def test_hand_geometry_matches_the_plain_model(imu_hand):
    """With the arm at zero, finger keypoints relative to the wrist equal HandModel's."""
    plain = HandModel()
    pose = np.zeros(len(MODEL_JOINTS))
    pose[MODEL_JOINTS.index("index_pip_flex")] = 40.0
    plain.set_pose(pose[9:])
    imu_hand.set_state(pose)
    d = imu_hand.data
    wrist = d.site_xpos[imu_hand.model.site("wrist").id]
    for name in ("index_tip", "thumb_tip", "middle_pip"):
        got = d.site_xpos[imu_hand.model.site(name).id] - wrist
        assert np.allclose(got, plain.keypoints()[KEYPOINT_SITES.index(name)], atol=1e-9)


def test_ring_little_on_cm_hinge(imu_hand):
    pose = np.zeros(len(MODEL_JOINTS))
    imu_hand.set_state(pose)
    d, m = imu_hand.data, imu_hand.model
    before = d.site_xpos[m.site("little_tip").id].copy(), d.site_xpos[m.site("index_tip").id].copy()
    pose[MODEL_JOINTS.index("ulnar_cm_flex")] = 20.0
    imu_hand.set_state(pose)
    assert np.linalg.norm(d.site_xpos[m.site("little_tip").id] - before[0]) > 0.01
    assert np.allclose(d.site_xpos[m.site("index_tip").id], before[1])


def test_placement_validation_names_the_problem():
    with pytest.raises(InvalidInputError, match="unknown sensor 'thumbb'"):
        ImuPlacement(tilts_deg={"thumbb": (1, 0, 0)})
    with pytest.raises(InvalidInputError, match="along"):
        ImuPlacement(along=1.5)


def test_tilt_moves_the_sensor_frame(imu_hand):
    h = ImuHand(placement=ImuPlacement(tilts_deg={"index_distal": (0, 0, 30)}))
    heading = []
    for hand in (imu_hand, h):
        hand.set_state(np.zeros(len(MODEL_JOINTS)))
        m = hand.data.sensordata[hand.sensor_adr[("index_distal", "mag")]:][:3]
        heading.append(np.degrees(np.arctan2(m[1], m[0])))
    # turning the sensor 30 deg about its z turns the field -30 deg in its frame
    assert heading[1] - heading[0] == pytest.approx(-30.0, abs=1e-6)


@pytest.mark.parametrize("side", ["right", "left"])
@pytest.mark.parametrize("tips", [True, False])
def test_the_imu_arm_compiles_without_warning_and_uses_its_classes(side, tips):
    import xml.etree.ElementTree as ET

    import mujoco

    from handsynth.models import HandShape
    from handsynth.sensors.imu import ImuPlacement, imu_hand_mjcf

    caught: list = []
    old = mujoco.get_mju_user_warning()
    mujoco.set_mju_user_warning(caught.append)

    placement = ImuPlacement(tilts_deg={"index_distal": (5.0, 0.0, 0.0)})
    xml = imu_hand_mjcf(HandShape(1.05, 1.1, 1.05, 1.1), side=side, placement=placement,
                        tip_sensors=tips)
    try:
        m = mujoco.MjModel.from_xml_string(xml)
        d = mujoco.MjData(m)
        mujoco.mj_forward(m, d)
    finally:
        mujoco.set_mju_user_warning(old)
    assert not caught and all(w.number == 0 for w in d.warning)
    root = ET.fromstring(xml)
    assert root.get("model") == f"handsynth_{side}_imu_arm"
    sites = [s for s in root.iter("site") if s.get("name", "").startswith("imu_")]
    assert sites and all(s.get("class") == "imu" and "size" not in s.attrib for s in sites)
    assert [g.get("class") for g in root.iter("geom") if g.get("fromto")] == ["arm"]
