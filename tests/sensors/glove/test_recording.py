import numpy as np
import pytest

from handsynth.errors import InvalidInputError, RecordingError
from handsynth.models import JOINT_NAMES
from handsynth.sensors.glove import (
    SENSOR_NAMES,
    GloveRecording,
    read_glove_csv,
    write_angles_csv,
    write_glove_csv,
)


def test_csv_round_trip(tmp_path, cal_rec):
    rec = cal_rec.select(np.arange(cal_rec.n_samples) < 300)
    path = write_glove_csv(tmp_path / "r.csv", rec)
    back = read_glove_csv(path, kind="dg5")
    np.testing.assert_allclose(back.sensors, rec.sensors)
    np.testing.assert_allclose(back.angles, rec.angles, atol=1e-4)
    assert back.motion.tolist() == rec.motion.tolist()
    assert back.trial.tolist() == rec.trial.tolist()
    assert back.truth is None          # the simulator's truth is never written
    header = path.read_text().splitlines()[0].split(",")
    assert header[3:8] == list(SENSOR_NAMES) and header[8:] == list(JOINT_NAMES)


def test_sensors_only_and_nan_cells(tmp_path):
    p = tmp_path / "s.csv"
    p.write_text("time_s," + ",".join(SENSOR_NAMES) + "\n0,1,2,3,4,5\n0.1,1,,3,nan,5\n")
    rec = read_glove_csv(p)
    assert rec.angles is None and rec.n_samples == 2
    assert np.isnan(rec.sensors[1, [1, 3]]).all()


@pytest.mark.parametrize("names", [["Thumb", "Index", "Middle", "Ring", "Pinky"],
                                   ["thumb sensor", "index sensor", "middle sensor",
                                    "ring sensor", "little sensor"],
                                   ["Bend-Little", "Bend-Ring", "Bend-Middle", "Bend-Index",
                                    "Bend-Thumb"]])
def test_a_gloves_own_sensor_names_are_read_by_their_meaning(tmp_path, names):
    # before: "missing sensor column(s) sensor_thumb, ..." for a glove's own export
    from handsynth.sensors.glove import GloveWarning

    p = tmp_path / "own.csv"
    p.write_text("Time (s)," + ",".join(names) + "\n0,1,2,3,4,5\n0.1,6,7,8,9,10\n")
    with pytest.warns(GloveWarning, match=r"6 columns read by their meaning "
                                           r"\('Time \(s\)' as time_s, "):
        rec = read_glove_csv(p)
    np.testing.assert_array_equal(rec.time_s, [0.0, 0.1])
    fingers = [n.lower().replace("bend-", "").replace(" sensor", "").replace("pinky", "little")
               for n in names]
    order = [fingers.index(f) for f in ("thumb", "index", "middle", "ring", "little")]
    np.testing.assert_array_equal(rec.sensors, np.array([[1, 2, 3, 4, 5],
                                                         [6, 7, 8, 9, 10]])[:, order])
    twice = tmp_path / "twice.csv"
    twice.write_text(",".join(names + ["sensor-" + fingers[0]]) + "\n" + "1,2,3,4,5,6\n")
    with pytest.raises(RecordingError, match=rf"columns '{names[0]}' and 'sensor-{fingers[0]}' "
                                             rf"both read as sensor_{fingers[0]}"):
        read_glove_csv(twice)


def test_a_byte_order_mark_does_not_hide_the_first_column(tmp_path):
    """A spreadsheet's "CSV UTF-8" starts with a byte-order mark; the first
    column (here time_s) must still be found by name."""
    p = tmp_path / "bom.csv"
    p.write_bytes(("\ufefftime_s," + ",".join(SENSOR_NAMES) + "\r\n0.5,1,2,3,4,5\r\n"
                   "0.75,1,2,3,4,5\r\n").encode("utf-8"))
    assert read_glove_csv(p).time_s.tolist() == [0.5, 0.75]


def test_a_delimiter_after_every_data_row_is_read(tmp_path):
    # a serial logger's "0.5,1,2,3,4,5," was refused: "line 2: 7 fields, header has 6"
    p = tmp_path / "logger.csv"
    p.write_text("time_s," + ",".join(SENSOR_NAMES) + "\n0.5,1,2,3,4,5,\n0.75,1,2,3,4,6,\n")
    rec = read_glove_csv(p)
    assert rec.time_s.tolist() == [0.5, 0.75] and rec.sensors[1].tolist() == [1, 2, 3, 4, 6]
    p.write_text("time_s," + ",".join(SENSOR_NAMES) + "\n0.5,1,2,3,4,5,7\n")
    with pytest.raises(RecordingError, match="line 2: 7 fields, header has 6"):
        read_glove_csv(p)  # a value there is still refused


@pytest.mark.parametrize("text, msg", [
    ("a,b\n1,2\n", "missing sensor column"),
    ("time_s," + ",".join(SENSOR_NAMES) + "\n0,1,2,x,4,5\n", r"line 2: sensor_middle is 'x'"),
    ("time_s," + ",".join(SENSOR_NAMES) + "\n0,1,2,3\n", "line 2: 4 fields, header has 6"),
    (",".join(SENSOR_NAMES) + ",thumb_cmc_flex\n1,2,3,4,5,6\n", "joint columns are incomplete"),
    (",".join(SENSOR_NAMES) + "\n", "no data rows"),
])
def test_bad_csv_names_the_problem(tmp_path, text, msg):
    p = tmp_path / "bad.csv"
    p.write_text(text)
    with pytest.raises(RecordingError, match=msg):
        read_glove_csv(p)


def test_angles_csv_and_shape_errors(tmp_path):
    a = np.zeros((3, 20))
    a[1] = np.nan
    text = write_angles_csv(tmp_path / "a.csv", a).read_text().splitlines()
    assert text[0].split(",") == ["sample", *JOINT_NAMES] and "nan" in text[2]
    text = write_angles_csv(tmp_path / "t.csv", a, time_s=[0.0, 0.5, 1.0]).read_text().splitlines()
    assert text[0].startswith("time_s,") and text[2].startswith("0.500000,")
    # before, (3, 5) angles went out under a 20-joint header and a short time_s was an IndexError
    for kw, msg in ((dict(angles=np.zeros((3, 5))), r"angles must have shape \(N, 20\), got \(3, 5\)"),
                    (dict(angles=a, time_s=[0.0, 1.0]), r"time_s must be 3 finite numbers"),
                    (dict(angles=np.full((3, 20), np.inf)), "infinite")):
        with pytest.raises(InvalidInputError, match=msg):
            write_angles_csv(tmp_path / "x.csv", **kw)
    assert not (tmp_path / "x.csv").exists()
    with pytest.raises(RecordingError, match=r"sensors must have shape \(N, 5\)"):
        GloveRecording(sensors=np.zeros((3, 4)))


def test_two_trials_under_one_number_are_refused(tmp_path, cal_rec):
    """Before, repeats all numbered 1 were mixed into one trial and the calibration
    failed with "point 2 of 20 has 0 calibration samples"."""
    path = write_glove_csv(tmp_path / "r.csv", cal_rec)
    lines = path.read_text().splitlines()
    head, body = lines[0], [ln.split(",") for ln in lines[1:]]
    for cells in body:
        cells[2] = "1"
    path.write_text("\n".join([head, *(",".join(c) for c in body)]) + "\n")
    with pytest.raises(RecordingError, match=r"r.csv, line \d+: motion '\w+', trial 1 starts again "
                                             r"after other rows \(it stopped at line \d+\): two "
                                             "trials under one number"):
        read_glove_csv(path)
    # one motion, one trial number, time starting again: the repeats lie in one stretch
    p = tmp_path / "t.csv"
    p.write_text("time_s,motion,trial," + ",".join(SENSOR_NAMES) + "\n0,tripod,1,1,2,3,4,5\n"
                 "0.1,tripod,1,1,2,3,4,5\n0,tripod,1,1,2,3,4,5\n")
    with pytest.raises(RecordingError, match=r"t.csv, line 4: time_s goes back from 0.1 s \(line 3\) "
                                             "to 0 s within motion 'tripod', trial 1"):
        read_glove_csv(p)


def test_rows_keep_their_file_lines(tmp_path):
    p = tmp_path / "s.csv"
    p.write_text("# a comment\ntime_s," + ",".join(SENSOR_NAMES) + "\n0,1,2,3,4,5\n\n0.1,1,2,3,4,5\n")
    rec = read_glove_csv(p)
    assert rec.lines.tolist() == [3, 5]
    assert rec.select(np.array([False, True])).lines.tolist() == [5]
    with pytest.raises(RecordingError, match=r"lines must have shape \(2,\)"):
        GloveRecording(sensors=rec.sensors, lines=[1])


def test_a_file_without_a_header_line_is_named_so(tmp_path):
    p = tmp_path / "s.csv"
    p.write_text("0,standard,0,1,2,3,4,5\n0.1,standard,0,1,2,3,4,5\n")
    with pytest.raises(RecordingError, match=r"s.csv, line 1: the first line holds numbers, not "
                                             r"column names"):
        read_glove_csv(p)


def test_an_infinite_reading_is_named_as_such(tmp_path):
    p = tmp_path / "s.csv"
    p.write_text("time_s," + ",".join(SENSOR_NAMES) + "\n0,1,2,3,4,5\n0.1,1,inf,3,4,5\n")
    with pytest.raises(RecordingError, match=r"s.csv, line 3: sensor_index is 'inf', not a "
                                             r"finite number"):
        read_glove_csv(p)
