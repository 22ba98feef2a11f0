import csv
import json

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
    assert "1 of 60 rows have a NaN reading (first rows 7)" in res.output
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
    assert res.exit_code == 2 and "pass units='deg'" in res.output
