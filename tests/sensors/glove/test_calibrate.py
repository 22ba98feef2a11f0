import json
import re
import warnings

import numpy as np
import pytest

from handsynth.errors import EstimationError, InvalidInputError, OutputError
from handsynth.sensors.glove import (
    SENSOR_NAMES,
    CalibrationOptions,
    GloveRecording,
    GloveWarning,
    calibrate,
    load_calibration,
    save_calibration,
)


def _with(rec, sensors):
    return GloveRecording(sensors=sensors, angles=rec.angles, motion=rec.motion,
                          trial=rec.trial, time_s=rec.time_s, kind=rec.kind,
                          adc_max=rec.adc_max)


def test_dead_sensor_refuses_calibration(cal_rec):
    s = cal_rec.sensors.copy()
    s[:, 3] = 1777.0
    with pytest.raises(EstimationError, match=r"sensor_ring is dead \(it reads 1777 counts"):
        calibrate(_with(cal_rec, s), where="cal.csv")


def test_nan_and_saturated_rows_are_dropped_with_warnings(cal_rec):
    s = cal_rec.sensors.copy()
    s[[10, 20, 30], 0] = np.nan
    s[100:140, 2] = cal_rec.adc_max
    with warnings.catch_warnings(record=True) as got:
        warnings.simplefilter("always")
        est = calibrate(_with(cal_rec, s), where="cal.csv",
                        options=CalibrationOptions(synergy_k=0))
    msgs = " | ".join(str(w.message) for w in got if issubclass(w.category, GloveWarning))
    assert "cal.csv: dropped 3 of" in msgs and "first at row indices 10, 20, 30" in msgs
    assert "dropped 40 of" in msgs and "sensor_middle saturated (at 4095 counts) in 40" in msgs
    assert "synergy" not in est


def test_too_few_samples_warn_with_t_values(cal_rec):
    keep = np.zeros(cal_rec.n_samples, dtype=bool)
    for m in set(cal_rec.motion):
        idx = np.flatnonzero((cal_rec.motion == m) & (cal_rec.trial == 0))
        keep[idx[::6]] = True                       # ~35 samples per motion
    with warnings.catch_warnings(record=True) as got:
        warnings.simplefilter("always")
        calibrate(cal_rec.select(keep), options=CalibrationOptions(n_points=4, synergy_k=0))
    msgs = [str(w.message) for w in got if issubclass(w.category, GloveWarning)
            and "calibration samples" in str(w.message)]
    assert len(msgs) == 3                            # one per motion, not one per model
    std = next(m for m in msgs if "'standard'" in m)
    assert re.match(r"calibration: motion 'standard' \(model2\): only \d+ calibration "
                    r"samples for up to 6 coefficients", std)
    assert re.search(r"index_mcp_flex: sensor_thumb\^1 t=-?\d+\.\d\d, sensor_index\^1 t=",
                     std)


def test_no_reference_angles_or_motions_raise(cal_rec):
    bare = GloveRecording(sensors=cal_rec.sensors, kind="dg5")
    with pytest.raises(EstimationError, match="no reference joint angles"):
        calibrate(bare)
    unl = GloveRecording(sensors=cal_rec.sensors, angles=cal_rec.angles, kind="dg5")
    with pytest.raises(EstimationError, match="no rows labelled with a motion"):
        calibrate(unl)


def test_options_are_checked():
    with pytest.raises(InvalidInputError, match="model7"):
        CalibrationOptions(models=("model7",))
    with pytest.raises(TypeError):
        CalibrationOptions(t_treshold=2.0)


def test_file_round_trip_and_bad_files(tmp_path, estimators, cal_rec):
    path = save_calibration(tmp_path / "cal.json", estimators, kind="dg5",
                            range_reference=(np.zeros(5), np.ones(5)))
    cal = load_calibration(path)
    assert cal["kind"] == "dg5" and set(cal["estimators"]) == set(estimators)
    s = cal_rec.sensors[::40]
    np.testing.assert_allclose(cal["estimators"]["model4"].predict(s),
                               estimators["model4"].predict(s))
    np.testing.assert_allclose(cal["range_reference"][1], np.ones(5))
    bad = tmp_path / "bad.json"
    bad.write_text("{not json")
    with pytest.raises(InvalidInputError, match="bad.json: not a calibration file"):
        load_calibration(bad)
    bad.write_text(json.dumps({"format": "something else"}))
    with pytest.raises(InvalidInputError, match="not a handsynth glove calibration"):
        load_calibration(bad)
    with pytest.raises(InvalidInputError, match="no such file"):
        load_calibration(tmp_path / "missing.json")


def test_failed_write_leaves_no_file(tmp_path, monkeypatch, estimators):
    import handsynth._io as io_mod

    def boom(*a, **k):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(io_mod.os, "fsync", boom)  # the write fails in the atomic writer
    with pytest.raises(OutputError, match="cannot write the glove calibration .*no space left"):
        save_calibration(tmp_path / "cal.json", estimators)
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("field, value, msg", [
    ("pooled", "no", "pooled must be True or False, got 'no'"),
    ("pooled", 0, "pooled must be True or False, got 0"),
    ("models", "model4", "models must be a tuple of model names"),
    ("n_points", 2.5, r"n_points must be an integer >= 1 and <= 200, got 2.5"),
    ("n_points", 0, r"n_points must be an integer >= 1 and <= 200, got 0"),
    # before: a 56 GiB allocation and a traceback
    ("n_points", 100_000_000, r"n_points must be an integer >= 1 and <= 200, got 100000000"),
    ("synergy_k", True, r"synergy_k must be an integer >= 0 and <= 20, got True"),
    ("synergy_k", 21, r"synergy_k must be an integer >= 0 and <= 20, got 21"),
    ("t_threshold", "2", "t_threshold must be a finite number, got '2'"),
    ("ridge", float("nan"), "ridge must be a finite number, got nan"),
])
def test_option_types_and_ranges_are_checked(field, value, msg):
    # pooled='no' (a truthy string) used to fit pooled_model4
    with pytest.raises(InvalidInputError, match=f"CalibrationOptions.{msg}"):
        CalibrationOptions(**{field: value})
    assert CalibrationOptions(models=["model4"]).models == ("model4",)


def test_calibrate_checks_its_arguments(cal_rec):
    with pytest.raises(InvalidInputError, match="options must be a CalibrationOptions, got dict"):
        calibrate(cal_rec, options={"pooled": False})
    with pytest.raises(InvalidInputError, match="rec must be a GloveRecording, got ndarray"):
        calibrate(cal_rec.sensors)


def test_the_reading_range_is_that_of_the_samples_kept(cal_rec, estimators):
    low_high = np.stack([cal_rec.sensors.min(axis=0), cal_rec.sensors.max(axis=0)])
    for est in estimators.values():
        np.testing.assert_array_equal(est.reading_range, low_high)
    sensors = cal_rec.sensors.copy()
    sensors[5, 0] = cal_rec.adc_max          # a saturated sample is dropped, not the range's end
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", GloveWarning)
        est = calibrate(_with(cal_rec, sensors), options=CalibrationOptions(synergy_k=0))
    assert est["model1"].reading_range[1, 0] == low_high[1, 0]


def test_the_range_travels_with_the_file_and_older_files_take_it_from_meta(
        tmp_path, estimators, cal_rec):
    path = save_calibration(tmp_path / "cal.json", estimators, kind="dg5")
    cal = load_calibration(path)
    for name, est in cal["estimators"].items():
        np.testing.assert_array_equal(est.reading_range, estimators[name].reading_range)
    d = json.loads(path.read_text())
    for entry in d["estimators"].values():          # an older file: the range in meta only
        entry.pop("reading_range")
    old = tmp_path / "old.json"
    old.write_text(json.dumps(d))
    assert all(e.reading_range is None for e in load_calibration(old)["estimators"].values())
    d["meta"] = {"sensor_min": [0.0] * 5, "sensor_max": [10.0] * 5}
    old.write_text(json.dumps(d))
    for est in load_calibration(old)["estimators"].values():
        np.testing.assert_array_equal(est.reading_range, [[0.0] * 5, [10.0] * 5])
    with pytest.warns(GloveWarning) as got:
        load_calibration(old)["estimators"]["model4"].predict(cal_rec.sensors[:20])
    assert [str(w.message).split(" (read there")[0] for w in got] == [
        f"model4: 100 % of the {s} readings lie off the calibration's range 0-10 counts"
        for s in SENSOR_NAMES]


def test_a_damaged_estimator_entry_is_named_not_blamed_on_the_range_reference(tmp_path, cal_rec):
    # before, a field missing inside an estimator read "field 'range_reference' lacks ..."
    import json

    from handsynth.sensors.glove import load_calibration, save_calibration

    path = save_calibration(tmp_path / "c.json", calibrate(cal_rec), kind="dg5")
    d = json.loads(path.read_text())
    name = next(iter(d["estimators"]))
    del d["estimators"][name]["type"]
    path.write_text(json.dumps(d))
    with pytest.raises(InvalidInputError, match=rf"c\.json: estimator '{name}'"):
        load_calibration(path)


def test_a_zero_reading_scale_in_a_calibration_file_is_refused(tmp_path, cal_rec):
    # before: every estimate NaN, with numpy's "divide by zero" as the only word
    import json

    from handsynth.sensors.glove import load_calibration, save_calibration

    path = save_calibration(tmp_path / "c.json", calibrate(cal_rec), kind="dg5")
    d = json.loads(path.read_text())
    hit = [n for n, e in d["estimators"].items() if isinstance(e.get("mixer"), dict)]
    assert hit
    d["estimators"][hit[0]]["mixer"]["scale"] = [0.0] * 5
    path.write_text(json.dumps(d))
    with pytest.raises(InvalidInputError, match=rf"estimator '{hit[0]}': field 'scale' must be positive"):
        load_calibration(path)


def test_an_all_saturated_recording_says_so(cal_rec):
    # every row dropped for saturation; the error said "no samples labelled with a motion"
    sensors = np.full_like(cal_rec.sensors, cal_rec.adc_max)
    with pytest.raises(EstimationError) as got:
        calibrate(_with(cal_rec, sensors), where="cal.csv")
    msg = str(got.value)
    assert "labelled" not in msg and "dead" not in msg, msg
    n = cal_rec.n_samples
    assert msg.startswith(f"cal.csv: no row is left to calibrate on: of the {n} rows, {n} have "
                          "a saturated reading")
    for name in SENSOR_NAMES:
        assert f"{name} saturated (at 4095 counts) in {n} rows" in msg, msg


def test_readings_above_the_full_scale_ask_for_it(cal_rec):
    rec = GloveRecording(sensors=cal_rec.sensors, angles=cal_rec.angles, motion=cal_rec.motion,
                         trial=cal_rec.trial, time_s=cal_rec.time_s, kind="dg5", adc_max=1.0)
    with pytest.raises(EstimationError, match=r"sensor_thumb above the full scale 1 counts .*"
                                              r"is the full scale \(--adc-max\) right\?"):
        calibrate(rec, where="cal.csv")


def test_negative_readings_are_dropped_as_below_range(cal_rec):
    s = cal_rec.sensors.copy()
    s[100:110, 1] = -4.0
    with warnings.catch_warnings(record=True) as got:
        warnings.simplefilter("always")
        calibrate(_with(cal_rec, s), where="cal.csv", options=CalibrationOptions(synergy_k=0))
    msgs = " | ".join(str(w.message) for w in got if issubclass(w.category, GloveWarning))
    assert "dropped 10 of" in msgs and "sensor_index below the converter's range (negative, " \
        "down to -4 counts) in 10 rows" in msgs, msgs
    assert "saturated" not in msgs, msgs


def _holds(open_, fist, n=20, adc_max=4095.0):
    sensors = np.vstack([np.tile(open_, (n, 1)), np.tile(fist, (n, 1))]).astype(float)
    sensors[:, :] += np.arange(2 * n)[:, None] % 3       # a count or two of noise
    sensors = np.minimum(sensors, adc_max)
    return GloveRecording(sensors=sensors, motion=["range_open"] * n + ["range_fist"] * n,
                          trial=[0] * n + [1] * n, adc_max=adc_max)


def test_saturated_range_holds_are_named():
    from handsynth.errors import RecordingError
    from handsynth.sensors.glove import range_readings

    open_, fist = np.full(5, 1500.0), np.full(5, 2500.0)
    fist[2] = 4095.0                                     # the middle sensor saturates in a fist
    with pytest.raises(RecordingError, match=r"range.csv: sensor_middle is saturated \(at 4095 "
                                             r"counts\) in 20 of the 20 rows labelled "
                                             r"range_fist: its reading in that hold is not known"):
        range_readings(_holds(open_, fist), where="range.csv")
    open_[0] = -20.0                                     # below the range: not "saturated"
    with pytest.raises(RecordingError, match=r"sensor_thumb is below the converter's range "
                                             r"\(negative, down to -20 counts\) in 20 of the 20 "
                                             r"rows labelled range_open"):
        range_readings(_holds(open_, np.full(5, 2500.0)), where="range.csv")


def test_a_partly_saturated_range_hold_is_warned_about():
    from handsynth.sensors.glove import range_readings

    rec = _holds(np.full(5, 1500.0), np.full(5, 4093.0))  # 4093 + noise: some at 4095
    with pytest.warns(GloveWarning) as caught:  # one warning per saturated sensor
        _, fist = range_readings(rec, where="range.csv")
    assert any(re.match(r"range.csv: sensor_thumb is saturated \(at 4095 counts\) in \d of the 20 "
                        r"rows labelled range_fist", str(w.message)) for w in caught)
    assert (fist >= 4093).all()


def test_a_failed_fit_names_the_recording(cal_rec):
    # "motion 'standard' (model1), thumb_mcp_flex: the regressors are collinear", no file
    tiny = cal_rec.select(np.arange(cal_rec.n_samples) < 5)
    with pytest.raises(EstimationError, match=r"^cal.csv: motion 'standard'"):
        calibrate(tiny, where="cal.csv", options=CalibrationOptions(synergy_k=0))


def test_a_t_threshold_that_keeps_no_sensor_is_warned_about(cal_rec):
    with pytest.warns(GloveWarning) as caught:  # and the t-values of the fits
        calibrate(cal_rec, where="cal.csv",
                  options=CalibrationOptions(t_threshold=1e6, synergy_k=0, pooled=False))
    assert any(re.match(r"cal.csv: model4 keeps no sensor \(every \|t\| < 1e\+06, the t "
                        r"threshold\) in 15 of 15 joint-3 fits", str(w.message)) for w in caught)


def test_drift_of_the_readings_over_the_calibration_is_warned_about(cal_rec):
    # an offset creeping by 150 counts over the recording was fitted as posture, unsaid
    from dataclasses import replace

    ramp = np.linspace(0.0, 150.0, cal_rec.n_samples)[:, None]
    drifting = replace(cal_rec, sensors=cal_rec.sensors + ramp)
    opts = CalibrationOptions(models=("model1",), pooled=False, synergy_k=0)
    with pytest.warns(GloveWarning, match=r"rec.csv: the open-hand reading at the start of the "
                                          r"trials creeps over the \d+ s of the recording "
                                          r"\(sensor_thumb \+\d+ counts"):
        calibrate(drifting, options=opts, where="rec.csv")
    # none without the drift, also with each motion's trials one after the other (a short
    # stretch of a long recording, where the trials' own spread looked like a trend)
    order = sorted(range(cal_rec.n_samples), key=lambda i: (cal_rec.motion[i], cal_rec.trial[i]))
    grouped = replace(cal_rec, sensors=cal_rec.sensors[order], angles=cal_rec.angles[order],
                      motion=cal_rec.motion[order], trial=cal_rec.trial[order],
                      truth=None, time_s=np.arange(cal_rec.n_samples) / 60.0)
    with warnings.catch_warnings():
        warnings.simplefilter("error", GloveWarning)
        calibrate(cal_rec, options=opts)
        calibrate(grouped, options=opts)
