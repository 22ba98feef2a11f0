import dataclasses
import json
import re

import h5py
import numpy as np
import pytest
from click.testing import CliRunner
from scipy.io import savemat

from handsynth.cli._main import cli
from handsynth.sensors.imu import (
    delayed,
    free_motion,
    simulate_imu,
    truth_chain_model,
    write_imu_csv,
)
from handsynth.sensors.imu._filters import _Q_NWU_FROM_ENU
from handsynth.sensors.imu._quat import qconj, qmul


@pytest.fixture(scope="module")
def sim():
    return simulate_imu(free_motion(8.0, seed=2), seed=3)


def test_track_csv_writes_quaternions(tmp_path, sim):
    rec = sim.subset(("forearm_1", "index_distal"))
    src, out = tmp_path / "rec.csv", tmp_path / "q.csv"
    write_imu_csv(rec, src)
    res = CliRunner().invoke(cli, ["imu", "track", str(src), "--filter", "raw", "--align", "2,4",
                                   "--out", str(out)])
    assert res.exit_code == 0, res.output
    header = out.read_text().splitlines()[0].split(",")
    assert header[:5] == ["time_s", "forearm_1_qw", "forearm_1_qx", "forearm_1_qy", "forearm_1_qz"]
    q = np.loadtxt(out, delimiter=",", skiprows=1)[:, 1:].reshape(-1, 2, 4).transpose(1, 0, 2)
    from handsynth.sensors.imu._quat import angle_deg

    err = angle_deg(q, sim.truth.quat[[0, 16]])
    # two uncalibrated compasses (4.5 deg azimuth s.d., 1 uT hard iron) leave about
    # 5 deg of common heading error; a wrong column order or convention gives tens
    assert np.sqrt(np.mean(err**2)) < 8.0


def test_track_stamps_rows_with_the_recordings_own_times(tmp_path, sim):
    # a logger's epoch stamps: the rows were stamped from 0, so they could not be lined up
    # with another stream of the same clock; epoch seconds also need more than 8 digits
    from dataclasses import replace

    rec = replace(sim.subset(("forearm_1",)), start_s=1_764_200_000.25)
    src, out = tmp_path / "rec.csv", tmp_path / "q.csv"
    write_imu_csv(rec, src)
    first = src.read_text().splitlines()[2].split(",")[0]
    assert first == "1764200000.250000"
    res = CliRunner().invoke(cli, ["imu", "track", str(src), "--filter", "raw", "--out", str(out)])
    assert res.exit_code == 0, res.output
    t = np.loadtxt(out, delimiter=",", skiprows=1)[:, 0]
    np.testing.assert_allclose(t, 1_764_200_000.25 + np.arange(rec.n) / rec.rate_hz, atol=2e-6)
    np.testing.assert_allclose(rec.slice(100, 200).start_s, 1_764_200_000.25 + 100 / rec.rate_hz)
    assert rec.slice(-50, None).start_s == pytest.approx(1_764_200_000.25 + (rec.n - 50) / rec.rate_hz)


def test_track_wrong_units_is_one_line(tmp_path, sim):
    src = tmp_path / "rec.csv"
    write_imu_csv(sim.subset(("forearm_1",)), src)
    res = CliRunner().invoke(cli, ["imu", "track", str(src), "--acc-units", "g",
                                   "--out", str(tmp_path / "q.csv")])
    assert res.exit_code == 2
    assert res.output.startswith("handsynth: error:") and "m/s^2" in res.output
    assert "Traceback" not in res.output
    assert not (tmp_path / "q.csv").exists()


def test_track_refuses_readings_held_by_the_logger_unless_bridged(tmp_path, sim):
    # a wireless link's dropout, the last reading repeated: before, read without a word
    rec = sim.subset(("forearm_1", "index_distal"))
    gyr = rec.gyr.copy()
    acc, mag = rec.acc.copy(), rec.mag.copy()
    for a in (acc, gyr, mag):
        a[1, 500:520] = a[1, 499]
    src, out = tmp_path / "held.csv", tmp_path / "q.csv"
    write_imu_csv(dataclasses.replace(rec, acc=acc, gyr=gyr, mag=mag), src)
    res = CliRunner().invoke(cli, ["imu", "track", str(src), "--filter", "raw", "--out", str(out)])
    assert res.exit_code == 2 and not out.exists()
    assert res.output.startswith(f"handsynth: error: {src}: sensor 'index_distal' repeats its "
                                 "accelerometer and gyro readings bit for bit for 0.2 s "
                                 "(20 samples) from t=5 s (sample 500)"), res.output
    assert "--bridge-lost" in res.output and res.output.count("\n") == 1
    res = CliRunner().invoke(cli, ["imu", "track", str(src), "--filter", "raw", "--bridge-lost",
                                   "--out", str(out)])
    assert res.exit_code == 0, res.output
    assert f"handsynth: warning: {src}: bridged: sensor 'index_distal' repeats" in res.output
    q = np.loadtxt(out, delimiter=",", skiprows=1)
    assert q.shape == (rec.n, 9) and np.isfinite(q).all()



def test_a_hold_longer_than_the_default_is_bridged_only_when_asked(tmp_path, sim):
    rec = sim.subset(("forearm_1", "index_distal"))
    arrays = {name: getattr(rec, name).copy() for name in ("acc", "gyr", "mag")}
    for a in arrays.values():
        a[1, 500:580] = a[1, 499]  # 0.8 s
    src, out = tmp_path / "held.csv", tmp_path / "q.csv"
    write_imu_csv(dataclasses.replace(rec, **arrays), src)
    res = CliRunner().invoke(cli, ["imu", "track", str(src), "--filter", "raw", "--out", str(out)])
    assert res.exit_code == 2 and "cut the recording there (longer than the 0.5 s bridged by " \
        "default; --bridge-lost --bridge-max SECONDS fills it in, further off)" in res.output
    res = CliRunner().invoke(cli, ["imu", "track", str(src), "--filter", "raw", "--bridge-lost",
                                   "--out", str(out)])
    assert res.exit_code == 2 and "longer than the 0.5 s bridged (--bridge-max; library: max_s)" \
        in res.output and not out.exists(), res.output
    res = CliRunner().invoke(cli, ["imu", "track", str(src), "--filter", "raw", "--bridge-lost",
                                   "--bridge-max", "1", "--out", str(out)])
    assert res.exit_code == 0, res.output
    assert "for 0.8 s (80 samples) from t=5 s (sample 500)" in res.output
    assert "meanwhile (longer than the 0.5 s bridged by default: that sensor reads further off)" \
        in res.output, res.output
    assert np.isfinite(np.loadtxt(out, delimiter=",", skiprows=1)).all()
    for args, message in ((["--bridge-max", "1"], "--bridge-max needs --bridge-lost"),
                          (["--bridge-lost", "--bridge-max", "0"],
                           "--bridge-max must be a number of seconds > 0, got 0"),
                          (["--bridge-lost", "--bridge-max", "nan"],
                           "--bridge-max must be a number of seconds > 0, got nan")):
        res = CliRunner().invoke(cli, ["imu", "track", str(src), "--filter", "raw", *args,
                                       "--out", str(out)])
        assert res.exit_code == 2 and res.output == f"handsynth: error: {message}\n", res.output

def test_track_reads_empty_cells_as_samples_lost(tmp_path, sim):
    # before: "line 303: index_distal_acc_x is '', not a number", with no way to fill them
    rec = sim.subset(("forearm_1", "index_distal"))
    src, out = tmp_path / "gaps.csv", tmp_path / "q.csv"
    write_imu_csv(rec, src)
    lines = src.read_text().split("\n")
    k = next(i for i, line in enumerate(lines) if line.startswith("time_s,"))
    for i in range(k + 301, k + 306):
        cells = lines[i].split(",")
        lines[i] = ",".join(cells[:10] + [""] * 9)
    src.write_text("\n".join(lines))
    res = CliRunner().invoke(cli, ["imu", "track", str(src), "--filter", "raw", "--out", str(out)])
    assert res.exit_code == 2 and "sensor 'index_distal' acc axis x is not finite at sample 300" \
        in res.output and "--bridge-lost" in res.output, res.output
    res = CliRunner().invoke(cli, ["imu", "track", str(src), "--filter", "raw", "--bridge-lost",
                                   "--out", str(out)])
    assert res.exit_code == 0, res.output
    assert "bridged: sensor 'index_distal' has values that are not finite numbers (empty cells, " \
           "NaN) for 0.05 s (5 samples) from t=3 s (sample 300)" in res.output, res.output
    assert np.isfinite(np.loadtxt(out, delimiter=",", skiprows=1)).all()


def _write_broad(path, rec, sensor, kind):
    k = rec.index(sensor)
    q_enu = qmul(qconj(_Q_NWU_FROM_ENU), rec.truth.quat[k])
    q_enu[300:310] = np.nan  # marker dropout, as in the dataset
    movement = np.zeros(rec.n, bool)
    movement[400:] = True
    fields = dict(imu_acc=rec.acc[k], imu_gyr=rec.gyr[k], imu_mag=rec.mag[k], opt_quat=q_enu,
                  movement=movement, sampling_rate=np.array([[rec.rate_hz]]))
    if kind == "mat":
        savemat(path, fields)
    else:  # the dataset's layout: arrays as datasets, the rate as the file's attribute
        with h5py.File(path, "w") as f:
            for k, v in fields.items():
                if k == "sampling_rate":
                    f.attrs[k] = float(rec.rate_hz)
                else:
                    f[k] = v


def test_broad_on_a_synthetic_trial(tmp_path, sim):
    d = tmp_path / "broad"
    (d / "data_mat").mkdir(parents=True)
    (d / "data_hdf5").mkdir()
    _write_broad(d / "data_mat" / "01_synthetic_a.mat", sim, "index_middle", "mat")
    rec2 = simulate_imu(free_motion(8.0, seed=5), seed=6)
    _write_broad(d / "data_hdf5" / "02_synthetic_b.hdf5", rec2, "thumb_distal", "hdf5")
    out = tmp_path / "broad.json"
    res = CliRunner().invoke(cli, ["imu", "broad", str(d), "--filter", "constant,raw,vqf",
                                   "--json", str(out)])
    assert res.exit_code == 0, res.output
    data = json.loads(out.read_text())
    assert set(data["trials"]) == {"01_synthetic_a", "02_synthetic_b"}
    m = data["mean"]
    assert m["raw"]["total_rmse_deg"] < m["constant"]["total_rmse_deg"]
    assert m["vqf"]["total_rmse_deg"] < 15.0
    assert "2.9" in res.output
    assert "01_synthetic_a: best" in res.output and "02_synthetic_b: best" in res.output


def test_broad_missing_field_is_named(tmp_path, sim):
    d = tmp_path / "b"
    d.mkdir()
    savemat(d / "01_bad.mat", dict(imu_acc=sim.acc[0]))
    res = CliRunner().invoke(cli, ["imu", "broad", str(d)])
    assert res.exit_code == 2
    assert "missing BROAD field(s) imu_gyr" in res.output and "01_bad.mat" in res.output


@pytest.mark.slow
def test_eval_writes_json_with_baselines(tmp_path):
    out = tmp_path / "eval.json"
    res = CliRunner().invoke(cli, ["imu", "eval", "--config", "tuning", "--duration", "8",
                                   "--elbow", "fixed", "--filter", "constant,raw,filter4",
                                   "--no-grasps", "--json", str(out), "--plots", str(tmp_path / "p")])
    assert res.exit_code == 0, res.output
    for png in ("orientation_error.png", "stick_figure.png"):
        assert (tmp_path / "p" / png).read_bytes()[:4] == b"\x89PNG"
    rep = json.loads(out.read_text())
    assert set(rep["summary"]) == {"constant", "raw", "filter4"}
    assert rep["trials"][0]["duration_s"] == 8.0
    assert "rotation_method" in res.output


def test_eval_seed_draws_the_configuration_again(tmp_path):
    runs = {}
    for seed in (None, "1", "5"):
        out = tmp_path / f"eval{seed}.json"
        args = ["imu", "eval", "--config", "tuning", "--duration", "8", "--elbow", "fixed",
                "--filter", "raw", "--no-grasps", "--json", str(out)]
        res = CliRunner().invoke(cli, args + (["--seed", seed] if seed else []))
        assert res.exit_code == 0, res.output
        rep = json.loads(out.read_text())
        runs[seed] = (rep["config"]["seed"], rep["summary"]["raw"]["orientation_mean_deg"])
    assert [runs[k][0] for k in (None, "1", "5")] == [0, 1, 5]
    assert runs["5"][1] != runs["1"][1] != runs[None][1]
    res = CliRunner().invoke(cli, ["imu", "eval", "--seed", "-2"])
    assert res.exit_code == 2 and "--seed must be a seed >= 0, got -2" in res.output


def test_eval_prints_its_table_without_a_json_file():
    # the README's `handsynth imu eval` failed: --json was required
    res = CliRunner().invoke(cli, ["imu", "eval", "--config", "tuning", "--duration", "8",
                                   "--elbow", "fixed", "--filter", "constant,raw", "--no-grasps"])
    assert res.exit_code == 0, res.output
    assert "orientation RMSE per segment" in res.output and "\nraw " in res.output



@pytest.mark.slow
def test_eval_of_six_axis_sensors_leaves_the_compass_filters_out(tmp_path):
    out = tmp_path / "eval6.json"
    res = CliRunner().invoke(cli, ["imu", "eval", "--six-axis", "--config", "tuning", "--duration",
                                   "8", "--elbow", "fixed", "--no-grasps", "--json", str(out)])
    assert res.exit_code == 0, res.output
    rep = json.loads(out.read_text())
    assert rep["config"]["six_axis"] is True
    assert rep["filters"] == ["constant", "raw", "filter4", "filter4b", "gated", "vqf", "vqf_online"]
    joints = {k: v["joint_angle_mean_rmse_deg"] for k, v in rep["summary"].items()}
    assert max(v for k, v in joints.items() if k != "constant") < 0.25 * joints["constant"], joints
    res = CliRunner().invoke(cli, ["imu", "eval", "--six-axis", "--filter", "raw,mahony",
                                   "--duration", "8", "--no-grasps"])
    assert res.exit_code == 2 and res.output == (
        "handsynth: error: filter(s) mahony observe the compass, which 6-axis sensors lack; leave "
        "them out\n"), res.output

def test_tips_out_needs_the_calibration(tmp_path, sim):
    src = tmp_path / "rec.csv"
    write_imu_csv(sim, src)
    res = CliRunner().invoke(cli, ["imu", "track", str(src), "--out", str(tmp_path / "q.csv"),
                                   "--tips-out", str(tmp_path / "t.csv")])
    assert res.exit_code == 2 and "--tips-out needs --calibration" in res.output
    res = CliRunner().invoke(cli, ["imu", "track", str(src), "--out", str(tmp_path / "q.csv"),
                                   "--bvh-out", str(tmp_path / "h.bvh")])
    assert res.exit_code == 2 and "--bvh-out needs --calibration" in res.output
    res = CliRunner().invoke(cli, ["imu", "track", str(src), "--out", str(tmp_path / "q.csv"),
                                   "--bvh-shape", "standard"])
    assert res.exit_code == 2 and "--bvh-out was not given" in res.output
    assert not any(tmp_path.glob("*.bvh")) and not (tmp_path / "q.csv").exists()


def test_eval_unknown_filter_is_one_line(tmp_path):
    res = CliRunner().invoke(cli, ["imu", "eval", "--filter", "kalman9", "--json",
                                   str(tmp_path / "x.json")])
    assert res.exit_code == 2 and "unknown filter 'kalman9'" in res.output


def test_eval_plots_folder_is_checked_before_the_evaluation(tmp_path):
    """Before, a --plots path under a file failed after the evaluation's minutes."""
    (tmp_path / "afile").write_text("")
    res = CliRunner().invoke(cli, ["imu", "eval", "--plots", str(tmp_path / "afile" / "p")])
    assert res.exit_code == 2 and "cannot create the --plots folder" in res.output, res.output
    (tmp_path / "p" / "stick_figure.png").mkdir(parents=True)
    res = CliRunner().invoke(cli, ["imu", "eval", "--plots", str(tmp_path / "p")])
    assert res.exit_code == 2 and "--plots file" in res.output and "it is a folder" in res.output
    # before: the folder was made where the JSON goes, then the JSON refused as "a folder"
    same = str(tmp_path / "s.json")
    res = CliRunner().invoke(cli, ["imu", "eval", "--json", same, "--plots", same])
    assert res.exit_code == 2 and "--json and --plots name the same path" in res.output
    assert not (tmp_path / "s.json").exists()


def _check_track_bvh(path, rec) -> None:
    """``track --bvh-out``: read by an independent BVH parser and posed, the index fingertip
    is where the simulated one was (from the elbow), far nearer than the first pose held."""
    import bvh
    from scipy.spatial.transform import Rotation

    from handsynth.sensors.imu import POINTS

    mocap = bvh.Bvh(path.read_text())
    assert mocap.nframes == rec.n and mocap.frame_time == pytest.approx(1 / rec.rate_hz)
    chain = ["palm", "index_proximal", "index_middle", "index_distal"]
    end = next(c for c in mocap.get_joint(chain[-1]).children if c.value[:2] == ["End", "Site"])
    kp = rec.truth.keypoints
    got, true = [], []
    for frame in range(400, rec.n, 20):
        place = np.array(mocap.frame_joint_channels(frame, "palm",
                                                    ["Xposition", "Yposition", "Zposition"]))
        turn = Rotation.identity()
        for k, name in enumerate(chain):
            if k:
                place = place + turn.apply(np.array(mocap.joint_offset(name), float))
            zyx = mocap.frame_joint_channels(frame, name, ["Zrotation", "Yrotation", "Xrotation"])
            turn = turn * Rotation.from_euler("ZYX", zyx, degrees=True)
        got.append(place + turn.apply(np.array([float(v) for v in end["OFFSET"]])))
        true.append(1e2 * (kp[frame, POINTS.index("index_tip")] - kp[frame, POINTS.index("elbow")]))
    err = np.linalg.norm(np.array(got) - np.array(true), axis=1)
    held = np.linalg.norm(np.array(got[:1]) - np.array(true), axis=1)
    rms, held_rms = np.sqrt(np.mean(err ** 2)), np.sqrt(np.mean(held ** 2))
    assert rms < 2.0 and rms < 0.3 * held_rms, (rms, held_rms)  # cm


def _bvh_bones_mm(path) -> dict[str, float]:
    """Each bone's length in a BVH file of centimetres, mm, by the point it ends at."""
    import bvh

    mocap = bvh.Bvh(path.read_text())
    ends = {"thumb_metacarpal": "thumb_cmc", "thumb_proximal": "thumb_mcp", "thumb_distal": "thumb_ip",
            **{f"{f}_{s}": f"{f}_{j}" for f in ("index", "middle", "ring", "little")
               for s, j in (("proximal", "mcp"), ("middle", "pip"), ("distal", "dip"))}}
    out = {}
    for name, bone in ends.items():
        out[bone] = 10.0 * float(np.linalg.norm(mocap.joint_offset(name)))
        for child in mocap.get_joint(name).children:
            if child.value[:2] == ["End", "Site"]:
                tip = np.array([float(v) for v in child["OFFSET"]])
                out[bone.rsplit("_", 1)[0] + "_tip"] = 10.0 * float(np.linalg.norm(tip))
    return out


def _check_track_bvh_bones(tmp_path, q_csv, model) -> dict[str, float]:
    """``track --bvh-out``'s bones are the calibration's measure of them (from the attitudes
    it wrote), near the standard hand's, on which it was simulated; returns the standard
    hand's bones, mm."""
    from handsynth.models import BVH_BONE_STARTS, BVH_BONES, KEYPOINT_SITES, HandModel, HandShape
    from handsynth.sensors.imu import ImuCalibration, bone_lengths_mm, fingertip_positions

    cal = ImuCalibration.load(model)
    table = np.genfromtxt(q_csv, delimiter=",", names=True)
    quats = np.stack([np.column_stack([table[f"{s}_q{c}"] for c in "wxyz"]) for s in cal.sensors])
    want = bone_lengths_mm(fingertip_positions(quats, cal.sensors, cal.model))
    got = _bvh_bones_mm(tmp_path / "hand.bvh")
    np.testing.assert_allclose([got[b] for b in BVH_BONES], [want[b] for b in BVH_BONES],
                               atol=1e-3)
    kp, names = HandModel(HandShape(), forearm=False).keypoints(), list(KEYPOINT_SITES)
    standard = {b: 1e3 * float(np.linalg.norm(kp[names.index(b)] - kp[names.index(a)]))
                for b, a in BVH_BONE_STARTS.items()}
    # measured on the standard hand here: near its bones, not its exact numbers
    diff = np.abs([want[b] - standard[b] for b in BVH_BONES])
    assert diff.max() < 5.0 and diff.max() > 0.1, diff
    return standard


@pytest.mark.slow
def test_calibrate_then_track_joint_angles(tmp_path):
    from handsynth.models import JOINT_NAMES
    from handsynth.sensors.imu import MPU9250_DATASHEET, ImuHand, calibration_motion
    from handsynth.sensors.imu._simulate import _fixed_errors

    hand = ImuHand(tip_sensors=True)
    # the same physical sensors (device_seed) in the calibration and the later recording
    cal = simulate_imu(calibration_motion(acc_poses=True), hand=hand, seed=11, device_seed=5)
    cal_csv, seg_json, model = tmp_path / "cal.csv", tmp_path / "seg.json", tmp_path / "cal.json"
    write_imu_csv(cal, cal_csv)
    seg_json.write_text(json.dumps({lab: [a / cal.rate_hz, b / cal.rate_hz]
                                    for lab, a, b in cal.truth.segments}))
    res = CliRunner().invoke(cli, ["imu", "calibrate", str(cal_csv), "--segments", str(seg_json),
                                   "--out", str(model)])
    assert res.exit_code == 0, res.output
    assert "accelerometer/gyro/magnetometer calibration: 25 sensors" in res.output
    # the file holds corrections that undo the sensors' own errors
    stored = json.loads(model.read_text())
    assert stored["version"] == 6 and len(stored["sensor_calibration"]) == 25
    (m_acc, b_acc), (m_gyr, _) = _fixed_errors(MPU9250_DATASHEET, cal.sensors, 5)
    ratio: dict = {"acc": [], "gyr": [], "bias": []}
    for k, s in enumerate(cal.sensors):
        sc = stored["sensor_calibration"][s]
        c, g = np.array(sc["acc_matrix"]), np.array(sc["gyr_matrix"])
        # accelerometer: C M a rotation (lengths kept; a rotation is left to the link frames)
        ca = c @ m_acc[k]
        ratio["acc"].append(np.abs(ca.T @ ca - np.eye(3)).max()
                            / np.abs(m_acc[k].T @ m_acc[k] - np.eye(3)).max())
        ratio["gyr"].append(np.abs(g @ m_gyr[k] - np.eye(3)).max() / np.abs(m_gyr[k] - np.eye(3)).max())
        ratio["bias"].append(np.linalg.norm(np.array(sc["acc_bias_mps2"]) - b_acc[k])
                             / np.linalg.norm(b_acc[k]))
    # median over the 25 sensors (the forearm plate's poses are the least varied: its
    # sensors 1 and 2 are fitted worst)
    med = {k: float(np.median(v)) for k, v in ratio.items()}
    assert med["acc"] < 0.3 and med["gyr"] < 0.6 and med["bias"] < 0.3, med
    # the thesis' hinge centres, for reproduction: the thumb's IP link moves along its axis
    res = CliRunner().invoke(cli, ["imu", "calibrate", str(cal_csv), "--segments", str(seg_json),
                                   "--out", str(tmp_path / "thesis.json"), "--hinge-centres", "thesis"])
    assert res.exit_code == 0, res.output
    thesis = json.loads((tmp_path / "thesis.json").read_text())

    def link(d, sensor):
        return np.array(next(v for s, _, _, v in d["links_m"] if s == sensor))

    truth = truth_chain_model(cal).links[("thumb_proximal", "thumb_mcp", "thumb_ip")]
    err_plane = np.linalg.norm(link(stored, "thumb_proximal") - truth) * 1e3
    err_thesis = np.linalg.norm(link(thesis, "thumb_proximal") - truth) * 1e3
    assert err_plane < 2.0 < err_thesis, (err_plane, err_thesis)
    rec = simulate_imu(free_motion(10.0, seed=12), seed=13, device_seed=5)
    rec_csv, q_csv, ang_csv = tmp_path / "rec.csv", tmp_path / "q.csv", tmp_path / "a.csv"
    write_imu_csv(rec, rec_csv)
    res = CliRunner().invoke(cli, ["imu", "track", str(rec_csv), "--calibration", str(model),
                                   "--align", "2,4", "--out", str(q_csv), "--angles-out", str(ang_csv),
                                   "--tips-out", str(tmp_path / "tips.csv"),
                                   "--bvh-out", str(tmp_path / "hand.bvh")])
    assert res.exit_code == 0, res.output
    assert "sensor calibration applied" in res.output
    _check_track_bvh(tmp_path / "hand.bvh", rec)
    standard = _check_track_bvh_bones(tmp_path, q_csv, model)
    res = CliRunner().invoke(cli, ["imu", "track", str(rec_csv), "--calibration", str(model),
                                   "--align", "2,4", "--out", str(tmp_path / "q2.csv"),
                                   "--bvh-out", str(tmp_path / "standard.bvh"),
                                   "--bvh-shape", "standard"])
    assert res.exit_code == 0, res.output
    got = _bvh_bones_mm(tmp_path / "standard.bvh")
    assert all(abs(got[b] - v) < 1e-3 for b, v in standard.items())
    assert "read as exchanged" not in res.output and "out of step" not in res.output
    # two sensors put back on each other's phalanges: their columns exchanged by name
    lines = rec_csv.read_text().split("\n")
    k = next(i for i, line in enumerate(lines) if line.startswith("time_s,"))  # after a comment
    lines[k] = lines[k].replace("index_proximal", "@").replace("middle_proximal", "index_proximal")
    lines[k] = lines[k].replace("@", "middle_proximal")
    swapped_csv = tmp_path / "swapped.csv"
    swapped_csv.write_text("\n".join(lines))
    res = CliRunner().invoke(cli, ["imu", "track", str(swapped_csv), "--calibration", str(model),
                                   "--align", "2,4", "--out", str(tmp_path / "q2.csv"),
                                   "--angles-out", str(tmp_path / "a2.csv")])
    assert res.exit_code == 0, res.output
    assert "handsynth: warning: sensors read as exchanged since the calibration: " in res.output
    assert re.search(r"(index_proximal and middle_proximal|middle_proximal and index_proximal) "
                     r"\(their joints agree [0-9.]+ times better exchanged", res.output), res.output
    assert "out of step" not in res.output
    # ... read as put back: the angles of the recording as made, and no warning of them left
    res = CliRunner().invoke(cli, ["imu", "track", str(swapped_csv), "--calibration", str(model),
                                   "--align", "2,4", "--out", str(tmp_path / "q4.csv"),
                                   "--angles-out", str(tmp_path / "a4.csv"), "--undo-misplaced"])
    assert res.exit_code == 0, res.output
    # (the columns, not the sensors: each column read with its own sensor's calibration)
    assert ("handsynth: warning: read as put back: index_proximal and middle_proximal exchanged "
            "back (as columns of the recording exchanged, not sensors: their magnetometers read "
            "a steadier field so, ") in res.output
    assert "read as exchanged" not in res.output
    made, faulty, undone = (np.loadtxt(tmp_path / f, delimiter=",", skiprows=1)[:, 1:]
                            for f in ("a.csv", "a2.csv", "a4.csv"))
    assert np.nanmax(np.abs(faulty - made)) > 10.0
    assert np.nanmax(np.abs(undone - made)) < 1e-6
    # one sensor's stream 30 ms late (a wireless logger's latency): named
    late_csv = tmp_path / "late.csv"
    write_imu_csv(delayed(rec, "ring_middle", 3), late_csv)
    res = CliRunner().invoke(cli, ["imu", "track", str(late_csv), "--calibration", str(model),
                                   "--align", "2,4", "--out", str(tmp_path / "q3.csv")])
    assert res.exit_code == 0, res.output
    assert re.search(r"handsynth: warning: sensor streams out of step: ring_middle \d+ ms behind "
                     r"ring_(proximal|distal).*\(ring_middle in two pairs", res.output), res.output
    # ... read realigned: no stream left out of step
    res = CliRunner().invoke(cli, ["imu", "track", str(late_csv), "--calibration", str(model),
                                   "--align", "2,4", "--out", str(tmp_path / "q5.csv"),
                                   "--angles-out", str(tmp_path / "a5.csv"), "--realign-late"])
    assert res.exit_code == 0, res.output
    assert re.search(r"handsynth: warning: read realigned: ring_middle (29|30|31) ms earlier "
                     r"\(realign_late\)", res.output), res.output
    assert "out of step" not in res.output
    realigned = np.loadtxt(tmp_path / "a5.csv", delimiter=",", skiprows=1)[:, 1:]
    assert np.nanmax(np.sqrt(np.nanmean((realigned - made) ** 2, axis=0))) < 0.2
    with open(tmp_path / "tips.csv", encoding="utf-8") as fh:
        header = fh.readline().strip().split(",")
    assert header[:4] == ["time_s", "thumb_tip_x_mm", "thumb_tip_y_mm", "thumb_tip_z_mm"]
    tips = np.loadtxt(tmp_path / "tips.csv", delimiter=",", skiprows=1)
    assert tips.shape == (rec.n, 16)
    from handsynth.sensors.imu import POINTS

    kp = rec.truth.keypoints
    true = (kp[:, POINTS.index("index_tip")] - kp[:, POINTS.index("elbow")]) * 1e3
    got = tips[:, 4:7]  # the index fingertip
    err = np.linalg.norm(got[400:] - true[400:], axis=1)
    still = np.linalg.norm(got[400:401] - true[400:], axis=1)  # the first position held
    assert np.sqrt(np.mean(err**2)) < 60.0 and np.sqrt(np.mean(err**2)) < 0.5 * np.sqrt(
        np.mean(still**2))
    ang = np.loadtxt(ang_csv, delimiter=",", skiprows=1)[:, 1:]
    err = ang[400:] - rec.truth.angles[400:, 9:]
    j = [JOINT_NAMES.index(n) for n in ("index_pip_flex", "middle_mcp_flex", "little_dip_flex")]
    assert np.sqrt(np.mean(err[:, j] ** 2)) < 5.0
    # against a constant answer (the first frame held) the error is far larger
    const = ang[400:400 + 1] - rec.truth.angles[400:, 9:]
    assert np.sqrt(np.mean(err[:, j] ** 2)) < 0.3 * np.sqrt(np.mean(const[:, j] ** 2))
    # the same recording without the stored sensor calibration: worse angles
    raw_csv = tmp_path / "a_raw.csv"
    res = CliRunner().invoke(cli, ["imu", "track", str(rec_csv), "--calibration", str(model),
                                   "--align", "2,4", "--out", str(q_csv), "--angles-out",
                                   str(raw_csv), "--no-sensor-calibration"])
    assert res.exit_code == 0 and "calibration applied" not in res.output, res.output
    raw = np.loadtxt(raw_csv, delimiter=",", skiprows=1)[:, 1:]
    err_raw = raw[400:] - rec.truth.angles[400:, 9:]
    assert np.sqrt(np.nanmean(err**2)) < 0.5 * np.sqrt(np.nanmean(err_raw**2))
    # Filter 4 learning its gyro biases reads the same recording about as well
    b_csv = tmp_path / "a_b.csv"
    res = CliRunner().invoke(cli, ["imu", "track", str(rec_csv), "--calibration", str(model),
                                   "--filter", "filter4b", "--align", "2,4", "--out", str(q_csv),
                                   "--angles-out", str(b_csv)])
    assert res.exit_code == 0 and "filter4b" in res.output, res.output
    err_b = np.loadtxt(b_csv, delimiter=",", skiprows=1)[400:, 1:] - rec.truth.angles[400:, 9:]
    assert np.sqrt(np.mean(err_b[:, j] ** 2)) < 5.0
    assert not np.array_equal(err_b, err)
    assert "range of motion" not in res.output
    # the index's middle-phalanx sensor turned half a turn about its x axis after the
    # calibration (its y and z read reversed): said, naming it, and the angles still written
    k, flip = rec.sensors.index("index_middle"), np.array([1.0, -1.0, -1.0])
    arrays = {name: getattr(rec, name).copy() for name in ("acc", "gyr", "mag")}
    for a in arrays.values():
        a[k] *= flip
    turned_csv = tmp_path / "turned.csv"
    write_imu_csv(dataclasses.replace(rec, **arrays), turned_csv)
    res = CliRunner().invoke(cli, ["imu", "track", str(turned_csv), "--calibration", str(model),
                                   "--align", "2,4", "--out", str(q_csv), "--angles-out",
                                   str(tmp_path / "a_turned.csv")])
    assert res.exit_code == 0, res.output
    warning = next(line for line in res.output.splitlines() if "range of motion" in line)
    assert warning.startswith("handsynth: warning: 2 joint angles read more than 30 deg beyond")
    assert "index_pip_flex in 100 % of the samples" in warning
    assert "Most likely sensor index_middle (a sensor of 2 of those 2 joints) turned" in warning
    # the same sensors read as 6-axis ones (no magnetometer columns): calibrated and tracked,
    # their headings from the common rotation
    cal6_csv, rec6_csv, model6 = tmp_path / "cal6.csv", tmp_path / "rec6.csv", tmp_path / "cal6.json"
    write_imu_csv(dataclasses.replace(cal, mag=None), cal6_csv)
    write_imu_csv(dataclasses.replace(rec, mag=None), rec6_csv)
    res = CliRunner().invoke(cli, ["imu", "calibrate", str(cal6_csv), "--segments", str(seg_json),
                                   "--out", str(model6)])
    assert res.exit_code == 0, res.output
    assert "accelerometer/gyro (6-axis sensors, no magnetometer) calibration: 25 sensors" in res.output
    assert "magnetometer residual" not in res.output
    six_csv = tmp_path / "a6.csv"
    res = CliRunner().invoke(cli, ["imu", "track", str(rec6_csv), "--calibration", str(model6),
                                   "--align", "2,4", "--out", str(q_csv), "--angles-out", str(six_csv)])
    assert res.exit_code == 0, res.output
    assert "6-axis: headings from the common rotation" in res.output
    err6 = np.loadtxt(six_csv, delimiter=",", skiprows=1)[400:, 1:] - rec.truth.angles[400:, 9:]
    assert np.sqrt(np.mean(err6[:, j] ** 2)) < np.sqrt(np.mean(err[:, j] ** 2)) + 0.5
    # without the common rotation nothing gives them one heading: one line, no traceback
    res = CliRunner().invoke(cli, ["imu", "track", str(rec6_csv), "--calibration", str(model6),
                                   "--out", str(q_csv)])
    assert res.exit_code != 0 and "Traceback" not in res.output
    assert "6-axis sensors (no magnetometer) takes the sensors' headings from the common rotation" \
        in res.output


@pytest.mark.parametrize(("args", "message"), [
    (["--filter", "filter4b"], "--filter filter4b needs --calibration"),
    (["--filter", "filter4"], "--filter filter4 needs --calibration"),
    (["--calibration", "c.json", "--filter", "vqf"], "with --calibration the filter is one of filter4, "
                                                     "filter4b, got vqf"),
])
def test_chain_filters_and_the_calibration_go_together(tmp_path, sim, args, message):
    src = tmp_path / "rec.csv"
    write_imu_csv(sim.subset(("forearm_1",)), src)
    res = CliRunner().invoke(cli, ["imu", "track", str(src), "--out", str(tmp_path / "q.csv"), *args])
    assert res.exit_code == 2 and message in res.output, res.output


def test_no_sensor_calibration_needs_the_calibration(tmp_path, sim):
    src = tmp_path / "rec.csv"
    write_imu_csv(sim.subset(("forearm_1",)), src)
    res = CliRunner().invoke(cli, ["imu", "track", str(src), "--out", str(tmp_path / "q.csv"),
                                   "--no-sensor-calibration"])
    assert res.exit_code == 2 and "--no-sensor-calibration needs --calibration" in res.output


def test_calibrate_segment_outside_is_named(tmp_path, sim):
    src, seg = tmp_path / "rec.csv", tmp_path / "seg.json"
    write_imu_csv(sim.subset(("forearm_1",)), src)
    seg.write_text(json.dumps({"static": [0, 2], "elbow_flex": [5, 99]}))
    res = CliRunner().invoke(cli, ["imu", "calibrate", str(src), "--segments", str(seg),
                                   "--out", str(tmp_path / "c.json")])
    assert res.exit_code == 2 and "segment 'elbow_flex' = [5.0, 99.0] s lies outside" in res.output


def test_calibrate_segments_file_not_text_is_one_line(tmp_path, sim):
    src, seg = tmp_path / "rec.csv", tmp_path / "seg.json"
    write_imu_csv(sim.subset(("forearm_1",)), src)
    seg.write_bytes(b"\xff\xfe\x00{")
    res = CliRunner().invoke(cli, ["imu", "calibrate", str(src), "--segments", str(seg),
                                   "--out", str(tmp_path / "c.json")])
    assert res.exit_code == 2 and "seg.json: cannot read the segments JSON" in res.output
    assert "Traceback" not in res.output and not (tmp_path / "c.json").exists()


@pytest.fixture
def base(tmp_path, sim):
    src = tmp_path / "base.csv"
    write_imu_csv(sim.subset(("forearm_1", "index_distal")), src)
    return src


@pytest.mark.parametrize(("args", "message"), [
    (["--filter", "raw", "--out", "{base}"], "the --out file '{base}' is the input '{base}'"),
    (["--calibration", "{cal}", "--out", "{cal}"], "the --out file '{cal}' is the input '{cal}'"),
    (["--calibration", "{cal}", "--out", "{q}", "--angles-out", "{base}"],
     "the --angles-out file '{base}' is the input"),
    (["--calibration", "{cal}", "--out", "{q}", "--angles-out", "{q}"],
     "--out and --angles-out name the same file '{q}'"),
    (["--calibration", "{cal}", "--out", "{d}/nodir/q.csv", "--angles-out", "{d}/a.csv",
      "--tips-out", "{d}/t.csv"], "folder '{d}/nodir' does not exist"),
])
def test_track_outputs_are_checked_before_any_work(tmp_path, base, args, message):
    cal = tmp_path / "cal.json"
    cal.write_text("{}")
    keep = {p: p.read_bytes() for p in (base, cal)}
    names = dict(base=base, cal=cal, q=tmp_path / "q.csv", d=tmp_path)
    res = CliRunner().invoke(cli, ["imu", "track", str(base), *(a.format(**names) for a in args)])
    assert res.exit_code == 2 and message.format(**names) in res.output, res.output
    assert "Traceback" not in res.output
    assert {p: p.read_bytes() for p in keep} == keep
    assert sorted(p.name for p in tmp_path.iterdir()) == ["base.csv", "cal.json"]


def test_calibrate_and_broad_outputs_are_checked_first(tmp_path, base):
    seg = tmp_path / "seg.json"
    seg.write_text(json.dumps({"static": [0, 2]}))
    res = CliRunner().invoke(cli, ["imu", "calibrate", str(base), "--segments", str(seg),
                                   "--out", str(seg)])
    assert res.exit_code == 2 and f"the --out file '{seg}' is the input" in res.output, res.output
    assert json.loads(seg.read_text()) == {"static": [0, 2]}
    res = CliRunner().invoke(cli, ["imu", "calibrate", str(base), "--segments", str(seg),
                                   "--out", str(tmp_path / "nodir" / "x.json")])
    assert res.exit_code == 2 and "nodir' does not exist" in res.output, res.output
    d = tmp_path / "b"
    d.mkdir()
    savemat(d / "01_x.mat", dict(imu_acc=np.zeros((3, 3))))
    res = CliRunner().invoke(cli, ["imu", "broad", str(d), "--json", str(tmp_path / "no" / "x.json")])
    assert res.exit_code == 2 and "no' does not exist" in res.output, res.output
    res = CliRunner().invoke(cli, ["imu", "broad", str(d), "--json", str(d / "01_x.mat")])
    assert res.exit_code == 2 and "is the input" in res.output, res.output


@pytest.mark.parametrize(("args", "message"), [
    (["--rate", "0"], "rate_hz (--rate) must be a finite number > 0 Hz and at most 100000 Hz, got 0.0"),
    (["--rate", "nan"], "rate_hz (--rate) must be a finite number > 0 Hz and at most 100000 Hz, got nan"),
    (["--rate", "inf"], "rate_hz (--rate) must be a finite number > 0 Hz and at most 100000 Hz, got inf"),
    (["--rate", "-5"], "rate_hz (--rate) must be a finite number > 0 Hz and at most 100000 Hz, got -5.0"),
    (["--rate", "1e9"], "at most 100000 Hz, got 1000000000.0"),
    (["--static", "nan"], "static_s (--static) must be a finite number of seconds > 0, got nan"),
    (["--align", "2,2"], "(--align START,END) 2-2 s is empty"),
])
def test_track_bad_numbers_are_one_line(tmp_path, base, args, message):
    res = CliRunner().invoke(cli, ["imu", "track", str(base), "--filter", "vqf",
                                   "--out", str(tmp_path / "q.csv"), *args])
    assert res.exit_code == 2 and message in res.output, res.output
    assert res.output.startswith("handsynth: error:") and not (tmp_path / "q.csv").exists()


def test_track_warns_of_gyro_axes_in_another_convention(tmp_path, sim):
    # before: a logger writing every gyro's x and y axes exchanged was tracked without a word
    src, out = tmp_path / "rec.csv", tmp_path / "q.csv"
    write_imu_csv(dataclasses.replace(sim, truth=None, gyr=sim.gyr[..., [1, 0, 2]]), src)
    res = CliRunner().invoke(cli, ["imu", "track", str(src), "--filter", "raw", "--out", str(out)])
    assert res.exit_code == 0, res.output
    assert re.search(r"handsynth: warning: the gyros carry gravity's direction .* only with their "
                     r"axes read as \(y, x, z\): .* pooled over 20 sensors", res.output)
    assert out.exists()


def test_track_reads_axes_as_the_warning_names_them(tmp_path, sim):
    # an MPU-9250 logger writing the magnetometer in the AK8963's axes: warned of, with the
    # option that reads it; with the option, no warning and the attitudes of the right axes
    src = tmp_path / "rec.csv"
    ak = sim.mag[..., [1, 0, 2]] * np.array([1.0, 1.0, -1.0])
    write_imu_csv(dataclasses.replace(sim, truth=None, mag=ak), src)
    res = CliRunner().invoke(cli, ["imu", "track", str(src), "--out", str(tmp_path / "a.csv")])
    assert res.exit_code == 0 and "(--mag-axes y,x,-z; library: with_axes)" in res.output, res.output
    res = CliRunner().invoke(cli, ["imu", "track", str(src), "--mag-axes", "y,x,-z",
                                   "--out", str(tmp_path / "b.csv")])
    assert res.exit_code == 0 and "turns with its gyro" not in res.output, res.output
    plain = tmp_path / "plain.csv"
    write_imu_csv(sim, plain)
    res = CliRunner().invoke(cli, ["imu", "track", str(plain), "--out", str(tmp_path / "c.csv")])
    assert res.exit_code == 0, res.output
    b, c = (np.loadtxt(tmp_path / f, delimiter=",", skiprows=1) for f in ("b.csv", "c.csv"))
    assert np.array_equal(b, c)


@pytest.mark.parametrize(("args", "message"), [
    (["--gyr-axes", "x,y"], "--gyr-axes must name the axes x, y and z once each"),
    (["--mag-axes", "y,y,z"], "--mag-axes must name the axes x, y and z once each"),
])
def test_track_refuses_axes_that_are_not_three(tmp_path, sim, args, message):
    src = tmp_path / "rec.csv"
    write_imu_csv(sim.subset(("forearm_1", "index_distal")), src)
    res = CliRunner().invoke(cli, ["imu", "track", str(src), *args, "--out", str(tmp_path / "q.csv")])
    assert res.exit_code == 2 and res.output.startswith("handsynth: error:") and message in res.output


def test_track_refuses_mag_axes_without_magnetometers(tmp_path, sim):
    src = tmp_path / "rec.csv"
    write_imu_csv(dataclasses.replace(sim.subset(("forearm_1", "index_distal")), truth=None,
                                      mag=None), src)
    res = CliRunner().invoke(cli, ["imu", "track", str(src), "--mag-axes", "y,x,-z",
                                   "--out", str(tmp_path / "q.csv")])
    assert res.exit_code == 2 and "has no magnetometer columns" in res.output, res.output


def test_track_rate_contradicting_the_time_column_warns(tmp_path, base):
    res = CliRunner().invoke(cli, ["imu", "track", str(base), "--filter", "raw", "--rate", "120",
                                   "--out", str(tmp_path / "q.csv")])
    assert res.exit_code == 0, res.output
    assert "handsynth: warning:" in res.output and "120 Hz (--rate), contradicts" in res.output


@pytest.mark.parametrize(("spans", "message"), [
    ('{"static": [0, NaN]}', "must be finite"),
    ('{"static": [0, 1e400]}', "must be finite"),
    ('{"static": [0, "2"]}', "must be [start_s, end_s], two numbers, got [0, '2']"),
    ('[[0, 2]]', "expected an object of label"),
    ('{"static": [0, 2], "static": [0, 3]}', "label 'static' is given twice"),
])
def test_calibrate_bad_segment_numbers_are_refused(tmp_path, base, spans, message):
    seg = tmp_path / "seg.json"
    seg.write_text(spans)
    res = CliRunner().invoke(cli, ["imu", "calibrate", str(base), "--segments", str(seg),
                                   "--out", str(tmp_path / "c.json")])
    assert res.exit_code == 2 and message in res.output and "seg.json" in res.output, res.output
    assert "Traceback" not in res.output


def test_track_ignores_text_columns_and_finds_duplicates(tmp_path, base):
    lines = base.read_text().splitlines()
    noted = tmp_path / "noted.csv"
    noted.write_text("\n".join([lines[0], "note,when," + lines[1]]
                               + [f"ok,2024-01-01T00:00:{i % 60:02d}," + ln
                                  for i, ln in enumerate(lines[2:])]) + "\n")
    res = CliRunner().invoke(cli, ["imu", "track", str(noted), "--filter", "raw",
                                   "--out", str(tmp_path / "q.csv")])
    assert res.exit_code == 0, res.output
    dup = tmp_path / "dup.csv"
    header = lines[1].split(",")
    dup.write_text("\n".join([",".join(header + ["forearm_1_gyr_x"])]
                             + [ln + ",0" for ln in lines[2:]]) + "\n")
    res = CliRunner().invoke(cli, ["imu", "track", str(dup), "--filter", "raw",
                                   "--out", str(tmp_path / "q2.csv")])
    assert res.exit_code == 2 and "column 'forearm_1_gyr_x' stands twice" in res.output, res.output


@pytest.mark.parametrize(("change", "message"), [
    (lambda r: dict(gyr=np.degrees(r.gyr)), "times the full scale 34.91 rad/s: no sensor of that range "
                                            "reads that; "
                                            "deg/s given as rad/s? (gyro units 'deg/s': --gyr-units"),
    (lambda r: dict(mag=np.concatenate([r.mag[:1], 0 * r.mag[1:]])),
     "the magnetometer of sensor(s) 'index_distal' reads (almost) zero field"),
])
def test_track_content_errors_name_the_cause(tmp_path, sim, change, message):
    rec = sim.subset(("forearm_1", "index_distal"))
    src = tmp_path / "rec.csv"
    write_imu_csv(dataclasses.replace(rec, **change(rec)), src)
    res = CliRunner().invoke(cli, ["imu", "track", str(src), "--out", str(tmp_path / "q.csv")])
    assert res.exit_code == 2 and message in res.output, res.output
    assert "saturated" not in res.output and "magnetic disturbance" not in res.output


def test_track_start_in_motion_is_not_called_a_unit_error(tmp_path, sim):
    src = tmp_path / "rec.csv"
    write_imu_csv(sim.subset(("forearm_1", "index_distal")).slice(300, sim.n), src)
    res = CliRunner().invoke(cli, ["imu", "track", str(src), "--out", str(tmp_path / "q.csv")])
    assert res.exit_code == 2 and "is not still during the static start" in res.output, res.output
    assert "deg/s" not in res.output and "--static" in res.output


def test_broad_skips_a_trial_without_reference_and_writes_no_nan(tmp_path, sim):
    d = tmp_path / "broad"
    d.mkdir()
    _write_broad(d / "01_a.mat", sim, "index_middle", "mat")
    _write_broad(d / "02_b.mat", sim, "thumb_distal", "mat")
    from scipy.io import loadmat

    f = {k: v for k, v in loadmat(d / "02_b.mat").items() if not k.startswith("__")}
    f["opt_quat"][400:] = np.nan
    savemat(d / "02_b.mat", f)
    out = tmp_path / "b.json"
    res = CliRunner().invoke(cli, ["imu", "broad", str(d), "--filter", "raw", "--json", str(out)])
    assert res.exit_code == 0, res.output
    assert "handsynth: warning:" in res.output and "02_b.mat: the reference opt_quat is NaN" in res.output
    data = json.loads(out.read_text())
    assert list(data["trials"]) == ["01_a"] and "NaN" not in out.read_text()


def test_track_full_scale_ranges(tmp_path, base):
    out = tmp_path / "q.csv"
    for flag, value, top in (("--gyr-range", "nan", "50000"), ("--acc-range", "1e308", "1000"),
                             ("--gyr-range", "-1", "50000")):
        res = CliRunner().invoke(cli, ["imu", "track", str(base), flag, value, "--out", str(out)])
        assert res.exit_code == 2, res.output
        assert f"{flag} must be a number > 0 and <= {top}, got {float(value)!r}" in res.output
    res = CliRunner().invoke(cli, ["imu", "track", str(base), "--gyr-range", "20", "--out", str(out)])
    assert res.exit_code == 2 and "full scale 0.3491 rad/s" in res.output, res.output
    assert "--gyr-range" in res.output and not out.exists()


def test_magnetometer_units_and_eval_durations_out_of_range_are_named(tmp_path, sim):
    # --mag-units nT on a file in uT ran with exit 0 (joint angles off by up to 220 deg);
    # --duration 1e9 asked for 745 GiB
    src = tmp_path / "rec.csv"
    write_imu_csv(sim, src)
    res = CliRunner().invoke(cli, ["imu", "track", str(src), "--filter", "raw", "--out",
                                   str(tmp_path / "q.csv"), "--mag-units", "nT"])
    assert res.exit_code == 2 and "--mag-units" in res.output, res.output
    for duration in ("1e9", "5.9"):  # 5.9 s passed here and failed after a trial's work
        res = CliRunner().invoke(cli, ["imu", "eval", "--duration", duration])
        assert res.exit_code == 2 and "--duration must be within [6, 600] s" in res.output


def test_calibrate_refuses_a_rotation_labelled_over_a_still_stretch(tmp_path):
    # before: accepted, and the calibration held a sensor-to-joint vector of metres
    from handsynth.sensors.imu import ImuRecording

    rng = np.random.default_rng(1)
    n = 1000
    gyr = 0.003 * rng.standard_normal((2, n, 3))
    gyr[1, 500:, 0] += np.sin(np.pi * np.arange(500) / 100.0)
    rec = ImuRecording(100.0, ("forearm_1", "index_middle"),
                       np.tile([0.0, 0.0, 9.81], (2, n, 1)) + 0.02 * rng.standard_normal((2, n, 3)),
                       gyr, np.tile([20.0, 0.0, -40.0], (2, n, 1)) + 0.3 * rng.standard_normal((2, n, 3)))
    src, seg, out = tmp_path / "cal.csv", tmp_path / "seg.json", tmp_path / "c.json"
    write_imu_csv(rec, src)
    seg.write_text(json.dumps({"static": [0, 2], "index_pip_flex": [2, 5]}))
    res = CliRunner().invoke(cli, ["imu", "calibrate", str(src), "--segments", str(seg),
                                   "--out", str(out)])
    assert res.exit_code == 2, res.output
    (line,) = res.output.strip().splitlines()
    assert line.startswith(f"handsynth: error: {src}: segment 'index_pip_flex' (samples 200-499 "
                           "(2.00-5.00 s)) is still"), line
    assert not out.exists() and "Traceback" not in res.output


def _damaged_csv(tmp_path, rec, edit):
    """`rec` written as CSV, then `edit` (a function of the lines) applied to its text."""
    src = tmp_path / "rec.csv"
    write_imu_csv(rec, src)
    src.write_text("\n".join(edit(src.read_text().splitlines())) + "\n")
    return src


def _set_column(lines, name, value_of):
    """Lines with column `name` of every data row replaced by value_of(row index, old text)."""
    header = next(i for i, line in enumerate(lines) if not line.startswith("#"))
    j = lines[header].split(",").index(name)
    out = list(lines)
    for i in range(header + 1, len(lines)):
        cells = out[i].split(",")
        cells[j] = value_of(i - header - 1, cells[j])
        out[i] = ",".join(cells)
    return out


@pytest.mark.parametrize("kind, words", [
    # 1e300 uT in one sample: only a "magnetic disturbance" warning, then exit 0
    ("huge-mag", "sensor 'forearm_1' mag axis y reads 1e+300 uT at sample 300, beyond any "
                 "magnetometer's full scale"),
    # a gyro reading 0.0 in every sample: tracked without a word
    ("dead-gyro", "the gyro of sensor(s) 'forearm_1' reads exactly 0 on every axis in all 800"),
    # a file in rad/s read with --gyr-units deg/s: 57 times too little rotation, exit 0
    ("rad-as-deg", "but its gyro turns"),
    # no header: "column '0' stands twice"
    ("no-header", "line 1: the first line holds numbers"),
    # the estimator's refusal, without the file
    ("short", "rec.csv: the static start --static 2 s is longer than the recording (5 samples"),
])
def test_track_damaged_recordings_are_one_line(tmp_path, sim, kind, words):
    rec = sim.subset(("forearm_1", "index_distal"))
    args = []
    if kind == "huge-mag":
        src = _damaged_csv(tmp_path, rec, lambda lines: _set_column(
            lines, "forearm_1_mag_y", lambda i, v: "1e300" if i == 300 else v))
    elif kind == "dead-gyro":
        def zero(lines):
            for axis in "xyz":
                lines = _set_column(lines, f"forearm_1_gyr_{axis}", lambda i, v: "0")
            return lines
        src = _damaged_csv(tmp_path, rec, zero)
    elif kind == "rad-as-deg":
        src = _damaged_csv(tmp_path, rec, lambda lines: lines)
        args = ["--gyr-units", "deg/s"]
    elif kind == "no-header":
        src = _damaged_csv(tmp_path, rec, lambda lines: lines[2:])
    else:
        src = _damaged_csv(tmp_path, rec, lambda lines: lines[:7])
    out = tmp_path / "q.csv"
    res = CliRunner().invoke(cli, ["imu", "track", str(src), "--filter", "raw", "--out", str(out),
                                   *args])
    assert res.exit_code == 2, res.output
    (line,) = res.output.strip().splitlines()
    assert line.startswith(f"handsynth: error: {src}") and words in line, line
    assert not out.exists()


def test_a_filter_option_naming_no_filter_is_refused():
    # "--filter ," ran every filter for minutes
    res = CliRunner().invoke(cli, ["imu", "eval", "--filter", ","])
    assert res.exit_code == 2 and "--filter ',' names no filter" in res.output, res.output


def test_track_names_the_files_and_a_sensor_named_differently(tmp_path, sim):
    # before: "the recording lacks sensor(s) index_middle of the calibration", naming neither
    # the recording nor the calibration file, nor the column block named otherwise
    from handsynth.sensors.imu import ImuCalibration, truth_chain_model

    model = truth_chain_model(sim)
    cal = ImuCalibration(model, {s: np.eye(3) for s in model.own}, np.zeros(20),
                         tuple(model.own)).save(tmp_path / "cal.json")
    src, out = tmp_path / "rec.csv", tmp_path / "q.csv"
    write_imu_csv(sim, src)
    src.write_text(src.read_text().replace("index_middle_", "index_mid_"))
    res = CliRunner().invoke(cli, ["imu", "track", str(src), "--calibration", str(cal),
                                   "--out", str(out)])
    assert res.exit_code == 2, res.output
    assert len(res.output.strip().splitlines()) == 1 and "Traceback" not in res.output
    assert res.output.startswith(f"handsynth: error: {src} (calibration {cal}): the recording "
                                 "lacks sensor(s) index_middle of the calibration (columns "
                                 "index_middle_acc_x .. index_middle_mag_z); it has sensor(s) "
                                 "the calibration does not know: index_mid")
    assert not out.exists()


@pytest.fixture(scope="module")
def streamed_files(tmp_path_factory):
    """A calibration file and a 6-s recording CSV of the same simulated sensors."""
    import warnings

    from handsynth.sensors.imu import ImuHand, calibrate, calibration_motion

    folder = tmp_path_factory.mktemp("stream")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        cal = calibrate(simulate_imu(calibration_motion(), hand=ImuHand(tip_sensors=True), seed=1,
                                     device_seed=2), sensor_calibration=False)
    csv = folder / "rec.csv"
    write_imu_csv(simulate_imu(free_motion(6.0, seed=3), hand=ImuHand(), seed=4, device_seed=2), csv)
    return cal.save(folder / "cal.json"), csv


def test_stream_writes_what_track_writes_line_by_line(tmp_path, streamed_files):
    """Lines piped in one by one come out as track's joint angles; bad lines are one line."""
    cal_path, csv = streamed_files
    res = CliRunner().invoke(cli, ["imu", "track", str(csv), "--calibration", str(cal_path),
                                   "--out", str(tmp_path / "q.csv"),
                                   "--angles-out", str(tmp_path / "a.csv"),
                                   "--tips-out", str(tmp_path / "t.csv")])
    assert res.exit_code == 0, res.output
    tracked = np.loadtxt(tmp_path / "a.csv", delimiter=",", skiprows=1)
    tips = tmp_path / "t.csv"
    res = CliRunner().invoke(cli, ["imu", "stream", "--calibration", str(cal_path), "--rate",
                                   "100", "--tips", "--input", str(csv)])
    assert res.exit_code == 0, res.output
    with_tips = [line.split(",") for line in res.stdout.splitlines()]
    assert with_tips[0][21:] == tips.read_text().splitlines()[0].split(",")[1:] + ["held_sensors"]
    np.testing.assert_allclose(np.array(with_tips[1:], float)[:, 21:36],
                               np.loadtxt(tips, delimiter=",", skiprows=1)[:, 1:], atol=6e-5)
    lines = csv.read_text().splitlines()
    res = CliRunner().invoke(cli, ["imu", "stream", "--calibration", str(cal_path), "--rate", "100"],
                             input="\n".join(lines) + "\n")
    assert res.exit_code == 0, res.output
    out = res.stdout.splitlines()
    assert out[0].startswith("time_s,thumb_cmc_flex")
    streamed = np.array([[float(v) for v in line.split(",")] for line in out[1:]])
    assert streamed.shape == (600, 22) and tracked.shape == (600, 21)
    np.testing.assert_allclose(streamed[:, :21], tracked, rtol=0, atol=6e-5)  # 4 decimals
    assert out[0].endswith(",little_dip_flex,held_sensors") and not streamed[:, 21].any()
    # a spreadsheet's export: semicolons, decimal commas, quoted names
    sheet = [lines[1].replace(",", ";").replace("time_s", '"time_s"')] + [
        line.replace(",", ";").replace(".", ",") for line in lines[2:]]
    res = CliRunner().invoke(cli, ["imu", "stream", "--calibration", str(cal_path), "--rate", "100"],
                             input="\n".join(sheet) + "\n")
    assert res.exit_code == 0, res.output
    assert res.stdout == "\n".join(out) + "\n"
    assert "600 samples tracked (filter4)" in res.stderr
    # a damaged line is one line naming it, after the answers already written
    bad = lines[:300] + [lines[300].replace(lines[300].split(",")[5], "x1.5", 1)] + lines[301:]
    res = CliRunner().invoke(cli, ["imu", "stream", "--calibration", str(cal_path), "--rate", "100"],
                             input="\n".join(bad) + "\n")
    assert res.exit_code != 0
    assert len(res.stdout.splitlines()) == 1 + 297  # line 301 is sample 298 (a comment, a header)
    column = lines[1].split(",")[5]
    assert f"standard input, line 301: {column} is 'x1.5', not a number" in res.stderr
    assert "Traceback" not in res.output


def test_stream_fills_in_lines_a_logger_dropped(streamed_files):
    """Time stamps that skip samples are samples lost: filled in, marked, or refused."""
    cal_path, csv = streamed_files
    lines = csv.read_text().splitlines()  # a comment, the header, samples 0..599
    run = ["imu", "stream", "--calibration", str(cal_path), "--rate", "100"]
    whole = CliRunner().invoke(cli, run, input="\n".join(lines) + "\n")
    assert whole.exit_code == 0, whole.output
    dropped = lines[:2 + 500] + lines[2 + 510:]  # samples 500-509 never arrive
    res = CliRunner().invoke(cli, run, input="\n".join(dropped) + "\n")
    assert res.exit_code == 0, res.output
    full = np.array([[float(v) for v in line.split(",")] for line in whole.stdout.splitlines()[1:]])
    got = np.array([[float(v) for v in line.split(",")] for line in res.stdout.splitlines()[1:]])
    assert got.shape == full.shape == (600, 22)
    np.testing.assert_allclose(got[:, 0], full[:, 0])  # every sample's time, the lost too
    assert (got[500:510, 21] == 20).all() and got[:500, 21].sum() == got[510:, 21].sum() == 0
    assert np.abs(got[:499, 1:21] - full[:499, 1:21]).max() < 1e-3
    assert np.abs(got[:, 1:21] - full[:, 1:21]).max() < 10.0
    # more than --max-hold lost, and stamps that go back: one line each
    res = CliRunner().invoke(cli, run + ["--max-hold", "0.05"], input="\n".join(dropped) + "\n")
    assert res.exit_code != 0 and "Traceback" not in res.output
    assert "line 503: 10 samples missing before this line (time_s 5.1" in res.stderr
    back = lines[:2 + 450] + [lines[2 + 440]] + lines[2 + 451:]
    res = CliRunner().invoke(cli, run, input="\n".join(back) + "\n")
    assert res.exit_code != 0 and "line 453: time stamps do not increase (time_s 4.4" in res.stderr


def test_stream_warns_of_sensors_exchanged_in_a_stretch(streamed_files):
    """Two sensors' columns exchanged: the first stretch checked says so, once, on stderr."""
    cal_path, csv = streamed_files
    lines = csv.read_text().splitlines()
    header = (lines[1].replace("index_proximal_", "tmp_").replace("middle_proximal_", "index_proximal_")
              .replace("tmp_", "middle_proximal_"))
    text = "\n".join([lines[0], header] + lines[2:]) + "\n"
    run = ["imu", "stream", "--calibration", str(cal_path), "--rate", "100"]
    res = CliRunner().invoke(cli, run + ["--check-every", "5"], input=text)
    assert res.exit_code == 0, res.output
    assert len(res.stdout.splitlines()) == 601
    assert res.stderr.count("sensors read as exchanged") == 1
    assert ("the stream's 0.0-5.0 s: sensors read as exchanged since the calibration: "
            "index_proximal and middle_proximal") in res.stderr.replace("\n", " ")
    # 20 s, longer than the stream: what is left checked at its end; 0: never
    res = CliRunner().invoke(cli, run, input=text)
    assert res.exit_code == 0, res.output
    assert "the stream's 0.0-6.0 s: sensors read as exchanged" in res.stderr.replace("\n", " ")
    res = CliRunner().invoke(cli, run + ["--check-every", "0"], input=text)
    assert res.exit_code == 0 and "exchanged" not in res.stderr, res.output


def test_stream_refuses_a_rate_its_time_stamps_deny(streamed_files):
    """--rate half or double the logger's (or under half its period) stops before any answer."""
    cal_path, csv = streamed_files
    text = csv.read_text()                                     # 100 Hz, time_s
    for rate, said in (("50", "the 50 Hz given (--rate)"),     # (steps of half its period)
                       ("200", "the time stamps step by 0.01 s (the median of the first 20 "
                                "steps), 100 Hz, not the 200 Hz given (--rate)"),
                       ("30", "line 4: time stamps step by 0.01 s (time_s 0.010000 after 0), under "
                              "half the period of the 30 Hz given (--rate)")):
        res = CliRunner().invoke(cli, ["imu", "stream", "--calibration", str(cal_path), "--rate",
                                       rate], input=text)
        assert res.exit_code != 0 and "Traceback" not in res.output, res.output
        assert said in res.stderr.replace("\n", " "), res.stderr
        assert len(res.stdout.splitlines()) == 1                # the header, no answer
