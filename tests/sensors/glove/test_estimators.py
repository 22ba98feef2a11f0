import numpy as np
import pytest

from handsynth.errors import EstimationError, InvalidInputError
from handsynth.models import JOINT_LIMITS_DEG, JOINT_NAMES
from handsynth.sensors.glove import (
    ConstantEstimator,
    GatedEstimator,
    GloveEstimator,
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
    with pytest.raises(InvalidInputError, match="motion 'wave' was not calibrated"):
        estimators["model2"].predict(np.zeros((3, 5)), motion="wave")
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
    np.testing.assert_allclose(gated.predict(far), estimators["synergy"].predict(far))
    near = cal_rec.sensors[w == 0][:5]
    np.testing.assert_allclose(gated.predict(near), estimators["model4"].predict(near))
