import dataclasses
import warnings

import numpy as np
import pytest

from handsynth.errors import EstimationError, InvalidInputError
from handsynth.models import JOINT_LIMITS_DEG, JOINT_NAMES
from handsynth.sensors.glove import (
    ConstantEstimator,
    GatedEstimator,
    GloveEstimator,
    GloveWarning,
    RangeNormalizer,
    RegressionEstimator,
    SynergyEstimator,
    calibrate,
    estimator_from_dict,
    motions_for,
)


def test_every_estimator_satisfies_the_protocol(estimators):
    assert {"constant", "model1", "model2", "model3", "model4", "pooled_model4",
            "synergy", "model4+synergy"} <= set(estimators)
    for name, est in estimators.items():
        assert isinstance(est, GloveEstimator), name
        assert est.name == name
    for cls in (ConstantEstimator, RegressionEstimator, SynergyEstimator, GatedEstimator):
        assert any(type(e) is cls for e in estimators.values())
    assert not isinstance(object(), GloveEstimator)


def test_round_trip_through_dict_predicts_the_same(estimators, cal_rec):
    s = cal_rec.sensors[::50]
    for name, est in estimators.items():
        back = estimator_from_dict(est.to_dict())
        np.testing.assert_allclose(back.predict(s), est.predict(s), err_msg=name)


def test_nan_rows_give_nan_and_outputs_stay_in_limits(estimators, cal_rec):
    s = cal_rec.sensors[:200].copy()
    s[5, 2] = np.nan
    s[7] = [0, 4095, 0, 4095, 0]              # absurd readings: clipped, not wild
    for est in estimators.values():
        out = est.predict(s)
        assert out.shape == (200, 20)
        assert np.isnan(out[5]).all() and np.isfinite(np.delete(out, 5, axis=0)).all()
        ok = np.delete(out, 5, axis=0)
        assert (ok >= JOINT_LIMITS_DEG[:, 0]).all() and (ok <= JOINT_LIMITS_DEG[:, 1]).all()


def test_known_motion_beats_constant_on_held_out_trial(cal_rec):
    """Trials 0-2 calibrate, trial 3 (not seen) is estimated."""
    est = calibrate(cal_rec.select(cal_rec.trial < 3))
    test = cal_rec.select(cal_rec.trial == 3)
    mcp = [JOINT_NAMES.index(n) for n in JOINT_NAMES if n.endswith("mcp_flex")]
    const = np.abs(est["constant"].predict(test.sensors)[:, mcp] - test.truth[:, mcp]).mean()
    for m in motions_for("dg5"):
        sel = test.motion == m
        pred = est["model4"].predict(test.sensors[sel], motion=m)
        err = np.abs(pred[:, mcp] - test.truth[sel][:, mcp]).mean()
        assert err < const / 2, (m, err, const)
    mixed = est["model4"].predict(test.sensors)
    assert np.abs(mixed[:, mcp] - test.truth[:, mcp]).mean() < const / 2


def test_unknown_motion_and_bad_shapes(estimators):
    with warnings.catch_warnings():
        warnings.simplefilter("error", GloveWarning)     # refused before any range warning
        for name in ("model2", "model4+synergy"):
            with pytest.raises(InvalidInputError, match="motion 'wave' was not calibrated"):
                estimators[name].predict(np.zeros((3, 5)), motion="wave")
    with pytest.raises(InvalidInputError, match=r"shape \(N, 5\), got \(3, 4\)"):
        estimators["model2"].predict(np.zeros((3, 4)))
    with pytest.raises(InvalidInputError, match="unknown estimator type 'svm'"):
        estimator_from_dict({"type": "svm"})


def test_mixing_weights_sum_to_one(estimators, cal_rec):
    r = estimators["model4"].weights(cal_rec.sensors[::20])
    assert r.shape[1] == 3
    np.testing.assert_allclose(r.sum(axis=1), 1.0)


def test_range_normalizer_maps_holds_and_refuses_a_dead_sensor():
    src_o, src_f = np.full(5, 1000.0), np.full(5, 1400.0)
    tgt_o, tgt_f = np.full(5, 1500.0), np.full(5, 1900.0) + np.arange(5)
    n = RangeNormalizer(src_o, src_f, tgt_o, tgt_f)
    np.testing.assert_allclose(n.apply(np.stack([src_o, src_f])), np.stack([tgt_o, tgt_f]))
    src_f[3] = 1000.0
    with pytest.raises(EstimationError, match="sensor_ring reads the same"):
        RangeNormalizer(src_o, src_f, tgt_o, tgt_f)


def test_gate_keeps_calibrated_readings_and_hands_far_ones_to_the_fallback(estimators, cal_rec):
    gated = estimators["model4+synergy"]
    w = gated.fallback_weight(cal_rec.sensors)
    assert np.mean(w == 0) > 0.9            # chi-square(5) 95 % quantile: ~5 % beyond
    far = cal_rec.sensors[:3] + np.array([0.0, 0.0, 0.0, 0.0, 300.0])
    far[:, 1] = cal_rec.sensors[:, 1].max() + 200     # index far beyond, little bent
    assert (gated.fallback_weight(far) == 1).all()
    with pytest.warns(GloveWarning, match="sensor_index readings lie off the calibration's"):
        np.testing.assert_allclose(gated.predict(far), estimators["synergy"].predict(far))
    near = cal_rec.sensors[w == 0][:5]
    np.testing.assert_allclose(gated.predict(near), estimators["model4"].predict(near))


def _off_range_warnings(record) -> list[str]:
    return [str(w.message) for w in record if issubclass(w.category, GloveWarning)
            and "off the calibration's range" in str(w.message)]


@pytest.mark.parametrize("name", ["constant", "model4", "pooled_model4", "synergy",
                                  "model4+synergy"])
def test_readings_off_the_calibrations_range_are_warned_about_once(estimators, cal_rec, name):
    # readings scaled to 0-1 or of another converter: the models clamp them and
    # answered about the same angles on every row, without a word
    est = estimators[name]
    assert est.reading_range.shape == (2, 5)
    for wrong in (cal_rec.sensors[:50] / 4095.0, np.full((50, 5), 1e5)):
        with warnings.catch_warnings(record=True) as got:
            warnings.simplefilter("always")
            est.predict(wrong)
        msgs = _off_range_warnings(got)
        assert len(msgs) == 5, msgs                       # one per sensor, not one per layer
        assert all(m.startswith(f"{name}: 100 % of the sensor_") for m in msgs), msgs
        assert got[0].filename == __file__                # points at the caller's line
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        est.predict(cal_rec.sensors[::10])


def test_the_reading_range_round_trips_and_older_entries_have_none(estimators):
    for name, est in estimators.items():
        d = est.to_dict()
        np.testing.assert_array_equal(estimator_from_dict(d).reading_range, est.reading_range)
        d.pop("reading_range")
        assert estimator_from_dict(d).reading_range is None, name
    with pytest.raises(InvalidInputError, match=r"reading_range.*shape \(2, 5\)"):
        ConstantEstimator(posture=np.zeros(20), reading_range=np.zeros(5))
    with pytest.raises(InvalidInputError, match="lowest sensor_index reading 9 lies above"):
        ConstantEstimator(posture=np.zeros(20),
                          reading_range=[[0, 9, 0, 0, 0], [1, 1, 1, 1, 1]])


def test_a_single_model_ignores_the_motion(estimators, cal_rec):
    # the protocol: estimators that do not use motions ignore `motion`
    s = cal_rec.sensors[::25]
    pooled = estimators["pooled_model4"]
    np.testing.assert_array_equal(pooled.predict(s, motion="standard"), pooled.predict(s))
    np.testing.assert_array_equal(pooled.predict(s, motion="wave"), pooled.predict(s))
    for name in ("constant", "synergy", "model4+synergy", "pooled_model4"):
        assert estimators[name].predict(s, motion="standard").shape == (len(s), 20)


def test_gate_thresholds_are_checked(estimators, cal_rec):
    gated = estimators["model4+synergy"]
    for lo, hi, msg in ((float("nan"), 20.5, "lo must be a finite number, got nan"),
                        (11.0, float("inf"), "hi must be a finite number, got inf"),
                        (30.0, 20.5, "lo must be below hi, got lo 30 and hi 20.5"),
                        (20.5, 20.5, "lo must be below hi")):
        with pytest.raises(InvalidInputError, match=f"GatedEstimator.{msg}"):
            dataclasses.replace(gated, lo=lo, hi=hi)
    with pytest.raises(InvalidInputError, match="primary must be a RegressionEstimator"):
        GatedEstimator(primary=estimators["synergy"], fallback=estimators["synergy"])
    ok = dataclasses.replace(gated, lo=5, hi=40)
    assert np.isfinite(ok.predict(cal_rec.sensors[::50])).all()


def test_estimator_fields_are_checked_and_converted(estimators):
    const = ConstantEstimator(posture=[0.0] * 20)
    assert const.to_dict()["posture"] == [0.0] * 20
    with pytest.raises(InvalidInputError, match=r"ConstantEstimator.posture must have shape "
                                                r"\(20,\), got \(5,\)"):
        ConstantEstimator(posture=np.zeros(5))
    with pytest.raises(InvalidInputError, match="ConstantEstimator.posture holds nan"):
        ConstantEstimator(posture=[np.nan] * 20)
    with pytest.raises(InvalidInputError, match="ConstantEstimator.name must be a non-empty"):
        ConstantEstimator(posture=np.zeros(20), name=None)
    syn = estimators["synergy"]
    with pytest.raises(InvalidInputError, match=r"SynergyEstimator.scale must be positive"):
        dataclasses.replace(syn, scale=np.zeros(5))
    with pytest.raises(InvalidInputError, match=r"SynergyEstimator.bend_coef must have shape"):
        dataclasses.replace(syn, bend_coef=np.zeros((4, 5)))
    with pytest.raises(InvalidInputError, match="glove kind"):
        dataclasses.replace(syn, kind="cyber")
    reg = estimators["model4"]
    with pytest.raises(InvalidInputError, match="RegressionEstimator.models must map"):
        dataclasses.replace(reg, models={})
    with pytest.raises(InvalidInputError, match=r"models\['standard'\] must be a MotionModel"):
        dataclasses.replace(reg, models={"standard": None})


def test_range_normalizer_takes_lists():
    o, f = [1000.0] * 5, [1400.0] * 5
    n = RangeNormalizer(o, f, [1500.0] * 5, [1900.0] * 5)
    assert isinstance(n.source_open, np.ndarray)
    np.testing.assert_allclose(n.apply(np.array([o, f])), [[1500.0] * 5, [1900.0] * 5])
    with pytest.raises(EstimationError, match="source_fist must be 5 finite readings"):
        RangeNormalizer(o, ["a"] * 5, o, f)
