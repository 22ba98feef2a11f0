"""``handsynth eval`` on the real command: table, JSON, plots, one-line errors."""

from __future__ import annotations

import json

import numpy as np
import pytest
from click.testing import CliRunner

from handsynth.cli._main import cli
from handsynth.models import JOINT_NAMES

SMALL = ["--count", "120", "--render-size", "120x80", "--frame-size", "360x240",
         "--hands", "2", "--frames", "10"]


def _run(*args):
    return CliRunner().invoke(cli, ["eval", *args], catch_exceptions=False)


@pytest.mark.slow
def test_eval_prints_table_and_writes_json_and_plots(tmp_path):
    out, js = tmp_path / "plots", tmp_path / "res" / "eval.json"
    js.parent.mkdir()  # the folder of an output file must exist (the plot folder is created)
    res = _run("--db", str(tmp_path / "dbs"), "--out", str(out), "--json", str(js),
               "--conditions", "standard,selected", "-q", *SMALL)
    assert res.exit_code == 0, res.output
    table = res.stdout
    assert "index_pip_flex" in table and "standard" in table and "selected" in table
    assert "selected beats standard" in table and res.stderr == ""
    assert table.startswith("The paper's experiment: test poses from the databases' own")
    assert "no better than the constant answer (handsynth eval --protocol)" in table
    d = json.loads(js.read_text())
    assert js.stat().st_mode & 0o044  # readable by others, as an ordinary file
    assert d["options"]["count"] == 120 and d["options"]["frame_size"] == [360, 240]
    assert set(d["conditions"]) == {"standard", "selected"}
    assert list(d["conditions"]["selected"]["all"]["joints"]) == list(JOINT_NAMES)
    assert d["conditions"]["standard"]["all"]["frames"] == 40
    assert "frames" not in d
    for name in ("eval_error_hist.png", "eval_error_vs_distance.png", "eval_joint_mae.png"):
        assert (out / name).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert d["options"]["db_pose_set"] == "paper"
    # a second run reuses the databases (verified, not rebuilt) and reports progress
    again = _run("--db", str(tmp_path / "dbs"), "--conditions", "standard,selected", *SMALL)
    assert again.exit_code == 0 and "0 built" in again.stderr


@pytest.mark.parametrize("args, word", [
    (["--frames", "0"], "--frames must be an integer >= 1 and <= 10000, got 0"),
    (["--hands", "-1"], "--hands must be an integer >= 1 and <= 1000, got -1"),
    (["--hands", "5000"], "--hands must be an integer >= 1 and <= 1000, got 5000"),
    (["--frames", "100000"], "--frames must be an integer >= 1 and <= 10000, got 100000"),
    (["--conditions", "standard,best"], "--conditions"),
    (["--conditions", ""], "--conditions must name at least one item"),  # was: every condition
    (["--protocol", "--conditions", ""], "--conditions must name at least one item"),
    (["--pose-sets", "paper,random"], "--pose-sets must be distinct names"),
    (["--frame-size", "720"], "--frame-size"),
    (["--ratio-margin", "9"], "--ratio-margin must be"),
    (["--ratio-margin", "nan"], "--ratio-margin must be"),
    (["--photo-mm-per-px", "0"], "--photo-mm-per-px must be"),
    (["--count", "0"], "--count must be an integer >= 1, got 0"),
    (["--seed", "-2"], "--seed must be an integer >= 0, got -2"),
    (["--json", ""], "--json must name a file, got ''"),  # was: no report, exit 0
    (["--render-size", ""], "--render-size must be WIDTHxHEIGHT"),  # was: the default size
    (["--workers", "100000"], "--workers must be an integer >= 1 and <= "),  # was: after a line
    (["--out", ""], "--out must name a folder, got ''"),
    (["--out", "plots", "--prefix", "sub/eval_"], "--prefix must be the start of a file name"),
])
def test_bad_options_give_one_line_errors(tmp_path, args, word):
    res = _run("--db", str(tmp_path), *args)
    assert res.exit_code == 2
    lines = res.output.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("handsynth: error:") and word in lines[0]


def test_mesh_hand_is_pluggable(tmp_path):
    js = tmp_path / "mesh.json"
    res = _run("--db", str(tmp_path / "dbs"), "--hand", "mesh", "--json", str(js), "-q",
               "--out", str(tmp_path / "plots"),
               "--conditions", "standard,selected", *SMALL[:6], "--hands", "1", "--frames", "4")
    assert res.exit_code == 0, res.output
    d = json.loads(js.read_text())
    hand = d["hands"][0]
    assert hand["kind"] == "mesh" and d["options"]["hand"] == "mesh"
    assert hand["databases"]["standard"] == "L1.000_W1.000_P1.000_T1.000"
    assert set(d["targets"]["all"]) == {"index_pip_sd_deg", "selected_beats_standard"}
    assert d["conditions"]["selected"]["all"]["frames"] == 8
    assert (tmp_path / "plots" / "eval_mesh_error_hist.png").is_file()


def test_a_json_report_in_a_missing_folder_is_refused_before_the_work(tmp_path):
    # issue 16 item 9: the check came after minutes of work, as a traceback
    res = _run("--db", str(tmp_path / "dbs"), "--json", str(tmp_path / "no" / "e.json"), "-q",
               *SMALL)
    assert res.exit_code == 2 and "folder" in res.output and "does not exist" in res.output
    assert not (tmp_path / "dbs").exists()


def test_a_bad_count_names_the_option(tmp_path):
    res = _run("--db", str(tmp_path / "dbs"), "--hands", "0", "-q")
    assert res.exit_code == 2 and res.output == (
        "handsynth: error: --hands must be an integer >= 1 and <= 1000, got 0\n")


def test_a_json_report_never_replaces_a_database_of_the_run(tmp_path):
    # --json naming the database in --db wrote JSON over it with exit 0
    dbs = tmp_path / "dbs"
    dbs.mkdir()
    existing = dbs / "L1.000_W1.000_P1.000_T1.000.h5"
    existing.write_bytes(b"\x89HDF\r\n\x1a\n")
    res = _run("--db", str(dbs), "--json", str(existing), "-q", *SMALL)
    assert res.exit_code == 2 and "never replaces an input" in res.output, res.output
    assert existing.read_bytes() == b"\x89HDF\r\n\x1a\n"
    res = _run("--db", str(dbs), "--json", str(dbs / "L1.100_W1.000_P1.000_T1.000.h5"), "-q",
               *SMALL)  # one the run would build
    assert res.exit_code == 2 and "would be a database file" in res.output, res.output


@pytest.mark.slow
def test_protocol_puts_the_constant_beside_every_method_and_writes_json(tmp_path):
    js = tmp_path / "protocol.json"
    res = _run("--protocol", "--db", str(tmp_path / "cache"), "--hands", "1", "--mesh", "mrtk",
               "--frames", "6", "--pose-sets", "natural", "--learned-hands", "8",
               "--conditions", "fingers,fingers_mean,ensemble", "--json", str(js), "-q",
               "--rest", "open", "--slip", "0.5", "--mesh-scale", "0.9")
    assert res.exit_code == 0, res.output
    d = json.loads(js.read_text())
    assert set(d["hands"]) == {"model0", "mrtk"}
    assert d["hands"]["mrtk"]["info"] == {"file": "hand_r.glb", "scale": 0.9}
    assert d["options"]["rest"] == "open" and d["options"]["slip"] == 0.5
    assert all(set(h["slipped_mount"]) >= {"height_mm", "tilt_deg"} for h in d["hands"].values())
    for hand in d["hands"].values():  # every finger joint rests flexed a few degrees
        flex = np.array(hand["rest_deg"])[[4, 6, 7, 8, 10, 11, 12, 14, 15, 16, 18, 19]]
        assert flex.min() > -1 and flex.max() < 9
    head = d["headline"]
    assert set(head) == {f"{kind}/natural/{m}" for kind in ("model", "mesh")
                         for m in ("fingers", "fingers_mean", "ensemble")}
    for key, v in head.items():
        assert v["constant"] > 0 and v["skill"] == pytest.approx(
            1 - v["flexion_mae"] / v["constant"], abs=2e-3)
        assert f"{key:32s} flexion MAE {v['flexion_mae']:6.2f}" in res.stdout
    mrtk = d["hands"]["mrtk"]["natural"]["fingers"]
    assert list(mrtk["method"]["joints"]) == list(JOINT_NAMES)
    # the report says which estimators its figures belong to, and learnt from what
    from handsynth import __version__
    from handsynth.estimate import LEARNED_ENSEMBLE

    assert d["handsynth"] == __version__
    assert d["methods"]["fingers_mean"]["learnt"]["local"] == "mean"
    members = d["methods"]["ensemble"]["ensemble"]
    assert [(m["learnt"]["kind"], m["learnt"]["seed"], m["weight"], m["learning_set_changes"])
            for m in members] == [(o.kind, o.seed, w, dict(c)) for o, w, c in LEARNED_ENSEMBLE]
    assert members[-1]["learning_set_changes"] == {"hands_factor": 4, "open_rest_share": 0.0}
    assert d["methods"]["learning_set"]["hands"] == 8
    assert mrtk["constant"]["groups_mae_deg"]["finger_flexion"] == pytest.approx(
        head["mesh/natural/fingers"]["constant"], abs=0.006)


@pytest.mark.parametrize(("args", "message"), [
    (["--protocol", "--count", "100"], "--count applies to the paper's experiment, not to --protocol"),
    (["--mesh", "mrtk"], "--mesh applies with --protocol only"),
    (["--rest", "open"], "--rest applies with --protocol only"),
    (["--slip", "0.5"], "--slip applies with --protocol only"),
    (["--mesh-scale", "0.9"], "--mesh-scale applies with --protocol only"),
    (["--breadth-follows-scale", "1"], "--breadth-follows-scale applies with --protocol only"),
    (["--protocol", "--hands", "1", "--breadth-follows-scale", "2.5"],
     "--breadth-follows-scale must be a finite number >= 0 and <= 2, got 2.5"),
    (["--protocol", "--hands", "0", "--mesh-scale", "3"],
     "--mesh-scale must be a number in [0.5, 2], got 3.0"),
    (["--protocol", "--slip", "-1", "--hands", "1"],
     "--slip must be a finite number >= 0 and <= 5, got -1.0"),
    (["--protocol", "--conditions", "fingers,tree"], "--conditions must be distinct names from"),
    # the options the user typed, not ProtocolOptions.frames and the like
    (["--protocol", "--frames", "1"], "--frames must be an integer >= 2 and <= 10000, got 1"),
    (["--protocol", "--seed", "-1"], "--seed must be an integer >= 0, got -1"),  # was: learnt first
    (["--protocol", "--pose-sets", "paper,paper"], "--pose-sets must name 'paper' and/or 'natural'"),
    (["--protocol", "--hands", "2000"], "--hands must be an integer >= 0 and <= 1000, got 2000"),
    (["--protocol", "--hand-spread", "inf"], "--hand-spread must be a finite number >= 0, got inf"),
    (["--protocol", "--learned-hands", "1000000"], "--learned-hands must be an integer in [1, 100,000]"),
    (["--protocol", "--hands", "0", "--mesh", "mrtk,mrtk"], "two test hands named 'mrtk'"),
    (["--protocol", "--db", ""], "--db must name a folder, got ''"),
    (["--protocol", "--json", ""], "--json must name a file, got ''"),
    (["--protocol", "--hands", "0", "--mesh", ""], "no test hands"),
    (["--protocol", "--hands", "0", "--mesh", "mrtk,nowhere/hand.glb"],
     "test hand file 'nowhere/hand.glb' does not exist"),
])
def test_protocol_options_are_checked_by_name(tmp_path, args, message):
    res = CliRunner().invoke(cli, ["eval", "--db", str(tmp_path / "c"), *args])
    assert res.exit_code == 2, res.output
    assert message in res.output and "Traceback" not in res.output


def test_a_damaged_glTF_hand_is_one_line_naming_it_before_any_learning(tmp_path):
    # before: a .glb zero-filled in the middle loaded, then the run learnt its estimators
    # (4,000 hands by default) and failed with "mesh hand: no surface at the middle of thumb
    # proximal", naming no file
    from handsynth.testhands import shipped_hand_path

    data = bytearray(shipped_hand_path("mrtk").read_bytes())
    data[len(data) // 2:len(data) // 2 + 20000] = bytes(20000)
    damaged = tmp_path / "damaged.glb"
    damaged.write_bytes(bytes(data))
    (tmp_path / "text.glb").write_text("a text file named .glb")
    for hand in (damaged, tmp_path / "text.glb"):
        res = CliRunner().invoke(cli, ["eval", "--protocol", "--db", str(tmp_path / "c"),
                                       "--hands", "0", "--mesh", str(hand)])
        assert res.exit_code == 2, res.output
        lines = res.output.strip().splitlines()
        assert len(lines) == 1 and lines[0].startswith("handsynth: error:") and hand.name in lines[0]
        assert not (tmp_path / "c").exists()  # nothing learnt, no folder made


def test_a_db_or_plot_folder_under_a_file_is_one_line_before_the_work(tmp_path):
    (tmp_path / "file").write_text("x")
    res = CliRunner().invoke(cli, ["eval", "--db", str(tmp_path / "file" / "dbs"), *SMALL])
    assert res.exit_code == 2 and res.output.strip().splitlines() == [
        f"handsynth: error: cannot create the --db folder {str(tmp_path / 'file' / 'dbs')!r}: "
        "not a directory"], res.output  # before: a progress line first
    res = CliRunner().invoke(cli, ["eval", "--db", str(tmp_path / "dbs"), "--out",
                                   str(tmp_path / "file" / "plots"), *SMALL])
    assert res.exit_code == 2 and "cannot create the --out folder" in res.output, res.output
    assert not (tmp_path / "dbs").exists()  # refused before any database was built


def test_a_glTF_hand_named_like_a_model_hand_is_refused_before_any_learning(tmp_path):
    import shutil

    from handsynth.testhands import shipped_hand_path

    shutil.copyfile(shipped_hand_path("mrtk"), tmp_path / "model0.glb")
    res = CliRunner().invoke(cli, ["eval", "--protocol", "--db", str(tmp_path / "c"), "--hands", "1",
                                   "--mesh", str(tmp_path / "model0.glb")])
    assert res.exit_code == 2 and res.output.startswith(
        "handsynth: error: two test hands named 'model0'"), res.output
    assert len(res.output.strip().splitlines()) == 1 and not (tmp_path / "c").exists()


@pytest.mark.parametrize("option", ["--json", "--out"])
def test_an_output_in_a_read_only_folder_is_refused_before_the_work(tmp_path, read_only_folder,
                                                                    option):
    # before: the whole run, then "cannot write ... the file system is read-only"
    target = read_only_folder / "r.json" if option == "--json" else read_only_folder
    res = _run("--db", str(tmp_path / "dbs"), option, str(target), "-q", *SMALL)
    assert res.exit_code == 2, res.output
    lines = res.output.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("handsynth: error: cannot write"), res.output
    assert f"folder {str(read_only_folder)!r}: the file system is read-only" in lines[0]
    assert not (tmp_path / "dbs").exists()
