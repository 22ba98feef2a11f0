import numpy as np
import pytest

from handsynth.errors import InvalidInputError
from handsynth.estimate import MoveCheck, MoveCheckOptions
from handsynth.eval import model_test_hands, natural_test_poses, paper_protocol_poses, relaxed_rest_posture
from handsynth.render import CameraMount, coverage

PAPER = CameraMount.paper()


def _grid(mask, mount=PAPER):
    return np.rint(coverage(mask, mount) * 255).astype(np.uint8)


@pytest.fixture(scope="module")
def hand():
    """A model hand beyond the learning spread, its rest grid and 40 poses moving every digit."""
    h = model_test_hands(1, seed=8, spread=1.5)[0]
    rng = np.random.default_rng(2)
    rest = relaxed_rest_posture(rng)
    poses = np.vstack([paper_protocol_poses(rest, 20, rng)[0], natural_test_poses(rest, 20, rng)[0]])
    return h, _grid(h.make().mask(rest)), poses


def test_fingers_and_thumb_moving_do_not_move_the_device(hand):
    h, rest, poses = hand
    check = MoveCheck(rest, PAPER)
    assert check.available
    changes = [check.change(_grid(m)) for m in h.make().masks(poses)]
    assert max(changes) < check.options.limit  # every frame, thumb motions included
    assert not any(check.update(_grid(m)) for m in h.make().masks(poses))


def test_a_slipped_device_is_called_moved_once_a_window_of_frames_says_so(hand):
    h, rest, poses = hand
    slipped = PAPER.replace(thumb_offset_mm=PAPER.thumb_offset_mm + 5, tilt_deg=3.0)
    check = MoveCheck(rest, PAPER, options=MoveCheckOptions(window=10))
    flags = [check.update(_grid(m)) for m in h.make(slipped).masks(poses)]
    assert flags[:9] == [False] * 9 and all(flags[9:])
    assert check.change(_grid(h.make(slipped).mask(poses[0]))) > 3 * check.options.limit


def test_a_fresh_check_starts_with_no_frames_and_leaves_the_original_alone(hand):
    """What a mirrored estimator's copy gets: its own window of frames."""
    h, rest, poses = hand
    slipped = PAPER.replace(thumb_offset_mm=PAPER.thumb_offset_mm + 5, tilt_deg=3.0)
    check = MoveCheck(rest, PAPER, options=MoveCheckOptions(window=3))
    for m in h.make(slipped).masks(poses[:3]):
        check.update(_grid(m))
    other = check.fresh()
    assert check.moved and not other.moved and len(other.state.changes) == 0
    other.update(_grid(h.make().mask(poses[0])))
    assert len(check.state.changes) == 3 and len(other.state.changes) == 1


def test_without_a_wrist_cut_there_is_nothing_to_check(hand):
    rest = hand[1]
    check = MoveCheck(rest, PAPER.replace(wrist_cut_mm=None), options=MoveCheckOptions(window=1))
    assert not check.available and np.isnan(check.change(rest))
    assert not check.update(np.zeros_like(rest))


def test_bad_options_and_grids_are_refused_by_name():
    with pytest.raises(InvalidInputError, match="window"):
        MoveCheckOptions(window=0)
    with pytest.raises(InvalidInputError, match="limit"):
        MoveCheckOptions(limit=1.5)
    with pytest.raises(InvalidInputError, match="rest_grid"):
        MoveCheck(np.zeros((30, 45)), PAPER)


def test_the_calibrated_perceptrons_report_a_slip_and_the_ensemble_passes_it_on(hand, tmp_path):
    from handsynth.estimate import LEARNED_PERCEPTRONS, learned_ensemble

    h, _, poses = hand
    est = learned_ensemble(tmp_path, members=LEARNED_PERCEPTRONS)  # shipped: nothing learnt
    rng = np.random.default_rng(2)
    rest_mask = h.make().mask(relaxed_rest_posture(rng))
    still = est.calibrated(rest_mask)
    assert not any(still.estimate(m).moved for m in h.make().masks(poses))
    moved = est.calibrated(rest_mask)
    slipped = PAPER.replace(along_mm=PAPER.along_mm - 8, height_mm=110.0, roll_deg=4.0)
    got = [moved.estimate(m).moved for m in h.make(slipped).masks(poses)]
    window = MoveCheckOptions().window
    assert got[:window - 1] == [False] * (window - 1) and all(got[window - 1:])


def test_a_left_hand_is_checked_alike():
    from handsynth.models import HandShape
    from handsynth.render import HandVariation, VariedRasterizer

    def maker(mount):
        r = VariedRasterizer(HandShape(), mount, side="left")
        r.vary(HandVariation.random(np.random.default_rng(1)))
        return r

    rng = np.random.default_rng(3)
    rest = relaxed_rest_posture(rng)
    poses = natural_test_poses(rest, 10, rng)[0]
    check = MoveCheck(_left(maker(PAPER).mask(rest)), PAPER, side="left")
    assert check.available
    assert max(check.change(_left(m)) for m in maker(PAPER).masks(poses)) < check.options.limit
    slipped = maker(PAPER.replace(thumb_offset_mm=30.0, tilt_deg=2.0)).masks(poses)
    assert min(check.change(_left(m)) for m in slipped) > 3 * check.options.limit


def _left(mask):
    return np.rint(coverage(mask, PAPER, side="left") * 255).astype(np.uint8)


@pytest.mark.parametrize("grid", [None, "x", np.zeros((30, 45)), np.zeros((10, 10), np.uint8)])
def test_a_grid_that_is_not_the_rest_frames_is_refused_by_name(hand, grid):
    # update(None) was numpy's reshape error
    _, rest, _ = hand
    with pytest.raises(InvalidInputError, match=r"^grid must be a 30x45 uint8 coverage grid, got "):
        MoveCheck(rest, PAPER).update(grid)
