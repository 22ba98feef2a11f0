
import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from handsynth.errors import RecordingError
from handsynth.sensors.trackers import (
    PlaneVarianceEstimator,
    load_recording,
    read_polhemus,
    read_recording,
    save_recording,
)


def _export(rec, path, *, units="cm", quaternion=False, drop=(), nan=()):
    scale = {"cm": 100.0, "in": 1 / 0.0254}[units]
    lines = ["Sensor X Y Z Az El Ro"]
    for i in range(rec.n_frames):
        for s in (0, 1):
            if (i, s) in drop:
                continue
            p = rec.positions[i, s] * scale
            r = Rotation.from_matrix(rec.rotations[i, s])
            a = r.as_quat()[[3, 0, 1, 2]] if quaternion else r.as_euler("ZYX", degrees=True)
            vals = [*p, *a]
            if (i, s) in nan:
                vals[0] = float("nan")
            lines.append(f"{s + 1} " + " ".join(f"{v:.6f}" for v in vals))
    path.write_text("\n".join(lines) + "\n")
    return path


def test_hdf5_roundtrip_is_exact(tmp_path, finger_rec):
    p = save_recording(tmp_path / "rec.h5", finger_rec)
    back = load_recording(p)
    np.testing.assert_array_equal(back.rotations, finger_rec.rotations)
    np.testing.assert_array_equal(back.truth.reference_centre, finger_rec.truth.reference_centre)
    assert back.labels == finger_rec.labels and back.metadata["seed"] == 3
    assert [f.name for f in tmp_path.iterdir()] == ["rec.h5"]  # no temp file left


def test_hdf5_errors(tmp_path):
    bad = tmp_path / "x.h5"
    bad.write_bytes(b"not hdf5")
    with pytest.raises(RecordingError, match="HDF5"):
        load_recording(bad)
    with pytest.raises(RecordingError, match="cannot open"):
        load_recording(tmp_path / "missing.h5")


@pytest.mark.parametrize("units,quaternion", [("cm", False), ("in", True)])
def test_polhemus_text_matches_recording(tmp_path, finger_rec, units, quaternion):
    path = _export(finger_rec, tmp_path / "rec.txt", units=units, quaternion=quaternion)
    rec = read_recording(path, units=units, angles="quaternion" if quaternion else "euler")
    np.testing.assert_allclose(rec.positions, finger_rec.positions, atol=2e-7)
    np.testing.assert_allclose(rec.rotations, finger_rec.rotations, atol=1e-5)
    a = PlaneVarianceEstimator().estimate(rec).centre_upper
    b = PlaneVarianceEstimator().estimate(finger_rec).centre_upper
    np.testing.assert_allclose(a, b, atol=1e-5)


def test_missing_and_nan_rows_are_named(tmp_path, finger_rec):
    path = _export(finger_rec, tmp_path / "rec.txt", drop={(5, 1)}, nan={(9, 0)})
    with pytest.raises(RecordingError, match=r"1 half frames.*1 frames with NaN.*lines \[\d+\]"):
        read_polhemus(path, on_invalid="raise")
    with pytest.warns(UserWarning, match="dropped"):
        rec = read_polhemus(path)
    assert rec.n_frames == finger_rec.n_frames - 2


def test_unparseable_and_wrong_format_files(tmp_path, finger_rec):
    junk = tmp_path / "junk.txt"
    junk.write_text("hello world\nthis is not a recording\n")
    with pytest.raises(RecordingError, match="no data line"):
        read_polhemus(junk)
    garbled = tmp_path / "garbled.txt"
    garbled.write_text("\n".join(["1 1 2 3 4 5 6"] * 50 + ["1 1 2 3 x y z"] * 10) + "\n")
    with pytest.raises(RecordingError, match="10 of 60 lines cannot be read"):
        read_polhemus(garbled)
    # Euler angles read as quaternions: the norm check says so
    path = _export(finger_rec, tmp_path / "rec.txt")
    path.write_text("\n".join(line + " 0.5" for line in path.read_text().splitlines()) + "\n")
    with pytest.raises(RecordingError, match="8 columns that are neither"):
        read_polhemus(path, angles="quaternion")


def _patch(path, fn):
    import h5py

    with h5py.File(path, "r+") as f:
        fn(f)
    return path


def test_hdf5_damage_is_refused(tmp_path, finger_rec):
    import h5py

    ok = save_recording(tmp_path / "ok.h5", finger_rec)
    with h5py.File(ok, "r") as f:
        assert str(f.attrs["checksum"]).startswith("sha256:")

    def flip_exponent_bit(f):
        a = f["positions"][()]
        raw = a.view(np.uint64)
        raw[5, 1, 2] ^= np.uint64(1) << np.uint64(60)  # an exponent bit
        f["positions"][...] = raw.view(np.float64)

    cases = {
        "bit": (flip_exponent_bit, "checksum"),
        "meta": (lambda f: f.attrs.__setitem__("metadata", "{not json"), "not JSON"),
        "bytes": (lambda f: f.attrs.__setitem__("joint", np.void(b"\x01\x02")), "not text"),
        "labels": (lambda f: f.attrs.__setitem__("labels", '["only one"]'), "labels"),
        "missing": (lambda f: f.__delitem__("rotations"), "damaged or incomplete"),
        "incomplete": (lambda f: f.attrs.__delitem__("complete"), "incomplete"),
        "version": (lambda f: f.attrs.__setitem__("version", "2"), "version"),
    }
    for name, (fn, msg) in cases.items():
        path = save_recording(tmp_path / f"{name}.h5", finger_rec)
        with pytest.raises(RecordingError, match=msg):
            load_recording(_patch(path, fn))


def test_hdf5_version_1_is_read_with_a_warning(tmp_path, finger_rec):
    def v1(f):
        f.attrs["version"] = 1
        f.attrs["labels"] = [b"index_middle", b"index_distal"]
        del f.attrs["checksum"]

    path = _patch(save_recording(tmp_path / "v1.h5", finger_rec), v1)
    with pytest.warns(UserWarning, match="no checksum"):
        rec = load_recording(path)
    assert rec.labels == ("index_middle", "index_distal")


def test_hdf5_of_another_kind_is_named_not_called_damaged(tmp_path):
    # item 19: the message was wrapped twice and said "damaged or incomplete"
    import h5py

    path = tmp_path / "h_other.h5"
    with h5py.File(path, "w") as f:
        f["x"] = [1.0, 2.0]
    with pytest.raises(RecordingError) as err:
        load_recording(path)
    assert str(err.value) == f"{str(path)!r} is not a handsynth recording (format=None)"
