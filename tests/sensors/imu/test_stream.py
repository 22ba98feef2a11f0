import warnings

import numpy as np
import pytest

from handsynth.errors import InvalidInputError, RecordingError
from handsynth.sensors.imu import FILTER4B, ImuStream, StaticStart, TrackedSamples


def _feed(stream, rec, sizes):
    """Push `rec` in packets of `sizes` (cycled); return everything finished, closed."""
    out, i, k = [], 0, 0
    while i < rec.n:
        n = sizes[k % len(sizes)]
        out.append(stream.push(rec.acc[:, i:i + n], rec.gyr[:, i:i + n],
                               None if rec.mag is None else rec.mag[:, i:i + n]))
        i, k = i + n, k + 1
    out.append(stream.close())
    return out


def _joined(parts):
    return (np.concatenate([p.t_s for p in parts]), np.concatenate([p.quat for p in parts], axis=1),
            np.concatenate([p.angles_deg for p in parts]),
            {f: np.concatenate([p.tips_m[f] for p in parts if len(p)]) for f in parts[-1].tips_m})


@pytest.mark.parametrize("options", [None, FILTER4B], ids=["filter4", "filter4b"])
def test_a_stream_reads_what_track_reads(worn, options):
    """Sample by sample and in uneven packets, the stream's answers are track's."""
    cal, rec = worn
    rec = rec.slice(0, 700)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # track's notes on the simulated recording
        whole = cal.track(rec, options=options)
    sub = rec.subset(cal.sensors)
    for sizes in ([1], [3, 1, 37, 2, 150, 5]):
        stream = ImuStream(cal, rate_hz=rec.rate_hz, options=options, start_s=2.5)
        with warnings.catch_warnings():
            warnings.simplefilter("error")  # the warm-up of this recording warns of nothing
            parts = _feed(stream, sub, sizes)
        t, q, angles, tips = _joined(parts)
        # nothing before the static start and the common rotation (4 s), then everything
        first = next(k for k, p in enumerate(parts) if len(p))
        assert sum(sizes[k % len(sizes)] for k in range(first + 1)) >= stream.warmup_n == 401
        np.testing.assert_allclose(t, 2.5 + np.arange(rec.n) / rec.rate_hz)
        np.testing.assert_allclose(q, whole["quat"], rtol=0, atol=1e-9)
        np.testing.assert_allclose(angles, whole["angles"], rtol=0, atol=1e-7)
        for f, v in whole["tips"].items():
            np.testing.assert_allclose(tips[f], v, rtol=0, atol=1e-9)
    assert isinstance(parts[-1], TrackedSamples) and len(parts[-1]) == 1  # close: the last


def test_lost_readings_are_predicted_then_refused(worn):
    cal, rec = worn
    sub = rec.subset(cal.sensors).slice(0, 800)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        clean = _joined(_feed(ImuStream(cal, rate_hz=rec.rate_hz), sub, [10]))[2]
    k = cal.sensors.index("index_middle")
    acc, gyr, mag = sub.acc.copy(), sub.gyr.copy(), sub.mag.copy()
    gyr[k, 600:620] = np.nan            # 0.2 s lost
    acc[k, 650, 1] = np.inf
    lost = type(sub)(sub.rate_hz, sub.sensors, acc, gyr, mag)
    stream = ImuStream(cal, rate_hz=rec.rate_hz)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        parts = _feed(stream, lost, [10])
    held = _joined(parts)[2]
    assert stream.state.held_count[k] == 21 and stream.state.held_count.sum() == 21
    flags = np.concatenate([p.held for p in parts], axis=1)
    assert flags.shape == (20, 800) and flags.sum() == 21
    assert flags[k, 600:620].all() and flags[k, 650]
    assert np.isfinite(held).all() and not stream.state.models  # forgotten once read again
    err = np.abs(held - clean)
    assert np.abs(held[:599] - clean[:599]).max() == 0.0  # 599 reads 600 (its derivative)
    # predicted from the other sensors, the sensor's joints (index PIP and DIP) stay within
    # a degree through the gap (holding its last reading: 8.0 deg, a scratch run)
    assert 0.1 < err[600:625, 6:8].max() < 2.0
    gyr[k, 600:630] = np.nan            # 0.3 s: more than max_hold_s
    stream = ImuStream(cal, rate_hz=rec.rate_hz, max_hold_s=0.25)
    with pytest.raises(RecordingError, match=r"sensor index_middle: readings not finite for "
                                             r"more than 0.25 s .* t = 6.250 s: a sensor lost"):
        _feed(stream, type(sub)(sub.rate_hz, sub.sensors, acc, gyr, mag), [10])
    with pytest.raises(RecordingError, match=r"closed \(by close\(\), or by the error that "
                                             r"stopped it\)"):
        stream.push(sub.acc[:, 700], sub.gyr[:, 700], sub.mag[:, 700])


def test_a_sensor_lost_before_enough_was_seen_is_held(worn):
    """Right after a short warm-up too few samples were read to fit a prediction."""
    cal, rec = worn
    sub = rec.subset(cal.sensors).slice(0, 300)
    gyr = sub.gyr.copy()
    gyr[3, 105:110] = np.nan
    stream = ImuStream(cal, rate_hz=rec.rate_hz, static=StaticStart(1.0, None, None))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        stream.push(sub.acc[:, :106], gyr[:, :106], sub.mag[:, :106])
        assert stream.tracking and stream.state.held_run[3] == 1 and not stream.state.models
        stream.push(sub.acc[:, 106:300], gyr[:, 106:300], sub.mag[:, 106:300])
    assert stream.state.held_count[3] == 5 and stream.state.held_run[3] == 0


def test_a_stream_says_what_it_lacks(worn):
    cal, rec = worn
    sub = rec.subset(cal.sensors)
    stream = ImuStream(cal, rate_hz=rec.rate_hz, static=StaticStart(1.0, None, None))
    assert stream.warmup_n == 101 and not stream.tracking
    assert len(stream.push(sub.acc[:, :50], sub.gyr[:, :50], sub.mag[:, :50])) == 0
    with pytest.raises(RecordingError, match=r"mag given in some pushes and not in others"):
        stream.push(sub.acc[:, 50], sub.gyr[:, 50])
    with pytest.raises(RecordingError, match=r"gyr has shape \(19, 3\), expected \(20, 3\) or "
                                             r"\(20, n, 3\) with n = 1: one row per sensor"):
        stream.push(sub.acc[:, 50], sub.gyr[1:, 50], sub.mag[:, 50])
    with pytest.raises(RecordingError, match=r"ended after 50 samples, before its static start "
                                             r"and common rotation \(101 samples at 100 Hz\)"):
        stream.close()
    with pytest.raises(RecordingError, match="the stream is closed"):
        stream.push(sub.acc[:, 50], sub.gyr[:, 50], sub.mag[:, 50])


def test_a_start_that_moves_is_refused_when_the_warm_up_is_read(worn):
    cal, rec = worn
    sub = rec.subset(cal.sensors)
    gyr = sub.gyr.copy()
    gyr[:, :100] += np.radians(60.0)  # deg/s read as rad/s: a turning "still" start
    stream = ImuStream(cal, rate_hz=rec.rate_hz, static=StaticStart(1.0, None, None))
    assert len(stream.push(sub.acc[:, :100], gyr[:, :100], sub.mag[:, :100])) == 0
    with pytest.raises(RecordingError, match=r"stream: sensor .* gyro reads .* rad/s during the "
                                             r"static start"):
        stream.push(sub.acc[:, 100], gyr[:, 100], sub.mag[:, 100])


def test_six_axis_sensors_stream_as_they_track(worn):
    """Without magnetometers (headings from the common rotation) the answers are track's."""
    import dataclasses

    cal, rec = worn
    rec = dataclasses.replace(rec.subset(cal.sensors).slice(0, 600), mag=None)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        whole = cal.track(rec)["angles"]
        streamed = _joined(_feed(ImuStream(cal, rate_hz=rec.rate_hz), rec, [7]))[2]
    np.testing.assert_allclose(streamed, whole, rtol=0, atol=1e-7)


def _copied(rec):
    import dataclasses

    return dataclasses.replace(rec, acc=rec.acc.copy(), gyr=rec.gyr.copy(), mag=rec.mag.copy())


def _exchanged(rec, a, b):
    i, j = rec.sensors.index(a), rec.sensors.index(b)
    out = _copied(rec)
    for c in (out.acc, out.gyr, out.mag):
        c[[i, j]] = c[[j, i]]
    return out


def _said(rec, cal, **options):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        _feed(ImuStream(cal, rate_hz=rec.rate_hz, **options), rec, [25])
    return [str(w.message) for w in caught if "the stream's" in str(w.message)]


def test_each_stretch_is_checked_as_track_checks_a_recording(worn):
    """Sensors exchanged and a stream late are told in the stretch they are read in, once."""
    from handsynth.sensors.imu import delayed

    cal, rec = worn
    sub = rec.subset(cal.sensors)
    assert _said(sub, cal, check_s=5.0) == []                      # as worn: nothing
    said = _said(_exchanged(sub, "index_proximal", "middle_proximal"), cal, check_s=5.0)
    assert len(said) == 1 and said[0].startswith(                   # two stretches, said once
        "the stream's 0.0-5.0 s: sensors read as exchanged since the calibration: "
        "index_proximal and middle_proximal (their joints agree")
    said = _said(delayed(sub, "ring_middle", 3), cal, check_s=5.0)
    assert len(said) == 1 and "out of step: ring_middle 30 ms behind" in said[0]
    turned = _copied(sub)                          # the thumb's phalanx clipped on back to front
    for c in (turned.acc, turned.gyr, turned.mag):
        c[sub.index("thumb_proximal"), :, :2] *= -1.0
    said = _said(turned, cal, check_s=5.0)
    assert len(said) == 1 and said[0].startswith(
        "the stream's 0.0-5.0 s: sensors read as turned on their segments since the calibration: "
        "thumb_proximal half a turn about its z axis")
    # late from 5 s on: told in the second stretch, its gyro biases from the still start
    late, k = _copied(sub), sub.sensors.index("ring_middle")
    d = delayed(sub, "ring_middle", 3)
    for c, v in ((late.acc, d.acc), (late.gyr, d.gyr), (late.mag, d.mag)):
        c[k, 500:] = v[k, 500:]
    said = _said(late, cal, check_s=5.0, start_s=10.0)
    assert len(said) == 1 and said[0].startswith(
        "the stream's 15.0-20.0 s: sensor streams out of step: ring_middle 30 ms behind")
    assert _said(_exchanged(sub, "index_proximal", "middle_proximal"), cal, check_s=None) == []
    with pytest.raises(InvalidInputError, match=r"check_s must be a finite number >= 5, got 2.0"):
        ImuStream(cal, rate_hz=100.0, check_s=2.0)


def test_a_later_stretch_reads_its_lags_from_the_still_start(worn):
    """A stretch that does not begin still reads the gyros' biases from the still start given."""
    from handsynth.sensors.imu import delayed, sensor_lags

    cal, rec = worn
    late = delayed(cal.correct(rec.subset(cal.sensors)), "ring_middle", 3)
    later = late.slice(600, 1100)
    got = sensor_lags(later, cal.frames, static_n=200, still=late.slice(0, 200))
    assert got[("ring_proximal", "ring_middle")][0] == pytest.approx(0.03, abs=0.004)
    # read from the stretch's own first samples (moving) instead, the biases are off
    own = sensor_lags(later, cal.frames, static_n=200)
    assert own != got
