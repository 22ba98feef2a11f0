import json

import numpy as np
import pytest

from handsynth.errors import InvalidInputError
from handsynth.sensors.imu._eval import HELDOUT, TUNING, SimConfig, evaluate, make_filter


def test_configs_differ_in_what_the_filters_did_not_see():
    assert TUNING.noise.label != HELDOUT.noise.label
    assert HELDOUT.skin is not None and HELDOUT.tilt_sd_deg > 0 and HELDOUT.noise.disturbances
    assert HELDOUT.shape != TUNING.shape
    p = HELDOUT.placement()
    assert len(p.tilts_deg) == 20 and len(p.offsets_mm) == 20


def test_unknown_filter_is_named():
    with pytest.raises(InvalidInputError, match="unknown filter 'kalman9'"):
        make_filter("kalman9")
    with pytest.raises(InvalidInputError, match="filter4 needs a link model"):
        make_filter("filter4")


@pytest.mark.slow
def test_small_evaluation_is_json_and_has_baselines():
    cfg = SimConfig("small", seed=3)
    rep = evaluate(cfg, durations=(8.0,), elbows=("fixed",), filters=("constant", "raw", "filter4"),
                   grasps=False)
    json.dumps(rep)
    s = rep["summary"]
    assert s["raw"]["orientation_mean_deg"] < s["constant"]["orientation_mean_deg"]
    assert s["filter4"]["orientation_mean_deg"] < s["constant"]["orientation_mean_deg"]
    assert np.isfinite(s["filter4"]["fingertip_mean_rmse_mm"])
    v = rep["vectors"]
    assert v["rotation_method"]["median_mm"] < v["baseline_zero_vector"]["median_mm"]
