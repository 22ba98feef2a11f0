import json

import pytest
from click.testing import CliRunner

from handsynth.cli._main import cli
from handsynth.sensors.trackers import FlexionMotion, save_recording, simulate_recording


@pytest.fixture(scope="module")
def rec_path(tmp_path_factory):
    rec = simulate_recording(motion=FlexionMotion(duration_s=10.0), seed=7, geometry_source="table")
    return save_recording(tmp_path_factory.mktemp("rec") / "dip.h5", rec)


def test_estimate_writes_table_json_and_plot(tmp_path, rec_path):
    out, png = tmp_path / "out.json", tmp_path / "h.png"
    res = CliRunner().invoke(cli, ["joints", "estimate", str(rec_path), "--method", "patent",
                                   "--method", "score", "--lateral-axis", "recording",
                                   "--json", str(out), "--plot", str(png)])
    assert res.exit_code == 0, res.output
    assert "err_U" in res.output and "index_middle / index_distal" in res.output
    data = json.loads(out.read_text())
    got = {(r["method"], r["frames_mode"]) for r in data["results"]}
    assert got == {("patent", "all"), ("patent", "filtered"), ("score", "all"), ("score", "filtered")}
    patent = next(r for r in data["results"] if r["method"] == "patent" and r["frames_mode"] == "all")
    assert max(patent["error_mm"]) < 2.0 and patent["n_frames_used"] == 2400
    assert png.read_bytes()[:4] == b"\x89PNG"


def test_estimate_bad_file_is_one_line_exit_2(tmp_path):
    bad = tmp_path / "bad.txt"
    bad.write_text("garbage\n")
    res = CliRunner().invoke(cli, ["joints", "estimate", str(bad)])
    assert res.exit_code == 2
    assert "handsynth: error:" in res.output and "no data line" in res.output
    assert "Traceback" not in res.output


def test_eval_json(tmp_path):
    out = tmp_path / "eval.json"
    res = CliRunner().invoke(cli, ["joints", "eval", "--duration", "8", "--seeds", "1",
                                   "--json", str(out)])
    assert res.exit_code == 0, res.output
    rows = json.loads(out.read_text())["rows"]
    # 2 scenarios x 2 noise levels x 4 methods x 2 frame modes
    assert len(rows) == 32
    keys = {(r["scenario"], r["noise"], r["method"], r["frames"]) for r in rows}
    assert ("finger", "liberty-accuracy", "patent", "filtered") in keys
    mock = [r for r in rows if r["scenario"] == "mock" and r["noise"] == "liberty-accuracy"
            and r["method"] == "patent"]
    assert all(r["error_mm"] < 1.0 and r["distance_mm"] < 2.5 for r in mock)


# --------------------------------------------------------------------------- faults (issue 16)


@pytest.mark.parametrize("option", ["--json", "--plot"])
def test_outputs_in_a_missing_folder_are_one_line(tmp_path, rec_path, option):
    # item 9: FileNotFoundError tracebacks (after the work was done)
    res = CliRunner().invoke(cli, ["joints", "estimate", str(rec_path), "--method", "patent",
                                   option, str(tmp_path / "nowhere" / "x.out")])
    assert res.exit_code == 2, res.output
    assert "nowhere' does not exist" in res.output and "Traceback" not in res.output


def test_eval_json_in_a_missing_folder_is_refused_before_the_work(tmp_path):
    res = CliRunner().invoke(cli, ["joints", "eval", "--json", str(tmp_path / "no" / "e.json")])
    assert res.exit_code == 2 and "does not exist" in res.output, res.output


def test_json_on_a_full_disk_leaves_nothing(full_disk, rec_path):
    # item 9: a full disk left 0-byte or temporary files
    (full_disk / "filler").write_bytes(b"\0" * (256 * 1024 - 4096))
    out = full_disk / "out.json"
    res = CliRunner().invoke(cli, ["joints", "estimate", str(rec_path), "--json", str(out)])
    assert res.exit_code == 2 and "no space left" in res.output, res.output
    assert sorted(p.name for p in full_disk.iterdir()) == ["filler"]


def test_json_never_replaces_the_recording(rec_path):
    # item 11: --json equal to the recording overwrote it
    before = rec_path.read_bytes()
    res = CliRunner().invoke(cli, ["joints", "estimate", str(rec_path), "--json", str(rec_path)])
    assert res.exit_code == 2 and "never replaces an input" in res.output, res.output
    assert rec_path.read_bytes() == before


@pytest.mark.parametrize("args, words", [
    (["--duration", "0.01"], ["--duration must be between 2 and 3600 s", "got 0.01"]),  # 15
    (["--duration", "1e9"], ["--duration must be between 2 and 3600 s"]),                # 16
    (["--seeds", "100000"], ["--seeds must be between 1 and 100"]),
])
def test_eval_bounds_name_the_option(args, words):
    res = CliRunner().invoke(cli, ["joints", "eval", *args])
    assert res.exit_code == 2 and all(w in res.output for w in words), res.output
    assert "hold_s" not in res.output and "Traceback" not in res.output


def test_euler_angles_out_of_range_are_refused(tmp_path):
    # item 19: an elevation of 400 deg was accepted
    lines = [f"{s} 1.0 2.0 3.0 10.0 {400.0 if (k, s) == (3, 2) else 5.0} 1.0"
             for k in range(6) for s in (1, 2)]
    path = tmp_path / "rec.txt"
    path.write_text("\n".join(lines) + "\n")
    res = CliRunner().invoke(cli, ["joints", "estimate", str(path)])
    assert res.exit_code == 2, res.output
    assert "line 8: Euler angle a2 is 400 deg, outside [-90, 90]" in res.output
