import re

import cv2
import pytest
from click.testing import CliRunner

from handsynth.cli._main import cli
from handsynth.db import open_database


@pytest.mark.slow
def test_demo_writes_pictures_and_looks_up_frames(tmp_path):
    res = CliRunner().invoke(cli, ["demo", "--out", str(tmp_path), "--tile-width", "96",
                                   "--frames", "20", "--learned-hands", "10"])
    assert res.exit_code == 0, res.output
    for name in ("hands_paper_mount.png", "hands_whole_hand_mount.png"):
        img = cv2.imread(str(tmp_path / name))
        assert img is not None and img.shape[1] == 4 * 96 + 4 and img.std() > 10
    # four frames of the glTF hand: the device's view, the truth and the reading, side by side
    img = cv2.imread(str(tmp_path / "estimates_mrtk.png"))
    assert img is not None and img.shape == (3 * 64 + 4, 4 * 96 + 4, 3)
    rows = [img[2 + 64 * i:2 + 64 * (i + 1), 2:-2] for i in range(3)]
    assert all(r.std() > 10 for r in rows) and not (rows[1] == rows[2]).all()
    # the same hand over photographs: the frame, and the hand told by brightness and by colour
    img = cv2.imread(str(tmp_path / "backgrounds_mrtk.png"))
    assert img is not None and img.shape == (3 * 64 + 4, 4 * 96 + 4, 3)
    rows = [img[2 + 64 * i:2 + 64 * (i + 1), 2:-2] for i in range(3)]
    assert all(r.std() > 10 for r in rows) and (rows[1] != rows[2]).mean() > 0.1
    db = open_database(next((tmp_path / "db").glob("*.h5")))
    assert len(db) == 3000
    assert "looked up 20 frames" in res.output and "mean absolute error" in res.output
    line = next(x for x in res.output.splitlines() if x.startswith("calibrated to its open hand"))
    assert "pixels ignored" in line and "mean absolute error" in line
    assert "learned estimator (10 hands x 100 frames) ready" in res.output
    for pose_set in ("paper", "natural"):
        row = next(x for x in res.output.splitlines() if x.startswith(f"mesh/{pose_set}/fingers"))
        mae, const = (float(v) for v in re.findall(r"MAE +([\d.]+) \(constant +([\d.]+)", row)[0])
        assert const > 0 and mae > 0
        # the shipped perceptrons read the unseen glTF hand with skill
        row = next(x for x in res.output.splitlines() if x.startswith(f"mesh/{pose_set}/perceptrons"))
        mae, const = (float(v) for v in re.findall(r"MAE +([\d.]+) \(constant +([\d.]+)", row)[0])
        assert 0 < mae < 0.8 * const
    assert sorted(p.name.split("_")[0] for p in (tmp_path / "learned").iterdir()) == [
        "learned", "learning"]


def test_demo_bad_option_is_one_line(tmp_path):
    res = CliRunner().invoke(cli, ["demo", "--out", str(tmp_path), "--tile-width", "5"])
    assert res.exit_code == 2 and "tile-width" in res.output


def test_an_empty_or_impossible_out_folder_is_one_line_and_writes_nothing(tmp_path, monkeypatch):
    # before: --out '' was the current folder, which got the pictures and the databases
    monkeypatch.chdir(tmp_path)
    res = CliRunner().invoke(cli, ["demo", "--out", "", "--frames", "0", "--learned-hands", "0"])
    assert res.exit_code == 2 and res.output == "handsynth: error: --out must name a folder, got ''\n"
    assert list(tmp_path.iterdir()) == []
    (tmp_path / "file").write_text("x")  # a folder under a regular file: was an OSError traceback
    res = CliRunner().invoke(cli, ["demo", "--out", str(tmp_path / "file" / "pictures"),
                                   "--frames", "0", "--learned-hands", "0"])
    assert res.exit_code == 2, res.output
    lines = res.output.strip().splitlines()
    assert len(lines) == 1 and "cannot create the --out folder" in lines[0] and "file" in lines[0]


def test_a_read_only_out_folder_is_one_line_and_nothing_written(read_only_folder):
    res = CliRunner().invoke(cli, ["demo", "--out", str(read_only_folder), "--frames", "0",
                                   "--learned-hands", "0", "--tile-width", "64"])
    assert res.exit_code == 2, res.output
    assert res.output.strip().splitlines()[-1].startswith("handsynth: error: cannot write")
    assert "read-only" in res.output and "Traceback" not in res.output
    assert list(read_only_folder.iterdir()) == []
