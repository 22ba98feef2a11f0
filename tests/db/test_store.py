import os
import re
import shutil

import h5py
import numpy as np
import pytest

from handsynth.db import (
    KEYPOINT_SCALE_M,
    Database,
    extract_features_batch,
    open_database,
    verify,
    write_database,
)
from handsynth.errors import (
    DatabaseCorruptError,
    DatabaseError,
    DatabaseMismatchError,
    InvalidInputError,
)
from handsynth.models import JOINT_LIMITS_DEG

META = {
    "shape": {"r_length": 1.05, "r_width": 0.9, "r_palm": 1.0, "r_thumb": 1.1},
    "camera": {"distance_mm": 120.0, "fov_deg": 90.0},
    "pose_set": "paper-20448",
    "seed": 7,
    "handsynth_version": "0.1.0",
}


@pytest.fixture(scope="module")
def arrays(shapes):
    names = sorted(shapes)
    sils = np.stack([shapes[n] for n in names] * 3)
    n = len(sils)
    feats = extract_features_batch(sils)
    rng = np.random.default_rng(0)
    return {
        # within the joint limits, 1 degree clear of them
        "angles": rng.uniform(JOINT_LIMITS_DEG[:, 0] + 1, JOINT_LIMITS_DEG[:, 1] - 1,
                              (n, 20)).astype(np.float32),
        "hlac": feats["hlac"],
        "sil_bits": feats["sil_bits"],
        "ridge_bits": feats["ridge_bits"],
        "ridge_area": feats["ridge_area"],
        "keypoints": rng.uniform(-0.15, 0.25, (n, 21, 3)),
    }


def _reseal(path):
    """Seal a file edited with h5py again, as a tool that knows the format would.

    Written from the layout in handsynth/db/_store.py: a 512-byte user block
    with the format line, the SHA-256 and the length of every later byte.
    """
    import hashlib

    data = bytearray(path.read_bytes())
    body = bytes(data[512:])
    head = (f"handsynth.pose_database 2\nsha256:{hashlib.sha256(body).hexdigest()}\n"
            f"bytes:{len(body)}\n").encode()
    data[:512] = head.ljust(512, b"\0")
    path.write_bytes(bytes(data))


@pytest.fixture
def db_path(tmp_path, arrays):
    return write_database(tmp_path / "standard.h5", meta=META, **arrays)


def test_round_trip(db_path, arrays):
    db = open_database(db_path, expect=META)
    assert isinstance(db, Database)
    assert len(db) == len(arrays["angles"])
    assert db.meta == META
    for name in ("angles", "hlac", "sil_bits", "ridge_bits", "ridge_area"):
        got = getattr(db, name)
        np.testing.assert_array_equal(got, arrays[name])
        assert got.dtype == arrays[name].dtype, name
        assert got.flags.c_contiguous and not got.flags.writeable, name
    assert db.keypoints_raw.dtype == np.int16
    kp = db.keypoints_m()
    assert kp.dtype == np.float32 and kp.shape == arrays["keypoints"].shape
    np.testing.assert_array_equal(
        db.keypoints_raw, np.rint(arrays["keypoints"] / KEYPOINT_SCALE_M).astype(np.int16)
    )
    # quantisation (half a unit) plus float32 rounding of metres below 0.25 m
    assert np.abs(kp - arrays["keypoints"]).max() <= 0.5 * KEYPOINT_SCALE_M + 3e-8
    np.testing.assert_array_equal(db.keypoints_m(3), kp[3])
    assert verify(db_path, expect=META) == META
    assert not list(db_path.parent.glob("*.tmp-*"))


def test_expect_subset_and_json_normalisation(db_path):
    open_database(db_path, expect={"shape": {"r_width": 0.9}, "seed": 7})
    with pytest.raises(DatabaseMismatchError):
        open_database(db_path, expect={"seed": True})  # JSON true is not 7


def test_writes_are_byte_identical(tmp_path, arrays):
    a = write_database(tmp_path / "a.h5", meta=META, **arrays)
    b = write_database(tmp_path / "b.h5", meta=dict(reversed(list(META.items()))), **arrays)
    assert a.read_bytes() == b.read_bytes()
    changed = dict(arrays, angles=arrays["angles"] + np.float32(0.5))
    c = write_database(tmp_path / "c.h5", meta=META, **changed)
    assert c.read_bytes() != a.read_bytes()


def test_mismatch_names_key_values_and_path(db_path):
    expect = dict(META, shape=dict(META["shape"], r_length=1.0))
    with pytest.raises(DatabaseMismatchError) as info:
        open_database(db_path, expect=expect)
    msg = str(info.value)
    assert "'shape.r_length'" in msg and "1.05" in msg and "1.0 is expected" in msg
    assert str(db_path) in msg
    with pytest.raises(DatabaseMismatchError, match=r"'pose_set'.*\"paper-20448\".*\"other\""):
        verify(db_path, expect={"pose_set": "other"})
    with pytest.raises(DatabaseMismatchError, match=r"'feature_params' is \"<missing>\""):
        open_database(db_path, expect={"feature_params": {"block": 8}})


def test_truncated_file_is_refused(db_path):
    data = db_path.read_bytes()
    db_path.write_bytes(data[: len(data) // 2])
    for fn in (open_database, verify):
        with pytest.raises(DatabaseCorruptError, match=r"truncated or damaged") as info:
            fn(db_path)
        assert str(db_path) in str(info.value)


@pytest.mark.parametrize("name", ["angles", "hlac", "sil_bits", "keypoints"])
def test_flipped_byte_in_a_dataset_is_refused(db_path, name):
    with h5py.File(db_path, "r") as f:
        info = f[name].id.get_chunk_info(0)
    offset = info.byte_offset + info.size // 2
    with open(db_path, "r+b") as fh:
        fh.seek(offset)
        byte = fh.read(1)
        fh.seek(offset)
        fh.write(bytes([byte[0] ^ 0x10]))
    for fn in (open_database, verify):
        with pytest.raises(DatabaseCorruptError, match=r"checksum|cannot be read") as err:
            fn(db_path)
        assert str(db_path) in str(err.value)


def test_changed_dataset_value_fails_checksum(db_path):
    # rewritten through HDF5, so the chunk decompresses fine: only the
    # checksum can notice
    with h5py.File(db_path, "r+") as f:
        f["hlac"][5, 17] = f["hlac"][5, 17] ^ 1
    with pytest.raises(DatabaseCorruptError, match=r"fails its file checksum \(stored sha256:"):
        open_database(db_path)
    _reseal(db_path)
    with pytest.raises(DatabaseCorruptError, match=r"fails its checksum \(stored sha256:"):
        open_database(db_path)


def test_changed_metadata_fails_checksum(db_path):
    with h5py.File(db_path, "r+") as f:
        f.attrs["meta"] = str(f.attrs["meta"]).replace('"seed":7', '"seed":8')
    with pytest.raises(DatabaseCorruptError, match=r"fails its file checksum"):
        open_database(db_path)
    _reseal(db_path)
    with pytest.raises(DatabaseCorruptError, match=r"fails its checksum"):
        open_database(db_path)


def test_missing_complete_mark_is_refused(db_path):
    with h5py.File(db_path, "r+") as f:
        del f.attrs["complete"]
    _reseal(db_path)
    with pytest.raises(DatabaseCorruptError, match=r"no complete mark"):
        verify(db_path)


def test_missing_or_misshapen_dataset_is_refused(db_path, tmp_path):
    other = tmp_path / "other.h5"
    shutil.copy(db_path, other)
    with h5py.File(db_path, "r+") as f:
        del f["ridge_area"]
    _reseal(db_path)
    with pytest.raises(DatabaseCorruptError, match=r"no dataset 'ridge_area'"):
        open_database(db_path)
    with h5py.File(other, "r+") as f:
        data = f["hlac"][:, :800]
        del f["hlac"]
        f["hlac"] = data
    _reseal(other)
    with pytest.raises(DatabaseCorruptError, match=r"'hlac' has shape \(\d+, 800\)"):
        open_database(other)


def test_temporary_file_is_never_accepted(db_path):
    tmp = db_path.with_name(db_path.name + ".tmp-12345")
    shutil.copy(db_path, tmp)  # even a complete, valid copy
    for fn in (open_database, verify):
        with pytest.raises(DatabaseCorruptError, match=r"temporary file"):
            fn(tmp)


def test_failed_write_leaves_no_file(tmp_path, arrays, monkeypatch):
    def boom(src, dst):
        raise OSError("disk full")

    monkeypatch.setattr(os, "replace", boom)
    target = tmp_path / "x.h5"
    with pytest.raises(DatabaseError, match=r"disk full"):
        write_database(target, meta=META, **arrays)
    assert list(tmp_path.iterdir()) == []


def test_missing_file(tmp_path):
    with pytest.raises(DatabaseError, match=r"does not exist"):
        open_database(tmp_path / "nope.h5")


def test_write_validates_inputs(tmp_path, arrays):
    bad_meta = {"x": float("nan")}
    with pytest.raises(InvalidInputError, match=r"meta"):
        write_database(tmp_path / "m.h5", meta=bad_meta, **arrays)
    bad = dict(arrays, hlac=arrays["hlac"][:, :100])
    with pytest.raises(
        InvalidInputError, match=r"hlac must have shape \(\d+, 1600\), got .*\(\d+, 100\)"
    ):
        write_database(tmp_path / "m.h5", meta=META, **bad)
    bad = dict(arrays, ridge_area=arrays["ridge_area"] + 1)
    with pytest.raises(InvalidInputError, match=r"ridge_area\[0\] is \d+ but ridge_bits\[0\] has"):
        write_database(tmp_path / "m.h5", meta=META, **bad)
    angles = arrays["angles"].copy()
    angles[2, 5] = np.nan
    with pytest.raises(
        InvalidInputError, match=r"angles must be finite, got nan at index \(2, 5\)"
    ):
        write_database(tmp_path / "m.h5", meta=META, **dict(arrays, angles=angles))
    for value, joint in ((1e39, 5), (5000.0, 0), (-25.0, 9)):
        angles = arrays["angles"].astype(np.float64)
        angles[3, joint] = value
        shown = re.escape(f"{value:g}")
        with pytest.raises(InvalidInputError, match=rf"angles row 3: \w+={shown} deg is outside"):
            write_database(tmp_path / "m.h5", meta=META, **dict(arrays, angles=angles))
    with pytest.raises(InvalidInputError, match=r"keypoints must lie within .* got 0\.50000 m"):
        write_database(
            tmp_path / "m.h5", meta=META, **dict(arrays, keypoints=arrays["keypoints"] * 2)
        )
    with pytest.raises(InvalidInputError, match=r"path must not contain"):
        write_database(tmp_path / "m.h5.tmp-1", meta=META, **arrays)
    assert list(tmp_path.iterdir()) == []


# --------------------------------------------------------------------------- faults (issue 16)


def _small_real_database(folder):
    from handsynth.db import build_database

    return build_database(folder, count=40, render_size=(64, 48), workers=1)


def test_every_damaged_byte_gives_a_database_error(tmp_path):
    # item 2: single flipped bytes and zero-filled tails made h5py raise KeyError,
    # OSError, UnicodeEncodeError -- or crash the interpreter
    src = _small_real_database(tmp_path / "src")
    data = src.read_bytes()
    target = tmp_path / src.name
    offsets = list(range(0, 4096, 3)) + list(range(4096, len(data), 97))
    damaged = [data[:o] + bytes([data[o] ^ 0xFF]) + data[o + 1:] for o in offsets]
    damaged += [data[:cut] + bytes(len(data) - cut) for cut in (600, len(data) // 2, len(data) - 8)]
    damaged += [data[:cut] for cut in (0, 100, 511, 512, 2000)]
    for blob in damaged:
        target.write_bytes(blob)
        for fn in (open_database, verify):
            with pytest.raises(DatabaseError) as err:
                fn(target)
            assert str(target) in str(err.value)


def test_a_database_of_another_shape_under_this_shape_s_name_is_refused(tmp_path):
    # item 6: a database copied to another shape's file name was read as that shape's
    from handsynth.db import build_database
    from handsynth.models import HandShape

    src = build_database(tmp_path / "a", HandShape(length=1.1), count=30, render_size=(64, 48),
                         workers=1)
    fake = tmp_path / f"{HandShape().name}.h5"
    shutil.copy(src, fake)
    for fn in (open_database, verify):
        with pytest.raises(DatabaseMismatchError, match=r"named for shape L1.000_W1.000_P1.000_T1.000 "
                                                        r"but holds .* shape L1.100"):
            fn(fake)
    open_database(src)  # its own name is fine


def _edit_attr(path, name, value):
    with h5py.File(path, "r+") as f:
        if value is None:
            del f.attrs[name]
        else:
            f.attrs[name] = value
    _reseal(path)


@pytest.mark.parametrize("name, value, message", [
    ("format_version", "abc", r"'format_version' must be an int scalar, got 'abc'"),
    ("format_version", 2.0, r"'format_version' must be an int scalar, got 2.0"),
    ("format_version", 1.5, r"'format_version' must be an int scalar, got 1.5"),
    ("format_version", np.array([2, 2]), r"'format_version' must be an int scalar, got an array"),
    ("n_entries", np.array([3, 4]), r"'n_entries' must be an int scalar, got an array"),
    ("n_entries", -1, r"'n_entries' is -1"),
    ("meta", np.array([1.0, 2.0]), r"'meta' must be a str scalar"),
    ("meta", "{not json", r"'meta' is not JSON"),
    ("checksum", None, r"'checksum' is missing"),
    ("complete", np.array([1, 1]), r"'complete' must be a bool scalar"),
])
def test_hand_edited_attributes_name_the_field(db_path, name, value, message):
    # item 14: format_version="abc", arrays where scalars belong gave tracebacks;
    # format_version=1.5 was read as 1 (here: as 2, the current version)
    _edit_attr(db_path, name, value)
    for fn in (open_database, verify):
        with pytest.raises(DatabaseError, match=message) as err:
            fn(db_path)
        assert str(db_path) in str(err.value)


def test_a_soft_link_loop_names_the_dataset(db_path):
    # item 14: a soft-link loop in place of a dataset gave a traceback
    with h5py.File(db_path, "r+") as f:
        del f["ridge_area"]
        f["ridge_area"] = h5py.SoftLink("/loop")
        f["loop"] = h5py.SoftLink("/ridge_area")
    _reseal(db_path)
    with pytest.raises(DatabaseError, match=r"'ridge_area'"):
        open_database(db_path)


def test_an_edited_file_that_is_not_resealed_fails_the_file_checksum(db_path):
    with h5py.File(db_path, "r+") as f:
        f.attrs["format_version"] = "abc"
    with pytest.raises(DatabaseCorruptError, match=r"file checksum"):
        open_database(db_path)


def test_a_folder_or_dangling_link_in_place_of_a_file_is_named(tmp_path):
    # item 15: both said the database does not exist
    (tmp_path / "d.h5").mkdir()
    with pytest.raises(DatabaseError, match=r"is a folder, not a file"):
        open_database(tmp_path / "d.h5")
    (tmp_path / "l.h5").symlink_to(tmp_path / "gone.h5")
    with pytest.raises(DatabaseError, match=r"is a link to .*gone.h5.*which does not exist"):
        open_database(tmp_path / "l.h5")


def test_a_database_never_replaces_an_input(db_path, arrays):
    with pytest.raises(DatabaseError, match=r"never replaces an input"):
        write_database(db_path.with_name("out.h5"), meta=META, inputs=[db_path.with_name("out.h5")],
                       **arrays)


def test_a_full_disk_leaves_nothing_and_says_so(full_disk, arrays):
    # item 3 (library level): h5py raised RuntimeError and the process crashed later
    big = {k: np.concatenate([v] * 40) for k, v in arrays.items()}
    with pytest.raises(DatabaseError, match=r"no space left"):
        write_database(full_disk / "x.h5", meta=META, **big)
    assert list(full_disk.iterdir()) == []


def test_a_read_only_folder_gives_the_real_reason(read_only_folder, arrays):
    # item 4: the cleanup's unlink raised and hid the real error
    with pytest.raises(DatabaseError, match=r"read-only") as err:
        write_database(read_only_folder / "x.h5", meta=META, **arrays)
    assert "could not be removed" not in str(err.value)


def test_a_path_that_is_no_file_name_is_named():
    for fn in (open_database, verify):
        with pytest.raises(InvalidInputError, match=r"path must be a file name \(str or "
                                                    r"os.PathLike\), got NoneType"):
            fn(None)
