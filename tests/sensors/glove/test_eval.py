import json
import warnings

import numpy as np
import pytest

from handsynth.errors import InvalidInputError
from handsynth.models import FINGERS
from handsynth.sensors.glove import (
    CONDITIONS,
    LATER_CONDITIONS,
    OTHER_MOTIONS,
    EvalOptions,
    GloveWarning,
    eval_setup,
    evaluate,
    finger_joints,
    simulate_session,
)


@pytest.fixture(scope="module")
def result():
    return evaluate(EvalOptions(kind="dg5", trials=3, test_trials=1, seed=4))


def test_layout_matches_the_seed_tables(result):
    json.dumps(result)                                  # serialisable
    assert set(result["conditions"]) == set(CONDITIONS)
    loto = result["conditions"]["loto"]["representative"]
    assert loto["motions"] == ["standard", "lateral_contact", "tripod"]
    for variant in ("model1/known", "model2/known", "model3/known", "model4/known",
                    "model4/mixed", "pooled_model4", "synergy", "constant"):
        rows = loto["tables"][variant]
        assert set(rows) == {"standard", "lateral_contact", "tripod", "Ave."}
        for cell in rows["standard"].values():
            assert {"mcp_error_deg", "r2", "baseline_mcp_error_deg", "truth_sd_deg"} <= set(cell)
        assert list(rows["Ave."]) == list(FINGERS)
    assert set(result["fit_r2"]["model4"]["tripod"]) == set(FINGERS)
    other = result["conditions"]["second_user"]["other"]["tables"]
    assert "model4/known" not in other and "model4/mixed" in other


def test_estimates_beat_the_constant_and_range_calibration_matters(result):
    c = result["conditions"]
    # the second user is the hard case: only "better than the constant" is pinned there
    for cond, factor in (("loto", 0.4), ("new_session", 0.5), ("second_user", 0.8)):
        s = c[cond]["representative"]["summary"]
        assert s["model4/mixed"]["mcp_error_deg"] < factor * s["constant"]["mcp_error_deg"], cond
        assert s["constant"]["baseline_mcp_error_deg"] == s["constant"]["mcp_error_deg"]
    raw = c["second_user_raw"]["representative"]["summary"]["model4/mixed"]["mcp_error_deg"]
    norm = c["second_user"]["representative"]["summary"]["model4/mixed"]["mcp_error_deg"]
    assert raw > 1.5 * norm


def test_options_are_checked():
    with pytest.raises(InvalidInputError, match=r"trials \(--trials\) must be an integer in \[3, 100\]"):
        EvalOptions(trials=2)
    with pytest.raises(InvalidInputError, match="glove kind"):
        EvalOptions(kind="cyber")


def test_setup_gives_the_evaluation_s_own_samples(result):
    setup = eval_setup(EvalOptions(kind="dg5", trials=3, test_trials=1, seed=4))
    mcp = [f["j3"] for f in finger_joints()]
    for cond in LATER_CONDITIONS:
        data = setup.test_data(cond, "other")
        assert data.recording.n_samples == len(data.sensors)
        assert (data.normalizer is None) == (cond == "second_user_raw")
        again = simulate_session(data.user, data.donning, list(OTHER_MOTIONS), trials=1,
                                 seed=data.session_seed)
        assert np.array_equal(again.sensors, data.recording.sensors)
        truth = data.recording.truth[:, mcp]
        summary = result["conditions"][cond]["other"]["summary"]
        for name, variant in (("model4", "model4/mixed"), ("synergy", "synergy")):
            with warnings.catch_warnings():     # the raw condition lies off the range
                warnings.simplefilter("ignore", GloveWarning)
                pred = setup.estimators[name].predict(data.sensors)[:, mcp]
            assert np.abs(pred - truth).mean() == pytest.approx(
                summary[variant]["mcp_error_deg"], abs=1e-3)
    assert set(setup.test_data("new_session", "representative").recording.motion) == {
        "standard", "lateral_contact", "tripod"}
    with pytest.raises(InvalidInputError, match="condition must be one of"):
        setup.test_data("loto", "other")
    with pytest.raises(InvalidInputError, match="motion set must be one of"):
        setup.test_data("new_session", "named")


def test_calibration_options_must_be_calibration_options():
    with pytest.raises(InvalidInputError, match="EvalOptions.calibration must be "
                                                "CalibrationOptions, got dict"):
        EvalOptions(calibration={"pooled": False})
    with pytest.raises(InvalidInputError, match="EvalOptions.config must be a GloveConfig "
                                                r"\(GLOVE_TUNING, GLOVE_HELDOUT\), got str"):
        EvalOptions(config="heldout")


def test_the_tables_do_not_repeat_the_off_range_warning(recwarn):
    # second_user_raw and the uncalibrated motions put readings off the range on purpose
    evaluate(EvalOptions(kind="dg5", trials=3, test_trials=1, seed=4))
    assert not [w for w in recwarn if "off the calibration's range" in str(w.message)]
