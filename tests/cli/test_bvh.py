"""``handsynth bvh`` on the real command: the angles another command wrote, as a BVH file."""

from __future__ import annotations

import bvh
import numpy as np
import pytest
from click.testing import CliRunner

from handsynth.cli._main import cli
from handsynth.models import (
    BVH_CHANNELS,
    JOINT_NAMES,
    KEYPOINT_SITES,
    HandModel,
    HandShape,
    bvh_text,
    read_angle_table,
)


def _run(*args):
    return CliRunner().invoke(cli, [str(a) for a in args], prog_name="handsynth")


@pytest.fixture(scope="module")
def estimated(tmp_path_factory):
    """Rows ``handsynth estimate`` wrote (the shipped perceptrons: nothing to learn)."""
    path = tmp_path_factory.mktemp("bvh") / "est.csv"
    res = _run("estimate", "--synthetic", "--learned", "--learned-kind", "perceptrons",
               "--synthetic-motion", "natural", "--frames", 12, "--out", path)
    assert res.exit_code == 0, res.output
    return path


def _tip(mocap: bvh.Bvh, frame: int, chain: list[str]) -> np.ndarray:
    """The End Site of the last joint of `chain` (root first), by forward kinematics."""
    from scipy.spatial.transform import Rotation

    place, turn = np.zeros(3), Rotation.identity()
    for name in chain:
        place = place + turn.apply(np.array(mocap.joint_offset(name), float))
        values = mocap.frame_joint_channels(frame, name, list(BVH_CHANNELS))
        turn = turn * Rotation.from_euler("ZYX", values, degrees=True)
    end = next(c for c in mocap.get_joint(chain[-1]).children if c.value[:2] == ["End", "Site"])
    return place + turn.apply(np.array([float(v) for v in end["OFFSET"]]))


@pytest.mark.parametrize("side", ["right", "left"])
def test_estimate_rows_become_the_hand_they_describe(tmp_path, estimated, side):
    out = tmp_path / "hand.bvh"
    res = _run("bvh", estimated, "-o", out, "--side", side, "--units", "mm")
    assert res.exit_code == 0, res.output
    assert f"12 frames at 30 Hz on the handsynth {side} hand" in res.output
    mocap = bvh.Bvh(out.read_text())
    assert mocap.nframes == 12 and mocap.frame_time == pytest.approx(1 / 30, rel=1e-6)
    angles = read_angle_table(estimated).angles_deg
    model = HandModel(HandShape(), side=side, forearm=False)
    for frame in (0, 7, 11):
        model.set_pose(angles[frame])
        truth_mm = 1e3 * model.keypoints()
        for finger in ("thumb", "index", "little"):
            segments = (["thumb_metacarpal", "thumb_proximal", "thumb_distal"] if finger == "thumb"
                        else [f"{finger}_{s}" for s in ("proximal", "middle", "distal")])
            np.testing.assert_allclose(_tip(mocap, frame, ["palm", *segments]),
                                       truth_mm[KEYPOINT_SITES.index(f"{finger}_tip")], atol=1e-3)


def test_shape_and_a_table_without_times(tmp_path):
    path = tmp_path / "angles.csv"
    angles = np.random.default_rng(4).uniform(0, 40, (5, len(JOINT_NAMES)))
    path.write_text("sample," + ",".join(JOINT_NAMES) + "\n"
                    + "".join(f"{i}," + ",".join(f"{v:.4f}" for v in a) + "\n"
                              for i, a in enumerate(angles)))
    out = tmp_path / "hand.bvh"
    res = _run("bvh", path, "-o", out)
    assert res.exit_code == 2 and not out.exists()
    assert res.output.strip().splitlines() == [
        f"handsynth: error: {path}: no time column (time_s or timestamp_s): give the frame rate "
        "with --rate HZ"]
    shape = "L1.050_W0.900_P1.000_T1.000"
    res = _run("bvh", path, "-o", out, "--rate", 60, "--shape", shape)
    assert res.exit_code == 0, res.output
    expected = bvh_text(np.round(angles, 4), rate_hz=60.0, shape=HandShape.from_name(shape))
    assert out.read_text() == expected


@pytest.mark.parametrize(("args", "message"), [
    (["--rate", 0], "--rate must be"),
    (["--rate", "nan"], "--rate must be"),
    (["--shape", "L9"], "--shape 'L9'"),
    (["--shape", "standard", "--measurements", "m.json"], "give --shape or --measurements"),
    (["--units", "in"], "'in' is not one of"),
])
def test_bad_options_are_one_line(tmp_path, estimated, args, message):
    out = tmp_path / "hand.bvh"
    res = _run("bvh", estimated, "-o", out, *args)
    assert res.exit_code == 2 and not out.exists()
    lines = res.output.strip().splitlines()
    assert len(lines) == 1 and message in lines[0], res.output


def test_bad_files_are_one_line(tmp_path, estimated):
    res = _run("bvh", tmp_path / "none.csv", "-o", tmp_path / "a.bvh")
    assert res.exit_code == 2 and "no such file" in res.output
    res = _run("bvh", estimated, "-o", estimated)
    assert res.exit_code == 2 and "handsynth: error:" in res.output
    assert read_angle_table(estimated).angles_deg.shape == (12, 20)   # left as it was
    junk = tmp_path / "junk.csv"
    junk.write_bytes(b"\x00\x01\x02")
    res = _run("bvh", junk, "-o", tmp_path / "b.bvh")
    assert res.exit_code == 2 and "binary" in res.output
    assert "Traceback" not in res.output
