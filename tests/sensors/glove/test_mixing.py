import numpy as np
import pytest

from handsynth.errors import EstimationError
from handsynth.sensors.glove import fit_mixer


def _two_motions(rng, n_trials=6, n=100):
    """Motion 'a' bends sensor 0, motion 'b' sensor 4."""
    s, lab, ph = [], [], []
    for m, k in (("a", 0), ("b", 4)):
        for _ in range(n_trials):
            u = np.linspace(0, 1, n)
            x = 1000 + rng.normal(0, 2, (n, 5))
            x[:, k] += 300 * np.sin(np.pi * u) * rng.uniform(0.9, 1.1)
            s.append(x)
            lab += [m] * n
            ph.append(u)
    return np.vstack(s), np.array(lab), np.concatenate(ph)


def test_weights_pick_the_motion_and_sum_to_one():
    rng = np.random.default_rng(0)
    s, lab, ph = _two_motions(rng)
    mix = fit_mixer(s, lab, ph, motions=("a", "b"), centre=s.mean(0), scale=s.std(0),
                    n_points=10)
    test, tlab, tph = _two_motions(np.random.default_rng(1), n_trials=1)
    r = mix.weights(test)
    np.testing.assert_allclose(r.sum(axis=1), 1.0)
    bent = np.sin(np.pi * tph) > 0.5
    assert (r[(tlab == "a") & bent, 0] > 0.99).all()
    assert (r[(tlab == "b") & bent, 1] > 0.99).all()


def test_eq6_in_log_domain_equals_the_plain_ratio_and_survives_far_readings():
    rng = np.random.default_rng(0)
    s, lab, ph = _two_motions(rng)
    mix = fit_mixer(s, lab, ph, motions=("a", "b"), centre=s.mean(0), scale=s.std(0),
                    n_points=10)
    x = s[::37]
    lp = np.exp(mix.log_likelihood(x))          # eqs. 4-5 as written
    ok = lp.sum(axis=1) > 1e-200
    np.testing.assert_allclose(mix.weights(x)[ok], (lp / lp.sum(1, keepdims=True))[ok])
    far = np.full((1, 5), 1e6)
    assert np.isfinite(mix.weights(far)).all()


def test_sparse_bins_raise():
    rng = np.random.default_rng(0)
    s, lab, ph = _two_motions(rng, n_trials=1, n=10)
    with pytest.raises(EstimationError, match="point .* of 20 has"):
        fit_mixer(s, lab, ph, motions=("a", "b"), centre=s.mean(0), scale=s.std(0))


def test_long_inputs_are_processed_in_chunks_with_the_same_result():
    import handsynth.sensors.glove._mixing as mod

    rng = np.random.default_rng(0)
    s, lab, ph = _two_motions(rng)
    mix = fit_mixer(s, lab, ph, motions=("a", "b"), centre=s.mean(0), scale=s.std(0),
                    n_points=10)
    whole = mix.log_likelihood(s)
    old, mod._CHUNK = mod._CHUNK, 7
    try:
        np.testing.assert_allclose(mix.log_likelihood(s), whole)
    finally:
        mod._CHUNK = old
