"""``handsynth measure`` on the real command: measures a rendered photo, writes what it says."""

from __future__ import annotations

import json

import cv2
import numpy as np
import pytest
from click.testing import CliRunner

from handsynth.cli._main import cli
from handsynth.measure import render_measurement_photo
from handsynth.models import HandMeasurements, HandShape, model_measurements

SHAPE = HandShape(length=1.05, width=0.9, palm=1.0, thumb=1.1)


@pytest.fixture(scope="module")
def photos(tmp_path_factory):
    folder = tmp_path_factory.mktemp("photos")
    plain = render_measurement_photo(SHAPE, mm_per_px=0.5)
    card = render_measurement_photo(SHAPE, mm_per_px=0.5, card=True)
    cv2.imwrite(str(folder / "hand.png"), plain.image)
    cv2.imwrite(str(folder / "hand_card.jpg"), card.image, [cv2.IMWRITE_JPEG_QUALITY, 95])
    cv2.imwrite(str(folder / "blank.png"), np.full((300, 400, 3), 120, np.uint8))
    grey = cv2.cvtColor(plain.image, cv2.COLOR_BGR2GRAY)
    cv2.imwrite(str(folder / "hand_grey.png"), grey)
    cv2.imwrite(str(folder / "hand_grey.jpg"), grey)
    return folder


def _run(*args):
    return CliRunner().invoke(cli, ["measure", *[str(a) for a in args]], catch_exceptions=False)


def test_measure_prints_writes_and_annotates(tmp_path, photos):
    out, details, png = tmp_path / "m.json", tmp_path / "d.json", tmp_path / "a.png"
    res = _run(photos / "hand.png", "--mm-per-px", 0.5, "--out", out, "--details", details,
               "--annotate", png)
    assert res.exit_code == 0, res.output
    assert f"database: {SHAPE.name}" in res.output
    assert "P_width" in res.output and "thumb" in res.output
    got, true = HandMeasurements.from_file(out), model_measurements(SHAPE)
    np.testing.assert_allclose(got.L, true.L, rtol=0.04)
    np.testing.assert_allclose(got.W, true.W, rtol=0.04)
    assert abs(got.P_width - true.P_width) < 1.0 and abs(got.T_height - true.T_height) < 1.5
    data = json.loads(details.read_text())
    assert data["selection"]["shape"] == SHAPE.name
    assert data["diagnostics"]["scale_source"] == "mm_per_px"
    # the model shape, corrected for the method, is printed with the command that uses it
    found = HandShape.from_name(data["shape"]["name"])
    assert all(abs(getattr(found, n) - getattr(SHAPE, n)) < 0.02
               for n in ("length", "width", "palm", "thumb"))
    assert f"--shape {found.name} --personal" in res.output
    assert [f["name"] for f in data["diagnostics"]["fingers"]] == [
        "thumb", "index", "middle", "ring", "little"]
    pic = cv2.imread(str(png))
    assert pic.shape == (600, 600, 3)
    assert np.any(pic != cv2.imread(str(photos / "hand.png")))


def test_reference_card_and_csv(tmp_path, photos):
    out = tmp_path / "m.csv"
    res = _run(photos / "hand_card.jpg", "--reference-width-mm", 85.6, "--out", out)
    assert res.exit_code == 0, res.output
    assert "(reference)" in res.output and f"database: {SHAPE.name}" in res.output
    scale = float(res.output.split("scale: ")[1].split(" mm/px")[0])
    assert abs(scale - 0.5) < 0.003
    assert out.read_text().startswith("name,value_mm\nL1,")
    assert HandMeasurements.from_file(out).P_height > 70


@pytest.mark.parametrize("args, words", [
    (["hand.png"], "--mm-per-px"),
    (["hand.png", "--mm-per-px", "0.5", "--reference-width-mm", "85.6"], "--mm-per-px"),
    (["missing.png", "--mm-per-px", "0.5"], "cannot read the photo"),
    (["blank.png", "--mm-per-px", "0.5"], "no hand found"),
    (["hand.png", "--mm-per-px", "0.5", "--out", "m.txt"], "--out must end in"),
    (["hand.png", "--mm-per-px", "0.5", "--annotate", "a.jpg"], "--annotate must end in"),
    (["hand.png", "--reference-width-mm", "85.6"], "no reference object"),
    (["hand.png", "--mm-per-px", "-2"], "--mm-per-px must be a finite number > 0"),
    # an overflow (OverflowError traceback) before
    (["hand.png", "--mm-per-px", "1e300"], "--mm-per-px must be a finite number > 0 and <= 1000, "
                                           "got 1e+300"),
    (["hand_card.jpg", "--reference-width-mm", "1e308"], "--reference-width-mm must be a finite "
                                                          "number > 0 and <= 10000, got 1e+308"),
    (["hand.png", "--mm-per-px", "nan"], "--mm-per-px must be a finite number > 0"),
    # a scale far too large said the hand touches the border, not to check the scale
    (["hand.png", "--mm-per-px", "100"], "check the scale"),
    (["hand.png", "--mm-per-px", "1.2"], "check the scale"),
    # a grey photo on a background as grey as the hand's shaded edges: breadths ~2 mm
    # too small with exit 0 (PNG), or lost fingertips blamed on the border (JPEG)
    (["hand_grey.png", "--mm-per-px", "0.5"], "a colour photo is needed"),
    (["hand_grey.jpg", "--mm-per-px", "0.5"], "a colour photo is needed"),
])
def test_bad_input_is_one_line_exit_2(photos, args, words):
    args = [str(photos / args[0]), *args[1:]]
    res = _run(*args)
    assert res.exit_code == 2
    lines = res.output.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("handsynth: error:"), res.output
    assert words in lines[0]


# --------------------------------------------------------------------------- faults (issue 16)


@pytest.mark.parametrize("option, name", [("--details", "d.json"), ("--annotate", "a.png"),
                                          ("--out", "m.csv")])
def test_an_output_in_a_missing_folder_is_one_line(tmp_path, photos, option, name):
    # item 9: FileNotFoundError tracebacks
    res = CliRunner().invoke(cli, ["measure", str(photos / "hand.png"), "--mm-per-px", "0.5",
                                   option, str(tmp_path / "nowhere" / name)])
    assert res.exit_code == 2, res.output
    assert "nowhere' does not exist" in res.output and "Traceback" not in res.output


@pytest.mark.parametrize("option", ["--details", "--annotate"])
def test_an_output_on_a_full_disk_leaves_nothing(full_disk, photos, option):
    # item 9: 0-byte or temporary files left behind
    (full_disk / "filler").write_bytes(b"\0" * (256 * 1024 - 4096))
    name = "d.json" if option == "--details" else "a.png"
    res = CliRunner().invoke(cli, ["measure", str(photos / "hand.png"), "--mm-per-px", "0.5",
                                   option, str(full_disk / name)])
    assert res.exit_code == 2 and "no space left" in res.output, res.output
    assert sorted(p.name for p in full_disk.iterdir()) == ["filler"]


def test_the_annotated_picture_never_replaces_the_photo(tmp_path, photos):
    photo = tmp_path / "hand.png"
    photo.write_bytes((photos / "hand.png").read_bytes())
    res = CliRunner().invoke(cli, ["measure", str(photo), "--mm-per-px", "0.5", "--annotate",
                                   str(photo)])
    assert res.exit_code == 2 and "never replaces an input" in res.output, res.output
    assert photo.read_bytes() == (photos / "hand.png").read_bytes()


@pytest.mark.parametrize("args, line", [
    # before: '' was the folder '.', named as such ("cannot read the photo '.'", "--out must
    # end in .json or .csv, got '.'")
    (["", "--mm-per-px", "0.5"], "PHOTO must name a file, got ''"),
    (["{photos}/hand.png", "--mm-per-px", "0.5", "--out", ""], "--out must name a file, got ''"),
    (["{photos}/hand.png", "--mm-per-px", "0.5", "--annotate", " "],
     "--annotate must name a file, got ' '"),
])
def test_an_empty_path_is_refused_by_name(photos, args, line):
    res = _run(*[a.format(photos=photos) for a in args])
    assert res.exit_code == 2 and res.output == f"handsynth: error: {line}\n", res.output


@pytest.mark.slow
def test_damaged_photos_are_one_line_on_the_real_stderr(tmp_path, photos):
    # before: libpng printed "libpng error: Read Error" on the process's stderr above the error
    import os
    import subprocess
    import sys

    data = (photos / "hand.png").read_bytes()
    (tmp_path / "cut.png").write_bytes(data[:len(data) // 2])
    (tmp_path / "head.png").write_bytes(data[:60])
    (tmp_path / "text.png").write_text("a text file named .png")
    (tmp_path / "empty.png").write_bytes(b"")
    (tmp_path / "file").write_text("x")
    env = {k: v for k, v in os.environ.items() if k != "MUJOCO_GL"}
    env["MUJOCO_GL"] = "egl"
    for name in ("cut.png", "head.png", "text.png", "empty.png", "missing.png", "file/under.png"):
        proc = subprocess.run([sys.executable, "-c", "from handsynth.cli import main; main()",
                               "measure", str(tmp_path / name), "--mm-per-px", "0.5", "--out",
                               str(tmp_path / "m.json")], capture_output=True, text=True, env=env,
                              timeout=120)
        assert proc.returncode == 2 and proc.stdout == "", proc.stderr
        lines = proc.stderr.strip().splitlines()
        assert len(lines) == 1 and lines[0].startswith("handsynth: error: cannot read the photo"), \
            proc.stderr
        assert name in lines[0]
    assert not (tmp_path / "m.json").exists()


@pytest.mark.parametrize("option, name", [("--out", "m.json"), ("--details", "d.json"),
                                          ("--annotate", "a.png")])
def test_an_output_in_a_read_only_folder_is_one_line_and_nothing(read_only_folder, photos,
                                                                  option, name):
    res = _run(photos / "hand.png", "--mm-per-px", "0.5", option, read_only_folder / name)
    assert res.exit_code == 2, res.output
    assert res.output.strip().splitlines()[-1].startswith("handsynth: error: cannot write")
    assert "read-only" in res.output and "Traceback" not in res.output
    assert list(read_only_folder.iterdir()) == []
