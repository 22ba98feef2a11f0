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
                                          r"counts in all 100 valid samples"):
        chk = check_sensors(s, adc_max=4095, where="x.csv")
    assert chk.dead == (2,)


def test_saturated_sensor_is_named_with_counts():
    s = _live()
    s[:12, 4] = 4095
    with pytest.warns(GloveWarning, match=r"sensor_little is saturated \(at 4095 counts\) "
                                          r"in 12 of 100 samples \(12.0 %\)"):
        chk = check_sensors(s, adc_max=4095, where="x.csv")
    assert chk.saturated_sensors == (4,)


def test_nan_rows_are_listed():
    s = _live()
    s[[3, 50], 1] = np.nan
    with pytest.warns(GloveWarning, match=r"2 of 100 rows have a NaN reading \(first rows "
                                          r"3, 50\)"):
        chk = check_sensors(s, adc_max=4095, where="x.csv")
    assert chk.nan_rows.tolist() == [3, 50]
