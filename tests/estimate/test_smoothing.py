import numpy as np
import pytest

from handsynth.errors import InvalidInputError
from handsynth.estimate import (
    OneEuroFilter,
    OneEuroOptions,
    PoseEstimate,
    PoseEstimator,
    SmoothedEstimator,
    one_euro,
)


def _stream(f: OneEuroFilter, x: np.ndarray) -> np.ndarray:
    return np.stack([f(row) for row in x])


def test_streaming_filter_equals_the_plain_reference():
    rng = np.random.default_rng(0)
    t = np.arange(300) / 30.0
    x = np.column_stack([40 * np.sin(2 * t), np.where(t > 4, 60.0, 5.0), np.zeros_like(t)])
    x += rng.normal(0, 1.5, x.shape)
    for opts in (OneEuroOptions(), OneEuroOptions(min_cutoff_hz=2.0, beta=0.0),
                 OneEuroOptions(min_cutoff_hz=0.3, beta=0.2, derivative_cutoff_hz=3.0)):
        got = _stream(OneEuroFilter(30.0, options=opts), x)
        np.testing.assert_allclose(got, one_euro(x, rate_hz=30.0, options=opts), atol=1e-12)


def test_still_input_is_steadied_and_fast_motion_barely_lags():
    rng = np.random.default_rng(1)
    n, rate = 240, 30.0
    still = 20.0 + rng.normal(0, 1.0, (n, 1))
    out = one_euro(still, rate_hz=rate)
    assert np.std(out[30:]) < 0.35 * np.std(still[30:])
    # a ramp of 90 deg/s: the speed term opens the cut-off, a fixed low cut-off lags
    ramp = (90.0 * np.arange(n) / rate)[:, None]
    adaptive = one_euro(ramp, rate_hz=rate)
    fixed = one_euro(ramp, rate_hz=rate, options=OneEuroOptions(beta=0.0))
    lag_adaptive = np.mean(ramp[60:] - adaptive[60:])
    lag_fixed = np.mean(ramp[60:] - fixed[60:])
    assert 0 < lag_adaptive < 0.1 * lag_fixed
    # a constant passes unchanged, the first sample too
    np.testing.assert_allclose(one_euro(np.full((10, 3), 7.0), rate_hz=rate), 7.0)


def test_a_frame_without_a_hand_resets_the_filter():
    f = OneEuroFilter(30.0)
    f(np.zeros(2))
    f(np.zeros(2))
    gap = f(np.full(2, np.nan))
    assert np.isnan(gap).all() and f.state.value is None
    np.testing.assert_array_equal(f(np.array([50.0, -5.0])), [50.0, -5.0])


@pytest.mark.parametrize("kwargs, message", [
    ({"min_cutoff_hz": 0.0}, "min_cutoff_hz > 0"),
    ({"beta": -1.0}, "beta >= 0"),
    ({"derivative_cutoff_hz": "fast"}, "derivative_cutoff_hz must be a number, got 'fast'"),
    ({"min_cutoff_hz": float("nan")}, "min_cutoff_hz must be a number, got nan"),
])
def test_bad_options_are_named(kwargs, message):
    with pytest.raises(InvalidInputError, match=message):
        OneEuroOptions(**kwargs)


def test_bad_rates_and_arrays_are_named():
    with pytest.raises(InvalidInputError, match="rate_hz must be a finite number > 0, got 0"):
        OneEuroFilter(0)
    with pytest.raises(InvalidInputError, match="finite \\(N, J\\) array"):
        one_euro(np.zeros(5), rate_hz=30)
    with pytest.raises(TypeError):
        OneEuroOptions(min_cutof_hz=1.0)  # a typo raises


class _Steps:
    """A stand-in estimator: answers a fixed sequence of angles, calibrates by shifting them."""

    def __init__(self, values, shift=0.0):
        self.values, self.shift, self.i = list(values), shift, 0

    def calibrated(self, rest_frame):
        return _Steps(self.values, shift=float(np.mean(rest_frame)))

    def estimate(self, frame):
        v = self.values[self.i]
        self.i += 1
        angles = np.full(20, np.nan) if v is None else np.full(20, v + self.shift)
        return PoseEstimate(angles=angles, keypoints=np.full((21, 3), np.nan, np.float32),
                            confidence=1.0, entry=-1, error=0.0, low_confidence=False,
                            no_hand=v is None)


def test_smoothed_estimator_filters_answers_and_keeps_the_rest():
    values = [10.0, 30.0, 30.0, None, 30.0]
    est = SmoothedEstimator(_Steps(values), rate_hz=30.0)
    assert isinstance(est, PoseEstimator)
    frame = np.zeros((4, 4))
    got = [est.estimate(frame) for _ in values]
    want = one_euro(np.array(values[:3])[:, None], rate_hz=30.0)[:, 0]
    np.testing.assert_allclose([g.angles[0] for g in got[:3]], want)
    assert 10.0 < got[1].angles[0] < 30.0 and got[1].confidence == 1.0
    assert got[3].no_hand and np.isnan(got[3].angles).all()
    assert got[4].angles[0] == 30.0                 # fresh after the frame without a hand
    cal = est.calibrated(np.full((4, 4), 2.0))
    assert cal is not est and cal.filter.state.value is None
    assert cal.estimate(frame).angles[0] == 12.0
    with pytest.raises(InvalidInputError, match="has no estimate"):
        SmoothedEstimator(object(), rate_hz=30.0)


def test_one_euro_names_samples_that_are_not_numbers():
    # one_euro("abc") was numpy's "could not convert string to float"
    from handsynth.estimate import one_euro

    with pytest.raises(InvalidInputError, match=r"x must be a finite \(N, J\) array of numbers, got str"):
        one_euro("abc", rate_hz=30)
