import numpy as np
import pytest

from handsynth.errors import InvalidInputError
from handsynth.models import (
    JOINT_LIMITS_DEG,
    JOINT_NAMES,
    natural_pose_set,
    paper_pose_set,
    pose_set,
)


def test_paper_set_moves_one_finger_at_a_time():
    p = paper_pose_set()
    assert p.shape == (20448, 20)
    groups = [slice(0, 4)] + [slice(4 + 4 * k, 8 + 4 * k) for k in range(4)]
    moving = np.stack([np.any(p[:, g] != 0, axis=1) for g in groups], axis=1)
    assert moving.sum(axis=1).max() == 1  # never two fingers at once
    assert np.all(moving.sum(axis=0) > 2000)  # every finger and the thumb move
    # the full range of every joint is reached
    lo, hi = JOINT_LIMITS_DEG.T
    span = p.max(0) - p.min(0)
    dip = [JOINT_NAMES.index(f"{f}_dip_flex") for f in ("index", "middle", "ring", "little")]
    others = [j for j in range(20) if j not in dip]
    assert np.all(span[others] >= 0.97 * (hi - lo)[others])


def test_dip_follows_two_thirds_of_pip():
    for p in (paper_pose_set(2000), natural_pose_set(2000, seed=3)):
        for f in ("index", "middle", "ring", "little"):
            pip, dip = p[:, JOINT_NAMES.index(f"{f}_pip_flex")], p[:, JOINT_NAMES.index(f"{f}_dip_flex")]
            np.testing.assert_allclose(dip, np.clip(2 / 3 * pip, -10, 90), atol=1e-9)


def test_sets_are_deterministic_and_within_limits():
    a, b = natural_pose_set(500, seed=7), natural_pose_set(500, seed=7)
    np.testing.assert_array_equal(a, b)
    assert not np.array_equal(a, natural_pose_set(500, seed=8))
    lo, hi = JOINT_LIMITS_DEG.T
    for p in (a, paper_pose_set(777, seed=2)):
        assert np.all((p >= lo) & (p <= hi))
    # combined poses: several fingers flexed together
    flexed = (a[:, [6, 10, 14, 18]] > 30).sum(axis=1)
    assert np.mean(flexed >= 3) > 0.3


def test_bad_pose_set_arguments():
    with pytest.raises(InvalidInputError, match="unknown pose set 'foo'"):
        pose_set("foo")
    with pytest.raises(InvalidInputError, match="n must be a positive integer, got 0"):
        paper_pose_set(0)


@pytest.mark.parametrize("make", [lambda n: pose_set("paper", n), lambda n: natural_pose_set(n),
                                  lambda n: paper_pose_set(n)])
def test_a_pose_count_past_memory_is_refused_before_any_work(make):
    # 10**12 poses was a MemoryError, 10**10 ran for minutes
    from handsynth.models import MAX_POSES

    with pytest.raises(InvalidInputError, match=r"pose count n must be at most 10,000,000 .* "
                                                r"160,000 GB\), got 1000000000000"):
        make(10**12)
    assert MAX_POSES == 10_000_000


def test_complex_angles_are_refused_not_cut_to_their_real_parts():
    from handsynth.errors import InvalidPoseError
    from handsynth.models import as_angles

    with pytest.raises(InvalidPoseError, match="angles must be real joint angles, got complex"):
        as_angles(np.zeros(20) + 1j)
