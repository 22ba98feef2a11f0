import numpy as np
import pytest

from handsynth.errors import InvalidInputError
from handsynth.sensors.glove import default_synergies, fit_synergies


def test_pca_finds_planted_components():
    rng = np.random.default_rng(0)
    basis = np.linalg.qr(rng.normal(size=(20, 2)))[0].T
    poses = 20 + rng.normal(0, [30, 10], (2000, 2)) @ basis + rng.normal(0, 1, (2000, 20))
    syn = fit_synergies(poses, k=2)
    np.testing.assert_allclose(syn.components @ syn.components.T, np.eye(2), atol=1e-9)
    overlap = np.abs(syn.components @ basis.T)
    assert overlap.max(axis=1).min() > 0.99
    assert syn.explained.sum() > 0.95


def test_natural_pose_set_two_synergies_explain_most_variance():
    """Santello et al. 1998 report > 80 % for two synergies of real grasps."""
    syn = default_synergies(2)
    assert 0.6 < syn.explained.sum() < 1.0


def test_reconstruction_honours_exact_observations():
    syn = default_synergies(2)
    a = np.zeros((2, 20))
    a[0, 6], a[1, 10] = 1.0, 1.0          # observe index and middle PIP exactly
    b = np.array([[40.0, 60.0], [10.0, 90.0]])
    theta = syn.reconstruct(b, a, np.full(2, 1e-9))
    np.testing.assert_allclose(theta @ a.T, b, atol=1e-4)


def test_bad_input():
    # arguments are input errors; what valid input cannot give is an EstimationError
    with pytest.raises(InvalidInputError, match=r"^k must be an integer >= 1 and <= 20, got 0$"):
        fit_synergies(np.zeros((10, 20)), k=0)
    with pytest.raises(InvalidInputError, match="shape"):
        fit_synergies(np.zeros((10, 19)))


def test_the_shared_default_synergies_cannot_be_changed_by_a_caller():
    # before, default_synergies(2).mean[:] = 99 changed what every later call returned
    syn = default_synergies(2)
    assert default_synergies(2) is syn
    with pytest.raises(ValueError, match="read-only"):
        syn.mean[:] = 99.0
    with pytest.raises(InvalidInputError, match=r"^k must be an integer >= 1 and <= 20, got 2.0"):
        default_synergies(2.0)
