import numpy as np
import pytest

from handsynth.db import (
    LearningSetOptions,
    learning_poses,
    learning_set,
    random_rest_posture,
    render_learning_set,
)
from handsynth.errors import InvalidInputError
from handsynth.models import JOINT_LIMITS_DEG

SMALL = LearningSetOptions(hands=3, poses_per_hand=4, seed=5)


def test_a_learning_set_is_a_pure_function_of_its_options():
    a = render_learning_set(SMALL)
    b = render_learning_set(SMALL)
    assert a.grids.shape == (12, 30 * 45) and a.grids.dtype == np.uint8
    assert a.rest_grids.shape == (3, 30 * 45) and a.hand.tolist() == [0] * 4 + [1] * 4 + [2] * 4
    for k in ("grids", "rest_grids", "angles", "rest_angles"):
        assert np.array_equal(getattr(a, k), getattr(b, k))
    assert a.grids.max() == 255 and a.grids.any(axis=1).all()  # every frame shows a hand
    c = render_learning_set(LearningSetOptions(hands=3, poses_per_hand=4, seed=6))
    assert not np.array_equal(a.angles, c.angles)


def test_the_set_is_kept_in_the_caller_s_folder_and_a_broken_file_is_rendered_again(tmp_path):
    a = learning_set(tmp_path, SMALL)
    files = list(tmp_path.glob("learning_*.npz"))
    assert len(files) == 1
    b = learning_set(tmp_path, SMALL)
    assert np.array_equal(a.grids, b.grids)
    files[0].write_bytes(files[0].read_bytes()[:100])
    c = learning_set(tmp_path, SMALL)
    assert np.array_equal(a.grids, c.grids)
    assert not list(tmp_path.glob("*.tmp*"))


def test_learning_poses_stay_within_the_limits_and_from_rest_poses_move_one_digit():
    rng = np.random.default_rng(0)
    rest = random_rest_posture(rng)
    poses = learning_poses(rest, 300, rng, mix=(1.0, 0.0, 0.0))
    lo, hi = JOINT_LIMITS_DEG[:, 0], JOINT_LIMITS_DEG[:, 1]
    assert np.all(poses >= lo) and np.all(poses <= hi)
    digit = np.r_[0, 0, 0, 0, np.repeat(np.arange(1, 5), 4)]
    for p in poses:
        moved = np.unique(digit[np.abs(p - rest) > 1e-9])
        assert len(moved) <= 1
    mixed = learning_poses(rest, 300, rng)
    assert np.all(mixed >= lo) and np.all(mixed <= hi)
    many = np.array([len(np.unique(digit[np.abs(p - rest) > 1e-9])) for p in mixed])
    assert (many >= 3).mean() > 0.3  # fingers moving together


def test_bad_options_are_refused_by_name():
    with pytest.raises(InvalidInputError, match="hands"):
        LearningSetOptions(hands=0)
    with pytest.raises(InvalidInputError, match="mix"):
        LearningSetOptions(mix=(0.5, 0.5, 0.5))
    with pytest.raises(InvalidInputError, match="edge_px"):
        LearningSetOptions(edge_px=50)
