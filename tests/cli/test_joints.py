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
