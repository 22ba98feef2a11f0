"""Readers of the real export formats, on files written here by hand."""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from handsynth.errors import RecordingError
from handsynth.sensors.trackers import read_polhemus


def _write(path, lines):
    path.write_text("\n".join(lines) + "\n")
    return path


def _close(rec, ref, atol_m=2e-6):
    np.testing.assert_allclose(rec.positions, ref.positions, atol=atol_m)
    np.testing.assert_allclose(rec.rotations, ref.rotations, atol=1e-4)


@pytest.mark.parametrize("counter", [False, True])
@pytest.mark.parametrize("quaternion", [False, True])
def test_liberty_ascii_layouts_are_detected(tmp_path, finger_rec, liberty_lines, counter, quaternion):
    path = _write(tmp_path / "lib.txt", liberty_lines(finger_rec, scale=100.0, counter=counter,
                                                      quaternion=quaternion))
    rec = read_polhemus(path)
    _close(rec, finger_rec)
    assert ("frame" in rec.metadata["layout"]) == counter
    assert rec.metadata["angles"] == ("quaternion" if quaternion else "euler")
    assert rec.metadata["units"] == "cm" and rec.metadata["format"] == "liberty-ascii"


def test_frame_counter_is_never_taken_as_x(tmp_path, finger_rec, liberty_lines):
    """Main read the counter as X (7-35 mm errors, silently)."""
    path = _write(tmp_path / "lib.txt", liberty_lines(finger_rec, scale=100.0, counter=True,
                                                      quaternion=False))
    rec = read_polhemus(path)
    np.testing.assert_allclose(rec.times, finger_rec.times, atol=1e-9)
    assert np.abs(rec.positions - finger_rec.positions).max() < 1e-6


def test_lost_line_drops_the_half_frame_never_merges(tmp_path, finger_rec, liberty_lines):
    lines = liberty_lines(finger_rec, scale=100.0, counter=False, quaternion=False)
    del lines[2 * 40]  # station 1 of frame 40
    del lines[2 * 90]  # station 2 of frame 90 (index shifted by one: station 2 of frame 90)
    path = _write(tmp_path / "lost.txt", lines)
    with pytest.warns(UserWarning, match="2 half frames"):
        rec = read_polhemus(path)
    assert rec.n_frames == finger_rec.n_frames - 2
    keep = np.setdiff1d(np.arange(finger_rec.n_frames), [40, 90])
    _close(rec, finger_rec.take(keep))
    np.testing.assert_allclose(rec.times, finger_rec.times[keep], atol=1e-9)
    with pytest.raises(RecordingError, match="half frames"):
        read_polhemus(path, on_invalid="raise")


def test_lost_line_with_counter(tmp_path, finger_rec, liberty_lines):
    lines = liberty_lines(finger_rec, scale=100.0, counter=True, quaternion=True)
    del lines[2 * 10 + 1]
    with pytest.warns(UserWarning, match="1 half frames"):
        rec = read_polhemus(_write(tmp_path / "lost.txt", lines))
    _close(rec, finger_rec.take(np.setdiff1d(np.arange(finger_rec.n_frames), [10])))


def test_pimgr_csv_unix_times_duplicates_and_sign_flips(tmp_path, finger_rec, pimgr_lines):
    lines = pimgr_lines(finger_rec, scale=100.0, t0=1_700_000_000.0, duplicate_every=2)
    path = _write(tmp_path / "pimgr.csv", lines)
    with pytest.warns(UserWarning, match="duplicated rows"):
        rec = read_polhemus(path)
    assert rec.metadata["format"] == "pimgr-csv"
    assert rec.metadata["duplicates"] == (finger_rec.n_frames + 1) // 2
    assert rec.metadata["time_origin_unix_s"] == pytest.approx(1_700_000_000.0)
    assert rec.metadata["quaternion_sign_flips"] > 0
    assert rec.n_frames == finger_rec.n_frames
    np.testing.assert_allclose(rec.times, finger_rec.times, atol=1e-3)
    _close(rec, finger_rec)


def test_decimal_commas_are_read(tmp_path, finger_rec, liberty_lines):
    lines = liberty_lines(finger_rec, scale=100.0, counter=False, quaternion=False,
                          decimal_comma=True)
    rec = read_polhemus(_write(tmp_path / "dc.txt", lines))
    assert rec.metadata["decimal_comma"]
    _close(rec, finger_rec)
    semi = [";".join(line.split()) for line in lines]
    rec = read_polhemus(_write(tmp_path / "semi.txt", semi))
    _close(rec, finger_rec)


@pytest.mark.parametrize("unit,scale", [("in", 1 / 0.0254), ("mm", 1e3), ("m", 1.0)])
def test_units_auto_and_warned(tmp_path, finger_rec, liberty_lines, unit, scale):
    path = _write(tmp_path / "u.txt", liberty_lines(finger_rec, scale=scale, counter=False,
                                                    quaternion=True))
    rec = read_polhemus(path)
    assert rec.metadata["units"] == unit
    _close(rec, finger_rec, atol_m=1e-4 if unit == "m" else 2e-6)
    if unit != "in":  # cm and in overlap for some spacings; mm and m do not
        with pytest.warns(UserWarning, match="implausible.*look like"):
            read_polhemus(path, units="cm")


def test_glitches_are_counted_and_dropped(tmp_path, finger_rec, liberty_lines):
    lines = liberty_lines(finger_rec, scale=100.0, counter=False, quaternion=False)
    for frame in (100, 500, 501):
        f = lines[2 * frame].split()
        f[1] = f"{float(f[1]) + 64:.4f}"  # a 64 cm jump
        lines[2 * frame] = " ".join(f)
    with pytest.warns(UserWarning, match="3 glitch frames"):
        rec = read_polhemus(_write(tmp_path / "g.txt", lines))
    assert rec.metadata["glitch_frames"] == 3 and rec.n_frames == finger_rec.n_frames - 3


MALFORMED = {
    "empty.txt": b"",
    "blank.txt": b"\n\n  \n",
    "binary.txt": bytes(range(256)) * 20,
    "arrays.npz": b"PK\x03\x04" + b"\x00" * 100,
    "commas.txt": b",,,,,,\n,,,,,,\n",
    "nan.txt": b"1 nan nan nan nan nan nan\n2 nan nan nan nan nan nan\n" * 30,
    "mixed.txt": b"1 1 2 3 4 5 6\n2 1 2 3\n1 1 2 3 4 5 6 7 8 9 10\n2 5\n" * 10,
    "words.csv": b"Time,w1,x1\nfoo,bar,baz\n",
    "onestation.txt": b"1 1 2 3 4 5 6\n" * 40,
    "eight.txt": b"1 1.5 2 3 4 5 6 7\n2 1.5 2 3 4 5 6 7\n" * 40,
}


@pytest.mark.parametrize("name", sorted(MALFORMED))
def test_malformed_files_raise_recording_error(tmp_path, name):
    path = tmp_path / name
    path.write_bytes(MALFORMED[name])
    with pytest.raises(RecordingError) as err:
        read_polhemus(path)
    assert name in str(err.value) and "\n" not in str(err.value)


def test_rotations_of_header_csv_with_euler(tmp_path, finger_rec):
    lines = ["time,az1,el1,ro1,az2,el2,ro2,loc1_x,loc1_y,loc1_z,loc2_x,loc2_y,loc2_z"]
    for i in range(finger_rec.n_frames):
        e = [Rotation.from_matrix(finger_rec.rotations[i, s]).as_euler("ZYX", degrees=True)
             for s in (0, 1)]
        p = finger_rec.positions[i] * 1e3
        lines.append(",".join(f"{v:.6f}" for v in [finger_rec.times[i], *e[0], *e[1], *p[0], *p[1]]))
    rec = read_polhemus(_write(tmp_path / "e.csv", lines))
    assert rec.metadata["units"] == "mm"
    _close(rec, finger_rec)
