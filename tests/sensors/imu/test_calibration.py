import dataclasses
import json

import numpy as np
import pytest

from handsynth.errors import EstimationError, RecordingError
from handsynth.sensors.imu import (
    ImuCalibration,
    ThumbCmcModel,
    segments_from_seconds,
    truth_chain_model,
)


def test_save_load_round_trip(tmp_path, ideal_rec):
    model = truth_chain_model(ideal_rec)
    cal = ImuCalibration(model, {s: np.eye(3) for s in model.own}, np.arange(20.0),
                         tuple(model.own))
    back = ImuCalibration.load(cal.save(tmp_path / "c.json"))
    assert back.sensors == cal.sensors and np.array_equal(back.zero, cal.zero)
    for k, v in cal.model.links.items():
        assert np.allclose(back.model.links[k], v)
    assert back.cmc is None  # a calibration without the thumb CMC axes (version 1 files)
    with_cmc = ImuCalibration(model, cal.frames, cal.zero, cal.sensors,
                              ThumbCmcModel(np.eye(3)[:2], np.eye(3)))
    again = ImuCalibration.load(with_cmc.save(tmp_path / "d.json"))
    assert np.array_equal(again.cmc.axes, np.eye(3)[:2]) and np.array_equal(again.cmc.rest,
                                                                            np.eye(3))


def test_bad_calibration_files(tmp_path):
    p = tmp_path / "c.json"
    p.write_text("{not json")
    with pytest.raises(RecordingError, match="not a calibration JSON file"):
        ImuCalibration.load(p)
    p.write_text(json.dumps({"format": "handsynth-imu-calibration", "sensors": []}))
    with pytest.raises(RecordingError, match="missing field\\(s\\) own_m"):
        ImuCalibration.load(p)


def test_track_needs_the_calibrated_sensors(ideal_rec):
    model = truth_chain_model(ideal_rec)
    cal = ImuCalibration(model, {}, np.zeros(20), tuple(model.own))
    with pytest.raises(RecordingError, match="lacks sensor\\(s\\) forearm_3, hand_radial"):
        cal.track(ideal_rec.subset(("index_distal",)))


def test_segments_from_seconds():
    assert segments_from_seconds({"static": [0, 2]}, 100.0, 500) == (("static", 0, 200),)
    with pytest.raises(RecordingError, match="must be \\[start_s, end_s\\]"):
        segments_from_seconds({"static": 3}, 100.0, 500)


def _sensor_cal(sensors, scale=1.02, mag=True):
    from handsynth.sensors.imu import SensorCalibration

    n = len(sensors)
    extra = dict(mag_matrix=np.tile(np.eye(3) * 0.97, (n, 1, 1)), mag_bias_ut=np.full((n, 3), 1.5),
                 mag_residual=np.zeros(n)) if mag else {}
    return SensorCalibration(tuple(sensors), np.tile(np.eye(3) * scale, (n, 1, 1)),
                             np.full((n, 3), 0.1), np.tile(np.eye(3) / scale, (n, 1, 1)),
                             np.zeros(n), np.zeros(n), **extra)


def test_sensor_calibration_is_stored_and_applied(tmp_path, ideal_rec):
    model = truth_chain_model(ideal_rec)
    sensors = tuple(model.own)
    cal = ImuCalibration(model, {s: np.eye(3) for s in sensors}, np.zeros(20), sensors,
                         sensor_calibration=_sensor_cal(ideal_rec.sensors))
    path = cal.save(tmp_path / "c.json")
    d = json.loads(path.read_text())
    assert d["version"] == 6 and set(d["sensor_calibration"]) == set(ideal_rec.sensors)
    back = ImuCalibration.load(path)
    assert np.array_equal(back.sensor_calibration.acc_matrix, cal.sensor_calibration.acc_matrix)
    fixed = back.correct(ideal_rec)
    k, j = ideal_rec.index("index_distal"), fixed.sensors.index("index_distal")
    assert np.allclose(fixed.acc[j], 1.02 * (ideal_rec.acc[k] - 0.1))
    assert np.allclose(fixed.gyr[j], ideal_rec.gyr[k] / 1.02)
    assert np.allclose(fixed.mag[j], 0.97 * (ideal_rec.mag[k] - 1.5))
    raw = back.correct(ideal_rec, sensor_calibration=False)
    assert np.array_equal(raw.acc[j], ideal_rec.acc[k])


def test_version_3_file_leaves_the_magnetometers_as_read(tmp_path, ideal_rec):
    model = truth_chain_model(ideal_rec)
    sensors = tuple(model.own)
    d = ImuCalibration(model, {s: np.eye(3) for s in sensors}, np.zeros(20), sensors,
                       sensor_calibration=_sensor_cal(ideal_rec.sensors, mag=False)).to_dict()
    assert "mag_matrix" not in d["sensor_calibration"]["index_distal"]
    d["version"] = 3
    p = tmp_path / "v3.json"
    p.write_text(json.dumps(d))
    back = ImuCalibration.load(p)
    assert back.sensor_calibration.mag_matrix is None
    fixed = back.correct(ideal_rec)
    k, j = ideal_rec.index("index_distal"), fixed.sensors.index("index_distal")
    assert np.array_equal(fixed.mag[j], ideal_rec.mag[k])
    assert np.allclose(fixed.acc[j], 1.02 * (ideal_rec.acc[k] - 0.1))


def test_version_2_file_loads_without_sensor_calibration(tmp_path, ideal_rec):
    model = truth_chain_model(ideal_rec)
    sensors = tuple(model.own)
    d = ImuCalibration(model, {s: np.eye(3) for s in sensors}, np.zeros(20), sensors).to_dict()
    d["version"] = 2
    p = tmp_path / "v2.json"
    p.write_text(json.dumps(d))
    back = ImuCalibration.load(p)
    assert back.sensor_calibration is None
    assert np.array_equal(back.correct(ideal_rec).acc[0], ideal_rec.subset(sensors).acc[0])


def test_bad_sensor_calibration_in_the_file_is_named(tmp_path, ideal_rec):
    model = truth_chain_model(ideal_rec)
    sensors = tuple(model.own)
    good = ImuCalibration(model, {s: np.eye(3) for s in sensors}, np.zeros(20), sensors,
                          sensor_calibration=_sensor_cal(ideal_rec.sensors)).to_dict()
    p = tmp_path / "c.json"
    d = json.loads(json.dumps(good))
    d["sensor_calibration"]["thumb_distal"]["acc_matrix"] = [[1, 0], [0, 1]]
    p.write_text(json.dumps(d))
    with pytest.raises(RecordingError, match="c.json: sensor_calibration: sensor 'thumb_distal' "
                                             "'acc_matrix' must be finite with shape"):
        ImuCalibration.load(p)
    d = json.loads(json.dumps(good))
    del d["sensor_calibration"]["forearm_2"]
    p.write_text(json.dumps(d))
    with pytest.raises(RecordingError, match="sensor_calibration lacks sensor\\(s\\) forearm_2"):
        ImuCalibration.load(p)
    d = json.loads(json.dumps(good))
    d["version"] = 9
    p.write_text(json.dumps(d))
    with pytest.raises(RecordingError, match="version 9 is newer"):
        ImuCalibration.load(p)


@pytest.mark.parametrize(("edit", "message"), [
    (lambda d: d.update(frames=[]), "field frames must be a JSON object, got []"),
    (lambda d: d["zero_deg"].__setitem__(0, float("nan")),
     "field zero_deg holds nan at index 0; every value must be a finite number"),
    (lambda d: d.update(version="5"), "field version is '5'; expected a whole number from 1 to 6"),
    (lambda d: d["own_m"].update(index_distal=[0, 0, float("inf")]),
     "field own_m index_distal holds inf at index 2"),
])
def test_bad_calibration_values_are_refused_at_load(tmp_path, ideal_rec, edit, message):
    model = truth_chain_model(ideal_rec)
    cal = ImuCalibration(model, {s: np.eye(3) for s in model.own}, np.arange(20.0),
                         tuple(model.own))
    d = cal.to_dict()
    edit(d)
    p = tmp_path / "c.json"
    p.write_text(json.dumps(d))
    with pytest.raises(RecordingError) as info:
        ImuCalibration.load(p)
    assert str(info.value).startswith(f"{p}: ") and message in str(info.value)


def test_segments_must_be_finite_numbers():
    for span, message in (([0, float("nan")], "must be finite"), ([0, float("inf")], "must be finite"),
                          ([0, "2"], "two numbers"), ([True, 2], "two numbers"),
                          ([2, 2], "is empty")):
        with pytest.raises(RecordingError, match=message):
            segments_from_seconds({"static": span}, 100.0, 500, source="seg.json")


def test_a_missing_stretch_lists_the_labels_there_are():
    # "no labelled stretch 'elbow_flex'" did not show the misspelled 'elbow_flexx'
    from handsynth.errors import InvalidInputError
    from handsynth.sensors.imu._vectors import _segment

    with pytest.raises(InvalidInputError, match=r"'elbow_flex' \(its labels: static, "
                                                r"elbow_flexx; a label misspelled"):
        _segment((("static", 0, 10), ("elbow_flexx", 10, 90)), "elbow_flex")


@pytest.mark.slow
def test_a_left_hand_is_read_as_a_left_hand(tmp_path):
    # before, calibrate() measured every wearer as a right hand: a left hand's abductions
    # came out turned the other way (2.6 deg mean error on this motion against 0.1)
    import warnings

    from handsynth.models import JOINT_NAMES
    from handsynth.sensors.imu import ImuHand, calibrate, calibration_motion, free_motion, simulate_imu

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        cal = simulate_imu(calibration_motion(acc_poses=True),
                           hand=ImuHand(side="left", tip_sensors=True),
                           seed=1, device_seed=2)
        rec = simulate_imu(free_motion(duration_s=10.0, seed=3), hand=ImuHand(side="left"), seed=4,
                           device_seed=2)
        abd = [i for i, name in enumerate(JOINT_NAMES) if "abd" in name]
        truth = rec.truth.angles[400:, -20:]
        errors = {}
        for side in ("right", "left"):
            m = calibrate(cal, side=side)
            errors[side] = np.abs(m.track(rec)["angles"][400:] - truth)[:, abd].mean()
    assert errors["left"] < 0.3 < 1.0 < errors["right"]
    path = m.save(tmp_path / "left.json")
    assert json.loads(path.read_text())["side"] == "left"
    assert ImuCalibration.load(path).side == "left"
    d = json.loads(path.read_text())
    del d["side"]  # a file of version 5 or older: a right hand, as written then
    (tmp_path / "old.json").write_text(json.dumps(d))
    assert ImuCalibration.load(tmp_path / "old.json").side == "right"
    d["side"] = "Left"
    (tmp_path / "bad.json").write_text(json.dumps(d))
    with pytest.raises(RecordingError, match=r"field side must be \"right\" or \"left\", got 'Left'"):
        ImuCalibration.load(tmp_path / "bad.json")


def test_too_few_static_poses_for_the_sensor_calibration_are_warned_about():
    # before, 1-7 labelled poses were skipped silently and the readings used uncorrected
    import warnings

    from handsynth.sensors.imu import ImuHand, calibrate, calibration_motion, simulate_imu

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        rec = simulate_imu(calibration_motion(acc_poses=True), hand=ImuHand(tip_sensors=True),
                           seed=1, device_seed=2)
    kept = tuple(seg for seg in rec.truth.segments if not seg[0].startswith("acc_pose_")
                 or seg[0] in ("acc_pose_0", "acc_pose_1", "acc_pose_2"))
    few = dataclasses.replace(rec, segments=kept)
    with pytest.warns(UserWarning, match=r"^3 static pose\(s\) labelled acc_pose_<k>: .* needs 8"):
        cal = calibrate(few)
    assert cal.sensor_calibration is None


def test_a_link_frame_that_is_not_a_rotation_is_refused_at_load(tmp_path, ideal_rec):
    # before: read as given, and the joint it belongs to came out constant
    model = truth_chain_model(ideal_rec)
    cal = ImuCalibration(model, {s: np.eye(3) for s in model.own}, np.zeros(20), tuple(model.own))
    d = json.loads(cal.save(tmp_path / "c.json").read_text())
    name = next(iter(d["frames"]))
    d["frames"][name] = [[2, 0, 0], [0, 2, 0], [0, 0, 2]]
    (tmp_path / "bad.json").write_text(json.dumps(d))
    with pytest.raises(RecordingError, match=rf"field frames holds 1 .* not rotations \({name}\)"):
        ImuCalibration.load(tmp_path / "bad.json")


def test_a_segment_label_no_step_reads_is_warned_about():
    # before: a misspelt rotation was ignored without a word
    with pytest.warns(UserWarning, match=r"^s\.json: segment\(s\) 'index_mcp_flx' are no stretch"):
        out = segments_from_seconds({"static": [0, 2], "index_mcp_flx": [2, 4], "acc_pose_3": [4, 5]},
                                    100.0, 1000, source="s.json")
    assert [lab for lab, _, _ in out] == ["static", "index_mcp_flx", "acc_pose_3"]


def _still_then_turning(n=1000, rate=100.0, seed=0):
    """Two sensors still for `n` // 2 samples, then the second one turning at 1 rad/s peak."""
    from handsynth.sensors.imu import ImuRecording

    rng = np.random.default_rng(seed)
    acc = np.tile([0.0, 0.0, 9.81], (2, n, 1)) + 0.02 * rng.standard_normal((2, n, 3))
    gyr = 0.003 * rng.standard_normal((2, n, 3))
    t = np.arange(n // 2) / rate
    gyr[1, n // 2:, 0] += np.sin(2 * np.pi * 0.5 * t)
    mag = np.tile([20.0, 0.0, -40.0], (2, n, 1)) + 0.3 * rng.standard_normal((2, n, 3))
    return ImuRecording(rate, ("forearm_1", "index_middle"), acc, gyr, mag)


def test_a_rotation_labelled_over_a_still_stretch_is_refused():
    # before: accepted, and the sensor-to-joint vector came out metres long from the noise
    from handsynth.sensors.imu import calibrate
    from handsynth.sensors.imu._calibration import check_stretches

    rec = _still_then_turning()
    moving = dataclasses.replace(rec, segments=(("static", 0, 200), ("index_pip_flex", 500, 1000)))
    assert check_stretches(moving) == []
    still = dataclasses.replace(rec, segments=(("static", 0, 200), ("index_pip_flex", 200, 500)))
    message = (r"^cal\.csv: segment 'index_pip_flex' \(samples 200-499 \(2\.00-5\.00 s\)\) is "
               r"still: no sensor turns more than 0\.\d+ deg")
    with pytest.raises(RecordingError, match=message):
        check_stretches(still, source="cal.csv")
    with pytest.raises(RecordingError, match=message):
        calibrate(still, source="cal.csv")


@pytest.fixture(scope="module")
def calibration_rec():
    import warnings

    from handsynth.sensors.imu import ImuHand, calibration_motion, simulate_imu

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return simulate_imu(calibration_motion(), hand=ImuHand(tip_sensors=True), seed=1,
                            device_seed=2)


def test_a_rotation_too_short_is_called_too_short_not_still(calibration_rec):
    # before: a rotation of a few samples was "still" (its bias hold was all of it)
    from handsynth.errors import EstimationError
    from handsynth.sensors.imu import calibrate
    from handsynth.sensors.imu._calibration import check_stretches

    segments = tuple((lab, a, a + 4) if lab == "index_pip_flex" else (lab, a, b)
                     for lab, a, b in calibration_rec.truth.segments)
    short = dataclasses.replace(calibration_rec, segments=segments)
    assert check_stretches(short) == []
    with pytest.warns(UserWarning, match="no static poses"), \
            pytest.raises(EstimationError, match=r"rotation 'index_pip_flex' spans 4 samples .*"
                                                 r"at least 5 are needed"):
        calibrate(short, source="cal.csv")


@pytest.mark.parametrize(("label", "on", "still"), [
    ("middle_mcp_abd", "index_mcp_abd", "middle_proximal"),
    ("wrist_dev", "index_mcp_flex", "hand_ulnar"),
    ("humeral_rot", "wrist_flex", "forearm_1"),
    ("thumb_cmc_abd", "thumb_mcp_flex", "thumb_metacarpal"),
])
def test_an_abduction_or_rotation_label_on_another_rotations_stretch_is_refused(
        calibration_rec, label, on, still):
    # before: only flexion labels were checked for the sensor their rotation must turn
    from handsynth.sensors.imu._calibration import check_stretches

    spans = {lab: (a, b) for lab, a, b in calibration_rec.truth.segments}
    segments = tuple((lab, *spans[on]) if lab == label else (lab, a, b)
                     for lab, a, b in calibration_rec.truth.segments)
    with pytest.raises(RecordingError, match=rf"segment '{label}' .* does not turn {still} "):
        check_stretches(dataclasses.replace(calibration_rec, segments=segments))
    assert check_stretches(calibration_rec) == []


def test_a_short_rotation_is_measured_without_its_bias_hold():
    from handsynth.sensors.imu._calibration import check_stretches

    rec = _still_then_turning()  # turning from sample 500, 1 rad/s peak
    assert check_stretches(dataclasses.replace(rec, segments=(("index_pip_flex", 520, 580),))) == []
    with pytest.raises(RecordingError, match="is still"):
        check_stretches(dataclasses.replace(rec, segments=(("index_pip_flex", 100, 160),)))


def test_a_still_stretch_that_moves_is_warned_about():
    from handsynth.sensors.imu._calibration import check_stretches

    rec = dataclasses.replace(_still_then_turning(), segments=(("static", 0, 200),
                                                               ("acc_pose_0", 600, 800)))
    (warning,) = check_stretches(rec)
    assert warning.startswith("segment 'acc_pose_0' (samples 600-799 (6.00-8.00 s)) should be "
                              "still, but the gyro of index_middle moves by")


def test_a_non_finite_calibration_value_is_refused_by_name_and_nothing_is_written(tmp_path,
                                                                                  ideal_rec):
    # before: json.dump wrote the bare token NaN, which strict JSON readers refuse and
    # load() refused only after the file was there
    from handsynth.errors import OutputError

    model = truth_chain_model(ideal_rec)
    sensor = next(iter(model.own))
    own = dict(model.own, **{sensor: np.array([0.01, np.nan, 0.0])})
    bad = ImuCalibration(dataclasses.replace(model, own=own), {s: np.eye(3) for s in model.own},
                         np.zeros(20), tuple(model.own))
    out = tmp_path / "c.json"
    with pytest.raises(OutputError, match=rf"field own_m\.{sensor}\[1\] is nan, .*nothing was "
                                          "written"):
        bad.save(out)
    assert list(tmp_path.iterdir()) == []
    zero = np.zeros(20)
    zero[3] = np.inf
    with pytest.raises(OutputError, match=r"field zero_deg\[3\] is inf"):
        dataclasses.replace(bad, model=model, zero=zero).save(out)
    assert list(tmp_path.iterdir()) == []


def test_the_calibration_file_is_written_whole_or_not_at_all(tmp_path, ideal_rec, monkeypatch):
    import os

    from handsynth import _io
    from handsynth.errors import OutputError

    model = truth_chain_model(ideal_rec)
    cal = ImuCalibration(model, {s: np.eye(3) for s in model.own}, np.zeros(20), tuple(model.own))
    out = cal.save(tmp_path / "c.json")
    before = out.read_bytes()
    json.loads(before, parse_constant=lambda token: pytest.fail(f"non-JSON token {token}"))

    def fail(src, dst):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(_io.os, "replace", fail)
    changed = dataclasses.replace(cal, zero=np.ones(20))
    with pytest.raises(OutputError, match="no space left"):
        changed.save(out)
    monkeypatch.setattr(_io.os, "replace", os.replace)
    assert out.read_bytes() == before and sorted(p.name for p in tmp_path.iterdir()) == ["c.json"]


def test_a_flexion_labelled_over_another_joints_rotation_is_refused():
    # index_pip_flex over the DIP's rotation (index_middle still, index_distal turning) was
    # accepted and gave an index MCP-PIP link of half a metre
    from handsynth.sensors.imu import ImuRecording
    from handsynth.sensors.imu._calibration import check_stretches

    rec = _still_then_turning()
    three = ImuRecording(rec.rate_hz, ("forearm_1", "index_middle", "index_distal"),
                         rec.acc[[0, 0, 1]], rec.gyr[[0, 0, 1]], rec.mag[[0, 0, 1]])
    assert check_stretches(dataclasses.replace(three, segments=(("index_dip_flex", 500, 1000),))) == []
    wrong = dataclasses.replace(three, segments=(("index_pip_flex", 500, 1000),))
    with pytest.raises(RecordingError, match=r"^segment 'index_pip_flex' \(samples 500-999 "
                                             r"\(5\.00-10\.00 s\)\) does not turn index_middle "
                                             r"\(0\.\d+ deg\), .* while index_distal turns"):
        check_stretches(wrong)


def test_a_sensor_mounted_upside_down_gets_the_same_link_frame(calibration_rec):
    # before: the sign of a link frame's flexion axis came from the sensor's own z axis,
    # so a sensor turned 180 deg about its x axis (z toward the palm) read every flexion of
    # its joint as 360 deg less the true angle (index PIP: 301 deg for 59; 13.5 deg mean
    # joint-angle error on a 20-s free motion against 0.25 with the sensor mounted as usual)
    from handsynth.sensors.imu import chain_model, link_frames

    flip = np.array([1.0, -1.0, -1.0])  # the sensor turned 180 deg about its x axis
    k = calibration_rec.sensors.index("index_middle")
    arrays = {}
    for name in ("acc", "gyr", "mag"):
        a = getattr(calibration_rec, name).copy()
        a[k] *= flip
        arrays[name] = a
    flipped = dataclasses.replace(calibration_rec, **arrays)
    frames = link_frames(calibration_rec, chain_model(calibration_rec))
    frames_flipped = link_frames(flipped, chain_model(flipped))
    # the same link frame, seen from the turned sensor
    np.testing.assert_allclose(frames_flipped["index_middle"], frames["index_middle"] * flip,
                               atol=1e-6)
    np.testing.assert_allclose(frames_flipped["index_proximal"], frames["index_proximal"],
                               atol=1e-9)


def test_the_ring_little_side_of_the_hand_is_not_turned_over_where_its_vector_is_short():
    # one simulated device (seed 2) estimated hand_ulnar's height above the wrist's axis at
    # -4 mm (18-27 mm on the others): the link frame's side came from that sign alone, the
    # frame came out turned over, the zero pose read ring MCP -170.5 deg, and tracking wrote
    # ring MCP abduction 359 deg for -1 (4.7 deg RMSE once wrapped, against 0.4)
    import warnings

    from handsynth.models import JOINT_NAMES
    from handsynth.sensors.imu import ImuHand, calibrate, calibration_motion, free_motion, simulate_imu

    hand = ImuHand(tip_sensors=True)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        cal = calibrate(simulate_imu(calibration_motion(), hand=hand, seed=1, device_seed=2))
        rec = simulate_imu(free_motion(8.0, seed=4), hand=hand, seed=5, device_seed=2)
    assert np.abs(cal.zero).max() < 20.0
    got = cal.track(rec)["angles"]
    truth = rec.truth.angles[:, 9:]
    for joint in ("ring_mcp_abd", "little_mcp_abd", "ring_mcp_flex", "little_mcp_flex"):
        j = JOINT_NAMES.index(joint)
        assert np.abs(got[:, j]).max() < 90.0, joint
        assert np.sqrt(np.mean((got[:, j] - truth[:, j]) ** 2)) < 1.5, joint


def test_link_frames_half_a_turn_apart_are_refused_at_calibration(calibration_rec):
    from handsynth.sensors.imu import chain_model, link_frames, zero_offsets

    frames = link_frames(calibration_rec, chain_model(calibration_rec))
    frames["ring_proximal"] = frames["ring_proximal"] * np.array([[-1.0], [1.0], [-1.0]])
    with pytest.raises(EstimationError, match=r"ring_mcp_flex reads -?1\d\d\.\d deg, not about 0 .*"
                                              r"hand_ulnar and ring_proximal disagree by about "
                                              r"half a turn"):
        zero_offsets(calibration_rec, frames)


def test_a_calibration_without_the_fingertip_sensors_says_so():
    # before: "no sensor 'thumb_tip' in the recording" from deep inside the vector estimate
    import warnings

    from handsynth.sensors.imu import ImuHand, calibrate, calibration_motion, simulate_imu

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        rec = simulate_imu(calibration_motion(), hand=ImuHand(), seed=1)
    # said first: a recording without static poses is read uncorrected
    with pytest.warns(UserWarning, match=r"^cal.csv: no static poses labelled acc_pose_<k>: the "
                                         r"accelerometers and gyros are used uncorrected: .* "
                                         r"12 of 18 such calibrations were refused"), \
            pytest.raises(RecordingError, match=r"^cal.csv: the calibration needs the five "
                                                r"temporary fingertip sensors \(thumb_tip, "
                                                r".*little_tip\) .*missing thumb_tip, index_tip"):
        calibrate(rec, source="cal.csv")


@pytest.mark.slow
def test_a_refused_calibration_without_static_poses_names_the_uncorrected_sensors():
    """Held-out sensors (scale and axes off by a few per cent), the thesis' protocol without
    static poses: the link frames come out half a turn apart, and the refusal says that the
    uncorrected readings are the likelier cause than a hand that moved."""
    import dataclasses
    import warnings

    from handsynth.errors import EstimationError
    from handsynth.sensors.imu import HELDOUT, calibrate
    from handsynth.sensors.imu._eval import _calibration_recording

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the still-start notes
        rec = _calibration_recording(dataclasses.replace(HELDOUT, seed=2), acc_poses=False)
    with pytest.warns(UserWarning, match="no static poses"), \
            pytest.raises(EstimationError, match=r"^cal.csv: at the calibration's static start "
                                                 r".* reads .* deg, not about 0 .*; or, more likely "
                                                 r"here, the accelerometers and gyros are used "
                                                 r"uncorrected"):
        calibrate(rec, source="cal.csv")


@pytest.mark.slow
def test_calibration_rotations_too_small_are_warned_about(calibration_rec):
    # rotations a third as large as the default gave vectors 3-5 mm off and fingertips
    # 10-24 mm from the elbow, without a word
    import warnings

    from handsynth.sensors.imu import CALIBRATION_PLAN, ImuHand, calibrate, calibration_motion, simulate_imu

    def recording(scale):
        plan = tuple((label, joints, scale * amp, freq) for label, joints, amp, freq in CALIBRATION_PLAN)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            return simulate_imu(calibration_motion(plan=plan, acc_poses=True),
                                hand=ImuHand(tip_sensors=True), seed=1, device_seed=2)

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        calibrate(recording(1.0))
        calibrate(calibration_rec)  # without the static poses: not judged
    assert not [w for w in caught if "fit the calibration rotations poorly" in str(w.message)]
    rec = recording(0.3)
    with pytest.warns(UserWarning, match=r"^cal.csv: the sensor-to-joint vectors fit the calibration "
                                         r"rotations poorly: a quarter of the \d+ have R\^2 0\.[0-7]"):
        calibrate(rec, source="cal.csv")


@pytest.mark.slow
def test_a_sensor_calibration_fitted_already_is_applied_as_given():
    """``handsynth imu calibrate`` fits the static poses' sensor calibration first (to judge
    the magnetometers with it); handed to ``calibrate`` it gives what fitting there gives."""
    import warnings

    from handsynth.errors import InvalidInputError
    from handsynth.sensors.imu import (
        ImuHand,
        calibrate,
        calibration_motion,
        fit_sensor_calibration,
        simulate_imu,
    )

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        rec = simulate_imu(calibration_motion(acc_poses=True), hand=ImuHand(tip_sensors=True),
                           seed=3, device_seed=4)
    fitted = calibrate(rec)
    given = calibrate(rec, sensor_calibration=fit_sensor_calibration(rec))
    assert given.sensor_calibration is not None
    np.testing.assert_array_equal(given.sensor_calibration.acc_matrix,
                                  fitted.sensor_calibration.acc_matrix)
    for key, link in fitted.model.links.items():
        np.testing.assert_array_equal(given.model.links[key], link)
    np.testing.assert_array_equal(given.zero, fitted.zero)
    with pytest.raises(InvalidInputError, match="sensor_calibration must be True, False or a "
                                                "SensorCalibration, got str"):
        calibrate(rec, sensor_calibration="yes")
