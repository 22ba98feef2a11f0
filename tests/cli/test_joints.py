"""``handsynth joints``: the real command on files written here in every export format."""

import json

import numpy as np
import pytest
from click.testing import CliRunner
from scipy.spatial.transform import Rotation

from handsynth.cli._main import cli
from handsynth.sensors.trackers import FlexionMotion, SensorNoise, save_recording, simulate_recording


@pytest.fixture(scope="module")
def sim():
    return simulate_recording(motion=FlexionMotion(duration_s=10.0), seed=7, geometry_source="table")


@pytest.fixture(scope="module")
def rec_path(tmp_path_factory, sim):
    return save_recording(tmp_path_factory.mktemp("rec") / "dip.h5", sim)


def _run(*args):
    return CliRunner().invoke(cli, ["joints", *map(str, args)], prog_name="handsynth")


def test_estimate_writes_report_table_json_and_plot(tmp_path, rec_path):
    out, png = tmp_path / "out.json", tmp_path / "h.png"
    res = _run("estimate", rec_path, "--method", "patent", "--method", "score",
               "--lateral-axis", "recording", "--json", out, "--plot", png)
    assert res.exit_code == 0, res.output
    assert "err_U" in res.output and "index_middle / index_distal" in res.output
    assert "determinability:" in res.output and "range of motion" in res.output
    data = json.loads(out.read_text())
    got = {(r["method"], r["frames_mode"]) for r in data["results"]}
    assert got == {("patent", "all"), ("patent", "filtered"), ("score", "all"), ("score", "filtered")}
    patent = next(r for r in data["results"] if r["method"] == "patent" and r["frames_mode"] == "all")
    assert max(patent["error_mm"]) < 2.0 and patent["n_frames_used"] == 2400
    assert data["quality"]["determinability"]["expected_error_mm"][1] < 2.0
    assert png.read_bytes()[:4] == b"\x89PNG"


# --- the three export formats, written line by line here --------------------------------


def _liberty(sim, *, counter, lose=()):
    lines = []
    for i in range(sim.n_frames):
        for s in (0, 1):
            if (i, s) in lose:
                continue
            p = sim.positions[i, s] * 100.0  # cm
            e = Rotation.from_matrix(sim.rotations[i, s]).as_euler("ZYX", degrees=True)
            head = f"  {s + 1}" + (f" {5000 + i:7d}" if counter else "")
            lines.append(head + "".join(f" {v:9.4f}" for v in p) + "".join(f" {v:9.4f}" for v in e))
    return lines


def _pimgr(sim):
    lines = ["Time,w1,x1,y1,z1,w2,x2,y2,z2,loc1_x,loc1_y,loc1_z,loc2_x,loc2_y,loc2_z"]
    for i in range(sim.n_frames):
        q = [Rotation.from_matrix(sim.rotations[i, s]).as_quat()[[3, 0, 1, 2]] for s in (0, 1)]
        p = sim.positions[i] * 100.0
        row = ",".join(f"{v:.6f}" for v in (*q[0], *q[1], *p[0], *p[1]))
        t = 1_731_000_000.0 + sim.times[i]
        lines.append(f"{t:.4f},{row}")
        if i % 2 == 0:  # PiMgr writes about 1.5 rows per sample
            lines.append(f"{t + 0.002:.4f},{row}")
    return lines


@pytest.mark.parametrize("kind", ["liberty-counter", "liberty-lost-line", "pimgr-unix-duplicates"])
def test_real_formats_read_without_options(tmp_path, sim, kind):
    if kind == "liberty-counter":
        lines, want = _liberty(sim, counter=True), "station frame x y z"
    elif kind == "liberty-lost-line":
        lines, want = _liberty(sim, counter=False, lose={(100, 0), (300, 1)}), "half frames 2"
    else:
        lines, want = _pimgr(sim), "duplicates 1200"
    path = tmp_path / f"{kind}.{'csv' if 'pimgr' in kind else 'txt'}"
    path.write_text("\n".join(lines) + "\n")
    out = tmp_path / "c.json"
    res = _run("estimate", path, "--method", "obrien", "--frames", "all", "--json", out)
    assert res.exit_code == 0, res.output
    assert want in res.output and "units cm" in res.output
    r = json.loads(out.read_text())["results"][0]
    err = np.linalg.norm(np.array([r["centre_upper_mm"], r["centre_lower_mm"]])
                         - sim.truth.reference_centre * 1e3, axis=1)
    # the finger-like joint's centre slides 1.5 mm: no single point is nearer
    assert err.max() < 2.0, err
    expected_frames = sim.n_frames - (2 if kind == "liberty-lost-line" else 0)
    assert r["n_frames_used"] == expected_frames


MALFORMED = {
    "empty.txt": b"",
    "binary.txt": bytes(range(256)) * 8,
    "arrays.npz": b"PK\x03\x04\x14\x00\x00\x00" + b"\x00" * 200,
    "commas.txt": b",,,,,,,\n" * 5,
    "nan.txt": b"1 nan nan nan nan nan nan\n2 nan nan nan nan nan nan\n" * 30,
    "mixed.txt": b"1 1 2 3 4 5 6\n2 1 2 3\n1 1 2 3 4 5 6 7 8 9\n" * 20,
    "header-only.csv": b"Time,w1,x1,y1,z1,w2,x2,y2,z2,loc1_x,loc1_y,loc1_z,loc2_x,loc2_y,loc2_z\n",
    "underscore.txt": b"1 1_0.5 2 3 4 5 6\n2 1 2 3 4 5 6\n" * 20,
}


@pytest.mark.parametrize("name", sorted(MALFORMED))
def test_malformed_file_is_one_error_line(tmp_path, name):
    # one error line, after the warnings that explain it (NaN frames dropped)
    path = tmp_path / name
    path.write_bytes(MALFORMED[name])
    res = _run("estimate", path)
    assert res.exit_code == 2, res.output
    *warned, error = res.output.strip().splitlines()
    assert error.startswith("handsynth: error: ") and name in error, res.output
    assert all(line.startswith("handsynth: warning: ") for line in warned), res.output
    assert "Traceback" not in res.output


def test_undeterminable_motion_is_refused_by_every_method(tmp_path):
    # 10 deg of flexion under slowly varying (0.5 s) tracker error: few independent frames
    noise = SensorNoise(position_sd_mm=0.76, orientation_sd_deg=0.15, correlation_time_s=0.5)
    rec = simulate_recording(motion=FlexionMotion(duration_s=6.0, flexion_range_deg=(0, 10),
                                                  wobble_deg=0.0), seed=2, geometry_source="table",
                             noise=noise)
    res = _run("estimate", save_recording(tmp_path / "small.h5", rec))
    assert res.exit_code == 2
    assert "refused: " in res.output and "expected error" in res.output
    assert res.output.strip().splitlines()[-1].startswith("handsynth: error: no method gave a centre")


def test_eval_json_both_configurations(tmp_path):
    out = tmp_path / "eval.json"
    res = _run("eval", "--duration", "6", "--seeds", "1", "--json", out)
    assert res.exit_code == 0, res.output
    rows = json.loads(out.read_text())["rows"]
    # project: 2 scenarios x 2 noises x (4 methods x 2 frame modes + baseline);
    # independent: 2 scenarios x 1 error model x the same
    assert len(rows) == 2 * 2 * 9 + 2 * 1 * 9
    assert {r["config"] for r in rows} == {"project", "independent"}
    base = {(r["config"], r["scenario"], r["noise"]): r["error_mm"] for r in rows
            if r["method"] == "midpoint"}
    obrien = [r for r in rows if r["method"] == "obrien" and r["frames"] == "all"]
    # the linear method beats the constant answer on every row of both configurations
    assert all(r["error_mm"] < base[(r["config"], r["scenario"], r["noise"])] / 2 for r in obrien)


def test_eval_seed_sets_the_first_trial(tmp_path):
    from handsynth.sensors.trackers import evaluate

    out = tmp_path / "eval.json"
    res = _run("eval", "--config", "independent", "--duration", "6", "--seeds", "1",
               "--seed", "4", "--json", out)
    assert res.exit_code == 0, res.output
    doc = json.loads(out.read_text())
    assert doc["first_seed"] == 4 and doc["seeds"] == 1
    errors = [r["error_mm"] for r in doc["rows"]]
    assert errors == pytest.approx(
        [r["error_mm"] for r in evaluate(config="independent", duration_s=6.0, seeds=(4,))],
        nan_ok=True)
    seed0 = evaluate(config="independent", duration_s=6.0, seeds=(0,))
    assert errors != pytest.approx([r["error_mm"] for r in seed0], nan_ok=True)
    # one trial: its worst is its mean; two: the larger of the two trials' means
    one = [r for r in doc["rows"] if r["answered"]]
    assert [r["worst_error_mm"] for r in one] == pytest.approx([r["error_mm"] for r in one],
                                                               abs=2e-3)
    both = {(r["scenario"], r["method"], r["frames"]): r
            for r in evaluate(config="independent", duration_s=6.0, seeds=(0, 4))}
    zero = {(r["scenario"], r["method"], r["frames"]): r for r in seed0}
    four = {(r["scenario"], r["method"], r["frames"]): r for r in doc["rows"]}
    for key, r in both.items():
        if r["answered"] == 2:
            assert r["worst_error_mm"] == pytest.approx(
                max(zero[key]["error_mm"], four[key]["error_mm"]), abs=2e-3)
            assert r["worst_error_mm"] >= r["error_mm"] - 1e-9


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
    (["--seed", "-1"], ["--seed must be a seed >= 0", "got -1"]),
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


def test_json_and_plot_with_one_name_are_refused(tmp_path, rec_path):
    # item 18: --json x.json --plot x.json exited 0 with the PNG in x.json
    out = tmp_path / "x.json"
    res = _run("estimate", rec_path, "--method", "obrien", "--json", out,
               "--plot", tmp_path / "." / "x.json")
    assert res.exit_code == 2, res.output
    assert "--json and --plot name the same file" in res.output
    assert not out.exists()


@pytest.mark.parametrize("args, named", [
    (["--units", "cm"], "--units"),
    (["--angles", "euler", "--rate", "100"], "--angles, --rate"),
    (["--sensors", "2,1"], "--sensors"),
    (["--take", "2"], "--take"),
])
def test_text_export_options_with_hdf5_are_refused_by_name(rec_path, args, named):
    # item 19: the options were ignored without notice for an .h5 recording
    res = _run("estimate", rec_path, *args)
    assert res.exit_code == 2, res.output
    assert res.output.startswith(f"handsynth: error: {named} apply to text exports"), res.output


def test_stations_named_upper_second_are_paired_in_file_order(tmp_path, sim):
    # item 12: --sensors 2,1 warned of half frames and paired neighbouring frames
    path = tmp_path / "lib.txt"
    path.write_text("\n".join(_liberty(sim, counter=False)) + "\n")
    out = tmp_path / "c.json"
    res = _run("estimate", path, "--sensors", "2,1", "--method", "obrien", "--frames", "all",
               "--json", out)
    assert res.exit_code == 0, res.output
    assert "warning" not in res.output and "half frames" not in res.output, res.output
    assert json.loads(out.read_text())["results"][0]["n_frames_used"] == sim.n_frames


def test_rate_that_differs_from_the_time_column_is_warned_about(tmp_path, sim):
    # --rate 120 on an export with a 240 Hz time column was ignored without notice
    path = tmp_path / "pimgr.csv"
    path.write_text("\n".join(_pimgr(sim)) + "\n")
    res = _run("estimate", path, "--rate", "120", "--method", "obrien", "--frames", "all")
    assert res.exit_code == 0, res.output
    assert (f"handsynth: warning: --rate 120 Hz is not used: {path} has a time column, whose "
            f"times give 240 Hz; the time column is what is used") in res.output, res.output
    assert "at 240 Hz" in res.output
    # within 1 % of the time column, or not given: no warning
    for args in (["--rate", "241"], []):
        res = _run("estimate", path, *args, "--method", "obrien", "--frames", "all")
        assert res.exit_code == 0 and "--rate" not in res.output, res.output
    # without a time column --rate gives the times
    lib = tmp_path / "lib.txt"
    lib.write_text("\n".join(_liberty(sim, counter=False)) + "\n")
    res = _run("estimate", lib, "--rate", "120", "--method", "obrien", "--frames", "all")
    assert res.exit_code == 0 and "warning" not in res.output, res.output
    assert "at 120 Hz" in res.output


def test_take_reads_a_later_take_of_a_file_of_several(tmp_path, sim):
    # before, the second take of a file whose time restarts could not be read at all
    lines = _pimgr(sim)
    path = tmp_path / "two.csv"
    path.write_text("\n".join(lines + lines[1:]) + "\n")
    out = tmp_path / "c.json"
    res = _run("estimate", path, "--take", "2", "--method", "obrien", "--frames", "all",
               "--json", out)
    assert res.exit_code == 0, res.output
    assert "two takes in one file? take 2 is used" in res.output, res.output
    assert json.loads(out.read_text())["results"][0]["n_frames_used"] > 0
    res = _run("estimate", path, "--take", "3", "--method", "obrien")
    assert res.exit_code == 2, res.output
    assert "take=3, but the time restarts 1 time(s)" in res.output, res.output
    assert "Traceback" not in res.output



def test_eval_json_writes_refused_rows_as_null_not_nan(tmp_path, monkeypatch):
    # a row whose every trial was refused has NaN errors (and the midpoint row a NaN
    # distance): json.dumps wrote bare NaN tokens, which strict JSON readers refuse
    row = {"config": "project", "scenario": "mock", "noise": "datasheet", "method": "obrien",
           "frames": "all", "n_frames_used": 0, "error_upper_mm": float("nan"),
           "error_lower_mm": np.nan, "error_mm": np.float64("nan"), "worst_error_mm": np.nan,
           "distance_mm": float("inf"),
           "axis_error_mm": np.nan, "answered": 0, "warned": 0, "refused": 1, "time_ms": 1.0}
    monkeypatch.setattr("handsynth.sensors.trackers.evaluate", lambda **kw: [dict(row)])
    out = tmp_path / "eval.json"
    res = CliRunner().invoke(cli, ["joints", "eval", "--config", "project", "--seeds", "1",
                                   "--json", str(out)])
    assert res.exit_code == 0, res.output

    def refuse(token):
        raise AssertionError(f"bare {token} in the JSON file")

    (got,) = json.loads(out.read_text(), parse_constant=refuse)["rows"]
    assert got["error_upper_mm"] is None and got["error_mm"] is None
    assert got["worst_error_mm"] is None
    assert got["distance_mm"] is None and got["refused"] == 1 and got["method"] == "obrien"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["eval.json"]


def _damage(lines, row, col, value, sep=","):
    """`lines` with cell `col` of line index `row` replaced by `value`."""
    out = list(lines)
    cells = out[row].split(sep) if sep else out[row].split()
    cells[col] = value
    out[row] = (sep or " ").join(cells)
    return out


@pytest.mark.parametrize("fmt, col, value, named", [
    ("pimgr", 10, "1e300", "column 'loc1_y': value 1e+300"),     # a position
    ("pimgr", 12, "-1e200", "column 'loc2_x': value -1e+200"),
    ("pimgr", 1, "1e300", "column 'w1': value 1e+300"),          # a quaternion component
    ("pimgr", 0, "1e300", "column 'time': value 1e+300"),        # read as a restart before
    ("pimgr", 10, "1e20", "column 'loc1_y': value 1e+20"),       # no overflow, still no position
    ("liberty", 3, "1e300", "column 4: value 1e+300"),
    ("liberty", 1, "1e300", "column 2: value 1e+300"),           # the frame counter
])
def test_huge_values_are_one_line_naming_file_line_column_value(tmp_path, sim, fmt, col, value,
                                                                 named):
    # 1e300 in a position column let numpy's overflow warnings reach the terminal, then was
    # dropped as a glitch; in the time column it was read as a second take
    lines = _pimgr(sim) if fmt == "pimgr" else _liberty(sim, counter=True)
    path = tmp_path / f"huge.{'csv' if fmt == 'pimgr' else 'txt'}"
    path.write_text("\n".join(_damage(lines, 50, col, value, "," if fmt == "pimgr" else None))
                    + "\n")
    out = tmp_path / "c.json"
    res = _run("estimate", path, "--json", out)
    assert res.exit_code == 2, res.output
    assert res.output.strip().splitlines() == [res.output.strip()], res.output
    assert res.output.startswith("handsynth: error: ") and "huge." in res.output
    assert "line 51" in res.output and named in res.output, res.output
    assert "overflow" not in res.output and not out.exists()


def _header_edit(lines, old, new):
    return [lines[0].replace(old, new)] + lines[1:]


@pytest.mark.parametrize("kind, words", [
    # a header naming loc2_y twice read as "no position columns loc2_x, loc2_y, loc2_z"
    ("twice", "the header names column 'loc2_y' 2 times (columns 14, 15)"),
    # a used column named again at the end: the last one was read without a word
    ("again", "the header names column 'loc1_x' 2 times (columns 10, 16)"),
    # numpy's "All-NaN slice encountered" reached the terminal before the error
    ("nan-times", "the time column holds no number on any of its"),
    # "only 1 usable frames of 1" without the reason
    ("backwards", "the time column goes back or stands still on"),
    ("one-sample", "only 1 usable frames of 1 (59 duplicated rows dropped before"),
])
def test_damaged_pimgr_columns_are_one_line(tmp_path, sim, kind, words):
    lines = _pimgr(sim)[:1] + [row for i, row in enumerate(_pimgr(sim)[1:]) if i < 900]
    if kind == "twice":
        lines = _header_edit(lines, "loc2_z", "loc2_y")
    elif kind == "again":
        lines = [lines[0] + ",loc1_x"] + [row + "," + row.split(",")[9] for row in lines[1:]]
    elif kind == "nan-times":
        lines = lines[:1] + ["nan," + row.split(",", 1)[1] for row in lines[1:]]
    elif kind == "backwards":
        lines = lines[:1] + [f"{-float(row.split(',')[0])!r}," + row.split(",", 1)[1]
                             for row in lines[1:]]
    else:
        lines = lines[:1] + [lines[1]] * 60
    path = tmp_path / "bad.csv"
    path.write_text("\n".join(lines) + "\n")
    res = _run("estimate", path)
    assert res.exit_code == 2, res.output
    (line,) = res.output.strip().splitlines()
    assert line.startswith("handsynth: error: bad.csv: ") and words in line, line


@pytest.mark.parametrize("args, words", [
    (["--rate", "1e300"], "--rate must be a finite number > 0 and <= 100000, got 1e+300"),
    (["--rate", "nan"], "--rate must be a finite number > 0 and <= 100000, got nan"),
])
def test_rate_out_of_bounds_is_named(tmp_path, sim, args, words):
    # --rate 1e300 gave every frame a time of 1e-300 s apart
    path = tmp_path / "rec.txt"
    path.write_text("\n".join(_liberty(sim, counter=True)) + "\n")
    res = _run("estimate", path, *args)
    assert res.exit_code == 2 and res.output.strip() == f"handsynth: error: {words}", res.output


def test_a_huge_or_tiny_lateral_axis_is_a_direction(rec_path):
    # 1e300,0,0 let numpy's overflow warnings reach the terminal; 1e-300,0,0 was "zero"
    for value in ("1e300,0,0", "1e-300,0,0"):
        res = _run("estimate", rec_path, "--method", "obrien", "--lateral-axis", value)
        assert res.exit_code == 0 and "overflow" not in res.output, res.output
        assert "expected a non-zero 3-vector" not in res.output
