"""BVH files of joint angles: read by an independent parser, posed, and put beside the model."""

from __future__ import annotations

import warnings

import bvh
import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from handsynth.errors import InvalidInputError, InvalidPoseError, InvalidShapeError, OutputError
from handsynth.models import (
    BVH_BONE_STARTS,
    BVH_BONES,
    BVH_CHANNELS,
    JOINT_LIMITS_DEG,
    JOINT_NAMES,
    KEYPOINT_SITES,
    NAMED_POSES,
    HandModel,
    HandShape,
    bvh_text,
    write_bvh,
)

# the segment each keypoint is the origin of; the tips are the End Sites
_ORIGIN = {"palm": "wrist", "thumb_metacarpal": "thumb_cmc", "thumb_proximal": "thumb_mcp",
           "thumb_distal": "thumb_ip",
           **{f"{f}_{s}": f"{f}_{j}" for f in ("index", "middle", "ring", "little")
              for s, j in (("proximal", "mcp"), ("middle", "pip"), ("distal", "dip"))}}
_TIP = {"thumb_distal": "thumb_tip",
        **{f"{f}_distal": f"{f}_tip" for f in ("index", "middle", "ring", "little")}}


def _poses(n: int, seed: int) -> np.ndarray:
    lo, hi = JOINT_LIMITS_DEG.T
    random = np.random.default_rng(seed).uniform(lo, hi, (n, len(JOINT_NAMES)))
    return np.vstack([np.stack(list(NAMED_POSES.values())), random])


def _points(mocap: bvh.Bvh, frame: int) -> dict[str, np.ndarray]:
    """Each joint's and each End Site's place in the root's frame (forward kinematics)."""
    place: dict[str, np.ndarray] = {}
    turn: dict[str, Rotation] = {}
    for name in mocap.get_joints_names():
        channels = [c for c in mocap.joint_channels(name) if c.endswith("rotation")]
        values = mocap.frame_joint_channels(frame, name, channels)
        own = Rotation.from_euler("".join(c[0] for c in channels), values, degrees=True)
        offset = np.array(mocap.joint_offset(name), float)
        parent = mocap.joint_parent(name)
        if parent is None:
            place[name], turn[name] = offset, own
        else:
            place[name] = place[parent.name] + turn[parent.name].apply(offset)
            turn[name] = turn[parent.name] * own
        for child in mocap.get_joint(name).children:
            if child.value[:2] == ["End", "Site"]:
                tip = np.array([float(v) for v in child["OFFSET"]])
                place[f"{name}/end"] = place[name] + turn[name].apply(tip)
    return place


@pytest.mark.parametrize("side", ["right", "left"])
@pytest.mark.parametrize("shape", [HandShape(), HandShape(length=1.1, width=0.9, palm=1.05,
                                                             thumb=0.92)],
                         ids=lambda s: s.name)
def test_joint_centres_and_tips_are_the_models_keypoints(side, shape):
    angles = _poses(12, seed=3)
    mocap = bvh.Bvh(bvh_text(angles, rate_hz=60.0, shape=shape, side=side, units="mm"))
    model = HandModel(shape, side=side, forearm=False)
    assert mocap.nframes == len(angles)
    for frame, pose in enumerate(angles):
        model.set_pose(pose)
        truth_mm = 1e3 * model.keypoints()
        got = _points(mocap, frame)
        for body, site in _ORIGIN.items():
            np.testing.assert_allclose(got[body], truth_mm[KEYPOINT_SITES.index(site)],
                                       atol=1e-4, err_msg=f"{body}, frame {frame}")
        for body, site in _TIP.items():
            np.testing.assert_allclose(got[f"{body}/end"], truth_mm[KEYPOINT_SITES.index(site)],
                                       atol=1e-4, err_msg=f"{site}, frame {frame}")


# each bone: (the joint whose OFFSET it is, or the End Site of that joint) -> its parent point
_BONE_ENDS = {**{site: body for body, site in _ORIGIN.items()},
              **{site: f"{body}/end" for body, site in _TIP.items()}}


def _bones(place: dict[str, np.ndarray]) -> dict[str, float]:
    """Each bone's length from the posed points (mm), by the chain's point names."""
    where = {site: place[key] for site, key in _BONE_ENDS.items()}
    where["wrist"] = place["palm"]
    return {bone: float(np.linalg.norm(where[bone] - where[start]))
            for bone, start in BVH_BONE_STARTS.items()}


@pytest.mark.parametrize("side", ["right", "left"])
def test_bone_lengths_set_each_bone_along_the_hands_direction(side):
    shape = HandShape(length=0.93, palm=1.04)
    angles = _poses(4, seed=5)
    plain = bvh.Bvh(bvh_text(angles, rate_hz=30.0, shape=shape, side=side, units="mm"))
    own = _bones(_points(plain, 0))
    assert sorted(own) == sorted(BVH_BONES) and min(own.values()) > 10.0
    # the hand's own lengths give the same file
    assert bvh_text(angles, rate_hz=30.0, shape=shape, side=side, bone_lengths_mm=own) == \
        bvh_text(angles, rate_hz=30.0, shape=shape, side=side)
    lengths = dict(zip(BVH_BONES[::2], np.random.default_rng(1).uniform(12.0, 95.0, 10)))
    mocap = bvh.Bvh(bvh_text(angles, rate_hz=30.0, shape=shape, side=side, units="mm",
                             bone_lengths_mm=lengths))
    for frame in range(mocap.nframes):
        got, plain_pts = _bones(_points(mocap, frame)), _points(plain, frame)
        want = {**own, **lengths}  # the bones not given keep the hand's
        np.testing.assert_allclose([got[b] for b in BVH_BONES], [want[b] for b in BVH_BONES],
                                   atol=2e-5)
        # each bone along the direction the hand gives it in this pose
        scaled = _points(mocap, frame)
        for bone in ("index_pip", "thumb_cmc", "little_tip"):
            key = _BONE_ENDS[bone]
            prev = {"index_pip": "index_proximal", "thumb_cmc": "palm",
                    "little_tip": "little_distal"}[bone]
            d_plain = plain_pts[key] - plain_pts[prev]
            d_scaled = scaled[key] - scaled[prev]
            np.testing.assert_allclose(d_scaled / np.linalg.norm(d_scaled),
                                       d_plain / np.linalg.norm(d_plain), atol=1e-6)


@pytest.mark.parametrize(("lengths", "match"), [
    ({"index_nail": 10.0}, "unknown bone 'index_nail'"),
    ({"index_pip": 0.0}, r"bone_lengths_mm\['index_pip'\]"),
    ({"thumb_tip": float("nan")}, r"bone_lengths_mm\['thumb_tip'\]"),
    ({"ring_mcp": 900.0}, r"bone_lengths_mm\['ring_mcp'\]"),
    ([40.0] * 20, "mapping of bone name"),
])
def test_refuses_bone_lengths_it_cannot_use(lengths, match):
    with pytest.raises(InvalidInputError, match=match):
        bvh_text(np.zeros((1, 20)), rate_hz=30.0, bone_lengths_mm=lengths)


def test_frame_time_units_and_channels():
    angles = _poses(3, seed=1)
    mm = bvh.Bvh(bvh_text(angles, rate_hz=120.0, units="mm"))
    cm = bvh.Bvh(bvh_text(angles, rate_hz=120.0))
    m = bvh.Bvh(bvh_text(angles, rate_hz=120.0, units="m"))
    assert cm.frame_time == pytest.approx(1 / 120)
    assert len(cm.get_joints_names()) == 1 + 15
    for name in cm.get_joints_names()[1:]:
        assert tuple(cm.joint_channels(name)) == BVH_CHANNELS
        np.testing.assert_allclose(np.array(cm.joint_offset(name)),
                                   0.1 * np.array(mm.joint_offset(name)), atol=1e-6)
        np.testing.assert_allclose(np.array(m.joint_offset(name)),
                                   1e-3 * np.array(mm.joint_offset(name)), atol=1e-6)
        for frame in range(len(angles)):
            assert (cm.frame_joint_channels(frame, name, list(BVH_CHANNELS))
                    == mm.frame_joint_channels(frame, name, list(BVH_CHANNELS)))


def test_the_middle_angle_stays_clear_of_gimbal_lock():
    """The docstring's claim: over every joint's range the Y rotation stays within 49 deg."""
    angles = _poses(4000, seed=7)
    for side in ("right", "left"):
        mocap = bvh.Bvh(bvh_text(angles, rate_hz=30.0, side=side))
        frames = np.array(mocap.frames, float)
        assert np.abs(frames[:, 6 + 1::3]).max() < 49.0


def test_one_pose_and_the_open_hand():
    text = bvh_text(np.zeros(len(JOINT_NAMES)), rate_hz=30.0)
    mocap = bvh.Bvh(text)
    assert mocap.nframes == 1
    assert "-0.000000" not in text
    # the open hand: no finger segment flexed, the proximal ones at their rest fan, the
    # thumb's metacarpal at its rest orientation
    names = mocap.get_joints_names()
    for name in names[1:]:
        z, _y, x = mocap.frame_joint_channels(0, name, list(BVH_CHANNELS))
        if not name.startswith("thumb"):
            assert x == 0.0, name
            assert abs(z) <= (10.0 if name.endswith("proximal") else 0.0), name
    assert np.abs(mocap.frame_joint_channels(0, "thumb_metacarpal", list(BVH_CHANNELS))).max() > 10


def test_the_root_carries_the_hands_place_and_attitude():
    """World keypoints = place + attitude applied to the hand-frame keypoints, through a
    root turned far (channels unwrapped: no 360-deg jump between frames)."""
    n = 90
    angles = np.tile(_poses(1, seed=5)[-1], (n, 1))
    turn = Rotation.from_rotvec(np.linspace(0, 4 * np.pi, n)[:, None] * np.array([0.3, 0.9, 0.3]))
    quat = turn.as_quat()[:, [3, 0, 1, 2]]
    place = np.column_stack([np.linspace(0, 300, n), np.zeros(n), 50 * np.ones(n)])
    mocap = bvh.Bvh(bvh_text(angles, rate_hz=30.0, units="mm", root_quat=quat,
                             root_position_mm=place))
    model = HandModel(forearm=False)
    model.set_pose(angles[0])
    hand_mm = 1e3 * model.keypoints()
    for frame in (0, 17, 45, 89):
        root = mocap.frame_joint_channels(frame, "palm", ["Xposition", "Yposition", "Zposition"])
        np.testing.assert_allclose(root, place[frame], atol=1e-6)
        got = _points(mocap, frame)
        # _points starts the root at its offset: add the position channels
        world = turn[frame].apply(hand_mm) + place[frame]
        for body, site in _ORIGIN.items():
            np.testing.assert_allclose(got[body] + place[frame], world[KEYPOINT_SITES.index(site)],
                                       atol=1e-4, err_msg=f"{body}, frame {frame}")
    root_angles = np.array(mocap.frames, float)[:, 3:6]
    assert np.abs(np.diff(root_angles, axis=0)).max() < 90.0


@pytest.mark.parametrize("kwargs", [{"root_quat": np.zeros((2, 4))},
                                    {"root_quat": np.ones((3, 4))},
                                    {"root_quat": np.full((2, 4), np.nan)},
                                    {"root_position_mm": np.zeros((2, 2))},
                                    {"root_position_mm": np.full((2, 3), np.inf)}])
def test_refuses_a_root_motion_of_another_shape(kwargs):
    with pytest.raises(InvalidInputError, match="root_"):
        bvh_text(np.zeros((2, 20)), rate_hz=30.0, **kwargs)


@pytest.mark.parametrize(("kwargs", "error", "match"), [
    ({"angles": np.zeros((2, 19))}, InvalidPoseError, r"shape \(N, 20\).*\(2, 19\)"),
    ({"angles": np.zeros((0, 20))}, InvalidPoseError, r"\(0, 20\)"),
    ({"angles": np.where(np.arange(40).reshape(2, 20) == 26, np.nan, 0.0)}, InvalidPoseError,
     "row 1, index_pip_flex is nan"),
    ({"rate_hz": 0.0}, InvalidInputError, "rate_hz"),
    ({"rate_hz": float("inf")}, InvalidInputError, "rate_hz"),
    ({"units": "in"}, InvalidInputError, "units must be one of cm, mm, m, got 'in'"),
    ({"side": "both"}, InvalidInputError, "side"),
    ({"shape": "L1.0"}, InvalidShapeError, "shape"),
])
def test_refuses_what_it_cannot_write(kwargs, error, match):
    args = {"angles": np.zeros((2, 20)), "rate_hz": 30.0, **kwargs}
    with pytest.raises(error, match=match):
        bvh_text(args.pop("angles"), **args)


def test_write_is_whole_or_nothing(tmp_path):
    out = tmp_path / "hand.bvh"
    assert write_bvh(out, _poses(2, seed=0), rate_hz=30.0) == out
    assert bvh.Bvh(out.read_text()).nframes == len(NAMED_POSES) + 2
    with pytest.raises(OutputError, match="hand.bvh"):
        write_bvh(out, np.zeros((1, 20)), rate_hz=30.0, inputs=[out])
    with pytest.raises(InvalidPoseError):
        write_bvh(tmp_path / "bad.bvh", np.full((1, 20), np.nan), rate_hz=30.0)
    assert not (tmp_path / "bad.bvh").exists()
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        write_bvh(tmp_path / "quiet.bvh", _poses(50, seed=2), rate_hz=30.0)
