"""``handsynth eval`` on the real command: table, JSON, plots, one-line errors."""

from __future__ import annotations

import importlib.util
import json

import pytest
from click.testing import CliRunner

from handsynth.cli._main import cli
from handsynth.models import JOINT_NAMES

SMALL = ["--count", "120", "--render-size", "120x80", "--frame-size", "360x240",
         "--hands", "2", "--frames", "10"]


def _run(*args):
    return CliRunner().invoke(cli, ["eval", *args], catch_exceptions=False)


def test_eval_prints_table_and_writes_json_and_plots(tmp_path):
    out, js = tmp_path / "plots", tmp_path / "res" / "eval.json"
    res = _run("--db", str(tmp_path / "dbs"), "--out", str(out), "--json", str(js),
               "--conditions", "standard,selected", "-q", *SMALL)
    assert res.exit_code == 0, res.output
    table = res.stdout
    assert "index_pip_flex" in table and "standard" in table and "selected" in table
    assert "selected beats standard" in table and res.stderr == ""
    d = json.loads(js.read_text())
    assert d["options"]["count"] == 120 and d["options"]["frame_size"] == [360, 240]
    assert set(d["conditions"]) == {"standard", "selected"}
    assert list(d["conditions"]["selected"]["all"]["joints"]) == list(JOINT_NAMES)
    assert d["conditions"]["standard"]["all"]["frames"] == 40
    assert "frames" not in d
    for name in ("eval_error_hist.png", "eval_error_vs_distance.png", "eval_joint_mae.png"):
        assert (out / name).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    # a second run reuses the databases (verified, not rebuilt) and reports progress
    again = _run("--db", str(tmp_path / "dbs"), "--conditions", "standard,selected", *SMALL)
    assert again.exit_code == 0 and "0 built" in again.stderr


@pytest.mark.parametrize("args, word", [
    (["--frames", "0"], "frames_per_hand"),
    (["--hands", "-1"], "n_hands"),
    (["--conditions", "standard,best"], "conditions"),
    (["--pose-sets", "paper,random"], "pose_sets"),
    (["--frame-size", "720"], "--frame-size"),
    (["--ratio-margin", "9"], "ratio_margin"),
])
def test_bad_options_give_one_line_errors(tmp_path, args, word):
    res = _run("--db", str(tmp_path), *args)
    assert res.exit_code == 2
    lines = res.output.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("handsynth: error:") and word in lines[0]


def test_mesh_hand_without_its_module_is_one_line(tmp_path):
    if importlib.util.find_spec("handsynth.render._mesh_hand") is not None:
        pytest.skip("the mesh hand is installed; covered by the estimate tests")
    res = _run("--db", str(tmp_path), "--hand", "mesh")
    assert res.exit_code == 2 and "mesh" in res.output and len(res.output.splitlines()) == 1
