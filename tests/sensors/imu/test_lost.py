import dataclasses

import numpy as np
import pytest

from handsynth.errors import RecordingError
from handsynth.sensors.imu import (
    HELD_MIN_S,
    MAX_BRIDGE_S,
    LostStretch,
    bridge_lost,
    check_recording,
    lost_stretches,
)


def _held(rec, sensor, start, n):
    """`rec` with `sensor`'s readings from `start` on replaced by the one before, `n` times."""
    k = rec.index(sensor)
    arrays = {name: getattr(rec, name).copy() for name in ("acc", "gyr", "mag")}
    for a in arrays.values():
        a[k, start:start + n] = a[k, start - 1]
    return dataclasses.replace(rec, **arrays)


def test_a_recording_as_made_holds_nothing(free_rec, ideal_rec):
    # the noise-free one repeats every reading of its still start and of sensors that do not
    # move (gyro exactly 0), which is not a held reading
    assert lost_stretches(free_rec) == []
    assert lost_stretches(ideal_rec) == []
    assert bridge_lost(free_rec) == (free_rec, [])


def test_a_sensor_held_is_found_with_its_time_and_turn(free_rec):
    start = int(6.0 * free_rec.rate_hz)
    rec = _held(free_rec, "index_proximal", start, 20)
    (h,) = lost_stretches(rec)
    assert isinstance(h, LostStretch)
    assert (h.sensor, h.first, h.count) == ("index_proximal", start, 20)
    assert h.time_s == pytest.approx(start / rec.rate_hz)
    assert h.duration_s == pytest.approx(20 / rec.rate_hz)
    w = np.linalg.norm(free_rec.gyr[rec.index("index_proximal"), start - 1])
    assert h.turned_deg == pytest.approx(np.degrees(w * h.duration_s))
    # shorter than HELD_MIN_S: not a hold worth telling (BROAD's real sensors repeat for 31 ms)
    short = round(HELD_MIN_S * rec.rate_hz) - 1
    assert lost_stretches(_held(free_rec, "index_proximal", start, short)) == []


def test_check_recording_refuses_held_readings_naming_sensor_and_time(free_rec):
    # before: a sensor held 0.5 s put its segment 18-44 deg off without a word
    rec = _held(free_rec, "middle_middle", 600, 20)
    with pytest.raises(RecordingError) as e:
        check_recording(rec, source="rec.csv")
    msg = str(e.value)
    assert msg.startswith("rec.csv: sensor 'middle_middle' repeats its accelerometer and gyro")
    assert "from t=6 s (sample 600)" in msg and "--bridge-lost" in msg
    longer = _held(rec, "index_distal", 900, round((MAX_BRIDGE_S + 0.1) * rec.rate_hz))
    with pytest.raises(RecordingError, match=r"'index_distal'.*2 such stretches, this the "
                                             r"longest.*longer than the 0.5 s bridged by default; "
                                             r"--bridge-lost --bridge-max SECONDS fills it in"):
        check_recording(longer)


def test_bridging_without_prediction_draws_straight_lines_across_the_hold(free_rec):
    rec = _held(free_rec, "ring_middle", 500, 15)
    out, bridged = bridge_lost(rec, predict=False)
    assert [(h.sensor, h.first, h.count) for h in bridged] == [("ring_middle", 500, 15)]
    k = rec.index("ring_middle")
    for name in ("acc", "gyr", "mag"):
        a, b = getattr(rec, name)[k, 499], getattr(rec, name)[k, 515]
        expected = a + (b - a) * (np.arange(1, 16) / 16)[:, None]
        np.testing.assert_allclose(getattr(out, name)[k, 500:515], expected)
        # nothing else changed
        np.testing.assert_array_equal(np.delete(getattr(out, name), np.s_[500:515], axis=1),
                                      np.delete(getattr(rec, name), np.s_[500:515], axis=1))
    assert out.truth is rec.truth and out.start_s == rec.start_s
    assert lost_stretches(out) == []
    check_recording(out)  # accepted once bridged


@pytest.mark.parametrize("sensor", ["index_proximal", "middle_middle", "hand_radial"])
def test_bridging_from_the_other_sensors_comes_closer_to_what_was_lost(free_rec, sensor):
    start, n = 640, 40  # 0.4 s in the motion
    rec = _held(free_rec, sensor, start, n)
    k = rec.index(sensor)
    lines, _ = bridge_lost(rec, predict=False)
    out, _ = bridge_lost(rec)
    for name in ("acc", "gyr"):
        lost = getattr(free_rec, name)[k, start:start + n]
        err = np.sqrt(np.mean((getattr(out, name)[k, start:start + n] - lost) ** 2))
        err_lines = np.sqrt(np.mean((getattr(lines, name)[k, start:start + n] - lost) ** 2))
        assert err < 0.7 * err_lines, (name, err, err_lines)
    np.testing.assert_array_equal(np.delete(out.gyr, np.s_[start:start + n], axis=1),
                                  np.delete(rec.gyr, np.s_[start:start + n], axis=1))
    # one sensor alone has nothing to predict from: the straight lines
    alone = rec.subset((sensor,))
    np.testing.assert_allclose(bridge_lost(alone)[0].gyr, bridge_lost(alone, predict=False)[0].gyr,
                               atol=1e-9)



def test_the_samples_filled_in_are_marked(free_rec):
    rec = _held(_held(free_rec, "ring_middle", 500, 15), "thumb_distal", 800, 30)
    assert rec.filled is None
    out, _ = bridge_lost(rec)
    expected = np.zeros((len(rec.sensors), rec.n), bool)
    expected[rec.index("ring_middle"), 500:515] = True
    expected[rec.index("thumb_distal"), 800:830] = True
    np.testing.assert_array_equal(out.filled, expected)
    # kept by a part of the recording, for the sensors and samples kept
    part = out.subset(("thumb_distal", "ring_middle")).slice(790, 900)
    np.testing.assert_array_equal(part.filled, expected[[rec.index("thumb_distal"),
                                                         rec.index("ring_middle")], 790:900])
    # a mark of the wrong shape or type is refused when the recording is made
    with pytest.raises(RecordingError, match=r"filled must be booleans of shape \(S, N\) = "
                                             r"\(20, 1200\), got bool of shape \(20, 10\)"):
        dataclasses.replace(out, filled=np.zeros((20, 10), bool))
    with pytest.raises(RecordingError, match=r"filled must be booleans .* got float64"):
        dataclasses.replace(out, filled=np.zeros((20, 1200)))

def test_bridging_refuses_what_a_line_cannot_fill(free_rec):
    too_long = _held(free_rec, "thumb_distal", 400, round(2 * MAX_BRIDGE_S * free_rec.rate_hz))
    with pytest.raises(RecordingError, match=r"^f.csv: sensor 'thumb_distal'.*longer than the "
                                             r"0.5 s bridged"):
        bridge_lost(too_long, source="f.csv")
    assert len(bridge_lost(too_long, max_s=2.0)[1]) == 1
    n = free_rec.n
    at_end = _held(free_rec, "thumb_distal", n - 15, 15)
    with pytest.raises(RecordingError, match="to the end of the recording"):
        bridge_lost(at_end)


def test_a_hold_on_a_still_sensor_is_told_by_the_others_moving(free_rec):
    # a held gyro that read almost nothing (the segment still) while the rest move
    rec = _held(free_rec, "forearm_1", 100, 30)  # in the still start
    k = rec.index("forearm_1")
    assert np.linalg.norm(rec.gyr[k, 99]) < 0.05
    assert [h.sensor for h in lost_stretches(rec)] == ["forearm_1"]
    # ... and not where nothing else moves either (one sensor alone, still)
    assert lost_stretches(rec.subset(("forearm_1",))) == []


@pytest.mark.parametrize("bad", [0.0, -1.0, float("nan"), "0.1"])
def test_arguments_are_checked(free_rec, bad):
    with pytest.raises(RecordingError, match="min_s"):
        lost_stretches(free_rec, min_s=bad)
    with pytest.raises(RecordingError, match="max_s"):
        bridge_lost(free_rec, max_s=bad)
    with pytest.raises(RecordingError, match="predict"):
        bridge_lost(free_rec, predict="yes")
    with pytest.raises(RecordingError, match="rec"):
        lost_stretches(np.zeros((1, 10, 3)))


def _filled(rec, sensor, start, n, value):
    k = rec.index(sensor)
    arrays = {name: getattr(rec, name).copy() for name in ("acc", "gyr", "mag")}
    for a in arrays.values():
        a[k, start:start + n] = value
    return dataclasses.replace(rec, **arrays)


def test_zeros_written_for_lost_samples_are_named_and_bridged(free_rec):
    # before: read as a magnetic disturbance, the sensor taken for still and in free fall
    rec = _filled(free_rec, "index_middle", 700, 30, 0.0)
    (h,) = lost_stretches(rec)
    assert (h.sensor, h.first, h.count, h.kind) == ("index_middle", 700, 30, "zeros")
    with pytest.raises(RecordingError, match=r"sensor 'index_middle' reads exactly 0 on every "
                                             r"accelerometer and gyro axis for 0.3 s .*written "
                                             r"as zeros by the logger"):
        check_recording(rec)
    one = _filled(free_rec, "index_middle", 700, 1, 0.0)  # a single sample is no reading either
    assert [h.kind for h in lost_stretches(one)] == ["zeros"]
    out, _ = bridge_lost(rec)
    assert lost_stretches(out) == [] and np.all(out.acc[rec.index("index_middle"), 700:730] != 0)
    check_recording(out)


def test_empty_cells_are_bridged_and_a_gap_at_the_start_is_refused(free_rec):
    rec = _filled(free_rec, "little_distal", 820, 12, np.nan)
    (h,) = lost_stretches(rec)
    assert (h.first, h.count, h.kind) == (820, 12, "missing")
    out, bridged = bridge_lost(rec)
    assert bridged == [h] and np.isfinite(out.acc).all() and np.isfinite(out.mag).all()
    k = rec.index("little_distal")
    lost = free_rec.gyr[k, 820:832]
    assert np.sqrt(np.mean((out.gyr[k, 820:832] - lost) ** 2)) < 0.5 * np.sqrt(np.mean(
        (bridge_lost(rec, predict=False)[0].gyr[k, 820:832] - lost) ** 2))
    with pytest.raises(RecordingError, match="from the start of the recording"):
        bridge_lost(_filled(free_rec, "little_distal", 0, 5, np.nan))
