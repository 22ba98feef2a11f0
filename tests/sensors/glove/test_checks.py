import re

import numpy as np
import pytest

from handsynth.sensors.glove import GloveWarning, check_sensors


def _live(n=100, seed=0):
    return 1500 + np.random.default_rng(seed).normal(0, 3, (n, 5)).round()


def test_clean_readings_pass_quietly(recwarn):
    chk = check_sensors(_live(), adc_max=4095, where="x.csv")
    assert chk.nan_rows.size == 0 and chk.dead == () and chk.saturated_sensors == ()
    assert not [w for w in recwarn if issubclass(w.category, GloveWarning)]


def test_dead_sensor_is_named():
    s = _live()
    s[:, 2] = 812.0
    with pytest.warns(GloveWarning, match=r"x.csv: sensor_middle is dead: it reads 812 "
                                          r"counts in all 100 rows with five "
                                          r"readings"):
        chk = check_sensors(s, adc_max=4095, where="x.csv")
    assert chk.dead == (2,)


def test_saturated_sensor_is_named_with_counts():
    s = _live()
    s[:12, 4] = 4095
    with pytest.warns(GloveWarning, match=r"sensor_little is saturated \(at 4095 counts\) "
                                          r"in 12 of 100 rows \(12.0 %\)"):
        chk = check_sensors(s, adc_max=4095, where="x.csv")
    assert chk.saturated_sensors == (4,)


def test_nan_rows_are_listed():
    s = _live()
    s[[3, 50], 1] = np.nan
    with pytest.warns(GloveWarning, match=r"2 of 100 rows have a NaN reading \("
                                          r"first at row indices 3, 50\)"):
        chk = check_sensors(s, adc_max=4095, where="x.csv")
    assert chk.nan_rows.tolist() == [3, 50]


def test_a_negative_reading_is_below_the_range_not_saturated():
    # a negative reading was called "saturated (at 0 counts)"
    s = _live()
    s[:5, 1] = -3.0
    with pytest.warns(GloveWarning) as got:
        chk = check_sensors(s, adc_max=4095, where="x.csv")
    msgs = [str(w.message) for w in got]
    assert any("x.csv: sensor_index is below the converter's range (negative, down to -3 "
               "counts) in 5 of 100 rows (5.0 %)" in m for m in msgs), msgs
    assert not any("saturated" in m for m in msgs), msgs
    assert chk.below[:, 1].sum() == 5 and not chk.saturated.any()
    assert chk.out_of_range_sensors == (1,) and chk.off_scale[:5, 1].all()


def test_a_reading_above_full_scale_asks_for_the_full_scale():
    s = _live()
    with pytest.warns(GloveWarning) as caught:  # one warning per sensor
        chk = check_sensors(s, adc_max=1000, where="x.csv")
    assert any(re.search(r"sensor_thumb is above the full scale 1000 counts \(up to 15\d\d\) in "
                         r"100 of 100 rows .*--adc-max", str(w.message)) for w in caught)
    assert chk.above.all() and not chk.saturated.any()


def test_a_sensor_stuck_at_full_scale_is_saturated_not_dead(recwarn):
    s = _live()
    s[:, 3] = 4095
    chk = check_sensors(s, adc_max=4095, where="x.csv")
    msgs = [str(w.message) for w in recwarn if issubclass(w.category, GloveWarning)]
    assert chk.dead == () and chk.saturated_sensors == (3,)
    assert msgs == ["x.csv: sensor_ring is saturated (at 4095 counts) in 100 of 100 rows "
                    "(100.0 %)"]


@pytest.mark.parametrize(("rows", "words"), [
    (slice(None), "saturated or disconnected (at 0 counts) in 100 of 100 rows (100.0 %)"),
    (slice(0, 10), "saturated (at 0 counts) in 10 of 100 rows (10.0 %)"),
])
def test_a_sensor_at_zero_in_every_row_may_be_disconnected(recwarn, rows, words):
    s = _live()
    s[rows, 1] = 0
    check_sensors(s, adc_max=4095, where="x.csv")
    msgs = [str(w.message) for w in recwarn if issubclass(w.category, GloveWarning)]
    assert msgs == [f"x.csv: sensor_index is {words}"]


def test_rows_are_named_by_file_line_when_known():
    s = _live()
    s[[3, 50], 1] = np.nan
    with pytest.warns(GloveWarning, match=r"x.csv: 2 of 100 rows have a NaN reading \(first "
                                          r"at lines 5, 52\)"):
        check_sensors(s, adc_max=4095, where="x.csv", lines=np.arange(2, 102))


def test_readings_beyond_a_narrow_calibration_name_that_cause_too():
    # the warning named only another glove, full scale or wearing; a calibration recording
    # that did not bend the finger this far gives the same clamped angles
    from handsynth.sensors.glove._checks import check_reading_range

    s = np.tile(np.linspace(1500.0, 2500.0, 100)[:, None], (1, 5))
    with pytest.warns(GloveWarning, match="a calibration recording that bent the finger less "
                                          "than these readings does needs recording again"):
        assert check_reading_range(s, np.full(5, 1500.0), np.full(5, 1800.0), where="w") \
            == (0, 1, 2, 3, 4)


def test_two_channels_exchanged_are_named():
    # two cables plugged into each other's inputs: each sensor's readings lay off its own
    # range, and the warning named another glove, full scale or wearing only
    import warnings

    from handsynth.sensors.glove._checks import check_reading_range

    low = np.array([1400.0, 1250.0, 1550.0, 1600.0, 1300.0])
    high = np.array([1600.0, 1650.0, 1900.0, 2050.0, 1750.0])
    rng = np.random.default_rng(0)
    s = low + (high - low) * rng.random((200, 5))
    exchanged = s[:, [0, 2, 1, 3, 4]]  # index and middle
    with warnings.catch_warnings(record=True) as got:
        warnings.simplefilter("always")
        assert check_reading_range(exchanged, low, high, where="w") == (1, 2)
    said = [str(w.message) for w in got]
    assert "its readings fit sensor_middle's range and sensor_middle's fit its: were the two " \
           "channels exchanged?" in said[0]
    assert "its readings fit sensor_index's range and sensor_index's fit its" in said[1]
    # off range for another cause (a new wearing, all shifted): no exchange is named
    with warnings.catch_warnings(record=True) as got:
        warnings.simplefilter("always")
        check_reading_range(s + 600.0, low, high, where="w")
    assert got and not any("exchanged" in str(w.message) for w in got)
