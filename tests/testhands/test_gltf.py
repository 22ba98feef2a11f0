"""The realistic skinned glTF hands shipped in handsynth/testhands/data as test hands."""

import json

import numpy as np
import pytest

from handsynth import CameraMount
from handsynth.errors import InvalidInputError, InvalidPoseError
from handsynth.models import HandModel, named_pose
from handsynth.render import SilhouetteRenderer, preprocess
from handsynth.testhands import (
    TEST_HANDS,
    MeshHandRenderer,
    default_mesh_path,
    load_mesh_rig,
    shipped_hand_path,
)

MESH = default_mesh_path()

W, H = 360, 240


@pytest.fixture(scope="module")
def whole():
    with MeshHandRenderer(CameraMount.whole_hand(), width_px=W, height_px=H) as r:
        yield r


@pytest.fixture(scope="module")
def paper():
    with MeshHandRenderer(width_px=W, height_px=H) as r:
        yield r


def _iou(a, b):
    return (a & b).sum() / (a | b).sum()


def test_rig_is_a_right_hand_with_the_named_bones():
    rig = load_mesh_rig()
    assert rig.source_side == "right"
    assert len(rig.vertices) > 1000 and rig.faces.max() < len(rig.vertices)
    np.testing.assert_allclose(rig.bone_weight.sum(axis=1), 1.0, atol=1e-6)
    # the hand frame of the README: wrist at the origin, middle MCP on +y
    np.testing.assert_allclose(rig.joints["wrist"], 0.0, atol=1e-12)
    assert abs(rig.joints["middle_proximal"][0]) < 1e-9 and abs(rig.joints["middle_proximal"][2]) < 1e-9
    assert rig.joints["thumb_proximal"][0] < -0.03  # right thumb at -x
    # the rest pose fingers curl toward the palm (-z)
    for f in ("index", "middle", "ring", "little"):
        assert rig.joints[f"{f}_tip"][2] < rig.joints[f"{f}_proximal"][2] - 0.01


def test_size_is_a_real_hand(whole):
    # metres as in the file: wrist node to middle fingertip; handsynth's is 187 mm
    assert 170.0 < whole.hand_length_mm < 240.0
    kp = whole.keypoints()
    assert kp.shape == (21, 3)
    # the open pose is the model's zero pose: fingers straight in the palm plane
    for k in range(4):
        chain = kp[5 + 4 * k: 9 + 4 * k]
        np.testing.assert_allclose(chain[:, 2], chain[0, 2], atol=1e-9)


def test_open_keypoints_are_near_the_model_hand(whole):
    kp = whole.keypoints()
    ref = HandModel(forearm=False).keypoints()
    d_mm = np.linalg.norm(kp - ref, axis=1) * 1e3
    assert d_mm[0] == 0.0
    assert d_mm[1] < 15.0                 # thumb CMC
    assert d_mm.max() < 35.0              # the mesh's palm is ~25 mm longer than the model's
    assert d_mm.mean() < 25.0


def test_joint_senses_follow_the_readme(whole):
    kp0 = whole.keypoints()
    # flexion toward the palm (-z), abduction toward the thumb (-x for a right hand)
    kp = whole.keypoints({"index_mcp_flex": 45.0})
    assert kp[8, 2] < kp0[8, 2] - 0.03
    kp = whole.keypoints({"index_mcp_abd": 15.0, "little_mcp_abd": 15.0})
    assert kp[8, 0] < kp0[8, 0] - 0.01 and kp[20, 0] < kp0[20, 0] - 0.005
    # thumb MCP/IP flexion curls the thumb across the palm (toward +x) and palmar
    kp = whole.keypoints({"thumb_mcp_flex": 60.0, "thumb_ip_flex": 60.0})
    assert kp[4, 0] > kp0[4, 0] + 0.04 and kp[4, 2] < kp0[4, 2]
    # palmar abduction takes the thumb away from the palm plane (-z)
    kp = whole.keypoints({"thumb_cmc_abd": 60.0})
    assert kp[4, 2] < kp0[4, 2] - 0.04
    # a rigid palm: MCPs and the thumb CMC never move
    kp = whole.keypoints(named_pose("fist"))
    np.testing.assert_allclose(kp[[0, 1, 5, 9, 13, 17]], kp0[[0, 1, 5, 9, 13, 17]])


def test_open_pose_lies_inside_the_frame_with_sensible_size(whole, paper):
    model = SilhouetteRenderer(mount=CameraMount.whole_hand(), width_px=W, height_px=H,
                               forearm=False)
    m = whole.mask(named_pose("open"))
    ref = model.mask(named_pose("open"))
    assert not (m[0].any() or m[-1].any() or m[:, 0].any() or m[:, -1].any())
    assert 0.7 < m.sum() / ref.sum() < 1.6
    rows, cols = np.nonzero(m)
    ref_rows, ref_cols = np.nonzero(ref)
    assert abs(rows.mean() - ref_rows.mean()) < 0.1 * H
    assert abs(cols.mean() - ref_cols.mean()) < 0.15 * W
    # the paper's device at 120 mm sees the back of the hand in the middle of the frame
    p = paper.mask(named_pose("open"))
    assert p[H // 2, W // 2] and 0.25 < p.mean() < 0.8
    assert _iou(preprocess(p, paper.mount), preprocess(
        SilhouetteRenderer(width_px=W, height_px=H).mask(named_pose("open")), paper.mount)) > 0.5


def test_index_pip_flexion_moves_only_index_finger_pixels(whole):
    import cv2

    open_pose = named_pose("open")
    bent = open_pose.copy()
    bent[6] = 60.0  # index_pip_flex
    a, b = whole.mask(open_pose), whole.mask(bent)
    changed = a ^ b
    assert changed.sum() > 50
    # everything that changed lies on the index finger's middle/distal segments
    rig = whole.rig
    moving = [rig.bone(n) for n in ("index_intermediate", "index_distal", "index_tip")]
    on_index = np.isin(rig.bone_index, moving) & (rig.bone_weight > 0)
    faces = rig.faces[np.any(on_index.any(axis=1)[rig.faces], axis=1)]
    region = np.zeros((H, W), np.uint8)
    for pose in (open_pose, bent):
        uv = whole.mount.project(whole.vertices(pose), width_px=W, height_px=H)
        cv2.fillPoly(region, [np.round(uv[f] * 4).astype(np.int32) for f in faces], 1, shift=2)
    region = cv2.dilate(region, np.ones((5, 5), np.uint8)).astype(bool)
    assert not (changed & ~region).any()
    # and the finger's projection gets shorter: it points to the image's right
    tip_open, tip_bent = (whole.mount.project(whole.keypoints(p)[8:9], width_px=W, height_px=H)[0]
                          for p in (open_pose, bent))
    assert tip_bent[0] < tip_open[0] - 10
    cols = np.nonzero(region.any(axis=0))[0]
    band = np.zeros(W, bool)
    band[cols.min():cols.max() + 1] = True
    rows = np.nonzero(region.any(axis=1))[0]
    ext_open = np.nonzero(a[rows.min():rows.max() + 1][:, band].any(axis=0))[0].max()
    ext_bent = np.nonzero(b[rows.min():rows.max() + 1][:, band].any(axis=0))[0].max()
    assert b.sum() < a.sum()
    assert ext_bent <= ext_open


def test_masks_are_deterministic_and_batch_equals_single(paper):
    poses = np.stack([named_pose("pinch"), named_pose("fist")])
    batch = paper.masks(poses)
    assert batch.shape == (2, H, W) and batch.dtype == bool
    np.testing.assert_array_equal(paper.masks(poses), batch)
    for p, m in zip(poses, batch):
        np.testing.assert_array_equal(paper.mask(p), m)
    assert (batch[0] ^ batch[1]).sum() > 100


def test_mujoco_skin_equals_the_numpy_skinning(paper):
    pose = named_pose("grasp")
    paper.mask(pose)
    skinned = np.array(paper._renderer.scene.skinvert).reshape(-1, 3)[: len(paper.rig.vertices)]
    np.testing.assert_allclose(skinned, paper.vertices(pose), atol=1e-6)
    assert np.abs(paper.vertices(pose) - paper.vertices(named_pose("open"))).max() > 0.05


def test_left_hand_is_the_mirror_image():
    kw = {"width_px": W, "height_px": H}
    with MeshHandRenderer(**kw) as r, MeshHandRenderer(side="left", **kw) as left:
        for pose in ("open", "grasp"):
            a, b = r.mask(named_pose(pose)), left.mask(named_pose(pose))
            assert _iou(a, b[::-1]) > 0.98
            assert _iou(a, b) < 0.9
            skinned = np.array(left._renderer.scene.skinvert).reshape(-1, 3)
            np.testing.assert_allclose(skinned[: len(left.rig.vertices)],
                                       left.vertices(named_pose(pose)), atol=1e-6)
        np.testing.assert_allclose(left.keypoints()[:, 0], -r.keypoints()[:, 0])


@pytest.mark.parametrize("bad", [
    np.full(20, np.nan),
    np.r_[np.zeros(19), 500.0],
    np.zeros(7),
    {"index_pip_flx": 10.0},
])
def test_bad_angles_raise(paper, bad):
    with pytest.raises(InvalidPoseError):
        paper.mask(bad)
    with pytest.raises(InvalidPoseError):
        paper.masks(np.atleast_2d(bad) if not isinstance(bad, dict) else bad)


def test_measurements_select_a_database(whole):
    from handsynth.estimate import select_shape
    from handsynth.models import model_measurements

    m = whole.measurements()
    ref = model_measurements()
    ratios = np.array(m.L) / np.array(ref.L)
    assert np.all((ratios > 0.6) & (ratios < 1.8))
    assert np.all((np.array(m.W) > 10.0) & (np.array(m.W) < 30.0))
    assert 70.0 < m.P_width < 110.0 and 90.0 < m.P_height < 130.0
    assert select_shape(m).shape.name  # formulas (1)-(4) accept it


def test_missing_or_malformed_file_is_a_clear_error(tmp_path):
    with pytest.raises(InvalidInputError, match="does not exist"):
        MeshHandRenderer(path=tmp_path / "nope.gltf")
    doc = json.loads(MESH.read_text())
    doc["accessors"][0]["componentType"] = 1234
    bad = tmp_path / "bad.gltf"
    bad.write_text(json.dumps(doc))
    with pytest.raises(InvalidInputError, match=r"accessors\[0\]\.componentType"):
        load_mesh_rig(bad)
    doc = json.loads(MESH.read_text())
    for n in doc["nodes"]:
        n["name"] = n.get("name", "").replace("Ring", "Fourth")
    bad.write_text(json.dumps(doc))
    with pytest.raises(InvalidInputError, match="ring_proximal"):
        load_mesh_rig(bad)


@pytest.mark.parametrize("name", sorted(TEST_HANDS))
def test_every_shipped_hand_has_its_licence(name):
    path = shipped_hand_path(name)
    assert path.is_file() and any(p.name.lower().startswith("license") for p in path.parent.iterdir())


@pytest.mark.parametrize("name", sorted(TEST_HANDS))
def test_every_shipped_hand_is_a_right_hand_of_adult_size_seen_by_the_device(name):
    from handsynth.testhands import PROTOCOL_HANDS

    assert set(PROTOCOL_HANDS) <= set(TEST_HANDS)
    with MeshHandRenderer(width_px=W, height_px=H, path=shipped_hand_path(name)) as r:
        assert r.rig.source_side == "right" and 180.0 < r.hand_length_mm < 230.0
        m = r.mask(named_pose("open"))
        assert m[H // 2, W // 2] and 0.25 < m.mean() < 0.8
        assert r.mask(named_pose("fist")).sum() < 0.8 * m.sum()


def test_binary_gltf_with_nodes_one_joint_proximal_of_their_names_loads():
    # The MRTK hand (GLB) puts each node one joint proximal of its OpenXR name
    # (node index_intermediate at the index MCP, index_tip_end at the fingertip)
    # and has no wrist bone: the rig is renamed one step distal.
    from handsynth.testhands._gltf import _Gltf

    g = _Gltf(shipped_hand_path("mrtk"))
    rig = load_mesh_rig(shipped_hand_path("mrtk"))
    world = g.node_world()
    node = {str(n.get("name")): i for i, n in enumerate(g.doc["nodes"])}
    for canonical, name in (("index_proximal", "index_intermediate"), ("index_tip", "index_tip_end"),
                            ("thumb_metacarpal", "thumb_proximal"), ("wrist", "Armature")):
        p = rig.to_hand[:3, :3] @ world[node[name]][:3, 3] + rig.to_hand[:3, 3]
        np.testing.assert_allclose(rig.joints[canonical], p, atol=1e-9)
    np.testing.assert_allclose(rig.joints["wrist"], 0.0, atol=1e-12)
    # the tips and the wrist carry no skin weights; every posed bone carries some
    for name in ("wrist", "index_tip"):
        assert not np.any((rig.bone_index == rig.bone(name)) & (rig.bone_weight > 0))
    for name in ("index_proximal", "index_intermediate", "index_distal", "thumb_metacarpal"):
        assert np.any((rig.bone_index == rig.bone(name)) & (rig.bone_weight > 0))
    length = np.linalg.norm(rig.joints["middle_tip"] - rig.joints["wrist"]) * 1e3
    assert 180 < length < 210, length  # About.md: 196 mm
    assert json.loads(json.dumps(rig.tip_mm))  # every digit has a tip length


def test_a_rig_without_a_wrist_bone_is_refused_by_name(tmp_path):
    doc = json.loads(shipped_hand_path("godot_xr_tools").read_text())
    for n in doc["nodes"]:
        if n.get("name") == "Wrist_R":
            n["name"] = "Carpus"
    bad = tmp_path / "no_wrist.gltf"
    bad.write_text(json.dumps(doc))
    with pytest.raises(InvalidInputError, match="no bones named like wrist .*found"):
        load_mesh_rig(bad)


def test_webxr_joint_names_read_as_their_openxr_spellings(tmp_path):
    doc = json.loads(shipped_hand_path("godot_xr_tools").read_text())
    webxr = {"Metacarpal": "metacarpal", "Proximal": "phalanx-proximal",
             "Intermediate": "phalanx-intermediate", "Distal": "phalanx-distal", "Tip": "tip"}
    for n in doc["nodes"]:
        digit, _, rest = n.get("name", "").partition("_")
        bone = rest.removesuffix("_R")
        if digit in ("Index", "Middle", "Ring", "Little", "Thumb") and bone in webxr:
            word = {"Little": "pinky", "Thumb": "thumb"}.get(digit, digit.lower())
            finger = "" if digit == "Thumb" else "-finger"
            n["name"] = f"{word}{finger}-{webxr[bone]}"
        elif n.get("name") == "Wrist_R":
            n["name"] = "wrist"
    path = tmp_path / "webxr.gltf"
    path.write_text(json.dumps(doc))
    assert "index-finger-phalanx-proximal" in path.read_text()
    got, want = load_mesh_rig(path), load_mesh_rig(shipped_hand_path("godot_xr_tools"))
    assert got.bone_names == want.bone_names
    for name, p in want.joints.items():
        np.testing.assert_array_equal(got.joints[name], p)


def test_unknown_test_hand_is_refused():
    with pytest.raises(InvalidInputError, match="test hand"):
        shipped_hand_path("robot")


def test_truncated_glb_is_refused(tmp_path):
    raw = shipped_hand_path("mrtk").read_bytes()
    bad = tmp_path / "cut.glb"
    bad.write_bytes(raw[: len(raw) // 2])
    with pytest.raises(InvalidInputError, match="cut.glb"):
        load_mesh_rig(bad)


def test_a_scaled_rig_is_the_same_hand_larger_about_its_wrist():
    rig = load_mesh_rig()
    big = rig.scaled(1.25)
    for name, p in rig.joints.items():
        np.testing.assert_allclose(big.joints[name], 1.25 * p, atol=1e-12)
    np.testing.assert_allclose(big.vertices, 1.25 * rig.vertices, atol=1e-12)
    assert big.tip_mm["index"] == pytest.approx(1.25 * rig.tip_mm["index"])
    np.testing.assert_array_equal(big.faces, rig.faces)
    for name, frame in rig.frames.items():
        np.testing.assert_array_equal(big.frames[name], frame)
    with MeshHandRenderer(CameraMount.whole_hand(), width_px=W, height_px=H) as one, \
            MeshHandRenderer(CameraMount.whole_hand(), width_px=W, height_px=H, scale=0.8) as small:
        assert small.hand_length_mm == pytest.approx(0.8 * one.hand_length_mm)
        np.testing.assert_allclose(small.keypoints(named_pose("fist")),
                                   0.8 * one.keypoints(named_pose("fist")), atol=1e-12)
        # a smaller hand covers less of the same camera's frame
        pose = named_pose("open")
        assert 0.5 < small.mask(pose).sum() / one.mask(pose).sum() < 0.8


@pytest.mark.parametrize("bad", [0.3, 2.5, float("nan"), "1", True])
def test_a_scale_out_of_range_is_refused_by_value(bad):
    with pytest.raises(InvalidInputError, match=r"scale must be a number in \[0.5, 2\], got"):
        load_mesh_rig().scaled(bad)
