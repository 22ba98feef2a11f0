import h5py
import numpy as np
import pytest
from scipy.io import savemat

from handsynth.errors import RecordingError
from handsynth.sensors.imu import broad_errors, find_broad_trials, read_broad_trial
from handsynth.sensors.imu._quat import qexp, qmul


def _fields(n=500):
    rng = np.random.default_rng(0)
    q = np.tile([1.0, 0, 0, 0], (n, 1))
    return dict(imu_acc=np.tile([0, 0, 9.81], (n, 1)) + rng.normal(0, 0.01, (n, 3)),
                imu_gyr=rng.normal(0, 0.001, (n, 3)), imu_mag=np.tile([0, 20.0, -40.0], (n, 1)),
                opt_quat=q, movement=np.r_[np.zeros(100), np.ones(n - 100)].astype(np.uint8)[:, None],
                sampling_rate=np.array([[200.0]]))


def test_read_mat_trial(tmp_path):
    savemat(tmp_path / "05_test.mat", _fields())
    rec, opt, movement = read_broad_trial(tmp_path / "05_test.mat")
    assert opt.shape == (500, 4)
    assert rec.rate_hz == 200.0 and rec.sensors == ("05_test",) and movement.sum() == 400
    assert [p.name for p in find_broad_trials(tmp_path)] == ["05_test.mat"]


def test_read_hdf5_trial_with_the_rate_as_an_attribute(tmp_path):
    """The dataset's HDF5 files keep the sampling rate as a file attribute."""
    fields = _fields()
    with h5py.File(tmp_path / "06_test.hdf5", "w") as f:
        for k, v in fields.items():
            if k == "sampling_rate":
                f.attrs[k] = 285.7142857142857
            else:
                f[k] = np.asarray(v).reshape(500, -1).squeeze() if k == "movement" else v
    rec, opt, movement = read_broad_trial(tmp_path / "06_test.hdf5")
    savemat(tmp_path / "06_test.mat", fields)
    mat_rec, mat_opt, mat_movement = read_broad_trial(tmp_path / "06_test.mat")
    assert rec.rate_hz == pytest.approx(285.7142857142857)
    np.testing.assert_array_equal(rec.gyr, mat_rec.gyr)
    np.testing.assert_array_equal(opt, mat_opt)
    np.testing.assert_array_equal(movement, mat_movement)
    with h5py.File(tmp_path / "07_norate.hdf5", "w") as f:
        for k in ("imu_acc", "imu_gyr", "imu_mag", "opt_quat", "movement"):
            f[k] = fields[k]
    with pytest.raises(RecordingError, match="07_norate.hdf5: missing BROAD field.s. sampling_rate"):
        read_broad_trial(tmp_path / "07_norate.hdf5")


def test_metric_splits_heading_and_inclination():
    n = 50
    opt = np.tile([1.0, 0, 0, 0], (n, 1))
    move = np.ones(n, bool)
    e = broad_errors(qmul(qexp([0, 0, np.radians(4)]), opt), opt, move)
    assert e["total_rmse_deg"] == pytest.approx(4) and e["heading_rmse_deg"] == pytest.approx(4)
    assert e["inclination_rmse_deg"] == pytest.approx(0, abs=1e-6)
    opt_nan = opt.copy()
    opt_nan[:10] = np.nan  # lost markers are left out
    assert np.isfinite(broad_errors(opt, opt_nan, move)["total_rmse_deg"])


def test_bad_trials_are_named(tmp_path):
    f = _fields()
    f["imu_gyr"][7, 1] = np.nan
    savemat(tmp_path / "01_nan.mat", f)
    with pytest.raises(RecordingError, match="01_nan.mat: field imu_gyr is not finite at sample 7"):
        read_broad_trial(tmp_path / "01_nan.mat")
    f = _fields()
    f["movement"][:] = 0
    savemat(tmp_path / "02_still.mat", f)
    with pytest.raises(RecordingError, match="movement marks no sample"):
        read_broad_trial(tmp_path / "02_still.mat")
    (tmp_path / "03_junk.mat").write_text("junk")
    with pytest.raises(RecordingError, match="03_junk.mat: not a readable .mat file"):
        read_broad_trial(tmp_path / "03_junk.mat")
    with pytest.raises(RecordingError, match="not a directory"):
        find_broad_trials(tmp_path / "missing")
    (tmp_path / "empty").mkdir()
    with pytest.raises(RecordingError, match="no BROAD trial files"):
        find_broad_trials(tmp_path / "empty")


@pytest.mark.parametrize(("rate", "message"), [
    ("two hundred", "field sampling_rate is 'two hundred', not a number"),
    (np.zeros((0, 0)), "field sampling_rate must be one number (Hz), got 0 values"),
    (np.array([[0.0]]), "field sampling_rate is 0.0; expected a finite number > 0"),
])
def test_bad_sampling_rate_is_named(tmp_path, rate, message):
    f = _fields()
    f["sampling_rate"] = rate
    savemat(tmp_path / "01_rate.mat", f)
    with pytest.raises(RecordingError) as info:
        read_broad_trial(tmp_path / "01_rate.mat")
    assert "01_rate.mat: " in str(info.value) and message in str(info.value)


def test_bad_hdf5_layouts_are_named(tmp_path):
    fields = _fields()
    with h5py.File(tmp_path / "01_text.hdf5", "w") as f:
        for k, v in fields.items():
            if k == "sampling_rate":
                f.attrs[k] = "100 Hz"
            else:
                f[k] = v
    with pytest.raises(RecordingError, match="01_text.hdf5: field sampling_rate is '100 Hz', not a"):
        read_broad_trial(tmp_path / "01_text.hdf5")
    with h5py.File(tmp_path / "02_group.hdf5", "w") as f:
        for k, v in fields.items():
            if k == "imu_acc":
                f.create_group(k)["data"] = v
            else:
                f[k] = v
    with pytest.raises(RecordingError, match="02_group.hdf5: field imu_acc is an HDF5 group, not a"):
        read_broad_trial(tmp_path / "02_group.hdf5")


def test_transposed_field_gives_the_expected_shape(tmp_path):
    f = _fields()
    f["imu_gyr"] = f["imu_gyr"].T
    savemat(tmp_path / "01_t.mat", f)
    with pytest.raises(RecordingError, match=r"field imu_gyr has shape \(3, 500\), expected "
                                             r"\(N, 3\) with N = 500 samples \(stored transposed\?\)"):
        read_broad_trial(tmp_path / "01_t.mat")


def test_run_broad_skips_a_trial_without_reference_and_checks_content(tmp_path):
    import json
    import warnings

    from handsynth.sensors.imu import run_broad

    good = _fields()
    good["imu_gyr"][150:] += 0.3  # some motion
    savemat(tmp_path / "01_good.mat", good)
    f = _fields()
    f["opt_quat"] = f["opt_quat"].copy()
    f["opt_quat"][100:] = np.nan
    savemat(tmp_path / "02_noref.mat", f)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        res = run_broad(tmp_path, filters=("constant", "raw"))
    assert list(res["trials"]) == ["01_good"]
    assert any("02_noref.mat: the reference opt_quat is NaN over the whole movement phase"
               in str(w.message) for w in caught)
    json.dumps(res, allow_nan=False)  # no NaN anywhere
    f = _fields()
    f["imu_gyr"] = np.degrees(f["imu_gyr"]) + 5.0  # deg/s stored under a rad/s field
    savemat(tmp_path / "03_deg.mat", f)
    with pytest.raises(RecordingError, match="03_deg.mat: sensor '03_deg' gyro reads .* deg/s "
                                             "given as rad/s"), pytest.warns(UserWarning):
        run_broad(tmp_path, filters=("constant",))
    (tmp_path / "03_deg.mat").unlink()
    f = _fields()
    f["imu_mag"][:] = 0.0
    savemat(tmp_path / "04_nomag.mat", f)
    with pytest.raises(RecordingError, match="04_nomag.mat: the magnetometers read zero field"), \
            pytest.warns(UserWarning):
        run_broad(tmp_path, filters=("constant",))
