import dataclasses
import re

import pytest

from handsynth.sensors.imu import (
    CARRIED,
    HINGES,
    RIGID,
    delayed,
    late_sensors,
    sensor_lags,
    truth_chain_model,
    truth_link_frames,
)


@pytest.fixture(scope="module")
def frames(free_rec, imu_hand):
    return truth_link_frames(free_rec, truth_chain_model(free_rec), imu_hand)


def _late(rec, name, lag):
    return dataclasses.replace(delayed(rec, name, lag), truth=None)


def test_sensors_in_step_read_no_lag(free_rec, frames):
    lags = sensor_lags(free_rec, frames, static_n=100)
    # the thumb's CARRIED pair needs the two magnetometers to agree: not these, uncorrected
    assert set(lags) == set(HINGES) | set(RIGID)
    for lag_s, cor in lags.values():
        assert abs(lag_s) < 0.005 and cor > 0.9
    assert late_sensors(free_rec, frames, static_n=100) is None


@pytest.mark.parametrize("name, lag", [("index_middle", 3), ("ring_distal", 2),
                                       ("little_proximal", 5), ("forearm_1", 2),
                                       ("forearm_3", 2), ("hand_radial", 2),
                                       ("hand_ulnar", 3)])
def test_a_late_stream_is_named(free_rec, frames, name, lag):
    # before: a sensor 20-100 ms late read its joints 2-13 deg off without a word
    lags = sensor_lags(_late(free_rec, name, lag), frames, static_n=100)
    off = {pair: lag_s for pair, (lag_s, cor) in lags.items() if abs(lag_s) > 0.005}
    assert off and all(name in pair for pair in off)
    for (_, dist), lag_s in off.items():
        assert lag_s == pytest.approx(lag / 100 if dist == name else -lag / 100, abs=0.004)
    warning = late_sensors(_late(free_rec, name, lag), frames, static_n=100)
    m = re.search(rf"{name} (\d+) ms behind", warning or "")
    assert m and abs(int(m[1]) - lag * 10) <= 3, warning
    if name.endswith("_middle") or name == "forearm_1":
        assert f"({name} in two pairs: that sensor's clock)" in warning


def test_a_lag_under_the_limit_is_not_named(free_rec, frames):
    assert late_sensors(_late(free_rec, "index_middle", 1), frames, static_n=100) is None


def test_a_short_or_still_recording_is_not_judged(free_rec, frames):
    assert sensor_lags(free_rec.slice(0, 50), frames, static_n=10) == {}
    still = free_rec.slice(0, 150)   # the still start: no turn to correlate
    assert late_sensors(still, frames, static_n=100) is None


def test_pairs_without_both_sensors_are_left_out(free_rec, frames):
    sub = free_rec.subset(("index_proximal", "index_middle", "hand_radial"))
    assert set(sensor_lags(sub, frames, static_n=100)) == {("index_proximal", "index_middle")}
    partial = {k: v for k, v in frames.items() if k != "index_middle"}
    assert ("index_proximal", "index_middle") not in sensor_lags(free_rec, partial, static_n=100)


def test_the_thumbs_mcp_axis_is_carried_over_by_the_still_start(ideal_rec, frames):
    """The metacarpal sensor's link frame holds the CMC's axis: the MCP's is turned into its
    frame by gravity and the field over the still start.  Left out without magnetometers,
    and where the two read the field at angles to gravity 5 deg or more apart (a magnet)."""
    pair = CARRIED[0]
    assert pair == ("thumb_metacarpal", "thumb_proximal")
    lag_s, cor = sensor_lags(ideal_rec, frames, static_n=100)[pair]
    assert abs(lag_s) < 0.005 and cor > 0.99
    # about another axis (the CMC's) the two series agree less, and lag falsely
    wrong = dict(frames, thumb_proximal=frames["thumb_metacarpal"])
    lag_w, cor_w = sensor_lags(ideal_rec, wrong, static_n=100)[pair]
    assert cor_w < 0.95 and abs(lag_w) > 0.015
    late = late_sensors(_late(ideal_rec, "thumb_metacarpal", 2), frames, static_n=100)
    assert late is not None and re.search(r"thumb_metacarpal (\d+) ms behind thumb_proximal",
                                          late), late
    assert pair not in sensor_lags(dataclasses.replace(ideal_rec, mag=None), frames,
                                   static_n=100)
    mag = ideal_rec.mag.copy()
    mag[ideal_rec.sensors.index("thumb_metacarpal")] += [60.0, 0.0, 0.0]  # uT: a magnet
    assert pair not in sensor_lags(dataclasses.replace(ideal_rec, mag=mag), frames,
                                   static_n=100)


def test_track_with_a_calibration_warns_of_a_late_stream(worn):
    # the calibration's own link frames (not the simulator's axes) judge the hinges
    cal, rec = worn
    assert late_sensors(rec, cal.frames, static_n=100) is None
    with pytest.warns(UserWarning, match=r"sensor streams out of step: index_distal \d+ ms behind "
                                         r"index_middle"):
        cal.track(_late(rec, "index_distal", 3), sensor_calibration=False)


def test_delayed_refuses_what_it_cannot_delay(free_rec):
    from handsynth.errors import InvalidInputError

    with pytest.raises(InvalidInputError, match="sensor 'wrist' is not in the recording"):
        delayed(free_rec, "wrist", 2)
    with pytest.raises(InvalidInputError, match="samples"):
        delayed(free_rec, "index_distal", 0)
    with pytest.raises(InvalidInputError, match="samples"):
        delayed(free_rec, "index_distal", free_rec.n)


@pytest.mark.parametrize("name, lag", [("index_middle", 3), ("ring_distal", 2),
                                       ("little_proximal", 5), ("forearm_1", 2),
                                       ("forearm_3", 4)])
def test_the_late_sensor_is_read_as_the_fewest_off(free_rec, frames, name, lag):
    """A proximal phalanx late reads early against the middle one only; the middle and distal
    agree: it alone is off, as a middle phalanx is when it reads late against both."""
    from handsynth.sensors.imu import late_offsets

    offsets, undecided = late_offsets(_late(free_rec, name, lag), frames, static_n=100)
    assert list(offsets) == [name] and undecided == []
    assert offsets[name] == pytest.approx(lag / 100, abs=0.002)


def test_the_hands_two_sensors_are_not_told_apart(free_rec, frames):
    from handsynth.sensors.imu import late_offsets

    assert late_offsets(free_rec, frames, static_n=100) == ({}, [])
    offsets, undecided = late_offsets(_late(free_rec, "hand_radial", 3), frames, static_n=100)
    assert offsets == {} and [set(c) for c in undecided] == [{"hand_radial", "hand_ulnar"}]


def test_realign_late_reads_a_stream_earlier_by_a_fraction_of_a_sample():
    import numpy as np

    from handsynth.sensors.imu import ImuRecording, realign_late

    t = np.arange(50.0)
    ramp = np.stack([np.column_stack([t, 2 * t, t * t])] * 2)
    rec = ImuRecording(100.0, ("a", "b"), ramp, ramp.copy(), ramp.copy())
    got = realign_late(rec, {"a": 0.025, "b": -0.01})   # a 2.5 samples late, b 1 sample early
    for c in (got.acc, got.gyr, got.mag):
        np.testing.assert_allclose(c[0, :47, 0], t[:47] + 2.5)
        np.testing.assert_allclose(c[1, 1:, 1], 2 * (t[1:] - 1))
    # past the end (before the start) read back as in a mirror, not held, and marked
    np.testing.assert_allclose(got.acc[0, 47:, 0], [49 - 0.5, 49 - 1.5, 49 - 2.5])
    assert got.acc[1, 0, 0] == 1.0
    assert got.filled[0].sum() == 3 and got.filled[0, 47:].all()
    assert got.filled[1].sum() == 1 and got.filled[1, 0]
    np.testing.assert_array_equal(realign_late(rec, {}).acc, rec.acc)


def test_track_reads_a_late_stream_realigned(worn):
    import warnings

    import numpy as np

    cal, rec = worn
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        made = cal.track(rec, sensor_calibration=False)["angles"]
        late = cal.track(_late(rec, "index_distal", 5), sensor_calibration=False)["angles"]
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        out = cal.track(_late(rec, "index_distal", 5), sensor_calibration=False,
                        realign_late=True)
    said = [str(w.message) for w in caught]
    assert out["realigned"] == {"index_distal": pytest.approx(0.05, abs=0.002)}
    assert [m for m in said if "realigned" in m or "out of step" in m] == [
        "read realigned: index_distal 50 ms earlier (realign_late)"], said
    err_late = np.nanmax(np.abs(late - made))
    err = np.nanmax(np.sqrt(np.nanmean((out["angles"] - made) ** 2, axis=0)))
    assert err_late > 2.0 and err < 0.1, (err_late, err)


def test_sensors_exchanged_and_a_stream_late_are_read_as_made_together(worn):
    """Put back first, then realigned: either alone leaves the other fault's error."""
    import warnings

    import numpy as np

    cal, rec = worn
    i, j = rec.index("index_proximal"), rec.index("middle_proximal")
    order = list(range(len(rec.sensors)))
    order[i], order[j] = j, i
    swapped = dataclasses.replace(rec, acc=rec.acc[order], gyr=rec.gyr[order], mag=rec.mag[order])
    faulty = _late(swapped, "ring_middle", 4)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        made = cal.track(rec, sensor_calibration=False)["angles"]
        worst = {}
        for undo, realign in ((True, False), (False, True), (True, True)):
            got = cal.track(faulty, sensor_calibration=False, undo_misplaced=undo,
                            realign_late=realign)["angles"]
            worst[undo, realign] = np.nanmax(np.sqrt(np.nanmean((got - made) ** 2, axis=0)))
    assert worst[True, True] < 0.05, worst
    assert min(worst[True, False], worst[False, True]) > 1.0, worst
