"""The realistic skinned glTF hands shipped in handsynth/testhands/data as test hands."""

import itertools
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


def _godot_renamed(path, rename):
    """The shipped Godot hand with each node's name passed through `rename`, written to `path`
    (a node without a name reads as one named "", as the loader reads it)."""
    doc = json.loads(shipped_hand_path("godot_xr_tools").read_text())
    for n in doc["nodes"]:
        n["name"] = rename(n.get("name", ""))
    path.write_text(json.dumps(doc))
    return path


def test_a_rig_without_a_wrist_bone_is_refused_by_name(tmp_path):
    bad = _godot_renamed(tmp_path / "no_wrist.gltf", lambda name: {"Wrist_R": "Carpus"}.get(name, name))
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


# ---------------------------------------------------------------------------
# other rigging conventions: the shipped hands renamed, their tips moved
# ---------------------------------------------------------------------------
_THUMB = ("metacarpal", "proximal", "distal", "tip")
_FINGER = ("proximal", "intermediate", "distal", "tip")


def _numbered(bone):
    """Mixamo's / MANO's joint number of a canonical bone (None for a finger metacarpal)."""
    digit, _, b = bone.partition("_")
    order = _THUMB if digit == "thumb" else _FINGER
    return order.index(b) + 1 if b in order else None


def _mixamo(prefix="mixamorig:", side="Right"):
    """Mixamo's node name of a canonical bone (None where Mixamo has no node)."""
    def name(bone):
        if bone == "wrist":
            return f"{prefix}{side}Hand"
        k = _numbered(bone)
        digit = bone.partition("_")[0]
        return k and f"{prefix}{side}Hand{'Pinky' if digit == 'little' else digit.title()}{k}"
    return name


def _unity(bone):
    """Unity's humanoid bone name of a canonical bone (no tips, no finger metacarpals)."""
    if bone == "wrist":
        return "RightHand"
    digit, _, b = bone.partition("_")
    if digit == "thumb":  # Unity's thumb Proximal is the CMC joint
        b = {"metacarpal": "proximal", "proximal": "intermediate", "distal": "distal"}.get(b, "")
    return f"Right{digit.title()}{b.title()}" if b in ("proximal", "intermediate", "distal") else None


def _vrm1(bone):
    """VRM 1.0's humanoid bone name of a canonical bone (no tips, no finger metacarpals)."""
    if bone == "wrist":
        return "rightHand"
    digit, _, b = bone.partition("_")
    ok = ("metacarpal", "proximal", "distal") if digit == "thumb" else ("proximal", "intermediate", "distal")
    return f"right{digit.title()}{b.title()}" if b in ok else None


def _mano(wrist="wrist", little="pinky"):
    """A MANO-like export's joint name of a canonical bone (no tips, no finger metacarpals)."""
    def name(bone):
        if bone == "wrist":
            return wrist
        k = _numbered(bone)
        digit = bone.partition("_")[0]
        return k and k < 4 and f"{little if digit == 'little' else digit}{k}"
    return name


def _unreal(bone):
    """The Unreal mannequin's bone name of a canonical bone (no tips)."""
    if bone == "wrist":
        return "hand_r"
    digit = bone.partition("_")[0]
    k = _numbered(bone)
    word = "pinky" if digit == "little" else digit
    return f"{word}_metacarpal_r" if k is None else k < 4 and f"{word}_{k:02d}_r"


def _rigify(bone):
    """Blender Rigify's deforming bone name of a canonical bone (no tips, no finger metacarpals)."""
    if bone == "wrist":
        return "DEF-hand.R"
    digit = bone.partition("_")[0]
    k = _numbered(bone)
    word = {"little": "f_pinky", "thumb": "thumb"}.get(digit, f"f_{digit}")
    return k and k < 4 and f"DEF-{word}.{k:02d}.R"


def _read(hand):
    """The glTF document of a shipped hand (a copy), its GLB binary chunk or None, its node transforms."""
    from handsynth.testhands._gltf import _Gltf

    g = _Gltf(shipped_hand_path(hand))
    return json.loads(json.dumps(g.doc)), g._glb_bin, g.node_world()


def _write(tmp_path, stem, doc, binary):
    """`doc` as a .gltf, or as a .glb with `binary` as its BIN chunk."""
    import struct

    if binary is None:
        path = tmp_path / f"{stem}.gltf"
        path.write_text(json.dumps(doc))
        return path
    js = json.dumps(doc).encode()
    js += b" " * (-len(js) % 4)
    binary += b"\0" * (-len(binary) % 4)
    path = tmp_path / f"{stem}.glb"
    path.write_bytes(struct.pack("<4sII", b"glTF", 2, 28 + len(js) + len(binary))
                     + struct.pack("<I4s", len(js), b"JSON") + js
                     + struct.pack("<I4s", len(binary), b"BIN\0") + binary)
    return path


def _matrix(m):
    return [float(x) for x in np.asarray(m).T.ravel()]  # glTF: column-major


def _renamed(doc, worlds, name_of, tips):
    """The nodes of a shipped hand renamed by `name_of(canonical bone)`.

    A bone it gives no name loses its name (as if the convention had no such
    node: it no longer reads as a bone).  `tips`: "joint" renames the tip joints,
    "child" hides them and adds a node that is no skin joint at the same place,
    a child of the distal node, named by `name_of` or ``<distal>_end``;
    "loose" adds those nodes named by `name_of` at the top of the scene instead;
    "absent" hides them.
    """
    from handsynth.testhands._gltf import _parse_bone

    nodes = doc["nodes"]
    by_bone = {}
    for i, nd in enumerate(list(nodes)):
        bone, _ = _parse_bone(nd.get("name", ""))
        if bone is None:
            continue
        by_bone[bone] = i
        new = name_of(bone) if tips == "joint" or not bone.endswith("_tip") else None
        nd["name"] = new or f"helper_{i}"
    for digit in ("thumb", "index", "middle", "ring", "little") if tips in ("child", "loose") else ():
        tip, distal = by_bone[f"{digit}_tip"], by_bone[f"{digit}_distal"]
        if tips == "child":
            nodes.append({"name": name_of(f"{digit}_tip") or f"{nodes[distal]['name']}_end",
                          "matrix": _matrix(np.linalg.inv(worlds[distal]) @ worlds[tip])})
            nodes[distal].setdefault("children", []).append(len(nodes) - 1)
        else:
            nodes.append({"name": name_of(f"{digit}_tip"), "matrix": _matrix(worlds[tip])})
            doc["scenes"][doc.get("scene", 0)]["nodes"].append(len(nodes) - 1)
    return doc


def _under_root(doc, scale):
    """`doc` with its scene under a new root node of the given scale."""
    scene = doc["scenes"][doc.get("scene", 0)]
    doc["nodes"].append({"name": "Root", "scale": list(scale), "children": scene["nodes"]})
    scene["nodes"] = [len(doc["nodes"]) - 1]
    return doc


def _masks(path, side="right"):
    poses = np.stack([named_pose(p) for p in ("open", "fist", "pinch", "point", "spread")])
    with MeshHandRenderer(CameraMount.whole_hand(), width_px=W, height_px=H, path=path,
                          side=side) as r:
        m = r.measurements()
        return r.masks(poses), r.keypoints(named_pose("grasp")), np.r_[m.L, m.W, m.P_width, m.P_height]


def _assert_same_hand(got, want, *, tips):
    """`got` is the rig `want` read from renamed nodes; tips "node" equal, "skin" near."""
    np.testing.assert_allclose(got.vertices, want.vertices, atol=1e-9)
    np.testing.assert_array_equal(got.faces, want.faces)
    np.testing.assert_array_equal(got.bone_weight, want.bone_weight)
    assert got.source_side == want.source_side
    for name, p in want.joints.items():
        if name.endswith("_tip") and tips == "skin":
            # placed where the skin ends along the distal bone: the rig's fingertip keypoint
            digit = name.removesuffix("_tip")
            dist = f"{digit}_distal"
            end = want.joints[dist] + want.frames[dist][:, 1] * want.tip_mm[digit] * 1e-3
            assert np.linalg.norm(got.joints[name] - end) < 0.006, name
            assert got.tip_mm[digit] == pytest.approx(want.tip_mm[digit], abs=0.5)
        elif name in got.joints:
            np.testing.assert_allclose(got.joints[name], p, atol=1e-9, err_msg=name)
        else:
            assert name.endswith("metacarpal") and not name.startswith("thumb"), name
    if tips == "node":
        for name, frame in want.frames.items():
            np.testing.assert_allclose(got.frames[name], frame, atol=1e-9, err_msg=name)


def _assert_same_posed(path, ref_path, *, tips):
    """Masks, keypoints and measurements of two files equal (tips "node") or near ("skin")."""
    (got, kp, meas), (want, kp_ref, meas_ref) = _masks(path), _masks(ref_path)
    if tips == "node":
        np.testing.assert_array_equal(got, want)
        np.testing.assert_allclose(kp, kp_ref, atol=1e-9)
        np.testing.assert_allclose(meas, meas_ref, atol=1e-6)
    else:
        for a, b in zip(got, want):
            assert _iou(a, b) > 0.97
        assert np.abs(kp - kp_ref).max() < 0.003
        np.testing.assert_allclose(meas, meas_ref, atol=MEAS_TOL_MM)


MEAS_TOL_MM = 0.5  # the distal lengths and widths follow the placed tips

CONVENTIONS = {
    # name: (shipped hand, node names, tips, how the tips compare)
    "mixamo": ("godot_xr_tools", _mixamo(), "joint", "node"),
    "mixamo_tip_children": ("godot_xr_tools", _mixamo(), "child", "node"),
    "mixamo_unprefixed_loose_tips": ("webxr_generic", _mixamo(""), "loose", "node"),
    "mixamo1_no_tips": ("webxr_generic", _mixamo("mixamorig1:"), "absent", "skin"),
    "unity_end_children": ("godot_xr_tools", _unity, "child", "node"),
    "unity_no_tips": ("webxr_generic", _unity, "absent", "skin"),
    "vrm1_no_tips": ("godot_xr_tools", _vrm1, "absent", "skin"),
    "mano_no_tips": ("webxr_generic", _mano(), "absent", "skin"),
    "mano_root_little_no_tips": ("godot_xr_tools", _mano("root", "little"), "absent", "skin"),
    "unreal_no_tips": ("godot_xr_tools", _unreal, "absent", "skin"),
    "rigify_no_tips": ("webxr_generic", _rigify, "absent", "skin"),
}


@pytest.mark.parametrize("convention", sorted(CONVENTIONS))
def test_other_rigging_conventions_read_as_the_same_hand(tmp_path, convention):
    hand, name_of, tip_mode, tips = CONVENTIONS[convention]
    doc, binary, worlds = _read(hand)
    path = _write(tmp_path, convention, _renamed(doc, worlds, name_of, tip_mode), binary)
    got, want = load_mesh_rig(path), load_mesh_rig(shipped_hand_path(hand))
    _assert_same_hand(got, want, tips=tips)
    _assert_same_posed(path, shipped_hand_path(hand), tips=tips)


def test_a_left_hand_named_left_reads_as_the_mirrored_right_hand(tmp_path):
    doc, binary, worlds = _read("godot_xr_tools")
    doc = _under_root(_renamed(doc, worlds, _mixamo("mixamorig:", "Left"), "joint"), (-1.0, 1.0, 1.0))
    path = _write(tmp_path, "left", doc, binary)
    assert "mixamorig:LeftHandPinky2" in path.read_text()
    got, want = load_mesh_rig(path), load_mesh_rig(shipped_hand_path("godot_xr_tools"))
    assert got.source_side == "left"
    np.testing.assert_allclose(got.vertices, want.vertices, atol=1e-9)
    for name, p in want.joints.items():
        if name in got.joints:
            np.testing.assert_allclose(got.joints[name], p, atol=1e-9, err_msg=name)
    _assert_same_posed(path, shipped_hand_path("godot_xr_tools"), tips="node")


def _straightened(doc, worlds, dorsal_deg=0.0):
    """The Godot hand with its fingers straight in its palm plane, or bent `dorsal_deg` backward.

    Each finger is turned about its MCP joint into the palm plane and its
    phalanges in line with the proximal one: the rest pose of a T-pose export.
    """
    from handsynth.testhands._gltf import _parse_bone, _swing

    nodes = doc["nodes"]
    node = {b: i for i, n in enumerate(nodes) if (b := _parse_bone(n.get("name", ""))[0])}
    parent = {c: i for i, n in enumerate(nodes) for c in n.get("children", [])}
    pos = {b: worlds[i][:3, 3] for b, i in node.items()}
    normal = np.cross(pos["little_proximal"] - pos["index_proximal"], pos["middle_proximal"] - pos["wrist"])
    normal /= np.linalg.norm(normal)
    palmar = np.sign(np.mean([(pos[f"{f}_tip"] - pos[f"{f}_proximal"]) @ normal
                              for f in ("index", "middle", "ring", "little")])) * normal
    new = {}
    for digit in ("index", "middle", "ring", "little"):
        chain = [node[f"{digit}_{b}"] for b in ("proximal", "intermediate", "distal", "tip")]
        first = pos[f"{digit}_intermediate"] - pos[f"{digit}_proximal"]
        t = first - (first @ normal) * normal
        t /= np.linalg.norm(t)
        t = np.cos(np.radians(dorsal_deg)) * t - np.sin(np.radians(dorsal_deg)) * palmar
        at = worlds[chain[0]][:3, 3]
        for a, b in itertools.pairwise(chain):
            step = worlds[b][:3, 3] - worlds[a][:3, 3]
            m = np.eye(4)
            m[:3, :3] = _swing(step / np.linalg.norm(step), t) @ worlds[a][:3, :3]
            m[:3, 3] = at
            new[a] = m
            at = at + t * np.linalg.norm(step)
        new[chain[3]] = new[chain[2]] @ np.linalg.inv(worlds[chain[2]]) @ worlds[chain[3]]
    for i, m in new.items():
        up = new.get(parent[i], worlds[parent[i]])
        for key in ("translation", "rotation", "scale"):
            nodes[i].pop(key, None)
        nodes[i]["matrix"] = _matrix(np.linalg.inv(up) @ m)
    return doc


def _without_sides(doc):
    for n in doc["nodes"]:
        n["name"] = n.get("name", "").removesuffix("_R")
    return doc


def test_a_flat_rest_pose_takes_its_side_from_the_node_names(tmp_path):
    import re

    doc, binary, worlds = _read("godot_xr_tools")
    path = _write(tmp_path, "flat", _straightened(doc, worlds), binary)
    rig, want = load_mesh_rig(path), load_mesh_rig(shipped_hand_path("godot_xr_tools"))
    for f in ("index", "middle", "ring", "little"):  # flat: the fingers lie in the palm plane
        assert abs(rig.joints[f"{f}_tip"][2] - rig.joints[f"{f}_proximal"][2]) < 1e-6
    assert rig.source_side == "right"
    for name in ("wrist", "thumb_tip", "index_proximal", "little_proximal"):
        np.testing.assert_allclose(rig.joints[name], want.joints[name], atol=1e-9)
    # posed, it is the same hand: its zero pose does not depend on the rest pose
    (got, kp, _), (ref, kp_ref, _) = _masks(path), _masks(shipped_hand_path("godot_xr_tools"))
    for a, b in zip(got, ref):
        assert _iou(a, b) > 0.99
    np.testing.assert_allclose(kp, kp_ref, atol=1e-9)
    # its mirror image named as a left hand reads as a left hand: the same rig
    doc, binary, _ = _read("godot_xr_tools")
    doc = _renamed(_straightened(doc, worlds), worlds, _mixamo("", "Left"), "joint")
    left = load_mesh_rig(_write(tmp_path, "flat_left", _under_root(doc, (-1.0, 1.0, 1.0)), binary))
    assert left.source_side == "left"
    np.testing.assert_allclose(left.vertices, rig.vertices, atol=1e-9)
    np.testing.assert_allclose(left.joints["thumb_tip"], rig.joints["thumb_tip"], atol=1e-9)
    # no side in the names: refused, saying why
    doc, binary, _ = _read("godot_xr_tools")
    path = _write(tmp_path, "flat_unnamed", _without_sides(_straightened(doc, worlds)), binary)
    with pytest.raises(InvalidInputError, match=re.escape(str(path)) + ".*the rest-pose fingers are "
                       "flat and no node name says right or left"):
        load_mesh_rig(path)


def test_fingers_bent_backward_against_the_names_are_refused(tmp_path):
    # read by the curl alone, this right hand would load as a left hand, palm and back swapped
    doc, binary, worlds = _read("godot_xr_tools")
    path = _write(tmp_path, "bent_back", _straightened(doc, worlds, dorsal_deg=20.0), binary)
    with pytest.raises(InvalidInputError, match=r"bent_back.gltf: the node names say a right hand, "
                       r"but its rest-pose fingers curl toward the palm of a left hand \(\d+\.\d mm\)"):
        load_mesh_rig(path)


@pytest.mark.parametrize(("scale", "unit"), [(100.0, "centimetres"), (1000.0, "millimetres"),
                                             (1 / 0.0254, "inches"), (0.1, None)])
def test_a_hand_not_in_metres_is_refused_with_its_length(tmp_path, scale, unit):
    doc, binary, _ = _read("webxr_generic")
    path = _write(tmp_path, "units", _under_root(doc, (scale,) * 3), binary)
    length = 1e3 * scale * np.linalg.norm(load_mesh_rig(shipped_hand_path("webxr_generic")).joints[
        "middle_tip"])
    cause = (f"the file is likely in {unit} \\(that would make it {length / scale:.0f} mm\\)"
             if unit else "no common unit explains it")
    with pytest.raises(InvalidInputError, match=f"units.glb: the hand is {length:.1f} mm from the "
                       f"wrist to the middle fingertip .*outside the 100-300 mm .*; {cause}"):
        load_mesh_rig(path)
    # a root node that keeps metres changes nothing
    doc, binary, _ = _read("webxr_generic")
    path = _write(tmp_path, "metres", _under_root(doc, (1.0, 1.0, 1.0)), binary)
    np.testing.assert_allclose(load_mesh_rig(path).vertices,
                               load_mesh_rig(shipped_hand_path("webxr_generic")).vertices, atol=1e-12)


def test_a_skin_of_both_hands_is_refused_naming_both_nodes(tmp_path):
    path = _godot_renamed(tmp_path / "two.gltf", lambda name: {"Palm_R": "Wrist_L"}.get(name, name))
    with pytest.raises(InvalidInputError, match="two.gltf: the skin's nodes 'Wrist_[LR]' and "
                       "'Wrist_[LR]' both read as the bone wrist"):
        load_mesh_rig(path)


def test_an_unknown_naming_is_refused_with_the_conventions_read(tmp_path):
    path = _godot_renamed(tmp_path / "pointer.gltf", lambda name: name.replace("Index", "Pointer"))
    with pytest.raises(InvalidInputError, match=r"pointer.gltf: the skin has no bones named like "
                       r"index_proximal, index_intermediate, index_distal \(found wrist, .*"
                       r"other:Pointer_Proximal_R.*\); expected .*Mixamo.*Unity.*MANO"):
        load_mesh_rig(path)


# the shipped hands as the loader read them before it read other conventions: rest mesh,
# joints, frames, fingertips and two posed meshes (micrometres, hashed), the hand's
# length and the pixels of the open hand and the fist at 360x240
SHIPPED = {
    "godot_xr_tools": ("dfa1550df79a4d76", 216.2593, (13693, 7279)),
    "mrtk": ("cbe3e12827d17033", 195.852, (11444, 6315)),
    "webxr_generic": ("0869b7259adc8661", 190.9473, (10779, 6095)),
}


@pytest.mark.parametrize("name", sorted(TEST_HANDS))
def test_the_shipped_hands_are_read_as_before(name):
    import hashlib

    digest, length, pixels = SHIPPED[name]
    with MeshHandRenderer(CameraMount.whole_hand(), width_px=W, height_px=H,
                          path=shipped_hand_path(name)) as r:
        rig = r.rig
        h = hashlib.sha256()
        for a in (rig.vertices, rig.faces, [rig.joints[n] for n in sorted(rig.joints)],
                  [rig.frames[n] for n in sorted(rig.frames)], [rig.tip_mm[n] for n in sorted(rig.tip_mm)],
                  r.vertices(named_pose("fist")), r.vertices(named_pose("pinch"))):
            h.update(np.round(np.asarray(a, dtype=np.float64) * 1e6).astype(np.int64).tobytes())
        assert h.hexdigest()[:16] == digest
        assert r.hand_length_mm == pytest.approx(length, abs=1e-4)
        # the masks, within what another GL rasteriser may change
        for pose, n in zip(("open", "fist"), pixels):
            assert r.mask(named_pose(pose)).sum() == pytest.approx(n, rel=0.005)


def test_a_distal_bone_without_skin_is_refused_by_name(tmp_path):
    # before: numpy's "zero-size array to reduction operation maximum" (a traceback)
    swap = {"Index_Distal_R": "Index_Tip_R", "Index_Tip_R": "Index_Distal_R"}
    path = _godot_renamed(tmp_path / "swapped.gltf", lambda name: swap.get(name, name))
    with pytest.raises(InvalidInputError, match="swapped.gltf: bone index_distal .node 'Index_Distal_R'.: no "
                       "vertex of the skin is mostly weighted to it"):
        load_mesh_rig(path)
