import re
import warnings

import numpy as np
import pytest
from scipy import stats

from handsynth.errors import EstimationError, InvalidInputError
from handsynth.models import JOINT_NAMES
from handsynth.sensors.glove import (
    DIP_PIP_RATIO,
    GloveWarning,
    MotionModel,
    finger_joints,
    fit_motion_model,
)
from handsynth.sensors.glove._models import _ols


def _data(n=600, seed=0):
    """Sensors with known joint-3 dependence: index MCP on sensors 0 and 3 only."""
    rng = np.random.default_rng(seed)
    s = 1500 + rng.normal(0, 80, (n, 5))
    z = (s - s.mean(0)) / s.std(0)
    a = np.zeros((n, 20))
    fj = finger_joints()
    for i, f in enumerate(fj):
        a[:, f["j2"]] = 40 + 10 * z[:, i] + 2 * z[:, i] ** 2 - 0.5 * z[:, i] ** 3
    a[:, fj[1]["j3"]] = 30 + 8 * z[:, 0] - 6 * z[:, 3] + 3 * z[:, 3] ** 2 + rng.normal(0, 1, n)
    return s, a


def test_ols_t_values_match_scipy_simple_regression():
    rng = np.random.default_rng(3)
    x = rng.normal(0, 1, 200)
    y = 2.0 + 0.3 * x + rng.normal(0, 1, 200)
    fit = _ols(x[:, None], y, [(0, 1)], what="test")
    ref = stats.linregress(x, y)
    assert fit.t_values[0] == pytest.approx(ref.slope / ref.stderr, rel=1e-9)
    assert fit.r2 == pytest.approx(ref.rvalue**2, rel=1e-9)


def test_model3_keeps_only_significant_sensors_and_model4_adds_squares():
    s, a = _data()
    j = JOINT_NAMES.index("index_mcp_flex")
    m2 = fit_motion_model(s, a, model="model2", motion="standard")
    assert m2.fits[j].terms == tuple((f, 1) for f in range(5))
    t = m2.fits[j].t_values
    assert abs(t[0]) > 10 and abs(t[3]) > 10
    m3 = fit_motion_model(s, a, model="model3", motion="standard")
    kept = {f for f, _ in m3.fits[j].terms}
    assert {0, 3} <= kept and all(abs(t[f]) >= 2 for f in kept)
    assert all(abs(t[f]) < 2 for f in set(range(5)) - kept)
    m4 = fit_motion_model(s, a, model="model4", motion="standard")
    assert set(m4.fits[j].terms) == {(f, p) for f in kept for p in (1, 2)}
    # the squared term of sensor 3 is real, so model 4 fits better
    assert m4.fits[j].r2 > m3.fits[j].r2 + 0.01


def test_model1_cubic_recovers_pip_and_dip_is_two_thirds():
    s, a = _data()
    m = fit_motion_model(s, a, model="model1")
    pred = m.predict(s)
    for f in finger_joints():
        np.testing.assert_allclose(pred[:, f["j2"]], a[:, f["j2"]], atol=1e-6)  # eq. 2
        np.testing.assert_allclose(pred[:, f["j1"]], DIP_PIP_RATIO * pred[:, f["j2"]])  # eq. 1
    j = JOINT_NAMES.index("index_mcp_flex")
    assert m.fits[j].terms == ((1, 1), (1, 2), (1, 3))


def test_round_trip_through_dict():
    s, a = _data()
    m = fit_motion_model(s, a, model="model4", motion="tripod")
    back = MotionModel.from_dict(m.to_dict())
    np.testing.assert_allclose(back.predict(s), m.predict(s))


def test_few_samples_warn_with_t_values_and_too_few_raise():
    s, a = _data(n=40)
    with warnings.catch_warnings(record=True) as got:
        warnings.simplefilter("always")
        fit_motion_model(s, a, model="model2", motion="tripod")
    msgs = [str(w.message) for w in got if issubclass(w.category, GloveWarning)]
    assert len(msgs) == 1 and msgs[0].startswith("motion 'tripod' (model2): only 40 calibration samples")
    assert re.search(r"index_mcp_flex: sensor_thumb\^1 t=-?\d+\.\d\d, ", msgs[0])
    with pytest.raises(EstimationError, match="3 calibration samples cannot fit 4"):
        fit_motion_model(s[:3], a[:3], model="model1", motion="tripod")


def test_enough_samples_do_not_warn():
    s, a = _data(n=600)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        fit_motion_model(s, a, model="model4")


def test_dead_sensor_and_unknown_model_raise():
    s, a = _data()
    s[:, 3] = 1234.0
    with pytest.raises(EstimationError, match="sensor_ring reads a constant 1234"):
        fit_motion_model(s, a, model="model2", motion="standard")
    with pytest.raises(InvalidInputError, match="model must be one of .*, got 'model5'"):
        fit_motion_model(s, a, model="model5")


def test_readings_beyond_the_calibration_are_clamped_not_extrapolated():
    s, a = _data()
    m = fit_motion_model(s, a, model="model4")
    far = s.max(axis=0) + 5000.0
    edge = s.max(axis=0)
    np.testing.assert_allclose(m.predict(far[None]), m.predict(edge[None]))
    free = fit_motion_model(s, a, model="model4", clamp=False)
    assert np.abs(free.predict(far[None]) - m.predict(far[None])).max() > 100


def test_nan_rows_are_dropped_with_a_warning_naming_them():
    # one NaN angle used to make every joint's prediction NaN, without a word
    s, a = _data()
    a[7, 3] = np.nan
    s[11, 2] = np.nan
    with pytest.warns(GloveWarning, match=r"motion 'tripod' \(model4\): dropped 2 of 600 rows "
                                          r"with NaN \(first at row indices 7, 11\)"):
        m = fit_motion_model(s, a, model="model4", motion="tripod")
    clean = fit_motion_model(np.delete(s, [7, 11], axis=0), np.delete(a, [7, 11], axis=0),
                             model="model4", motion="tripod")
    np.testing.assert_allclose(m.predict(s[:20:3]), clean.predict(s[:20:3]))
    assert np.isfinite(m.predict(s[:6])).all()


def test_arguments_of_the_fit_are_checked_by_name():
    s, a = _data(n=100)
    for kwargs, msg in (
            ({"angles": a[:90]}, "sensors and angles must have the same number of rows, "
                                 "got 100 and 90"),
            ({"sensors": s.T}, r"sensors must have shape \(N, 5\), got \(5, 100\)"),
            ({"angles": a[:, :5]}, r"angles must have shape \(N, 20\), got \(100, 5\)"),
            ({"scale": np.zeros(5)}, r"scale must be positive, got \[0.0, "),
            ({"scale": np.ones(3)}, r"scale must have shape \(5,\), got \(3,\)"),
            ({"centre": np.zeros(3)}, r"centre must have shape \(5,\), got \(3,\)"),
            ({"centre": [np.nan] * 5}, "centre holds nan"),
            ({"t_threshold": -1.0}, "t_threshold must be >= 0, got -1.0")):
        args = {"sensors": s, "angles": a, **kwargs}
        with pytest.raises(InvalidInputError, match=msg):
            fit_motion_model(args.pop("sensors"), args.pop("angles"), model="model4", **args)


def test_motion_model_predict_checks_the_readings():
    s, a = _data(n=100)
    m = fit_motion_model(s, a, model="model4")
    with pytest.raises(InvalidInputError, match=r"sensors must have shape \(N, 5\), "
                                                r"got \(5, 100\)"):
        m.predict(s.T)
    with pytest.raises(InvalidInputError, match=r"sensors must have shape \(N, 5\), got \(7,\)"):
        m.predict(np.zeros(7))
    np.testing.assert_allclose(m.predict(s[0]), m.predict(s[:1]))
