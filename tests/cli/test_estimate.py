"""``handsynth estimate`` on the real command: synthetic, video in/out, default database, errors."""

from __future__ import annotations

import csv
import json
import os
import re
import signal
import subprocess
import sys
import time

import numpy as np
import pytest
from click.testing import CliRunner

from handsynth.cli._main import cli
from handsynth.db import (
    database_meta,
    database_path,
    open_database,
    render_entries,
    write_database,
)
from handsynth.estimate import one_euro
from handsynth.live import live_columns
from handsynth.live._writers import KEYPOINT_COLUMNS, TRUTH_COLUMNS
from handsynth.models import JOINT_LIMITS_DEG, JOINT_NAMES, HandShape, paper_pose_set, read_angle_table
from handsynth.render import CameraMount, SilhouetteRenderer

W, H = 180, 120
SMALL = ["--synthetic-size", f"{W}x{H}", "--fps", "8", "-q"]


@pytest.fixture(scope="module")
def db(tmp_path_factory):
    """A folder with a 200-entry paper database of the standard hand (small renders)."""
    folder = tmp_path_factory.mktemp("estimate_db")
    shape, mount = HandShape(), CameraMount()
    rows = render_entries(paper_pose_set(200, seed=1), shape, mount, render_size=(W, H))
    write_database(database_path(folder, shape),
                   **{k: rows[k] for k in ("angles", "hlac", "sil_bits", "ridge_bits",
                                           "ridge_area", "keypoints")},
                   meta=database_meta(shape, mount, side="right", pose_set="paper", count=200,
                                      seed=1, render_size=(W, H)))
    return folder


@pytest.fixture(scope="module")
def masks():
    """Eight masks of an off-grid hand in paper poses (the frames of a fake video)."""
    with SilhouetteRenderer(HandShape(length=1.02, thumb=1.03), width_px=W, height_px=H) as r:
        return r.masks(paper_pose_set(8, seed=7))


def _run(*args, env=None):
    return CliRunner(env=env).invoke(cli, ["estimate", *args], catch_exceptions=False)


def _lookup(*args, env=None):
    """``handsynth estimate --method paper ARGS``: the paper's database lookup."""
    return _run("--method", "paper", *args, env=env)


def _read_csv(path):
    with open(path, newline="", encoding="utf-8") as f:
        reader = csv.reader(f)
        header = next(reader)
        return header, [dict(zip(header, r, strict=True)) for r in reader]


def test_synthetic_run_writes_csv_and_prints_rates_and_error(tmp_path, db):
    out = tmp_path / "rows.csv"
    res = _lookup("--synthetic", "--db", str(db), "--frames", "24", "--out", str(out), *SMALL)
    assert res.exit_code == 0, res.output
    header, rows = _read_csv(out)
    assert tuple(header) == live_columns(truth=True)
    assert len(rows) == 24
    est = np.array([[float(r[n]) for n in JOINT_NAMES] for r in rows])
    truth = np.array([[float(r[c]) for c in TRUTH_COLUMNS] for r in rows])
    assert ((est >= JOINT_LIMITS_DEG[:, 0] - 1e-3) & (est <= JOINT_LIMITS_DEG[:, 1] + 1e-3)).all()
    text = res.stdout
    fps = re.search(r"estimate ([\d.]+) fps alone .* whole loop ([\d.]+) fps", text)
    assert fps and float(fps[1]) > float(fps[2]) > 0, text
    mae = re.search(r"mean absolute error vs truth ([\d.]+) deg over 24 frames", text)
    assert mae, text
    assert float(mae[1]) == pytest.approx(np.abs(est - truth).mean(), abs=0.01)
    assert float(mae[1]) < 6.0  # measured 2.1 deg (200 paper entries, default off-grid hand)
    const = re.search(r"the open hand answered on every frame: ([\d.]+) deg", text)
    assert const and float(const[1]) == pytest.approx(np.abs(truth).mean(), abs=0.01), text
    assert "stopped: reached 24 frames" in text
    assert f"rows: {out} (24 rows, csv)" in text
    assert "L1.020_W0.970_P1.010_T1.030" in text  # the off-grid default hand


def test_jsonl_with_keypoints_to_a_file_and_to_stdout(tmp_path, db):
    out = tmp_path / "rows.jsonl"
    res = _lookup("--synthetic", "--db", str(db), "--frames", "5", "--out", str(out), "--keypoints",
               "--synthetic-motion", "named", "--no-temporal", *SMALL)
    assert res.exit_code == 0, res.output
    rows = [json.loads(line) for line in out.read_text().splitlines()]
    assert len(rows) == 5
    assert all(tuple(r) == live_columns(keypoints=True, truth=True) for r in rows)
    assert all(isinstance(r[KEYPOINT_COLUMNS[-1]], float) for r in rows)
    assert rows[0]["frame"] == 0 and rows[-1]["timestamp_s"] == pytest.approx(4 / 8)

    res = _lookup("--synthetic", "--db", str(db), "--frames", "3", "--out", "-", "--format",
               "jsonl", *SMALL)
    assert res.exit_code == 0, res.output
    lines = res.stdout.splitlines()
    assert len(lines) == 3 and [json.loads(x)["frame"] for x in lines] == [0, 1, 2]
    assert "whole loop" in res.stderr


def test_video_in_and_side_by_side_video_out(tmp_path, db, masks, read_video):
    import cv2

    video = tmp_path / "hand.avi"
    writer = cv2.VideoWriter(str(video), cv2.VideoWriter_fourcc(*"MJPG"), 15.0, (W, H))
    for m in masks:
        writer.write(np.repeat(m.view(np.uint8)[:, :, None] * np.uint8(255), 3, axis=2))
    writer.release()
    out, video_out = tmp_path / "rows.csv", tmp_path / "side.mp4"
    res = _lookup("--video", str(video), "--db", str(db), "--out", str(out), "--video-out",
               str(video_out), "-q")
    assert res.exit_code == 0, res.output
    _, rows = _read_csv(out)
    assert len(rows) == len(masks)
    assert all(r["no_hand"] == "0" for r in rows)
    assert [float(r["timestamp_s"]) for r in rows] == pytest.approx(np.arange(8) / 15.0, abs=1e-5)
    assert "stopped: the source has no more frames" in res.stdout
    assert "mean absolute error" not in res.stdout  # no truth for a video
    frames, size = read_video(video_out)
    assert size == (2 * W, H) and len(frames) == len(masks)


def test_flaky_then_dead_camera_is_counted_and_ends_with_one_error_line(tmp_path, db, masks,
                                                                        monkeypatch):
    import handsynth.live as live

    class FakeCamera:
        def __init__(self, index):
            self.index, self.n = index, 0

        def read(self):
            self.n += 1
            if self.n > 12:
                return None  # unplugged
            return [masks[self.n % 8], None, np.empty((0, 0, 3), np.uint8)][self.n % 3]

        def close(self):
            pass

    monkeypatch.setattr(live, "CameraSource", FakeCamera)
    out = tmp_path / "rows.csv"
    res = _lookup("--camera", "0", "--db", str(db), "--out", str(out), "--max-dead", "6", "-q")
    assert res.exit_code == 2
    # reads 3, 6, 9, 12 are frames; 1, 2, 4, 5, 7, 8, 10, 11 drops; 13-18 the dead end
    assert "frames 4 (reads 18, dropped 14, invalid 0)" in res.stdout
    err = res.stderr.strip().splitlines()
    assert len(err) == 1
    assert err[0].startswith("handsynth: error: camera 0: no usable frame in 6 consecutive reads")
    _, rows = _read_csv(out)
    assert [int(r["frame"]) for r in rows] == [2, 5, 8, 11]


def test_default_database_is_built_in_the_cache_folder(tmp_path):
    res = _lookup("--synthetic", "--frames", "3", *SMALL,
               env={"HANDSYNTH_CACHE_DIR": str(tmp_path)})
    assert res.exit_code == 0, res.output
    path = database_path(tmp_path / "db", HandShape())
    assert len(open_database(path)) == 3000
    assert f"default database {path} ready" in res.stdout
    assert "frames 3 " in res.stdout


def test_killed_run_leaves_complete_lines(tmp_path, db):
    out = tmp_path / "rows.jsonl"
    cmd = [sys.executable, "-c", "from handsynth.cli import main; main()", "estimate",
           "--method", "paper", "--synthetic", "--db", str(db), "--frames", "100000", "--out",
           str(out), *SMALL]
    proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                            env={**os.environ, "MUJOCO_GL": os.environ.get("MUJOCO_GL", "egl")})
    deadline = time.monotonic() + 60
    try:
        while time.monotonic() < deadline and proc.poll() is None:
            if out.exists() and out.stat().st_size > 20_000:
                break
            time.sleep(0.02)
    finally:
        os.kill(proc.pid, signal.SIGKILL)
        proc.wait()
    assert proc.returncode == -signal.SIGKILL, "the run ended before it could be killed"
    text = out.read_text()
    assert text.endswith("\n")
    frames = [json.loads(line)["frame"] for line in text.splitlines()]
    assert len(frames) >= 10 and frames == list(range(len(frames)))


def test_a_damaged_video_file_is_one_error_line_without_ffmpegs_own(tmp_path, db):
    """FFmpeg writes to the terminal itself (not through Python): run the real process."""
    bad = tmp_path / "clip.mp4"
    bad.write_bytes(b"not a video at all\n" * 20)
    env = {k: v for k, v in os.environ.items() if k != "OPENCV_FFMPEG_LOGLEVEL"}
    proc = subprocess.run([sys.executable, "-c", "from handsynth.cli import main; main()",
                           "estimate", "--method", "paper", "--video", str(bad), "--db", str(db),
                           "--frames", "2"],
                          capture_output=True, text=True, timeout=120, env=env)
    assert proc.returncode == 2
    assert proc.stderr.strip().splitlines() == [
        f"handsynth: error: cannot open video file {str(bad)!r}: OpenCV cannot decode it"]


@pytest.mark.parametrize("args, word", [
    ([], "exactly one source"),
    (["--camera", "0", "--synthetic"], "exactly one source"),
    (["--camera", "99"], "camera 99 could not be opened"),
    (["--video", "{tmp}/missing.mp4"], "missing.mp4"),
    (["--synthetic", "--frames", "-1"], "--frames"),
    (["--synthetic", "--seconds", "0"], "--seconds"),
    (["--synthetic", "--max-dead", "0"], "--max-dead"),
    (["--synthetic", "--out", "{tmp}/rows.txt"], "rows.txt"),
    (["--synthetic", "--out", "-"], "--format"),
    (["--synthetic", "--synthetic-shape", "L1.0_bogus"], "L1.0_bogus"),
    (["--synthetic", "--synthetic-size", "180"], "--synthetic-size"),
    (["--synthetic", "--video-out", "{tmp}/side.gif"], "side.gif"),
    (["--synthetic", "--shape", "L0.950_W0.900_P0.950_T0.900"], "no database for the right hand of shape"),
    (["--synthetic", "--measurements", "{tmp}/hand.json"], "hand.json"),
    (["--synthetic", "--shape", "standard", "--measurements", "{tmp}/m.json"], "not both"),
])
def test_bad_options_give_one_line_errors(tmp_path, db, args, word):
    args = [a.replace("{tmp}", str(tmp_path)) for a in args]
    res = _lookup("--db", str(db), *SMALL, *args)
    assert res.exit_code == 2, res.output
    lines = res.output.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("handsynth: error:"), res.output
    assert word in lines[0]


def test_synthetic_angles_are_replayed_once_as_the_truth(tmp_path, db):
    """Another system's recording (uneven times, a joint beyond the model's range) shown
    frame by frame at --fps; the rows' truth is the recording's."""
    rng = np.random.default_rng(8)
    t = np.cumsum(rng.uniform(0.03, 0.06, 30))
    lo, hi = JOINT_LIMITS_DEG.T
    angles = rng.uniform(lo, hi, (30, 20))
    angles[5, JOINT_NAMES.index("index_mcp_abd")] = 30.0
    table = tmp_path / "imu_angles.csv"
    table.write_text("time_s," + ",".join(JOINT_NAMES) + "\n" + "".join(
        f"{ti:.6f}," + ",".join(f"{v:.4f}" for v in a) + "\n" for ti, a in zip(t, angles)))
    out = tmp_path / "rows.csv"
    res = _lookup("--synthetic", "--db", str(db), "--synthetic-angles", str(table),
                  "--out", str(out), *SMALL)  # at SMALL's --fps 8
    assert res.exit_code == 0, res.output
    assert "1 of" in res.output and "(index_mcp_abd); shown at the range's end" in res.output
    assert "stopped: the source has no more frames" in res.output
    _, rows = _read_csv(out)
    expected, rate = read_angle_table(table).resampled(8.0)
    assert rate == 8.0 and len(rows) == len(expected) == int((t[-1] - t[0]) * 8 + 1e-6) + 1
    truth = np.array([[float(r[c]) for c in TRUTH_COLUMNS] for r in rows])
    np.testing.assert_allclose(truth, np.clip(expected, lo, hi), atol=1e-3)
    res = _lookup("--camera", "0", "--db", str(db), "--synthetic-angles", str(table))
    assert res.exit_code == 2 and "--synthetic-angles is the motion of --synthetic" in res.output
    res = _lookup("--synthetic", "--db", str(db), "--synthetic-angles", str(tmp_path / "no.csv"))
    assert res.exit_code == 2 and "no such file" in res.output


def test_missing_database_folder(tmp_path):
    res = _lookup("--synthetic", "--db", str(tmp_path / "nowhere"), *SMALL)
    assert res.exit_code == 2
    assert res.output.strip() == (f"handsynth: error: database folder "
                                  f"{str(tmp_path / 'nowhere')!r} does not exist")


def test_personal_database_for_a_shape(tmp_path):
    shape = "L1.020_W0.970_P1.010_T1.030"
    res = _lookup("--synthetic", "--frames", "3", "--db", str(tmp_path), "--shape", shape,
               "--personal", "--personal-count", "40", *SMALL)
    assert res.exit_code == 0, res.output
    assert f"personal database {tmp_path / (shape + '.h5')} ready" in res.output
    db = open_database(tmp_path / f"{shape}.h5")
    assert len(db) == 40 and HandShape(**db.meta["shape"]).name == shape
    # another count replaces the file, and says so (before: silently)
    res = _lookup("--synthetic", "--frames", "3", "--db", str(tmp_path), "--shape", shape,
               "--personal", "--personal-count", "30", *SMALL)
    assert res.exit_code == 0, res.output
    assert "warning: built again, replacing an existing file" in res.output
    assert "'pose_set.count' is 40 in the file but 30 is expected" in res.output
    assert len(open_database(tmp_path / f"{shape}.h5")) == 30


@pytest.mark.parametrize("args, words", [
    (["--personal"], "--personal needs --shape NAME or --measurements FILE"),
    (["--personal-count", "10", "--shape", "standard"], "--build-count applies to a database"),
    (["--build-count", "10", "--calibrate", "--shape", "standard"], "--build-count applies"),
    (["--build-count", "0", "--calibrate"], "--build-count must be a positive integer, got 0"),
    (["--calibrate-image", "{tmp}/open.png"], "cannot read the calibration image"),
])
def test_personal_errors_are_one_line(tmp_path, args, words):
    args = [a.replace("{tmp}", str(tmp_path)) for a in args]
    res = _lookup("--synthetic", "--frames", "2", "--db", str(tmp_path), *args, *SMALL)
    assert res.exit_code != 0 and words in res.output and "Traceback" not in res.output


# --------------------------------------------------------------------------- calibration


def _open_mask(shape: HandShape | None = None):
    with SilhouetteRenderer(shape or HandShape(length=1.02, thumb=1.03), width_px=W,
                            height_px=H) as r:
        return r.mask(np.zeros(20))


def test_calibrate_synthetic_hand_on_a_chosen_database(tmp_path, db):
    out = tmp_path / "rows.csv"
    res = _lookup("--synthetic", "--calibrate", "--shape", "standard", "--db", str(db), "--frames",
               "6", "--out", str(out), *SMALL)
    assert res.exit_code == 0, res.output
    line = re.search(r"calibrated to the synthetic hand held open in [\d.]+ s: database "
                     r"L1.000_W1.000_P1.000_T1.000.h5, open-hand IoU (0\.\d+), (\d+) of 4096 "
                     r"pixels ignored", res.stdout)
    assert line, res.stdout
    assert 0.8 < float(line[1]) < 1.0 and int(line[2]) > 0  # an off-grid hand: some mismatch
    _, rows = _read_csv(out)
    assert len(rows) == 6 and rows[0]["frame"] == "0"
    assert float(rows[0]["confidence"]) == 1.0  # frame 0 of the paper motion is the open hand


def test_calibrate_on_the_first_hand_frame_of_a_video(tmp_path, db, masks):
    import cv2

    video = tmp_path / "hand.avi"
    frames = [np.zeros((H, W), bool), _open_mask(), *masks]  # no hand yet, then the open hand
    writer = cv2.VideoWriter(str(video), cv2.VideoWriter_fourcc(*"MJPG"), 15.0, (W, H))
    for m in frames:
        writer.write(np.repeat(m.view(np.uint8)[:, :, None] * np.uint8(255), 3, axis=2))
    writer.release()
    out = tmp_path / "rows.csv"
    res = _lookup("--video", str(video), "--calibrate", "--shape", "standard", "--db", str(db),
               "--out", str(out), "-q")
    assert res.exit_code == 0, res.output
    assert "hold the hand open and flat" in res.stdout
    assert "calibrated to the first frame showing a hand" in res.stdout
    _, rows = _read_csv(out)
    assert len(rows) == len(masks)  # the two calibration reads are not rows


def test_calibrate_image_chooses_and_builds_the_database(tmp_path):
    import cv2

    from handsynth.estimate import select_shape_from_frame

    image = tmp_path / "open.png"
    user = HandShape(length=1.02, thumb=1.03)
    cv2.imwrite(str(image), _open_mask(user).view(np.uint8) * np.uint8(255))
    expect = select_shape_from_frame(_open_mask(user)).shape
    dbs = tmp_path / "dbs"
    res = _lookup("--synthetic", "--synthetic-shape", user.name, "--calibrate-image", str(image),
               "--build-count", "30", "--db", str(dbs), "--frames", "4", *SMALL)
    assert res.exit_code == 0, res.output
    assert "calibrated to the calibration image in" in res.stdout
    assert f"database {expect.name}.h5, open-hand IoU" in res.stdout
    assert len(open_database(database_path(dbs, expect))) == 30
    assert "frames 4 " in res.stdout


# --------------------------------------------------------------------------- faults (issue 16)


def _write_video(path, frames):
    import cv2

    h, w = frames[0].shape[:2]
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"MJPG"), 15.0, (w, h))
    for f in frames:
        writer.write(f)
    writer.release()
    return path


@pytest.fixture
def hand_video(tmp_path, masks):
    frames = [np.repeat(m.view(np.uint8)[:, :, None] * np.uint8(255), 3, axis=2) for m in masks]
    return _write_video(tmp_path / "hand.avi", frames)


def test_rows_on_a_full_disk_are_one_error_and_complete_lines(full_disk, db):
    # item 7: a traceback and half a row
    out = full_disk / "rows.csv"
    (full_disk / "filler").write_bytes(b"\0" * (256 * 1024 - 24 * 1024))  # leave ~24 KiB
    res = _lookup("--synthetic", "--db", str(db), "--out", str(out), "--keypoints", "--frames",
               "400", *SMALL)
    assert res.exit_code == 2, res.output
    assert "Traceback" not in res.output
    assert "cannot write rows to" in res.output and "no space left" in res.output
    text = out.read_text()
    assert text and text.endswith("\n")
    header, rows = _read_csv(out)
    assert 0 < len(rows) < 400 and all(len(r) == len(header) and None not in r.values()
                                       for r in rows)


def test_side_by_side_video_on_a_full_disk_is_an_error_not_a_truncated_file(full_disk, db):
    # item 7: exit 0 and a truncated video reported as complete
    out = full_disk / "side.avi"
    res = _lookup("--synthetic", "--db", str(db), "--video-out", str(out), "--frames", "120", *SMALL)
    assert res.exit_code == 2, res.output
    assert "cannot write the video" in res.output and "Traceback" not in res.output
    assert list(full_disk.iterdir()) == []


@pytest.mark.parametrize("option", ["--out", "--video-out"])
def test_an_output_never_replaces_the_input_video(tmp_path, db, hand_video, option):
    # item 11: --out or --video-out equal to --video overwrote it with exit 0
    before = hand_video.read_bytes()
    link = tmp_path / "link.avi"
    link.symlink_to(hand_video)
    for target in (hand_video, link):
        args = [option, str(target)] + (["--format", "csv"] if option == "--out" else [])
        res = _lookup("--video", str(hand_video), "--db", str(db), *args, "-q")
        assert res.exit_code == 2 and "never replaces an input" in res.output, res.output
    assert hand_video.read_bytes() == before


def test_rows_never_replace_the_database(tmp_path, db):
    path = database_path(db, HandShape())
    before = path.read_bytes()
    res = _lookup("--synthetic", "--db", str(db), "--out", str(path), "--format", "csv", *SMALL)
    assert res.exit_code == 2 and "never replaces an input" in res.output, res.output
    assert path.read_bytes() == before


def test_a_video_whose_every_frame_is_refused_is_an_error(tmp_path, db):
    # item 12: exit 0 with 0 rows
    tiny = _write_video(tmp_path / "tiny.avi", [np.full((6, 6, 3), 200, np.uint8)] * 5)
    out = tmp_path / "rows.csv"
    res = _lookup("--video", str(tiny), "--db", str(db), "--out", str(out), "-q")
    assert res.exit_code == 2, res.output
    assert "no frame could be used" in res.output and "5 refused" in res.output


@pytest.mark.parametrize("args, words", [
    (["--format", "jsonl"], ["--format jsonl applies to the rows of --out"]),      # item 19
    (["--out", "{tmp}/nowhere/rows.csv"], ["folder", "nowhere", "does not exist"]),  # item 9
    (["--out", "{tmp}/sub.csv"], ["is a folder"]),
    (["--db", "{db_file}"], ["is a file; give the folder"]),                          # item 15
])
def test_misleading_or_silent_options_give_clear_errors(tmp_path, db, args, words):
    db_file = database_path(db, HandShape())
    (tmp_path / "sub.csv").mkdir()
    args = [a.format(tmp=tmp_path, db_file=db_file) for a in args]
    if "--db" not in args:
        args += ["--db", str(db)]
    res = _lookup("--synthetic", *args, *SMALL)
    assert res.exit_code == 2, res.output
    assert res.output.count("\n") == 1 and all(w in res.output for w in words), res.output


@pytest.mark.parametrize("kind", ["folder", "dangling link"])
def test_a_folder_or_dangling_link_named_like_a_database_is_named(tmp_path, kind):
    # item 15: "no database for shape X (have: X)"
    name = tmp_path / f"{HandShape().name}.h5"
    if kind == "folder":
        name.mkdir()
    else:
        name.symlink_to(tmp_path / "gone.h5")
    res = _lookup("--synthetic", "--db", str(tmp_path), *SMALL)
    assert res.exit_code == 2
    assert ("is a folder, not a file" if kind == "folder" else "which does not exist") \
        in res.output, res.output


@pytest.mark.parametrize("where", ["--db", "cache"])
def test_a_read_only_database_folder_names_the_real_reason(read_only_folder, where):
    # item 4: --personal and the default cache in a read-only folder hid the real error
    args = ["--synthetic", "--frames", "2", *SMALL]
    env = None
    if where == "--db":
        args += ["--shape", "standard", "--personal", "--db", str(read_only_folder),
                 "--build-count", "50"]
    else:
        env = {"HANDSYNTH_CACHE_DIR": str(read_only_folder)}
    res = _lookup(*args, env=env)
    assert res.exit_code == 2, res.output
    assert "read-only" in res.output and "Traceback" not in res.output


def test_learned_estimator_on_a_synthetic_hand_learns_once_then_reads_its_cache(tmp_path):
    cache = tmp_path / "learned"
    out = tmp_path / "rows.csv"
    args = ["--synthetic", "--learned", "--learned-cache", str(cache), "--learned-hands", "6",
            "--frames", "12", "--synthetic-motion", "natural", "--learned-kind", "fingers", *SMALL]
    res = _run(*args, "--out", str(out))
    assert res.exit_code == 0, res.output
    assert "learning set: 6 hands x 100 frames" in res.output
    assert "learning set: 6 of 6 hands rendered" in res.output  # what a first run waits for
    assert "(once, minutes; then read from the cache; --learned-kind perceptrons learns " \
        "nothing)" in res.output
    assert "with the learnt estimator (fingers)" in res.output
    assert "calibrated to the synthetic hand at rest (open)" in res.output
    header, rows = _read_csv(out)
    assert tuple(header) == live_columns(truth=True)
    est = np.array([[float(r[n]) for n in JOINT_NAMES] for r in rows])
    assert est.shape == (12, 20) and np.isfinite(est).all()
    assert ((est >= JOINT_LIMITS_DEG[:, 0] - 1e-3) & (est <= JOINT_LIMITS_DEG[:, 1] + 1e-3)).all()
    assert re.search(r"mean absolute error vs truth [\d.]+ deg over 12 frames", res.output)
    assert sorted(p.name.split("_")[0] for p in cache.iterdir()) == ["learned", "learning"]
    again = _run(*args, "--smoothing", "0.5", "--out", str(tmp_path / "smooth.csv"))
    assert again.exit_code == 0, again.output
    assert "learning set:" not in again.output  # read from the cache
    _, smooth_rows = _read_csv(tmp_path / "smooth.csv")
    smooth = np.array([[float(r[n]) for n in JOINT_NAMES] for r in smooth_rows])
    np.testing.assert_allclose(smooth[0], est[0])  # nothing to smooth with yet
    np.testing.assert_allclose(smooth[1], 0.5 * smooth[0] + 0.5 * est[1], atol=1e-3)
    steady = _run(*args, "--one-euro", "--out", str(tmp_path / "steady.csv"))
    assert steady.exit_code == 0, steady.output
    _, steady_rows = _read_csv(tmp_path / "steady.csv")
    got = np.array([[float(r[n]) for n in JOINT_NAMES] for r in steady_rows])
    # the frames' own answers through the One Euro filter at the synthetic source's rate
    np.testing.assert_allclose(got, one_euro(est, rate_hz=8.0), atol=2e-3)
    assert np.abs(got - est).max() > 0.01


@pytest.mark.slow
def test_learned_estimator_from_relaxed_rests_is_learnt_beside_the_default(tmp_path):
    args = ["--synthetic", "--learned", "--learned-cache", str(tmp_path), "--learned-hands", "6",
            "--learned-kind", "fingers", "--frames", "4", *SMALL]
    for extra in ([], ["--learned-rest", "relaxed"]):
        res = _run(*args, *extra)
        assert res.exit_code == 0, res.output
        assert "learning set: 6 hands x 100 frames" in res.output  # each learns its own
    assert len(list(tmp_path.glob("learning_*.npz"))) == 2


def test_the_learnt_estimator_is_the_default_method_and_the_paper_s_lookup_is_named(tmp_path, db):
    res = _run("--synthetic", "--learned-kind", "perceptrons", "--learned-cache", str(tmp_path),
               "--frames", "3", *SMALL)
    assert res.exit_code == 0, res.output
    assert "with the learnt estimator (perceptrons)" in res.output
    res = _run("--synthetic", "--method", "paper", "--db", str(db), "--frames", "3", *SMALL)
    assert res.exit_code == 0, res.output
    assert f"against {database_path(db, HandShape()).name} (200 entries)" in res.output


@pytest.mark.parametrize("side", ["right", "left"])  # a left hand: the right's perceptrons mirrored
def test_the_shipped_perceptrons_alone_run_on_a_first_run_without_learning_anything(tmp_path, side):
    cache = tmp_path / "learned"
    out = tmp_path / "rows.csv"
    res = _run("--synthetic", "--learned", "--learned-kind", "perceptrons", "--learned-cache",
               str(cache), "--frames", "24", "--synthetic-motion", "natural", "--out", str(out),
               "--side", side, *SMALL)
    assert res.exit_code == 0, res.output
    assert "with the learnt estimator (perceptrons)" in res.output
    assert len(set(re.findall(r"mlp \((learned_mlp_\w+\.npz)\): shipped with handsynth", res.output))) == 3
    assert "learning set" not in res.output and not list(cache.glob("learning_*"))
    _header, rows = _read_csv(out)
    est = np.array([[float(r[n]) for n in JOINT_NAMES] for r in rows])
    truth = np.array([[float(r["true_" + n]) for n in JOINT_NAMES] for r in rows])
    assert est.shape == (24, 20) and np.isfinite(est).all()
    # natural poses: far better than answering the open hand
    assert np.abs(est - truth).mean() < 0.5 * np.abs(truth).mean()


@pytest.mark.parametrize("side", ["right", "left"])
def test_learned_keypoints_are_the_named_hand_posed_by_the_written_angles(tmp_path, side):
    """--learned --keypoints: each row's keypoints are the --shape hand posed by its angles."""
    from handsynth.models import HandModel

    out = tmp_path / "rows.csv"
    shape = HandShape(length=1.1, width=0.95)
    res = _run("--synthetic", "--learned", "--learned-kind", "perceptrons", "--learned-cache",
               str(tmp_path / "learned"), "--frames", "10", "--synthetic-motion", "natural",
               "--keypoints", "--shape", shape.name, "--side", side, "--out", str(out), *SMALL)
    assert res.exit_code == 0, res.output
    assert f"keypoints of the handsynth hand {shape.name}" in res.output
    header, rows = _read_csv(out)
    assert header[-len(TRUTH_COLUMNS) - len(KEYPOINT_COLUMNS):-len(TRUTH_COLUMNS)] \
        == list(KEYPOINT_COLUMNS)
    model = HandModel(shape, side=side)
    tips = []
    for r in rows:
        model.set_pose([float(r[n]) for n in JOINT_NAMES])
        got = np.array([float(r[c]) for c in KEYPOINT_COLUMNS]).reshape(21, 3)
        np.testing.assert_allclose(got, model.keypoints(), atol=2e-6)  # written to 6 decimals
        tips.append(got[[4, 8, 12, 16, 20]])
    assert np.ptp(np.array(tips), axis=0).max() > 0.01  # the fingertips move with the hand
    # a left hand's thumb lies at +x, a right hand's at -x
    assert (np.array(tips)[:, 0, 0] > 0).all() == (side == "left")


@pytest.mark.parametrize(("extra", "message"), [
    (["--shape", "standard"], "--shape with the learnt estimator (the default method) says "
                              "whose keypoints to report, and --keypoints was not given"),
    (["--measurements", "m.json"],
     "--measurements with the learnt estimator (the default method) says whose"),
    (["--keypoints", "--shape", "standard", "--measurements", "m.json"],
     "give --shape or --measurements, not both"),
    (["--keypoints", "--shape", "L9"], "hand-shape name 'L9' is not of the form"),
    (["--personal", "--shape", "standard"], "--personal applies to the paper's database lookup"),
])
def test_learned_keypoint_options_are_checked_by_name(tmp_path, extra, message):
    res = CliRunner().invoke(cli, ["estimate", "--synthetic", "--learned", "--learned-cache",
                                   str(tmp_path / "c"), "--out", str(tmp_path / "r.csv"),
                                   *extra, *SMALL])
    assert res.exit_code == 2, res.output
    assert message in res.output
    assert "Traceback" not in res.output and not (tmp_path / "r.csv").exists()


@pytest.mark.slow
def test_learned_estimator_for_the_left_hand(tmp_path):
    res = _run("--synthetic", "--learned", "--side", "left", "--learned-cache", str(tmp_path),
               "--learned-hands", "6", "--learned-kind", "fingers", "--frames", "4", *SMALL)
    assert res.exit_code == 0, res.output
    assert "learnt estimator (fingers, left hand)" in res.output
    assert re.search(r"mean absolute error vs truth [\d.]+ deg over 4 frames", res.output)


@pytest.mark.parametrize(("extra", "message"), [
    (["--learned", "--db", "dbs"],
     "--db applies to the paper's database lookup (--method paper), not to the learnt estimator"),
    # the learnt estimator is the default: a lookup's option alone names the method to give
    (["--db", "dbs"], "--db applies to the paper's database lookup (--method paper)"),
    (["--shape", "standard"], "--method paper chooses a database by it"),
    (["--learned", "--calibrate", "--no-temporal"],
     "--calibrate, --no-temporal apply to the paper's database lookup (--method paper)"),
    (["--learned", "--method", "paper"], "--learned and --method paper name two methods"),
    (["--method", "paper", "--learned-hands", "5"], "apply to the learnt estimator, not to "
                                                     "--method paper"),
    (["--method", "paper", "--learned-kind", "ensemble"], "not to --method paper"),
    (["--method", "paper", "--smoothing", "0.3"], "not to --method paper"),
    (["--method", "paper", "--learned-rest", "relaxed"], "not to --method paper"),
    (["--method", "paper", "--one-euro"], "--segment and --one-euro apply to the learnt"),
    (["--method", "paper", "--segment", "colour"], "--segment and --one-euro apply to the learnt"),
    (["--learned", "--one-euro", "--smoothing", "0.3"],
     "--one-euro and --smoothing are two ways to steady the angles; give one"),
    (["--learned", "--smoothing", "1"], "--smoothing must be in [0, 1), got 1.0"),
    (["--learned", "--learned-hands", "0"], "--learned-hands must be a positive integer, got 0"),
    # found by trying: a MemoryError traceback (12 PiB of learning frames)
    (["--learned", "--learned-kind", "fingers", "--learned-hands", "99999999999"],
     "--learned-hands must be at most 100,000"),
])
def test_learned_options_that_do_not_apply_are_refused_by_name(tmp_path, extra, message):
    res = CliRunner().invoke(cli, ["estimate", "--synthetic", "--learned-cache" if "--learned" in
                                   extra else "--frames", str(tmp_path / "c") if "--learned" in
                                   extra else "1", *extra, *SMALL])
    assert res.exit_code == 2, res.output
    assert message in res.output
    assert "Traceback" not in res.output


def test_a_left_hands_lookup_opens_its_own_database(tmp_path):
    """A left hand's database is <shape>_left.h5; --side chooses it (the right's is refused)."""
    shape, mount = HandShape(), CameraMount()
    rows = render_entries(paper_pose_set(60, seed=1), shape, mount, side="left", render_size=(W, H))
    write_database(database_path(tmp_path, shape, side="left"),
                   **{k: rows[k] for k in ("angles", "hlac", "sil_bits", "ridge_bits",
                                           "ridge_area", "keypoints")},
                   meta=database_meta(shape, mount, side="left", pose_set="paper", count=60,
                                      seed=1, render_size=(W, H)))
    res = _lookup("--synthetic", "--side", "left", "--db", str(tmp_path), "--frames", "3", *SMALL)
    assert res.exit_code == 0 and "reached 3 frames" in res.output, res.output
    res = _lookup("--synthetic", "--db", str(tmp_path), "--frames", "3", *SMALL)
    assert res.exit_code == 2 and "no database for the right hand" in res.output, res.output
    assert "_left" in res.output


def test_a_measurement_file_chooses_the_database_measure_printed(tmp_path):
    """Measured millimetres, no palm-width scaling: as `measure` and --personal choose.
    Before, the lookup scaled by palm width and chose another shape (W1.000, T1.000)."""
    import json

    from handsynth.estimate import SelectionOptions, select_shape
    from handsynth.models import model_measurements

    meas = model_measurements(HandShape(length=0.97, width=1.06, palm=1.03, thumb=1.07))
    (tmp_path / "m.json").write_text(json.dumps(meas.as_dict()))
    want = select_shape(meas, options=SelectionOptions(normalize="none")).name
    (tmp_path / "dbs").mkdir()
    res = _lookup("--synthetic", "--db", str(tmp_path / "dbs"), "--measurements",
                  str(tmp_path / "m.json"), "--frames", "1", *SMALL)
    assert res.exit_code == 2 and f"no database for the right hand of shape {want}" in res.output, \
        res.output


def test_the_progress_line_says_when_the_device_has_moved():
    import io

    from handsynth.cli._estimate import _progress
    from handsynth.live import LiveSummary

    def summary(moved):
        return LiveSummary(reads=40, frames=40, dropped=0, invalid=0, no_hand=0, low_confidence=0,
                           lookup_s=0.1, wall_s=0.2, steady_wall_s=0.2, read_s=0.05,
                           first_lookup_ms=3.0, lookup_ms_median=2.5, lookup_ms_p99=4.0,
                           stop_reason="running", message="running", moved=moved)

    out = io.StringIO()
    _progress(out)(summary(0))
    assert "MOVED" not in out.getvalue()
    _progress(out)(summary(11))
    assert "DEVICE MOVED (11 frames): take the rest frame again" in out.getvalue()


def test_telling_the_skin_by_colour_needs_colour_frames(tmp_path):
    res = _run("--synthetic", "--learned", "--learned-kind", "perceptrons", "--learned-cache",
               str(tmp_path), "--frames", "3", "--segment", "colour", *SMALL)
    assert res.exit_code == 2, res.output
    assert "rest_frame must be a uint8 colour (H, W, 3) frame" in res.output
    assert "Traceback" not in res.output
    res = _run("--synthetic", "--learned", "--learned-kind", "perceptrons", "--learned-cache",
               str(tmp_path), "--frames", "3", "--segment", "brightness", *SMALL)
    assert res.exit_code == 0, res.output


def test_a_video_over_photographs_is_told_by_colour_and_brightness_says_it_fails(tmp_path):
    import cv2

    from handsynth.eval import background_photos, natural_test_poses, relaxed_rest_posture
    from handsynth.testhands import MeshHandRenderer, shipped_hand_path

    photos = background_photos()
    rng = np.random.default_rng(2)
    rest = relaxed_rest_posture(rng)
    poses = natural_test_poses(rest, 12, rng)[0]
    skin = np.array([95, 125, 180], np.uint8)

    def paint(mask, k):
        f = photos[k % len(photos)].copy()
        f[mask] = skin
        return f

    with MeshHandRenderer(path=shipped_hand_path("mrtk")) as r:
        cv2.imwrite(str(tmp_path / "rest.png"), paint(r.mask(rest), 0))
        video = tmp_path / "hand.avi"
        writer = cv2.VideoWriter(str(video), cv2.VideoWriter_fourcc(*"MJPG"), 15.0, (720, 480))
        for k, m in enumerate(r.masks(poses)):
            writer.write(paint(m, k))
        writer.release()
    args = ["--video", str(video), "--learned", "--learned-kind", "fingers", "--learned-hands", "6",
            "--learned-cache", str(tmp_path / "cache"), "--calibrate-image",
            str(tmp_path / "rest.png")]  # the per-digit member says what is unlike any learnt
    res = _run(*args)
    assert res.exit_code == 0, res.output
    assert "the hand is told by the skin's colour" in res.output
    res = _run(*args, "--segment", "brightness")
    assert res.exit_code == 0, res.output
    assert "the hand is told by brightness" in res.output
    assert re.search(r"\d+ of 12 frames were unlike any learnt: if the background is not dark, "
                     r"--segment colour", res.output)


def test_a_failed_run_leaves_an_earlier_rows_file_as_it_was(tmp_path, db, hand_video):
    # the rows file was opened (its header written over the earlier rows) before a bad
    # --video-out or --seconds was refused, or before the run found no usable frame
    out = tmp_path / "keep.csv"
    res = _lookup("--video", str(hand_video), "--db", str(db), "--out", str(out), "-q")
    assert res.exit_code == 0, res.output
    before = out.read_bytes()
    tiny = _write_video(tmp_path / "tiny.avi", [np.full((6, 6, 3), 200, np.uint8)] * 3)
    for args in (["--video", str(hand_video), "--video-out", str(tmp_path / "v.csv")],
                 ["--video", str(hand_video), "--video-out", str(tmp_path / "no" / "v.avi")],
                 ["--video", str(hand_video), "--seconds", "inf"],
                 ["--video", str(tiny)]):
        res = _lookup(*args, "--db", str(db), "--out", str(out), "-q")
        assert res.exit_code == 2, (args, res.output)
        assert out.read_bytes() == before, args
    fresh = tmp_path / "fresh.csv"
    res = _lookup("--video", str(tiny), "--db", str(db), "--out", str(fresh), "-q")
    assert res.exit_code == 2 and not fresh.exists()  # no header-only file either


def test_refused_frames_say_why(tmp_path, db):
    # "no frame could be used (... 5 refused)" and rates of nan, without the reason
    tiny = _write_video(tmp_path / "tiny.avi", [np.full((6, 6, 3), 200, np.uint8)] * 5)
    res = _lookup("--video", str(tiny), "--db", str(db), "-q")
    assert res.exit_code == 2
    assert "(the first refused: " in res.output and "nan" not in res.output, res.output


@pytest.mark.parametrize("args, words", [
    (["--synthetic", "--synthetic-size", "100000x100000"], "at most 4096x4096"),
    (["--synthetic", "--fps", "inf"], "--fps must be a positive finite number"),
    (["--video", "{tmp}"], "is a folder"),
    (["--synthetic", "--shape", "L9.000_W1.000_P1.000_T1.000"],
     "HandShape.length=9.0 is outside the supported range"),
])
def test_out_of_range_sizes_rates_and_names_are_named(tmp_path, db, args, words):
    args = [a.replace("{tmp}", str(tmp_path)) for a in args]
    res = _lookup(*args, "--db", str(db), "-q")
    assert res.exit_code == 2 and words in res.output, res.output


# --------------------------------------------------------------------------- found by trying

LEARNT = ["--learned", "--learned-kind", "perceptrons"]


def _measurement_files(folder):
    """Damaged measurement files, each with a word its error must hold (the field)."""
    from handsynth.models import model_measurements

    good = model_measurements(HandShape(length=1.05, width=0.95)).as_dict()
    cm = {k: ([x / 10 for x in v] if isinstance(v, list) else v / 10 if isinstance(v, float)
              else v) for k, v in good.items()}
    files = {
        "empty.csv": ("", "L1"),
        "text.json": ("hello\n", "JSON"),
        "negative.json": (json.dumps({**good, "L": [-x for x in good["L"]]}),
                          "L1"),
        "no_palm.json": (json.dumps({k: v for k, v in good.items() if k != "P_width"}),
                         "P_width"),
        "cm.json": (json.dumps(cm), ""),  # the field depends on the check that refuses it
    }
    for name, (text, _) in files.items():
        (folder / name).write_text(text)
    return {name: words for name, (_, words) in files.items()}


@pytest.mark.parametrize("learned", [True, False])
def test_a_damaged_measurement_file_is_one_line_naming_the_option_and_the_file(tmp_path, db,
                                                                               learned):
    # "measurements have unknown names [] and missing names [...]", "L1 must be a positive
    # finite length in mm, got -38.5", "HandShape.length=0.105 is outside the supported
    # range": no word of which option or file
    for name, words in _measurement_files(tmp_path).items():
        path = tmp_path / name
        args = ([*LEARNT, "--learned-cache", str(tmp_path / "c"), "--keypoints", "--out",
                 str(tmp_path / "r.csv")] if learned else ["--method", "paper", "--db", str(db)])
        res = _run("--synthetic", *args, "--measurements", str(path), "--frames", "2", *SMALL)
        assert res.exit_code == 2, (name, res.output)
        errors = [line for line in res.output.splitlines() if "error" in line]
        assert len(errors) == 1 and "Traceback" not in res.output, res.output
        assert "--measurements" in errors[0] and str(path) in errors[0], errors[0]
        assert words in errors[0], errors[0]
        assert not (tmp_path / "r.csv").exists()


def test_measurements_that_give_no_hand_fail_before_the_default_database_is_built(
        tmp_path, monkeypatch):
    # a file in centimetres was refused only after the default database had been built
    # (5 s; a first run's cache did not exist yet)
    _measurement_files(tmp_path)
    monkeypatch.setenv("HANDSYNTH_CACHE_DIR", str(tmp_path / "cache"))
    res = _lookup("--synthetic", "--measurements", str(tmp_path / "cm.json"), "--frames", "2")
    assert res.exit_code == 2, res.output
    assert res.output.splitlines()[-1].startswith("handsynth: error: --measurements"), res.output
    assert "millimetres" in res.output  # the warning says why
    assert not (tmp_path / "cache").exists()


@pytest.mark.parametrize("option", ["--video", "--measurements", "--calibrate-image", "--out",
                                    "--video-out"])
def test_an_empty_file_name_is_refused_by_option_not_read_as_the_current_folder(tmp_path, db,
                                                                                option):
    # --video '' said "video file '.' is a folder", --calibrate-image '' "cannot read the
    # calibration image '.'", --measurements '' "cannot read measurement file .: Is a directory"
    source = ["--video", str(tmp_path / "v.avi")] if option != "--video" else []
    res = _lookup(*source, "--db", str(db), option, "", "-q")
    assert res.exit_code == 2
    assert res.output.strip() == f"handsynth: error: {option} must name a file, got ''"


@pytest.mark.parametrize("fps", ["1e-310", "1e-300", "1e9"])
def test_a_frame_rate_far_outside_any_camera_is_refused(tmp_path, db, fps):
    # 1e-310: an OverflowError traceback (infinite media time); 1e-300: rows with timestamps
    # of 1e300 s written as valid; 1e9: every timestamp 0.0
    res = _lookup("--synthetic", "--db", str(db), "--frames", "3", "--out",
               str(tmp_path / "r.jsonl"), "--synthetic-size", f"{W}x{H}", "--fps", fps, "-q")
    assert res.exit_code == 2
    assert res.output.strip() == ("handsynth: error: --fps must be within [0.01, 10000] frames "
                                  f"per second, got {float(fps):g}")
    assert not (tmp_path / "r.jsonl").exists()


def test_hand_shape_options_name_themselves_and_take_standard_alike(tmp_path, db):
    # --shape standard was taken and --synthetic-shape standard refused; a bad name did not
    # say which of the two options it came from
    res = _lookup("--synthetic", "--db", str(db), "--synthetic-shape", "standard", "--frames", "2",
               *SMALL)
    assert res.exit_code == 0 and "synthetic hand L1.000_W1.000_P1.000_T1.000" in res.output, \
        res.output
    for option in ("--synthetic-shape", "--shape"):
        res = _lookup("--synthetic", "--db", str(db), option, "L9", "--frames", "2", *SMALL)
        assert res.exit_code == 2
        assert res.output.startswith(f"handsynth: error: {option} 'L9': hand-shape name 'L9' is "
                                     "not of the form"), res.output


def test_a_video_that_gives_no_rest_frame_is_named(tmp_path):
    # "the source ended before a frame showed a hand to calibrate with" and "frame is
    # 3840x2160 pixels; ..." without the video's name
    import cv2

    empty = tmp_path / "empty.avi"  # a header and no frame
    cv2.VideoWriter(str(empty), cv2.VideoWriter_fourcc(*"MJPG"), 15.0, (W, H)).release()
    wide_frames = [np.zeros((90, 160, 3), np.uint8) for _ in range(2)]
    for f in wide_frames:
        f[20:70, 40:120] = 255
    wide = _write_video(tmp_path / "wide.avi", wide_frames)
    for video, words in ((empty, "the source ended before a frame showed a hand"),
                         (wide, "frame is 160x90 pixels")):
        res = _run("--video", str(video), *LEARNT, "--learned-cache", str(tmp_path / "c"), "-q")
        assert res.exit_code == 2, res.output
        err = res.output.strip().splitlines()[-1]
        assert err.startswith(f"handsynth: error: video {video}: ") and words in err, err


def test_a_grey_video_is_no_hand_not_a_confident_pose(tmp_path):
    # the learnt estimator read a hand into the compression noise of a grey video (values
    # 126 and 128), with confidence 0.74-0.79 and no low_confidence; without a rest image
    # it even calibrated to the first grey frame
    grey = np.full((H, W, 3), 128, np.uint8)
    grey[: H // 3] = 126
    video = _write_video(tmp_path / "grey.avi", [grey] * 4)
    rest = tmp_path / "rest.png"
    import cv2

    cv2.imwrite(str(rest), _open_mask().view(np.uint8) * np.uint8(255))
    out = tmp_path / "rows.csv"
    res = _run("--video", str(video), *LEARNT, "--learned-cache", str(tmp_path / "c"),
               "--calibrate-image", str(rest), "--keypoints", "--out", str(out), "-q")
    assert res.exit_code == 0, res.output
    _, rows = _read_csv(out)
    assert len(rows) == 4 and all(r["no_hand"] == "1" and r["confidence"] == "0.0" for r in rows)
    assert all(r[c] == "" for r in rows for c in (*JOINT_NAMES, *KEYPOINT_COLUMNS))
    res = _run("--video", str(video), *LEARNT, "--learned-cache", str(tmp_path / "c"), "-q")
    assert res.exit_code == 2
    assert res.output.strip().splitlines()[-1] == (
        f"handsynth: error: video {video}: the source ended before a frame showed a hand to "
        "calibrate with")


def _bgr(mask):
    """A mask painted as skin on a dark ground (BGR)."""
    frame = np.full(mask.shape + (3,), 20, np.uint8)
    frame[mask] = (120, 150, 210)
    return frame


def test_a_video_starting_on_something_not_a_hand_calibrates_on_the_hand(tmp_path):
    # the first frame where anything stood out became the rest frame: a video opening on a
    # half-bright view, noise or a hand coming into the view read every later frame as
    # low-confidence (13 of 13), told the user to try --segment colour, and exited 0
    from handsynth.models import named_pose

    with SilhouetteRenderer(HandShape(length=1.02, thumb=1.03), width_px=W,
                            height_px=H) as r:
        rest = r.mask(np.zeros(20))
        posed = [r.mask(named_pose(n)) for n in ("pinch", "grasp", "point", "spread")]
    half = np.full((H, W, 3), 20, np.uint8)
    half[:, : W // 2] = 255
    noise = np.random.default_rng(0).integers(0, 256, (H, W, 3), dtype=np.uint8)
    coming = np.zeros_like(rest)
    coming[H // 2:] = rest[: H - H // 2]  # half the hand in view
    frames = [half, noise, _bgr(coming), _bgr(rest)] + [_bgr(m) for m in posed]
    video = _write_video(tmp_path / "clip.avi", frames)
    out = tmp_path / "rows.csv"
    res = _run("--video", str(video), *LEARNT, "--learned-cache", str(tmp_path / "c"),
               "--out", str(out), "-q")
    assert res.exit_code == 0, res.output
    assert "were unlike any learnt" not in res.output
    _, rows = _read_csv(out)
    assert len(rows) == 4 and [r["low_confidence"] for r in rows] == ["0"] * 4
    assert [r["timestamp_s"] for r in rows] == [str(round(k / 15.0, 6)) for k in range(4, 8)]
    only_bad = _write_video(tmp_path / "bad.avi", [half, noise])
    res = _run("--video", str(only_bad), *LEARNT, "--learned-cache", str(tmp_path / "c"), "-q")
    assert res.exit_code == 2
    err = res.output.strip().splitlines()[-1]
    assert err.startswith(f"handsynth: error: video {only_bad}: the source ended before a frame "
                          "showed a hand to calibrate with (2 frames where something stood out "
                          "read as no hand at rest"), err


def test_a_calibration_image_of_no_hand_at_rest_is_warned_about(tmp_path):
    import cv2

    half = np.full((H, W, 3), 20, np.uint8)
    half[:, : W // 2] = 255
    image = tmp_path / "rest.png"
    cv2.imwrite(str(image), half)
    video = _write_video(tmp_path / "clip.avi", [_bgr(_open_mask())] * 2)
    res = _run("--video", str(video), *LEARNT, "--learned-cache", str(tmp_path / "c"),
               "--calibrate-image", str(image), "--out", str(tmp_path / "rows.csv"), "-q")
    assert res.exit_code == 0, res.output
    assert f"handsynth: warning: --calibrate-image {image}: the image itself reads as unlike " \
           "any hand learnt" in res.output



@pytest.mark.parametrize(("turn", "side", "says"), [
    # a left hand's view is the right hand's turned top to bottom
    ("left", None, "read turned top to bottom, the rest frame is a left hand's: is the device on "
                   "the left hand? (give --side left)"),
    ("right", "left", "read turned top to bottom, the rest frame is a right hand's: is the device "
                      "on the right hand? (give --side right)"),
    ("half", None, "read turned half a turn, the rest frame is a hand's: is the camera mounted "
                   "upside down? (turn it over)"),
])
def test_a_rest_frame_of_the_other_hand_or_upside_down_says_so(tmp_path, turn, side, says):
    # before: "no hand at rest in full view, or a cluttered ground?", and every frame
    # low-confidence
    with SilhouetteRenderer(HandShape(length=1.02, thumb=1.03), width_px=W, height_px=H,
                            side="right" if turn == "half" else turn) as r:
        mask = r.mask(np.zeros(20))
    if turn == "half":
        mask = mask[::-1, ::-1]
    from handsynth.cli._estimate import REST_FRAME_PATIENCE

    # a clip that ends while the rest frame is looked for: the error says it
    video = _write_video(tmp_path / "short.avi", [_bgr(mask)] * 2)
    res = _run("--video", str(video), *LEARNT, *(["--side", side] if side else []),
               "--learned-cache", str(tmp_path / "c"), "--out", str(tmp_path / "rows.csv"), "-q")
    assert res.exit_code == 2, res.output
    assert res.output.strip().splitlines()[-1].endswith(f"; {says}"), res.output
    # a longer one: the frame after REST_FRAME_PATIENCE is taken, with the warning
    video = _write_video(tmp_path / "clip.avi", [_bgr(mask)] * (REST_FRAME_PATIENCE + 3))
    res = _run("--video", str(video), *LEARNT, *(["--side", side] if side else []),
               "--learned-cache", str(tmp_path / "c"), "--out", str(tmp_path / "rows.csv"), "-q")
    assert res.exit_code == 0, res.output
    assert f"reads as unlike any hand learnt; {says}" in res.output, res.output
    # and the run's summary repeats it (not the advice about the background's colour)
    assert f"frames were unlike any learnt; {says}" in res.output, res.output
    assert "--segment colour tells" not in res.output
    # the same hand with the right side and the camera turned back reads as a hand: no warning
    good = mask[::-1, ::-1] if turn == "half" else mask
    fixed = ["--side", turn] if turn != "half" else []
    video = _write_video(tmp_path / "good.avi", [_bgr(good)] * 2)
    res = _run("--video", str(video), *LEARNT, *fixed, "--learned-cache", str(tmp_path / "c"),
               "--out", str(tmp_path / "rows2.csv"), "-q")
    assert res.exit_code == 0 and "unlike any hand" not in res.output, res.output

def test_a_mirrored_camera_image_is_said_and_turned_back_by_mirrored_image(tmp_path):
    # a camera set to mirror its image read as a hand at rest, without a word, and every
    # frame with no skill; the rest frame now says so, and --mirrored-image turns the
    # frames back
    from handsynth.eval._testposes import REST_POSTURES

    rest = REST_POSTURES["relaxed"](np.random.default_rng(3))
    bent = rest.copy()
    bent[[6, 7, 10, 11]] = [60.0, 40.0, 70.0, 45.0]  # index and middle PIP and DIP
    with SilhouetteRenderer(HandShape(length=0.97, width=1.04, thumb=1.03), width_px=W,
                            height_px=H) as r:
        frames = [_bgr(r.mask(p)) for p in (rest, bent, bent)]
    mirrored = [np.ascontiguousarray(f[:, ::-1]) for f in frames]
    rows = {}
    for name, clip, flag in (("seen", frames, []), ("mirrored", mirrored, []),
                             ("turned back", mirrored, ["--mirrored-image"]),
                             ("turned twice", frames, ["--mirrored-image"])):
        video = _write_video(tmp_path / f"{name}.avi", clip)
        out = tmp_path / f"{name}.csv"
        res = _run("--video", str(video), *LEARNT, *flag, "--learned-cache",
                   str(tmp_path / "c"), "--out", str(out), "-q")
        assert res.exit_code == 0, res.output
        rows[name] = (res.output, np.array([[float(r[j]) for j in JOINT_NAMES]
                                            for r in _read_csv(out)[1]]))
    assert "reads mirrored" not in rows["seen"][0] + rows["turned back"][0]
    assert "handsynth: warning: the rest frame reads mirrored left to right (mirror check: " \
           in rows["mirrored"][0]
    assert "is the camera set to mirror its image? give --mirrored-image" in rows["mirrored"][0]
    # and the run's summary, printed last, says it again
    assert rows["mirrored"][0].strip().splitlines()[-2].startswith(
        "the rest frame reads mirrored left to right"), rows["mirrored"][0]
    assert "the camera does not seem to mirror its image; leave out --mirrored-image" \
           in rows["turned twice"][0]
    # turned back, the frames read as the camera's own view did (within 1.4 deg: MJPEG
    # compresses a frame and its mirror image a little differently)
    np.testing.assert_allclose(rows["turned back"][1], rows["seen"][1], atol=2.0)
    # read as they were, the bent fingers were not seen bent
    pip = [JOINT_NAMES.index(j) for j in ("index_pip_flex", "middle_pip_flex")]
    assert (rows["seen"][1][:, pip] > 30).all()
    assert np.abs(rows["mirrored"][1][:, pip] - bent[[6, 10]]).mean() > \
        3 * np.abs(rows["seen"][1][:, pip] - bent[[6, 10]]).mean()


def test_a_video_whose_hand_comes_into_view_after_ten_seconds_still_calibrates(tmp_path):
    # the rest frame was looked for in the first 300 frames only, as for a camera: a
    # recording whose hand came into view after 10 s at 30 fps failed ("no frame showed a
    # hand to calibrate with in 300 reads") though the file held the hand
    dark = np.full((H, W, 3), 20, np.uint8)
    hand = _bgr(_open_mask())
    video = _write_video(tmp_path / "clip.avi", [dark] * 320 + [hand] * 3)
    out = tmp_path / "rows.csv"
    res = _run("--video", str(video), *LEARNT, "--learned-cache", str(tmp_path / "c"),
               "--out", str(out), "-q")
    assert res.exit_code == 0, res.output
    _, rows = _read_csv(out)
    assert [r["timestamp_s"] for r in rows] == [str(round(k / 15.0, 6)) for k in (321, 322)]


def test_a_rest_frame_that_keeps_reading_as_no_hand_is_taken_after_a_second_with_a_warning(
        tmp_path):
    # a hand at rest over a cluttered ground can itself read as unlike any hand learnt (9 of
    # 60 rest frames over photographs): waiting for a frame that reads as a hand would never
    # end on such a scene, so after REST_FRAME_PATIENCE frames the next is taken, with a warning
    from handsynth.cli._estimate import REST_FRAME_PATIENCE

    half = np.full((H, W, 3), 20, np.uint8)
    half[:, : W // 2] = 255
    frames = [half] * (REST_FRAME_PATIENCE + 3)
    video = _write_video(tmp_path / "clip.avi", frames)
    out = tmp_path / "rows.csv"
    res = _run("--video", str(video), *LEARNT, "--learned-cache", str(tmp_path / "c"),
               "--out", str(out), "-q")
    assert res.exit_code == 0, res.output
    assert (f"handsynth: warning: the rest frame (taken after {REST_FRAME_PATIENCE} frames that "
            "read so) itself reads as unlike any hand learnt") in res.output
    _, rows = _read_csv(out)
    assert len(rows) == 2  # the frames after the one taken


# --------------------------------------------------------------------------- a real camera's lens


def _through_lens(masks, k, dist, size):
    """BGR frames of a real camera with matrix `k`, Brown-Conrady `dist` and frame `size`,
    at the device's place: each of its pixels samples a wide pinhole render along its own ray
    (OpenCV's undistortPoints, not the correction's inverse map)."""
    import cv2

    wide = CameraMount().replace(fov_deg=140.0, width_px=900, height_px=900)
    kw = wide.intrinsics()
    w, h = size
    u, v = np.meshgrid(np.arange(w, dtype=np.float64), np.arange(h, dtype=np.float64))
    rays = cv2.undistortPoints(np.column_stack([u.ravel(), v.ravel()])[:, None, :], k,
                               np.asarray(dist, np.float64), R=None, P=None,
                               criteria=(cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 40,
                                         1e-9))
    mx = (rays[:, 0, 0] * kw[0, 0] + kw[0, 2]).reshape(h, w).astype(np.float32)
    my = (rays[:, 0, 1] * kw[1, 1] + kw[1, 2]).reshape(h, w).astype(np.float32)
    with SilhouetteRenderer(HandShape(length=1.02, thumb=1.03), wide) as r:
        big = [m.astype(np.uint8) * 255 for m in masks(r)]
    return [_bgr(cv2.remap(b, mx, my, cv2.INTER_LINEAR) > 127) for b in big]


def _intrinsics_file(path, k, dist, size):
    import cv2

    fs = cv2.FileStorage(str(path), cv2.FILE_STORAGE_WRITE)
    fs.write("image_width", size[0])
    fs.write("image_height", size[1])
    fs.write("camera_matrix", k)
    fs.write("distortion_coefficients", np.asarray(dist, np.float64).reshape(1, -1))
    fs.release()
    return path


def _angles(path):
    _, rows = _read_csv(path)
    return np.array([[float(r[n]) for n in JOINT_NAMES] for r in rows])


def test_a_wide_angle_cameras_video_reads_as_the_device_once_its_lens_is_undone(tmp_path):
    # a 4:3 board camera of about 100 deg with barrel distortion, beside the device's own view
    from handsynth.models import named_pose

    poses = [np.zeros(20)] + [named_pose(n) for n in ("pinch", "grasp", "point", "spread",
                                                       "fist")]
    k = np.array([[240.0, 0, 243.0], [0, 240.0, 176.0], [0, 0, 1]])
    dist = (-0.28, 0.08, 0.001, -0.0008, -0.01)
    lens_frames = _through_lens(lambda r: r.masks(poses), k, dist, (480, 360))
    with SilhouetteRenderer(HandShape(length=1.02, thumb=1.03), width_px=720,
                            height_px=480) as r:
        device_frames = [_bgr(m) for m in r.masks(poses)]
    cam = _intrinsics_file(tmp_path / "camera.yaml", k, dist, (480, 360))
    runs = {}
    for name, frames, extra in (("device", device_frames, []),
                                ("corrected", lens_frames, ["--intrinsics", str(cam)])):
        video = _write_video(tmp_path / f"{name}.avi", frames)
        out = tmp_path / f"{name}.csv"
        res = _run("--video", str(video), *LEARNT, "--learned-cache", str(tmp_path / "c"),
                   "--out", str(out), "-q", *extra)
        assert res.exit_code == 0, res.output
        assert "warning" not in res.output
        runs[name] = _angles(out)
    assert runs["corrected"].shape == (5, 20)
    # the same camera's frames stretched to the device's ratio, as a user without the
    # calibration would give them
    import cv2

    stretched = _write_video(tmp_path / "raw.avi", [cv2.resize(f, (720, 480)) for f in lens_frames])
    res = _run("--video", str(stretched), *LEARNT, "--learned-cache", str(tmp_path / "c"),
               "--out", str(tmp_path / "raw.csv"), "-q")
    assert res.exit_code == 0, res.output
    raw = _angles(tmp_path / "raw.csv")
    off_corrected = np.abs(runs["corrected"] - runs["device"]).mean()
    off_raw = np.abs(raw - runs["device"]).mean()
    assert off_corrected < 2.0 and off_corrected < 0.4 * off_raw, (off_corrected, off_raw)
    # without the calibration the 4:3 video is refused by its ratio, naming its size
    res = _run("--video", str(tmp_path / "corrected.avi"), *LEARNT, "--learned-cache",
               str(tmp_path / "c"), "-q")
    assert res.exit_code != 0 and "480x360" in res.output


def test_intrinsics_problems_are_one_line_before_any_work(tmp_path, hand_video):
    bad = tmp_path / "camera.yaml"
    bad.write_text("image_width: 640\nimage_height: 480\ndistortion_coefficients: []\n")
    res = _run("--video", str(hand_video), *LEARNT, "--learned-cache", str(tmp_path / "c"),
               "--intrinsics", str(bad), "-q")
    assert res.exit_code == 2
    assert res.output.strip().splitlines() == [
        f"handsynth: error: camera intrinsics {bad}: no camera matrix (looked for camera_matrix, "
        "cameramatrix, k, intrinsic_matrix, intrinsics; found image_width, image_height, "
        "distortion_coefficients)"]
    assert not (tmp_path / "c").exists()
    res = _lookup("--synthetic", "--intrinsics", str(bad), *SMALL)
    assert res.exit_code == 2 and "--synthetic frames are already the device's view" in res.output
    # the video's frames (180x120) against a 4:3 calibration: both sizes named
    cam = _intrinsics_file(tmp_path / "cam43.yaml", np.array([[300.0, 0, 320], [0, 300, 240],
                                                              [0, 0, 1]]), (), (640, 480))
    res = _run("--video", str(hand_video), *LEARNT, "--learned-cache", str(tmp_path / "c"),
               "--intrinsics", str(cam), "-q")
    assert res.exit_code != 0
    assert "frames of 180x120 pixels cannot be corrected with intrinsics calibrated at 640x480" \
        in res.output.strip().splitlines()[-1]


def test_a_camera_narrower_than_the_device_is_warned_about(tmp_path, hand_video):
    cam = _intrinsics_file(tmp_path / "narrow.yaml", np.array([[150.0, 0, 89.5], [0, 150, 59.5],
                                                               [0, 0, 1]]), (), (180, 120))
    res = _run("--video", str(hand_video), *LEARNT, "--learned-cache", str(tmp_path / "c"),
               "--intrinsics", str(cam), "-q")
    assert re.search(r"handsynth: warning: --intrinsics \S+narrow.yaml: the camera does not see "
                     r"\d+% of the device's 90 deg view \(its own about 62 deg\)", res.output), \
        res.output


def test_the_learnt_estimators_side_by_side_video_draws_its_angles(tmp_path, read_video):
    # --video-out was refused with --learned: a wearer could not see what was read
    out, video = tmp_path / "rows.csv", tmp_path / "side.avi"
    res = _run("--synthetic", *LEARNT, "--learned-cache", str(tmp_path / "c"), "--frames", "6",
               "--synthetic-motion", "named", "--out", str(out), "--video-out", str(video),
               *SMALL)
    assert res.exit_code == 0, res.output
    assert f"video: {video} (6 frames, input | estimated pose)" in res.output
    frames, _ = read_video(video)
    assert len(frames) == 6 and frames[0].shape == (H, 2 * W, 3)
    # the right half is the standard hand posed by each row's angles, drawn through the device
    _, rows = _read_csv(out)
    with SilhouetteRenderer(HandShape(), width_px=W, height_px=H) as r:
        for f, row in zip(frames, rows):
            drawn = f[:, W:, 1] > 128
            drawn[:30] = False  # the label
            want = r.mask(np.array([float(row[n]) for n in JOINT_NAMES]))
            want[:30] = False
            assert (drawn & want).sum() / (drawn | want).sum() > 0.9
