import csv
import json
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from handsynth.cli._main import cli
from handsynth.models import JOINT_NAMES
from handsynth.sensors.glove import SENSOR_NAMES


def _run(*args):
    return CliRunner().invoke(cli, [str(a) for a in args], prog_name="handsynth")


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    d = tmp_path_factory.mktemp("glove")
    cal, wear = d / "cal.csv", d / "wear.csv"
    assert _run("glove", "simulate", cal, "--kind", "dg5", "--user", 3, "--trials", 4).exit_code == 0
    res = _run("glove", "simulate", wear, "--kind", "dg5", "--user", 3, "--donning", 9,
               "--seed", 5, "--trials", 1, "--motion", "tripod", "--motion", "fist")
    assert res.exit_code == 0, res.output
    out = d / "cal.json"
    res = _run("glove", "calibrate", cal, "-o", out, "--kind", "dg5")
    assert res.exit_code == 0, res.output
    return {"dir": d, "cal_csv": cal, "wear": wear, "cal": out, "calibrate_output": res.output}


def test_calibrate_writes_a_loadable_file_and_prints_fit_r2(files):
    data = json.loads(files["cal"].read_text())
    assert data["format"] == "handsynth-glove-calibration" and data["kind"] == "dg5"
    assert set(data["estimators"]) == {"constant", "model1", "model2", "model3", "model4",
                                       "pooled_model4", "synergy", "model4+synergy"}
    assert data["range_reference"] is not None
    out = files["calibrate_output"]
    assert "R^2 of the joint-3 (MCP) fits of model4" in out and "lateral_contact" in out


def test_apply_writes_canonical_angles_close_to_the_truth(files):
    out = files["dir"] / "angles.csv"
    res = _run("glove", "apply", files["cal"], files["wear"], "-o", out, "--range", files["wear"])
    assert res.exit_code == 0, res.output
    with out.open() as f:
        rows = list(csv.reader(f))
    assert rows[0] == ["time_s", *JOINT_NAMES]
    est = np.array(rows[1:], dtype=float)[:, 1:]
    with files["wear"].open() as f:
        ref_rows = list(csv.DictReader(f))
    ref = np.array([[float(r[j]) for j in JOINT_NAMES] for r in ref_rows])
    assert est.shape == ref.shape
    mcp = [JOINT_NAMES.index(n) for n in JOINT_NAMES if n.endswith("_mcp_flex")]
    err = np.abs(est[:, mcp] - ref[:, mcp]).mean()
    spread = np.abs(ref[:, mcp] - ref[:, mcp].mean(axis=0)).mean()
    assert err < 0.7 * spread, (err, spread)


def test_apply_flags_bad_readings_and_keeps_rows(files):
    bad = files["dir"] / "bad.csv"
    lines = [",".join(["time_s", *SENSOR_NAMES])]
    rng = np.random.default_rng(0)
    for i in range(60):
        vals = 1500 + rng.normal(0, 3, 5).round()
        vals[2] = 1234                           # dead middle sensor
        vals[4] = 4095 if i < 10 else vals[4]    # little saturated at first
        cells = [f"{v:g}" for v in vals]
        if i == 7:
            cells[0] = ""                        # dropped thumb sample
        lines.append(",".join([f"{i / 60:.4f}", *cells]))
    bad.write_text("\n".join(lines) + "\n")
    out = files["dir"] / "bad_angles.csv"
    res = _run("glove", "apply", files["cal"], bad, "-o", out)
    assert res.exit_code == 0, res.output
    assert "handsynth: warning: " in res.output
    assert "sensor_middle is dead" in res.output
    assert "sensor_little is saturated (at 4095 counts) in 10 of 60" in res.output
    assert "bad.csv: 1 of 60 rows have a NaN reading (at line 9)" in res.output
    with out.open() as f:
        rows = list(csv.reader(f))[1:]
    assert len(rows) == 60 and rows[7][1] == "nan" and rows[8][1] != "nan"


def test_errors_are_one_line(files, tmp_path):
    res = _run("glove", "apply", files["cal"], files["wear"], "-o", tmp_path / "x.csv",
               "--motion", "wave")
    assert res.exit_code == 2 and "handsynth: error: motion 'wave' was not calibrated" in res.output
    res = _run("glove", "apply", files["cal"], files["wear"], "-o", tmp_path / "x.csv",
               "--model", "svm")
    assert res.exit_code == 2 and "no estimator 'svm'" in res.output
    junk = tmp_path / "junk.csv"
    junk.write_text("a,b\n1,2\n")
    res = _run("glove", "calibrate", junk, "-o", tmp_path / "c.json", "--kind", "dg5")
    assert res.exit_code == 2 and "missing sensor column" in res.output
    assert "Traceback" not in res.output
    assert not (tmp_path / "c.json").exists()
    nocal = tmp_path / "wear_only.csv"
    assert _run("glove", "simulate", nocal, "--trials", 1, "--no-angles").exit_code == 0
    res = _run("glove", "calibrate", nocal, "-o", tmp_path / "c.json", "--kind", "dg5")
    assert res.exit_code == 2 and "no reference joint angles" in res.output


def test_calibrate_warns_about_few_samples(tmp_path):
    few = tmp_path / "few.csv"
    assert _run("glove", "simulate", few, "--trials", 1, "--no-range-holds").exit_code == 0
    with few.open() as f:
        rows = list(csv.reader(f))
    few.write_text("\n".join(",".join(r) for r in [rows[0], *rows[1::12]]) + "\n")
    res = _run("glove", "calibrate", few, "-o", tmp_path / "c.json", "--kind", "dg5",
               "--points", 3, "--synergies", 0)
    assert res.exit_code == 0, res.output
    assert "handsynth: warning: " in res.output and "t-values of the joint-3 regressions" in res.output


def test_eval_json_has_the_seed_table_layout(tmp_path):
    out = tmp_path / "eval.json"
    res = _run("glove", "eval", "--kind", "5dt", "--trials", 3, "--test-trials", 1,
               "--seeds", 2, "--json", out)
    assert res.exit_code == 0, res.output
    assert "leave one trial out" in res.output and "model4/known" in res.output
    data = json.loads(out.read_text())
    r = data["results"]["5dt"]
    assert r["config"]["seeds"] == [0, 1]
    # what was asked, not averaged over the seeds (the mean of seeds 0 and 1 was 0.5)
    assert r["config"]["seed"] == 0 and r["config"]["trials"] == 3
    assert type(r["config"]["trials"]) is int and r["config"]["rate_hz"] == 60.0
    assert r["config"]["representative_motions"] == ["standard", "lateral_contact", "tripod",
                                                    "parallel_extension"]
    loto = r["conditions"]["loto"]["representative"]
    cell = loto["tables"]["model4/known"]["parallel_extension"]["index"]
    assert {"mcp_error_deg", "r2", "baseline_mcp_error_deg", "truth_sd_deg"} <= set(cell)
    summ = loto["summary"]["model4/known"]
    assert len(summ["mcp_error_deg_per_seed"]) == 2
    assert summ["mcp_error_deg"] < summ["baseline_mcp_error_deg"] / 2


def test_calibrate_learns_synergies_from_a_cyberglove_export(files, tmp_path):
    from handsynth.models import natural_pose_set
    from handsynth.sensors.glove import CYBERGLOVE_COLUMNS

    poses = natural_pose_set(200, seed=9)
    idx = {n: i for i, n in enumerate(JOINT_NAMES)}
    cols = []
    for c in CYBERGLOVE_COLUMNS:
        if c == "thumb_rotation":
            cols.append(poses[:, idx["thumb_cmc_flex"]])
        elif c == "thumb_abduction":
            cols.append(poses[:, idx["thumb_cmc_abd"]])
        elif f"{c}_flex" in idx:
            cols.append(poses[:, idx[f"{c}_flex"]])
        else:                                  # relative abductions, palm, wrist
            cols.append(np.zeros(len(poses)))
    export = tmp_path / "cyber.csv"
    np.savetxt(export, np.column_stack(cols), delimiter=",", fmt="%.4f")
    out = tmp_path / "c.json"
    res = _run("glove", "calibrate", files["cal_csv"], "-o", out, "--kind", "dg5",
               "--synergy-csv", export, "--synergies", 3)
    assert res.exit_code == 0, res.output
    assert "synergies from" in res.output and "3 explain" in res.output
    syn = json.loads(out.read_text())["estimators"]["synergy"]["synergies"]
    assert syn["source"].endswith("cyber.csv") and len(syn["components"]) == 3
    res = _run("glove", "calibrate", files["cal_csv"], "-o", out, "--kind", "dg5",
               "--synergy-csv", export, "--synergy-units", "rad")
    assert res.exit_code == 2 and "--synergy-units deg" in res.output


def _edit_csv(src, dst, edit):
    """Copy the glove CSV `src` to `dst` with `edit(header, rows)` applied to its cells."""
    with open(src, newline="") as f:
        header, *rows = list(csv.reader(f))
    header, rows = edit(header, rows)
    with open(dst, "w", newline="") as f:
        csv.writer(f).writerows([header, *rows])
    return dst


@pytest.mark.parametrize("command", ["apply-readings", "apply-calibration", "calibrate"])
def test_an_output_never_replaces_an_input(files, tmp_path, command):
    # both commands replaced their input with exit 0
    import shutil

    if command == "calibrate":
        victim = shutil.copy(files["cal_csv"], tmp_path / "rec.csv")
        args = ["calibrate", victim, "-o", victim, "--kind", "dg5"]
    elif command == "apply-readings":
        victim = shutil.copy(files["wear"], tmp_path / "w.csv")
        args = ["apply", files["cal"], victim, "-o", victim]
    else:
        victim = shutil.copy(files["cal"], tmp_path / "c.json")
        args = ["apply", victim, files["wear"], "-o", victim]
    before = Path(victim).read_bytes()
    res = _run("glove", *args)
    assert res.exit_code == 2 and "never replaces an input" in res.output, res.output
    assert Path(victim).read_bytes() == before


def test_the_warnings_that_explain_a_failure_are_printed(files, tmp_path):
    # a broken reference sensor: every row dropped for NaN; the error alone said
    # "no samples labelled with a motion"
    def blank(header, rows):
        k = header.index("thumb_mcp_flex")
        return header, [r[:k] + [""] + r[k + 1:] for r in rows]

    rec = _edit_csv(files["cal_csv"], tmp_path / "blank.csv", blank)
    res = _run("glove", "calibrate", rec, "-o", tmp_path / "c.json", "--kind", "dg5")
    assert res.exit_code == 2, res.output
    *warned, error = res.output.strip().splitlines()
    assert error.startswith("handsynth: error: ")
    assert any("NaN" in w and w.startswith("handsynth: warning: ") for w in warned), res.output


def test_reference_angles_in_radians_are_refused(files, tmp_path):
    def radians(header, rows):
        cols = [header.index(j) for j in JOINT_NAMES]
        out = []
        for r in rows:
            r = list(r)
            for k in cols:
                r[k] = str(float(np.radians(float(r[k]))))
            out.append(r)
        return header, out

    rec = _edit_csv(files["cal_csv"], tmp_path / "rad.csv", radians)
    res = _run("glove", "calibrate", rec, "-o", tmp_path / "c.json", "--kind", "dg5")
    assert res.exit_code == 2 and "radians" in res.output and "rad.csv" in res.output, res.output


def test_readings_off_the_calibrations_range_are_warned_about(files, tmp_path):
    # a 10-bit converter's readings: the models clamp them, the answer hardly moved, no word
    def quarter(header, rows):
        cols = [header.index(s) for s in SENSOR_NAMES]
        return header, [[str(float(c) / 4) if k in cols else c for k, c in enumerate(r)]
                        for r in rows]

    wear = _edit_csv(files["wear"], tmp_path / "w10.csv", quarter)
    res = _run("glove", "apply", files["cal"], wear, "-o", tmp_path / "a.csv")
    assert res.exit_code == 0, res.output
    assert "off the calibration's range" in res.output and "--adc-max" in res.output
    res = _run("glove", "apply", files["cal"], files["wear"], "-o", tmp_path / "b.csv",
               "--range", files["wear"])
    assert res.exit_code == 0 and "off the calibration" not in res.output, res.output


def test_two_channels_exchanged_are_named(files, tmp_path):
    # the same wearing recorded again with two sensors' cables in each other's inputs: the
    # warning named only another glove, full scale or wearing
    again = tmp_path / "again.csv"
    res = _run("glove", "simulate", again, "--kind", "dg5", "--user", 3, "--seed", 7,
               "--trials", 1, "--motion", "tripod", "--motion", "fist")
    assert res.exit_code == 0, res.output

    def exchange(header, rows):
        names = {"sensor_index": "sensor_middle", "sensor_middle": "sensor_index"}
        return [names.get(c, c) for c in header], rows

    res = _run("glove", "apply", files["cal"], _edit_csv(again, tmp_path / "x.csv", exchange),
               "-o", tmp_path / "a.csv")
    assert res.exit_code == 0, res.output
    assert "its readings fit sensor_middle's range and sensor_middle's fit its: were the two " \
           "channels exchanged?" in res.output, res.output
    res = _run("glove", "apply", files["cal"], again, "-o", tmp_path / "b.csv")
    assert res.exit_code == 0 and "channels exchanged" not in res.output, res.output


def test_the_range_is_on_the_estimators_and_warned_about_once_per_sensor(files, tmp_path):
    data = json.loads(files["cal"].read_text())
    for name, entry in data["estimators"].items():
        low, high = np.array(entry["reading_range"])
        assert low.shape == (5,) and (low < high).all(), name
    assert "sensor_min" not in data["meta"]

    def volts(header, rows):                     # readings in volts, not counts
        cols = [header.index(s) for s in SENSOR_NAMES]
        return header, [[str(float(c) / 1000) if k in cols else c for k, c in enumerate(r)]
                        for r in rows]

    wear = _edit_csv(files["wear"], tmp_path / "volts.csv", volts)
    res = _run("glove", "apply", files["cal"], wear, "-o", tmp_path / "a.csv",
               "--model", "model4+synergy")
    assert res.exit_code == 0, res.output
    warned = [w for w in res.output.splitlines() if "off the calibration's range" in w]
    assert len(warned) == 5, res.output          # once per sensor, not once per layer
    assert all(w.startswith("handsynth: warning: model4+synergy: 100 % of the sensor_")
               for w in warned), res.output


def test_an_older_calibration_file_is_still_checked_from_its_meta(files, tmp_path):
    data = json.loads(files["cal"].read_text())
    for entry in data["estimators"].values():
        entry.pop("reading_range", None)
    data["meta"].update(sensor_min=[3000.0] * 5, sensor_max=[3500.0] * 5)
    old = tmp_path / "old.json"
    old.write_text(json.dumps(data))
    res = _run("glove", "apply", old, files["wear"], "-o", tmp_path / "a.csv")
    assert res.exit_code == 0, res.output
    assert res.output.count("off the calibration's range 3000-3500 counts") == 5, res.output


@pytest.mark.parametrize("cell", ["nan", "1e30"])
def test_a_bad_trial_number_is_one_line(files, tmp_path, cell):
    def bad(header, rows):
        k = header.index("trial")
        rows[1][k] = cell
        return header, rows

    wear = _edit_csv(files["wear"], tmp_path / "t.csv", bad)
    res = _run("glove", "apply", files["cal"], wear, "-o", tmp_path / "a.csv")
    assert res.exit_code == 2 and "line 3: trial" in res.output, res.output
    assert "Traceback" not in res.output


@pytest.mark.parametrize("edit, words", [
    (lambda d: d.update(estimators=[]), "field 'estimators' must map names"),
    (lambda d: d.pop("estimators"), "field 'estimators' must map names"),
    (lambda d: d["estimators"].update(model4=None), "must be an object, got NoneType"),
    (lambda d: d["estimators"]["model4"].update(models={}), "field 'models' must map"),
    (lambda d: d["estimators"]["model4"]["models"]["standard"].update(centre=[1, 2, 3]),
     "field 'centre' must have shape (5,), got (3,)"),
    (lambda d: d["estimators"]["model4"]["models"]["standard"].update(centre="1732"),
     "field 'centre' must have shape (5,), got ()"),
    (lambda d: d["estimators"]["model4"]["models"]["standard"]["centre"].__setitem__(0, None),
     "field 'centre' holds nan"),
    (lambda d: d["estimators"]["model4"]["models"]["standard"]["fits"].pop("thumb_mcp_flex"),
     "missing thumb_mcp_flex"),
    (lambda d: d["estimators"]["model4"]["models"]["standard"]["fits"]["index_pip_flex"]
     .update(terms=[[7, 1]]), "[sensor 0-4, power 1-3]"),
    (lambda d: d["estimators"]["model4"]["models"]["standard"]["fits"]["index_pip_flex"]
     .update(coef=[1.0]), "field 'coef' must have shape"),
    (lambda d: d.update(range_reference={"open": "abc"}), "field 'open' must be numbers"),
    (lambda d: d["range_reference"].update(open=[1, 2, 3]), "field 'open' must have shape (5,)"),
    (lambda d: d["estimators"]["constant"].update(posture=None), "field 'posture'"),
    (lambda d: d.update(kind="cyberglove"), "field 'kind' must be one of dg5, 5dt"),
    # an inverted z_range clipped every reading to one value: constant angles with exit 0
    (lambda d: d["estimators"]["model4"]["models"]["standard"].update(
        z_range=[[1.0] * 5, [-1.0] * 5]), "field 'z_range' must hold [lowest, highest]"),
    # equal holds were blamed on the readings' file ("5 of 5 sensors go the other way")
    (lambda d: d["range_reference"].update(open=d["range_reference"]["fist"]),
     "field 'range_reference': sensor_thumb reads the same open"),
])
def test_a_hand_edited_calibration_is_refused_by_field(files, tmp_path, edit, words):
    # each of these crashed apply with a traceback or gave wrong angles with exit 0
    data = json.loads(files["cal"].read_text())
    edit(data)
    cal = tmp_path / "edited.json"
    cal.write_text(json.dumps(data))
    res = _run("glove", "apply", cal, files["wear"], "-o", tmp_path / "a.csv",
               "--model", "constant" if "posture" in words else "model4",
               "--range", files["wear"])
    assert res.exit_code == 2, res.output
    assert "edited.json" in res.output and words in res.output, res.output
    assert "Traceback" not in res.output
    assert not (tmp_path / "a.csv").exists()


def test_a_damaged_estimator_is_named_once(files, tmp_path):
    # the name stood two or three times: "estimator 'model4': estimator 'model4': ..."
    data = json.loads(files["cal"].read_text())
    data["estimators"]["model4"]["models"].pop("tripod")
    cal = tmp_path / "edited.json"
    cal.write_text(json.dumps(data))
    res = _run("glove", "apply", cal, files["wear"], "-o", tmp_path / "a.csv")
    assert res.exit_code == 2, res.output
    assert res.output.count("estimator 'model4'") == 1, res.output
    assert "its mixer weighs motions without a model: tripod" in res.output


def test_a_calibration_saved_with_a_byte_order_mark_is_read(files, tmp_path):
    cal = tmp_path / "bom.json"
    cal.write_bytes(b"\xef\xbb\xbf" + files["cal"].read_bytes())
    res = _run("glove", "apply", cal, files["wear"], "-o", tmp_path / "a.csv")
    assert res.exit_code == 0, res.output


def test_a_column_named_twice_is_refused(files, tmp_path):
    def twice(header, rows):
        return header + ["sensor_thumb"], [r + ["0"] for r in rows]

    wear = _edit_csv(files["wear"], tmp_path / "dup.csv", twice)
    res = _run("glove", "apply", files["cal"], wear, "-o", tmp_path / "a.csv")
    assert res.exit_code == 2 and "column 'sensor_thumb' stands twice" in res.output, res.output


def test_range_holds_swapped_or_empty_are_named(files, tmp_path):
    def swap(header, rows):
        k = header.index("motion")
        names = {"range_open": "range_fist", "range_fist": "range_open"}
        return header, [r[:k] + [names.get(r[k], r[k])] + r[k + 1:] for r in rows]

    def blank(header, rows):
        k, m = header.index("sensor_thumb"), header.index("motion")
        return header, [r[:k] + [""] + r[k + 1:] if r[m] == "range_open" else r for r in rows]

    swapped = _edit_csv(files["wear"], tmp_path / "swapped.csv", swap)
    res = _run("glove", "apply", files["cal"], files["wear"], "-o", tmp_path / "a.csv",
               "--range", swapped)
    assert res.exit_code == 2 and "the other way round" in res.output, res.output
    empty = _edit_csv(files["wear"], tmp_path / "empty.csv", blank)
    res = _run("glove", "apply", files["cal"], files["wear"], "-o", tmp_path / "a.csv",
               "--range", empty)
    assert res.exit_code == 2 and "empty.csv: sensor_thumb has no reading" in res.output, \
        res.output


@pytest.mark.parametrize("value", ["0", "-5", "nan"])
def test_a_bad_full_scale_is_refused(files, tmp_path, value):
    res = _run("glove", "apply", files["cal"], files["wear"], "-o", tmp_path / "a.csv",
               "--adc-max", value)
    assert res.exit_code == 2 and "--adc-max" in res.output, res.output


def test_eval_on_the_held_out_simulator_configuration(tmp_path):
    out = tmp_path / "eval.json"
    res = _run("glove", "eval", "--kind", "dg5", "--trials", 3, "--test-trials", 1,
               "--config", "heldout", "--json", out)
    assert res.exit_code == 0, res.output
    assert "== dg5 (heldout simulator configuration)" in res.output
    sim = json.loads(out.read_text())["results"]["dg5"]["config"]["simulator"]
    assert sim["label"] == "heldout" and sim["hysteresis_deg"] == [4.0, 8.0]
    res = _run("glove", "eval", "--config", "other")
    assert res.exit_code == 2 and "'other' is not one of 'tuning', 'heldout'" in res.output


def test_eval_checks_its_json_path_before_evaluating(tmp_path):
    res = _run("glove", "eval", "--json", tmp_path / "nodir" / "x.json")
    assert res.exit_code == 2 and "does not exist" in res.output
    assert "==" not in res.output  # no table: nothing was evaluated


def test_synergies_from_postures_that_do_not_vary_are_refused(files, tmp_path):
    from handsynth.sensors.glove import CYBERGLOVE_COLUMNS

    export = tmp_path / "still.csv"
    np.savetxt(export, np.tile(np.linspace(1, 22, len(CYBERGLOVE_COLUMNS)), (50, 1)),
               delimiter=",", fmt="%.4f")
    res = _run("glove", "calibrate", files["cal_csv"], "-o", tmp_path / "c.json", "--kind",
               "dg5", "--synergy-csv", export)
    assert res.exit_code == 2 and "hardly vary" in res.output, res.output
    wide = tmp_path / "wide.csv"  # a time stamp before the 22 angles, no header
    np.savetxt(wide, np.random.default_rng(0).uniform(0, 40, (50, 23)), delimiter=",")
    res = _run("glove", "calibrate", files["cal_csv"], "-o", tmp_path / "c.json", "--kind",
               "dg5", "--synergy-csv", wide)
    assert res.exit_code == 2 and "23 fields, expected 22" in res.output, res.output


@pytest.mark.parametrize("args, words", [
    (["simulate", "{tmp}/x.csv", "--seed", "-1"], "--seed must be a seed >= 0"),
    (["simulate", "{tmp}/x.csv", "--donning", "-1"], "--donning must be a seed >= 0"),
    (["eval", "--trials", "1000000"], "(--trials) must be an integer in [3, 100]"),
])
def test_seeds_and_counts_out_of_range_name_the_option(tmp_path, args, words):
    res = _run("glove", *[a.replace("{tmp}", str(tmp_path)) for a in args])
    assert res.exit_code == 2 and words in res.output and "Traceback" not in res.output, \
        res.output


def test_a_corrupt_huge_cell_is_refused_by_line(files, tmp_path):
    # one 1e308 reference angle gave a calibration of infinities, exit 0
    def huge(header, rows):
        rows[5][header.index("index_mcp_flex")] = "1e308"
        return header, rows

    rec = _edit_csv(files["cal_csv"], tmp_path / "huge.csv", huge)
    res = _run("glove", "calibrate", rec, "-o", tmp_path / "c.json", "--kind", "dg5")
    assert res.exit_code == 2 and "line 7: index_mcp_flex is '1e308'" in res.output, res.output
    assert not (tmp_path / "c.json").exists()


def test_motion_labels_are_read_whatever_their_case(files, tmp_path):
    # STANDARD and RANGE_OPEN were taken for unknown motions of a few samples each
    def upper(header, rows):
        k = header.index("motion")
        return header, [r[:k] + [r[k].upper()] + r[k + 1:] for r in rows]

    rec = _edit_csv(files["cal_csv"], tmp_path / "upper.csv", upper)
    res = _run("glove", "calibrate", rec, "-o", tmp_path / "c.json", "--kind", "dg5")
    assert res.exit_code == 0, res.output
    assert "range holds (open, fist): stored" in res.output


def test_motion_labels_written_with_spaces_are_read(files, tmp_path):
    # "Range Open" and "Lateral Contact" (a spreadsheet's labels) were taken for motions of
    # their own: calibrate failed on "motion 'Range Open': point 1 of 20 has 1 ... samples"
    def spaced(header, rows):
        k = header.index("motion")
        return header, [r[:k] + [r[k].replace("_", " ").title()] + r[k + 1:] for r in rows]

    rec = _edit_csv(files["cal_csv"], tmp_path / "spaced.csv", spaced)
    out = tmp_path / "c.json"
    res = _run("glove", "calibrate", rec, "-o", out, "--kind", "dg5")
    assert res.exit_code == 0, res.output
    assert "range holds (open, fist): stored" in res.output
    assert set(json.loads(out.read_text())["estimators"]["model4"]["models"]) == {
        "standard", "lateral_contact", "tripod"}


def test_readings_scaled_to_one_with_range_holds_are_named_as_such(files, tmp_path):
    # readings normalised to 0-1 were refused as "sensor_thumb reads the same for the open
    # hand and the fist (0.42 counts); is it dead?"
    def scaled(header, rows):
        ks = [header.index(n) for n in SENSOR_NAMES]
        return header, [[f"{float(c) / 4095:.6f}" if i in ks else c for i, c in enumerate(r)]
                        for r in rows]

    wear = _edit_csv(files["wear"], tmp_path / "scaled.csv", scaled)
    out = tmp_path / "a.csv"
    res = _run("glove", "apply", files["cal"], wear, "-o", out, "--range", wear)
    assert res.exit_code == 2, res.output
    assert "scaled.csv" in res.output and "less than 1 count" in res.output, res.output
    assert "instead of the converter's counts" in res.output and "dead" not in res.output
    assert "Traceback" not in res.output and not out.exists()


def test_simulate_trials_are_bounded(tmp_path):
    # before: --trials 100000000 ran on for ever
    res = _run("glove", "simulate", tmp_path / "s.csv", "--trials", 100_000_000)
    assert res.exit_code == 2 and "--trials" in res.output and not (tmp_path / "s.csv").exists()


def _one_error_line(res, *words):
    """The run failed with exit 2 and one error line naming `words`, no traceback."""
    assert res.exit_code == 2, res.output
    errors = [ln for ln in res.output.splitlines() if ln.startswith("handsynth: error: ")]
    assert len(errors) == 1 and "Traceback" not in res.output, res.output
    for w in words:
        assert w in errors[0], res.output
    return errors[0]


def test_an_all_saturated_recording_names_the_saturated_sensors(files, tmp_path):
    # the error was "no samples labelled with a motion" (calibrate) or a file of
    # meaningless angles with exit 0 (apply)
    rec = tmp_path / "sat.csv"
    res = _run("glove", "simulate", rec, "--trials", 1, "--adc-max", 1)
    assert res.exit_code == 0, res.output
    res = _run("glove", "calibrate", rec, "-o", tmp_path / "c.json", "--kind", "dg5",
               "--adc-max", 1)
    line = _one_error_line(res, "sat.csv", "have a saturated reading")
    assert "labelled" not in line
    for name in SENSOR_NAMES:
        assert f"{name} saturated (at 1 counts) in " in line, line
    res = _run("glove", "apply", files["cal"], rec, "-o", tmp_path / "a.csv", "--adc-max", 1)
    _one_error_line(res, "sat.csv: every reading is saturated",
                    "sensor_little saturated (at 1 counts) in ")
    assert not (tmp_path / "a.csv").exists() and not (tmp_path / "c.json").exists()
    res = _run("glove", "apply", files["cal"], files["wear"], "-o", tmp_path / "a.csv",
               "--adc-max", 1)                          # readings above the full scale
    _one_error_line(res, "above the full scale 1 counts", "--adc-max")
    assert not (tmp_path / "a.csv").exists()


def test_saturated_range_holds_are_named_by_hold_and_sensor(files, tmp_path):
    # a fist hold at the converter's end was taken as the hold's reading, without a word
    def fist_at_top(header, rows):
        k, m = header.index("sensor_index"), header.index("motion")
        return header, [r[:k] + ["4095"] + r[k + 1:] if r[m] == "range_fist" else r
                        for r in rows]

    def open_negative(header, rows):
        k, m = header.index("sensor_ring"), header.index("motion")
        return header, [r[:k] + ["-12"] + r[k + 1:] if r[m] == "range_open" else r
                        for r in rows]

    cal = _edit_csv(files["cal_csv"], tmp_path / "calfist.csv", fist_at_top)
    res = _run("glove", "calibrate", cal, "-o", tmp_path / "c.json", "--kind", "dg5")
    _one_error_line(res, "calfist.csv: sensor_index is saturated (at 4095 counts) in 30 of the "
                         "30 rows labelled range_fist")
    assert not (tmp_path / "c.json").exists()
    rng = _edit_csv(files["wear"], tmp_path / "neg.csv", open_negative)
    res = _run("glove", "apply", files["cal"], files["wear"], "-o", tmp_path / "a.csv",
               "--range", rng)
    line = _one_error_line(res, "neg.csv: sensor_ring is below the converter's range (negative, "
                                "down to -12 counts) in 30 of the 30 rows labelled range_open")
    assert "saturated" not in line.split("neg.csv: ", 1)[1]
    assert not (tmp_path / "a.csv").exists()


def test_warnings_count_rows_and_name_them_by_file_line(files, tmp_path):
    # the same rows were "rows" (counted from 0 after the header) in one warning and
    # "samples" in the next
    def holes(header, rows):
        k = header.index("sensor_thumb")
        for i in (3, 40):
            rows[i][k] = ""
        rows[7][header.index("sensor_middle")] = "-5"
        return header, rows

    rec = _edit_csv(files["cal_csv"], tmp_path / "holes.csv", holes)
    res = _run("glove", "calibrate", rec, "-o", tmp_path / "c.json", "--kind", "dg5")
    assert res.exit_code == 0, res.output
    n = len(files["cal_csv"].read_text().splitlines()) - 1
    assert f"holes.csv: dropped 2 of {n} rows with NaN (first at lines 5, 42)" in res.output
    assert (f"holes.csv: dropped 1 of {n} rows with an out-of-range reading (sensor_middle below "
            "the converter's range (negative, down to -5 counts) in 1 row; at line 9)"
            in res.output), res.output


def test_apply_writes_what_the_library_function_writes(files, tmp_path):
    from handsynth.sensors.glove import apply_calibration

    res = _run("glove", "apply", files["cal"], files["wear"], "-o", tmp_path / "cli.csv",
               "--range", files["wear"], "--model", "model4+synergy")
    assert res.exit_code == 0, res.output
    apply_calibration(files["cal"], files["wear"], tmp_path / "lib.csv", model="model4+synergy",
                      range_csv=files["wear"])
    assert (tmp_path / "cli.csv").read_bytes() == (tmp_path / "lib.csv").read_bytes()


@pytest.mark.parametrize("content, words", [
    ("0,pinch,0,1,2,3,4,5\n1,pinch,0,1,2,3,4,5\n", "line 1: the first line holds numbers"),
    ("time_s,sensor_thumb,sensor_index,sensor_middle,sensor_ring,sensor_little\n"
     "0,1500,1500,1500,1500,inf\n", "line 2: sensor_little is 'inf', not a finite number"),
    ("time_s,sensor_thumb,sensor_index,sensor_middle,sensor_ring,sensor_little\n"
     "0,1500,,1500,1500,1500\n0.1,nan,1500,1500,1500,1500\n", "none of the 2 rows has all five"),
    ("time_s,sensor_thumb,sensor_index,sensor_middle,sensor_ring,sensor_little\n"
     "0,1500,1500,1500\n", "line 2: 4 fields, header has 6"),
    ("time_s,sensor_thumb,sensor_index,sensor_middle,sensor_ring\n0,1,2,3,4\n",
     "missing sensor column(s) sensor_little"),
    ("", "empty file"),
])
def test_a_damaged_readings_file_is_one_line_and_nothing_is_written(files, tmp_path, content,
                                                                    words):
    bad = tmp_path / "bad.csv"
    bad.write_text(content)
    res = _run("glove", "apply", files["cal"], bad, "-o", tmp_path / "a.csv")
    _one_error_line(res, "bad.csv", words)
    assert not (tmp_path / "a.csv").exists()


@pytest.mark.parametrize("args, words", [
    (["calibrate", "{cal}", "-o", "{tmp}/c.json", "--kind", "dg5", "--t-threshold", "-1"],
     "--t-threshold must be a finite number >= 0, got -1"),
    (["calibrate", "{cal}", "-o", "{tmp}/c.json", "--kind", "dg5", "--t-threshold", "nan"],
     "--t-threshold must be a finite number >= 0, got nan"),
    (["calibrate", "{cal}", "-o", "{tmp}/c.json", "--kind", "dg5", "--points", "0"],
     "--points must be an integer >= 1 and <= 200, got 0"),
    (["calibrate", "{cal}", "-o", "{tmp}/c.json", "--kind", "dg5", "--synergies", "21"],
     "--synergies must be an integer >= 0 and <= 20, got 21"),
    (["simulate", "{tmp}/s.csv", "--motion", "tripod", "--motion", "tripod"],
     "--motion tripod is given twice"),
    (["simulate", "{tmp}/s.csv", "--motion", "wave"], "--motion: unknown motion 'wave'"),
    (["simulate", "{tmp}/s.csv", "--adc-max", "0"], "--adc-max must be an integer >= 1, got 0"),
])
def test_options_past_their_limits_name_the_option(files, tmp_path, args, words):
    args = [a.replace("{tmp}", str(tmp_path)).replace("{cal}", str(files["cal_csv"]))
            for a in args]
    res = _run("glove", *args)
    _one_error_line(res, words)
    assert not list(tmp_path.iterdir())


def test_a_corrupt_synergy_export_is_one_line(files, tmp_path):
    # a 1e308 cell crashed calibrate with a traceback from the eigen-decomposition
    from handsynth.sensors.glove import CYBERGLOVE_COLUMNS

    data = np.random.default_rng(0).uniform(0, 40, (50, len(CYBERGLOVE_COLUMNS)))
    data[7, 5] = 1e308
    export = tmp_path / "cyber.csv"
    np.savetxt(export, data, delimiter=",")
    res = _run("glove", "calibrate", files["cal_csv"], "-o", tmp_path / "c.json", "--kind",
               "dg5", "--synergy-csv", export)
    _one_error_line(res, "cyber.csv, line 8: index_pip is", "beyond any joint angle")
    assert not (tmp_path / "c.json").exists()


def test_readings_that_hold_their_own_range_are_read_and_warned_about_once(files, tmp_path):
    # export-style names: "6 columns read by their meaning" was printed twice, once for the
    # readings and once for the same file as --range
    names = {"sensor_thumb": "Thumb", "sensor_index": "index sensor", "sensor_middle": "Bend-Middle",
             "sensor_ring": "Ring", "sensor_little": "pinky", "time_s": "Time (s)"}
    wear = _edit_csv(files["wear"], tmp_path / "export.csv",
                     lambda header, rows: ([names.get(h, h) for h in header], rows))
    out = tmp_path / "a.csv"
    res = _run("glove", "apply", files["cal"], wear, "-o", out, "--range", wear)
    assert res.exit_code == 0, res.output
    assert res.output.count("read by their meaning") == 1, res.output
    plain = tmp_path / "b.csv"
    assert _run("glove", "apply", files["cal"], files["wear"], "-o", plain, "--range",
                files["wear"]).exit_code == 0
    assert out.read_text() == plain.read_text()  # the same angles either way


def test_stream_writes_what_apply_writes_line_by_line(files):
    """Lines piped in come out as apply's angles; bad readings are NaN rows, said once."""
    out = files["dir"] / "applied.csv"
    for extra in ([], ["--model", "model1", "--motion", "tripod"], ["--model", "synergy"]):
        res = _run("glove", "apply", files["cal"], files["wear"], "-o", out, "--range",
                   files["wear"], *extra)
        assert res.exit_code == 0, res.output
        res = CliRunner().invoke(cli, ["glove", "stream", str(files["cal"]), "--range",
                                       str(files["wear"]), *extra],
                                 input=files["wear"].read_text())
        assert res.exit_code == 0, res.output
        assert res.stdout.splitlines()[0] == "time_s," + ",".join(JOINT_NAMES)
        applied = np.loadtxt(out, delimiter=",", skiprows=1)
        streamed = np.array([[float(v) for v in line.split(",")]
                             for line in res.stdout.splitlines()[1:]])
        assert streamed.shape == applied.shape
        np.testing.assert_allclose(streamed, applied, rtol=0, atol=6e-5)  # 4 decimals
    # readings beyond the converter and at its end, a damaged cell: NaN row, one warning
    # each, one line naming the cell
    lines = files["wear"].read_text().splitlines()
    header = lines[0].split(",")
    k = header.index("sensor_index")

    def with_reading(line, value):
        cells = line.split(",")
        cells[k] = value
        return ",".join(cells)

    bad = [lines[0], with_reading(lines[1], "5000"), with_reading(lines[2], "6000"),
           with_reading(lines[3], "4095"), lines[4]]
    res = CliRunner().invoke(cli, ["glove", "stream", str(files["cal"])],
                             input="\n".join(bad) + "\n")
    assert res.exit_code == 0, res.output
    rows = [line.split(",") for line in res.stdout.splitlines()[1:]]
    assert len(rows) == 4 and rows[0][1:] == rows[1][1:] == ["nan"] * 20
    assert "nan" not in rows[2] + rows[3]
    assert res.stderr.count("outside the converter's range 0-4095") == 1
    assert res.stderr.count("sensor_index reads 4095, the end of the converter's range") == 1
    res = CliRunner().invoke(cli, ["glove", "stream", str(files["cal"])],
                             input="\n".join([lines[0], with_reading(lines[1], "x7")]) + "\n")
    assert res.exit_code != 0 and "Traceback" not in res.output
    assert "standard input, line 2: sensor_index is 'x7', not a number" in res.stderr


def test_stream_warns_once_of_a_sensor_stuck_while_the_others_move(files):
    """A sensor that stops changing (a broken lead) while the hand moves is warned of."""
    lines = files["wear"].read_text().splitlines()
    k = lines[0].split(",").index("sensor_middle")
    cells = [line.split(",") for line in lines[1:]]
    held = cells[20][k]
    for row in cells[20:]:
        row[k] = held                     # stuck from the 21st sample on
    stuck = [lines[0]] + [",".join(row) for row in cells]
    assert len(stuck) > 140
    res = CliRunner().invoke(cli, ["glove", "stream", str(files["cal"])],
                             input="\n".join(stuck) + "\n")
    assert res.exit_code == 0, res.output
    said = res.stderr.replace("\n", " ")
    assert said.count("has read") == 1, said
    assert (f"standard input, line 121: sensor_middle has read {float(held):g} for the last 100 "
            "lines while sensor_") in said
    assert len(res.stdout.splitlines()) == len(stuck)   # every line still answered
    res = CliRunner().invoke(cli, ["glove", "stream", str(files["cal"])],
                             input="\n".join(lines) + "\n")
    assert res.exit_code == 0 and "has read" not in res.stderr, res.output
