"""Every variant of the MJCF compiles without a MuJoCo warning."""

import mujoco
import numpy as np
import pytest

from handsynth import HandShape
from handsynth.models import NAMED_POSES, HandModel, hand_mjcf, named_pose
from handsynth.render import CameraMount
from handsynth.render._scene import scene_mjcf


@pytest.fixture
def no_warnings():
    caught = []
    old = mujoco.get_mju_user_warning()
    mujoco.set_mju_user_warning(caught.append)
    yield caught
    mujoco.set_mju_user_warning(old)
    assert not caught, f"MuJoCo warned: {caught}"


@pytest.mark.parametrize("side", ["right", "left"])
@pytest.mark.parametrize("forearm", [True, False])
@pytest.mark.parametrize("silhouette", [True, False])
def test_variants_compile_without_warning(side, forearm, silhouette, no_warnings):
    for shape in (HandShape(0.95, 0.9, 0.95, 0.9), HandShape(1.05, 1.1, 1.05, 1.1)):
        for xml in (hand_mjcf(shape, side=side, forearm=forearm, silhouette=silhouette),
                    scene_mjcf(shape, CameraMount.whole_hand(), side=side, forearm=forearm,
                               silhouette=silhouette)):
            m = mujoco.MjModel.from_xml_string(xml)
            d = mujoco.MjData(m)
            for k in range(m.nkey):
                mujoco.mj_resetDataKeyframe(m, d, k)
                mujoco.mj_forward(m, d)
            assert all(w.number == 0 for w in d.warning)
            assert m.nq == 20 and m.nkey == len(NAMED_POSES)


def test_keyframes_are_the_named_poses():
    h = HandModel()
    for k, name in enumerate(NAMED_POSES):
        mujoco.mj_resetDataKeyframe(h.model, h.data, k)
        np.testing.assert_allclose(h.angles, NAMED_POSES[name], atol=1e-9)


def test_flexion_moves_toward_palm_and_abduction_toward_thumb():
    h = HandModel()
    tip0 = h.keypoints()[8]  # index tip
    h.set_pose({"index_pip_flex": 45})
    assert h.keypoints()[8][2] < tip0[2] - 0.01  # toward -z (palm side)
    h.set_pose({"index_mcp_abd": 15})
    assert h.keypoints()[8][0] < tip0[0] - 0.01  # toward -x, the right thumb's side
    h.set_pose({"thumb_cmc_abd": 40})
    assert h.keypoints()[4][2] < -0.03  # palmar abduction of the thumb


def test_hand_frame_definition():
    k = HandModel().keypoints()
    np.testing.assert_allclose(k[0], 0, atol=1e-12)  # wrist at the origin
    middle_mcp = k[9]
    assert middle_mcp[0] == pytest.approx(0, abs=1e-12) and middle_mcp[2] == pytest.approx(0)
    assert middle_mcp[1] > 0.05
    assert k[1][0] < 0 and k[17][0] > 0  # right thumb at -x, little at +x


def test_left_hand_is_the_mirror_image():
    for pose in ("open", "fist", "pinch", "spread"):
        r, l = HandModel(side="right"), HandModel(side="left")
        r.set_pose(named_pose(pose))
        l.set_pose(named_pose(pose))
        np.testing.assert_allclose(l.keypoints(), r.keypoints() * [-1, 1, 1], atol=1e-9)


def test_pinch_closes_thumb_and_index_tips():
    h = HandModel()
    h.set_pose(named_pose("pinch"))
    k = h.keypoints()
    assert np.linalg.norm(k[4] - k[8]) < 0.005
