"""Readers of the real export formats, on files written here by hand."""

import re
import warnings

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from handsynth.errors import InvalidInputError, RecordingError
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
    if unit == "m":  # cm and in overlap for some spacings; mm and m do not
        with pytest.warns(UserWarning, match="implausible.*look like 'm'") as caught:
            read_polhemus(path, units="cm")
        assert len(caught) == 1  # positions 100 times too small: no glitches either
    elif unit == "mm":
        # ten times too large: the 0.76 mm noise becomes 7.6 mm, and most frames
        # would pass for 10 mm glitches; the file is refused, not cut to a quarter
        with pytest.warns(UserWarning, match="implausible.*look like 'mm'") as caught, \
                pytest.raises(RecordingError, match=r"too many to be glitches.*units='cm'"):
            read_polhemus(path, units="cm")
        assert len(caught) == 1


def test_most_frames_off_their_neighbours_are_not_glitches(tmp_path, finger_rec, liberty_lines):
    path = _write(tmp_path / "g.txt", liberty_lines(finger_rec, scale=100.0, counter=False,
                                                    quaternion=True))
    # a threshold below the 0.76 mm noise: nearly every frame would be dropped
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(RecordingError, match=r"of 2880 frames have a position > 0.5 mm "
                           r"off its neighbours, too many to be glitches .*units='cm'"):
            read_polhemus(path, glitch_mm=0.5)
    assert _no_warnings(lambda: read_polhemus(path)).metadata["glitch_frames"] == 0


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
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # a refusal, with no warning before it
        with pytest.raises(RecordingError) as err:
            read_polhemus(path)
    assert name in str(err.value) and "\n" not in str(err.value)
    if name == "nan.txt":  # the refusal says why no frame is usable
        assert re.search(r"only 0 usable frames of 30 \(30 frames with NaN values", str(err.value))


def test_too_few_usable_frames_refused_with_the_reasons(tmp_path, finger_rec, liberty_lines):
    lines = liberty_lines(finger_rec, scale=100.0, counter=False, quaternion=False)[:40]
    for i in range(0, 36, 2):
        lines[i] = lines[i].split()[0] + " nan" * 6
    path = _write(tmp_path / "mostly_nan.txt", lines)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(RecordingError, match=r"only 2 usable frames of 20 \(18 frames with NaN"):
            read_polhemus(path)
    lines = liberty_lines(finger_rec, scale=100.0, counter=False, quaternion=False)[:60]
    lines[0] = lines[0].split()[0] + " nan" * 6
    with pytest.warns(UserWarning, match=r"1 frames with NaN values .*; dropped"):
        assert read_polhemus(_write(tmp_path / "one_nan.txt", lines), units="cm").n_frames == 29


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


# --- found by trying real exports: station order, dropouts, frozen stretches, quotes, times, radians ---


def _no_warnings(call):
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        return call()


@pytest.mark.parametrize("swap", [False, True])
def test_stations_in_either_order_pair_within_a_frame(tmp_path, finger_rec, liberty_lines, swap):
    # item 12: --sensors 2,1 (or a file writing station 2 first) paired station 2 of frame i
    # with station 1 of frame i + 1 and reported "2 half frames"
    lines = liberty_lines(finger_rec, scale=100.0, counter=False, quaternion=False)
    if swap:
        lines = [lines[i + d] for i in range(0, len(lines), 2) for d in (1, 0)]
    path = _write(tmp_path / "lib.txt", lines)
    rec = _no_warnings(lambda: read_polhemus(path, sensors=(2, 1)))
    assert rec.metadata["half_frames"] == 0 and rec.n_frames == finger_rec.n_frames
    np.testing.assert_allclose(rec.positions, finger_rec.positions[:, ::-1], atol=2e-6)
    rec = _no_warnings(lambda: read_polhemus(path))
    _close(rec, finger_rec)


def test_lost_line_in_a_station_2_first_file_is_not_merged(tmp_path, finger_rec, liberty_lines):
    lines = liberty_lines(finger_rec, scale=100.0, counter=False, quaternion=False)
    lines = [lines[i + d] for i in range(0, len(lines), 2) for d in (1, 0)]
    del lines[2 * 40]  # station 2 of frame 40
    for sensors in (None, (2, 1)):
        with pytest.warns(UserWarning, match="1 half frames"):
            rec = read_polhemus(_write(tmp_path / "lost.txt", lines), sensors=sensors)
        keep = np.setdiff1d(np.arange(finger_rec.n_frames), [40])
        ref = finger_rec.take(keep)
        got = rec.positions if sensors is None else rec.positions[:, ::-1]
        np.testing.assert_allclose(got, ref.positions, atol=2e-6)
        np.testing.assert_allclose(rec.times, finger_rec.times[keep], atol=1e-9)


@pytest.mark.parametrize("frames", [[700, 701, 702], list(range(700, 750))])
def test_dropouts_to_zero_are_dropped_and_named(tmp_path, finger_rec, liberty_lines, frames):
    # item 13: 3 or more consecutive zeroed frames passed the glitch filter (the centre moved
    # 1.4 mm); 50 made every method refuse with a misleading message
    lines = liberty_lines(finger_rec, scale=100.0, counter=False, quaternion=False)
    for f in frames:
        lines[2 * f] = "  1 0.0000 0.0000 0.0000 0.0000 0.0000 0.0000"
    path = _write(tmp_path / "zero.txt", lines)
    with pytest.warns(UserWarning, match=f"{len(frames)} dropout frames .*lines \\[{2 * 700 + 1}, "):
        rec = read_polhemus(path)
    assert rec.metadata["dropout_frames"] == len(frames)
    assert rec.metadata["glitch_frames"] == 0
    _close(rec, finger_rec.take(np.setdiff1d(np.arange(finger_rec.n_frames), frames)))
    with pytest.raises(RecordingError, match="dropout"):
        read_polhemus(path, on_invalid="raise")


def test_pimgr_dropout_identity_and_zero_position(tmp_path, finger_rec, pimgr_lines):
    lines = pimgr_lines(finger_rec, scale=100.0)
    for r in range(1001, 1051):
        f = lines[r].split(",")
        f[1:5] = ["1", "0", "0", "0"]
        f[9:12] = ["0", "0", "0"]
        lines[r] = ",".join(f)
    with pytest.warns(UserWarning, match="50 dropout frames"):
        rec = read_polhemus(_write(tmp_path / "zero.csv", lines))
    _close(rec, finger_rec.take(np.setdiff1d(np.arange(finger_rec.n_frames), range(1000, 1050))))


def test_partly_frozen_sensor_is_dropped_and_named(tmp_path, finger_rec, pimgr_lines):
    # item 14: a sensor frozen over rows 1000-1099 passed unnoticed; frame 1000 (line 1002)
    # is the real sample that the tracker then repeated 99 times: it is kept
    lines = pimgr_lines(finger_rec, scale=100.0)
    held = lines[1001].split(",")
    for r in range(1001, 1101):
        f = lines[r].split(",")
        f[1:5], f[9:12] = held[1:5], held[9:12]
        lines[r] = ",".join(f)
    with pytest.warns(UserWarning, match="99 frozen frames.*lines \\[1003, 1004"):
        rec = read_polhemus(_write(tmp_path / "frozen.csv", lines))
    assert rec.metadata["frozen_frames"] == 99
    _close(rec, finger_rec.take(np.setdiff1d(np.arange(finger_rec.n_frames), range(1001, 1100))))
    # a few repeated samples are not a frozen sensor
    lines = pimgr_lines(finger_rec, scale=100.0)
    for r in range(1002, 1005):
        f = lines[r].split(",")
        f[1:5], f[9:12] = held[1:5], held[9:12]
        lines[r] = ",".join(f)
    rec = _no_warnings(lambda: read_polhemus(_write(tmp_path / "short.csv", lines)))
    assert rec.metadata["frozen_frames"] == 0 and rec.n_frames == finger_rec.n_frames


@pytest.mark.parametrize("every_cell", [False, True])
def test_quoted_pimgr_csv_is_read(tmp_path, finger_rec, pimgr_lines, every_cell):
    # item 15: a quoted header (or quoted numbers) was not recognised
    lines = pimgr_lines(finger_rec, scale=100.0)
    quote = [0] if not every_cell else range(len(lines))
    for r in quote:
        lines[r] = ",".join(f'"{c}"' for c in lines[r].split(","))
    rec = read_polhemus(_write(tmp_path / "q.csv", lines))
    assert rec.metadata["format"] == "pimgr-csv"
    _close(rec, finger_rec)


def _retime(lines, times):
    return [lines[0]] + [f"{t:.4f}," + line.split(",", 1)[1] for t, line in zip(times, lines[1:])]


def test_pimgr_time_column_problems_are_named(tmp_path, finger_rec, pimgr_lines):
    # item 16: a constant time column, a restart and milliseconds were silent or misleading
    lines = pimgr_lines(finger_rec, scale=100.0)
    n = finger_rec.n_frames
    with pytest.raises(RecordingError, match=f"time column is 0 on all {n} rows"):
        read_polhemus(_write(tmp_path / "t0.csv", _retime(lines, np.zeros(n))))
    with pytest.warns(UserWarning, match=f"line {n + 2}: the time restarts.*{n} rows"):
        rec = read_polhemus(_write(tmp_path / "two.csv", lines + lines[1:]))
    assert rec.n_frames == n and rec.metadata["rows_after_restart"] == n
    with pytest.warns(UserWarning, match="looks like milliseconds"):
        rec = read_polhemus(_write(tmp_path / "ms.csv", _retime(lines, finger_rec.times * 1e3)))
    assert rec.metadata["time_looks_like_ms"]
    _no_warnings(lambda: read_polhemus(_write(tmp_path / "s.csv", lines)))


def test_euler_angles_in_radians_are_warned_about(tmp_path, finger_rec, liberty_lines):
    # item 17: radians gave a misleading "flex the joint further" refusal
    lines = []
    for line in liberty_lines(finger_rec, scale=100.0, counter=False, quaternion=False):
        f = line.split()
        lines.append(" ".join(f[:4] + [f"{np.radians(float(v)):.6f}" for v in f[4:]]))
    with pytest.warns(UserWarning, match="look like radians"):
        read_polhemus(_write(tmp_path / "rad.txt", lines))


def test_the_rate_of_rounded_stamps_is_their_mean_step():
    # 240 Hz stamps written with four decimals read as 238 Hz (the median step)
    from handsynth.sensors.trackers import Recording

    def rec(times):
        n = len(times)
        return Recording(times=times, positions=np.zeros((n, 2, 3)),
                         rotations=np.broadcast_to(np.eye(3), (n, 2, 3, 3)).copy())

    times = np.round(np.arange(960) / 240.0, 4)
    assert abs(rec(times).rate_hz - 240.0) < 0.5
    assert abs(rec(np.delete(times, np.s_[100:110])).rate_hz - 240.0) < 0.5  # frames dropped


# --- two takes by frame counter, frozen stretches' real sample, cut-off files, underscores ---


@pytest.mark.parametrize("quaternion", [False, True])
def test_frame_counter_restart_keeps_the_first_take(tmp_path, finger_rec, liberty_lines,
                                                     quaternion):
    # the export written twice into one file: before, "8 columns that are neither a frame
    # counter (column 2) nor a unit quaternion (columns 5-8); give the layout with
    # columns=(...)" (9 columns: "no increasing integer counter in column 2")
    lines = liberty_lines(finger_rec, scale=100.0, counter=True, quaternion=quaternion)
    n = finger_rec.n_frames
    path = _write(tmp_path / "two.txt", lines + lines)
    with pytest.warns(UserWarning, match=f"two.txt line {2 * n + 1}: the frame counter restarts "
                                         f"\\({999 + n} -> 1000\\): two takes in one file\\? only "
                                         f"the rows before line {2 * n + 1} are used "
                                         f"\\({2 * n} rows of the other take dropped; "
                                         f"take=N, --take N, reads another\\)"):
        rec = read_polhemus(path)
    assert rec.n_frames == n and "frame" in rec.metadata["layout"]
    assert rec.metadata["restart_line"] == 2 * n + 1
    assert rec.metadata["rows_after_restart"] == 2 * n
    np.testing.assert_allclose(rec.times, finger_rec.times, atol=1e-9)
    _close(rec, finger_rec)


@pytest.mark.parametrize("counter", [True, False])
def test_a_later_take_is_read_when_asked(tmp_path, finger_rec, liberty_lines, pimgr_lines,
                                         counter):
    # before, only the first take of a file with several could be read: the others were
    # dropped with a warning, and the user had to cut the file by hand
    import dataclasses

    n = finger_rec.n_frames
    # the second take another recording: the hand 3 cm farther from the transmitter
    moved = dataclasses.replace(finger_rec, positions=finger_rec.positions + [0.03, 0.0, 0.0])
    if counter:  # Liberty ASCII: the frame counter restarts
        lines = liberty_lines(finger_rec, scale=100.0, counter=True, quaternion=False)
        other = liberty_lines(moved, scale=100.0, counter=True, quaternion=False)
        path = _write(tmp_path / "three.txt", lines + other + lines)
        per_take, column, first_line = 2 * n, "frame counter", 1
    else:  # PiMgr CSV: the time column restarts (its header on line 1)
        lines = pimgr_lines(finger_rec, scale=100.0)
        other = pimgr_lines(moved, scale=100.0)
        path = _write(tmp_path / "three.csv", lines + other[1:] + lines[1:])
        per_take, column, first_line = n, "time", 2
    with pytest.warns(UserWarning, match=rf"the {column} restarts .*: 3 takes in one file\? "
                                         rf"take 2 is used \(lines {first_line + per_take}-"
                                         rf"{first_line + 2 * per_take - 1}\) "
                                         rf"\({2 * per_take} rows of the other takes dropped"):
        rec = read_polhemus(path, take=2)
    assert rec.n_frames == n and rec.metadata["takes"] == 3 and rec.metadata["take"] == 2
    np.testing.assert_allclose(rec.times, finger_rec.times, atol=1e-3)
    _close(rec, moved)
    with pytest.warns(UserWarning, match=r"take 3 is used"):
        _close(read_polhemus(path, take=3), finger_rec)
    with pytest.raises(RecordingError, match=rf"take=4, but the {column} restarts 2 time\(s\) "
                                             rf".*the file holds 3 takes"):
        read_polhemus(path, take=4)


def test_a_later_take_of_a_file_of_one_take_is_refused(tmp_path, finger_rec, pimgr_lines):
    path = _write(tmp_path / "one.csv", pimgr_lines(finger_rec, scale=100.0))
    with pytest.raises(RecordingError, match=r"take=2, but the file holds one take"):
        read_polhemus(path, take=2)
    for bad in (0, 1.0, "2", True):
        with pytest.raises(InvalidInputError, match=r"take must be an integer >= 1"):
            read_polhemus(path, take=bad)


def test_frozen_stretch_keeps_the_real_sample_before_it(tmp_path, finger_rec, liberty_lines):
    # station 1 measured frame 1000, then repeated it over frames 1001-1099: before, frame
    # 1000 (the real sample) was dropped with the 99 repeats
    lines = liberty_lines(finger_rec, scale=100.0, counter=False, quaternion=False)
    for frame in range(1001, 1100):
        lines[2 * frame] = lines[2 * 1000]
    with pytest.warns(UserWarning, match="99 frozen frames.*lines \\[2003, 2005"):
        rec = read_polhemus(_write(tmp_path / "frozen.txt", lines))
    assert rec.metadata["frozen_frames"] == 99
    assert rec.n_frames == finger_rec.n_frames - 99
    kept = np.setdiff1d(np.arange(finger_rec.n_frames), range(1001, 1100))
    np.testing.assert_allclose(rec.times, finger_rec.times[kept], atol=1e-9)
    assert 1000 in np.round(rec.times * 240).astype(int)  # the real sample
    _close(rec, finger_rec.take(kept))


def _cut_warning(path, line):
    return (f"{path}, line {line}: the file ends without a line end, as a recording cut off "
            f"while being written does; line {line} was left out")


@pytest.mark.parametrize("fmt", ["liberty", "pimgr"])
def test_file_without_a_final_line_end_leaves_the_last_line_out(tmp_path, finger_rec,
                                                                  liberty_lines, pimgr_lines, fmt):
    # a recording cut off while being written ends mid-number: before, 12.3 of 12.345 was read
    # as a complete sample
    if fmt == "liberty":
        lines = liberty_lines(finger_rec, scale=100.0, counter=False, quaternion=False)
    else:
        lines = pimgr_lines(finger_rec, scale=100.0)
    path = tmp_path / f"cut.{'txt' if fmt == 'liberty' else 'csv'}"
    path.write_text("\n".join(lines)[:-2])
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        rec = read_polhemus(path)
    messages = [str(w.message) for w in caught]
    assert messages[0] == _cut_warning(path, len(lines))
    assert rec.metadata["cut_off_line"] == len(lines)
    assert rec.n_frames == finger_rec.n_frames - 1  # Liberty: a half frame, named as one
    assert (fmt == "liberty") == any("1 half frames" in m for m in messages[1:])
    _close(rec, finger_rec.take(np.arange(finger_rec.n_frames - 1)))
    # complete files, CRLF line ends included, read without a warning
    path.write_bytes(("\r\n".join(lines) + "\r\n").encode())
    assert _no_warnings(lambda: read_polhemus(path)).n_frames == finger_rec.n_frames


def test_header_only_without_a_line_end_keeps_its_error(tmp_path, pimgr_lines, finger_rec):
    path = tmp_path / "head.csv"
    path.write_text(pimgr_lines(finger_rec, scale=100.0)[0])
    with pytest.raises(RecordingError, match="no data line of numbers found"):
        _no_warnings(lambda: read_polhemus(path))


@pytest.mark.parametrize("fmt", ["liberty", "pimgr"])
def test_numbers_with_underscores_are_refused(tmp_path, finger_rec, liberty_lines, pimgr_lines,
                                              fmt):
    # float() reads 1_000 as 1000, but no exporter writes it
    if fmt == "liberty":
        lines = liberty_lines(finger_rec, scale=100.0, counter=False, quaternion=False)
        cells = lines[10].split()
        cells[1], cell = "1_000.5", "1_000.5"
        lines[10] = " ".join(cells)
    else:
        lines = pimgr_lines(finger_rec, scale=100.0)
        cell = "1_700_000_000.0042"
        lines[10] = cell + "," + lines[10].split(",", 1)[1]
    path = _write(tmp_path / f"u.{'txt' if fmt == 'liberty' else 'csv'}", lines)
    with pytest.raises(RecordingError) as err:
        read_polhemus(path)
    assert str(err.value) == (f"{path}, line 11: {cell!r} is not a number as recordings write "
                              "them (an underscore)")


def test_pimgr_sensors_option_chooses_the_upper_sensor(tmp_path, finger_rec, pimgr_lines):
    """Before, sensors=(2, 1) was ignored on a file with both sensors on one line."""
    from handsynth.errors import InvalidInputError

    path = _write(tmp_path / "pimgr.csv", pimgr_lines(finger_rec, scale=100.0))
    plain = read_polhemus(path)
    swapped = read_polhemus(path, sensors=(2, 1))
    np.testing.assert_array_equal(swapped.positions, plain.positions[:, ::-1])
    np.testing.assert_array_equal(swapped.rotations, plain.rotations[:, ::-1])
    assert swapped.metadata["sensors"] == [2, 1] and plain.metadata["sensors"] == [1, 2]
    with pytest.raises(InvalidInputError, match=r"holds sensors 1 and 2 .* not 1 and 3"):
        read_polhemus(path, sensors=(1, 3))


def test_cm_or_inches_far_from_the_typical_spacing_is_warned(tmp_path, liberty_lines):
    """Sensors 14.7 mm apart in a cm file read as inches (37.4 mm): the centre 2.54x off.
    Nothing in the data tells cm from inches, so a spacing far from 28 mm is warned about."""
    from handsynth.sensors.trackers import FlexionMotion, SensorMount, simulate_recording

    close = simulate_recording(
        "index_dip", motion=FlexionMotion(duration_s=3.0), seed=3, geometry_source="table",
        upper_mount=SensorMount(along=0.75, pitch_deg=15.0),
        lower_mount=SensorMount(along=0.2, pitch_deg=-15.0))
    path = _write(tmp_path / "close.txt", liberty_lines(close, scale=100.0, counter=False,
                                                        quaternion=True))
    with pytest.warns(UserWarning, match=r"unit is ambiguous: in 'in' .* 37\.4 mm .*'cm' 14\.7 mm"):
        rec = read_polhemus(path)
    assert rec.metadata["units"] == "in"  # the guess is wrong, and said to be a guess
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert read_polhemus(path, units="cm").metadata["units"] == "cm"


def test_cm_at_the_typical_spacing_is_not_warned(tmp_path, finger_rec, liberty_lines):
    path = _write(tmp_path / "dip.txt", liberty_lines(finger_rec, scale=100.0, counter=False,
                                                      quaternion=True))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        rec = read_polhemus(path)  # 26 mm in cm (66 mm in inches): decided, no warning
    assert rec.metadata["units"] == "cm"
