from dataclasses import replace

import numpy as np
import pytest

from handsynth.db import render_mirror_set
from handsynth.errors import DatabaseCorruptError, DatabaseError, InvalidInputError
from handsynth.estimate import (
    LEARNED_PERCEPTRONS,
    TURNS,
    MirrorCheck,
    MirrorCheckOptions,
    learned_ensemble,
    mirror_check,
    read_rest_frame,
)
from handsynth.eval import model_test_hands
from handsynth.eval._testposes import REST_POSTURES
from handsynth.render import CameraMount

SMALL = MirrorCheckOptions(hands=1500, epochs=15)


@pytest.fixture(scope="module")
def perceptrons(tmp_path_factory):
    return learned_ensemble(tmp_path_factory.mktemp("cache"), members=LEARNED_PERCEPTRONS)


@pytest.fixture(scope="module")
def small():
    return MirrorCheck.learn(SMALL)


def test_the_shipped_check_still_matches_the_hands_it_learnt_from():
    check = mirror_check()
    assert check.options == MirrorCheckOptions() and check.mount == CameraMount.paper()
    assert check.fingerprint_matches(), (
        "the hand generator or the rasteriser changed: learn the mirror check again "
        "(python scripts/ship_mirror_check.py)")


def test_rest_frames_of_hands_it_never_learnt_read_mirrored_only_when_mirrored(perceptrons):
    # held-out model hands of another seed and at 1.5 times the learning spread, resting
    # relaxed and near open; without a forearm in view the check must not lean on one
    check = mirror_check()
    rng = np.random.default_rng(21)
    hands = model_test_hands(2, seed=61, spread=1.5)
    for hand, rest_kind in zip(hands, ("relaxed", "open"), strict=True):
        made = hand.make()
        try:
            rest = made.mask(REST_POSTURES[rest_kind](rng))
        finally:
            made.close()
        seen = check.read(perceptrons, rest)
        turned = check.read(perceptrons, rest[:, ::-1])
        assert not seen.mirrored and turned.mirrored, (hand.name, seen, turned)
        # one frame's two views, read in turn: the same two scores, swapped
        assert turned.seen == pytest.approx(seen.turned, abs=1e-6)
        assert turned.turned == pytest.approx(seen.seen, abs=1e-6)


def test_a_mirror_image_scores_below_the_view_it_came_from(small):
    seen, turned = render_mirror_set(40, seed=99)
    a = np.array([small.score(g.reshape(small.cells)) for g in seen])
    b = np.array([small.score(g.reshape(small.cells)) for g in turned])
    # learnt from 1,500 hands (the shipped check: 12,000), most views of other hands score
    # above their mirror images
    assert (a > b).mean() > 0.8


def test_a_saved_check_reads_back_the_same(small, tmp_path):
    path = tmp_path / "check.npz"
    small.save(path)
    back = MirrorCheck.load(path)
    assert back.options == small.options and back.mount == small.mount
    g = render_mirror_set(1, seed=5)[0][0].reshape(small.cells)
    assert back.score(g) == small.score(g)
    assert back.fingerprint_matches()


def test_damaged_and_missing_files_are_named(small, tmp_path):
    path = tmp_path / "check.npz"
    small.save(path)
    cut = tmp_path / "cut.npz"
    cut.write_bytes(path.read_bytes()[:5000])
    with pytest.raises(DatabaseCorruptError, match=f"mirror check {cut} is unreadable"):
        MirrorCheck.load(cut)
    with pytest.raises(DatabaseError, match="does not exist"):
        MirrorCheck.load(tmp_path / "none.npz")
    partial = tmp_path / "partial.npz"
    with np.load(path) as z:
        np.savez(partial, **{k: z[k] for k in z.files if k != "w0"})
    with pytest.raises(DatabaseCorruptError, match="missing array"):
        MirrorCheck.load(partial)


def test_grids_and_estimators_of_another_view_are_refused(small, perceptrons):
    with pytest.raises(InvalidInputError, match=r"grid must be a 30x45 uint8 coverage grid, got "
                                                r"float64 of shape \(30, 45\)"):
        small.score(np.zeros((30, 45)))
    other = MirrorCheck(small._a, options=small.options,
                        mount=replace(CameraMount.paper(), height_mm=140.0), side="right",
                        cells=small.cells)
    frame = np.zeros((480, 720), bool)
    frame[150:330, 200:600] = True
    with pytest.raises(InvalidInputError, match="learn a MirrorCheck for its device"):
        other.read(perceptrons, frame)
    with pytest.raises(InvalidInputError, match="must be a LearnedEstimator or an ensemble"):
        small.read(object(), frame)


def test_options_name_what_is_wrong():
    with pytest.raises(InvalidInputError, match="MirrorCheckOptions.hands"):
        MirrorCheckOptions(hands=1)
    with pytest.raises(InvalidInputError, match="MirrorCheckOptions.forearm_share"):
        MirrorCheckOptions(forearm_share=1.5)
    with pytest.raises(InvalidInputError, match=r"MirrorCheckOptions.hidden must be a "
                                                r"non-empty tuple"):
        MirrorCheckOptions(hidden=[64])
    with pytest.raises(InvalidInputError, match="MirrorCheckOptions.margin"):
        MirrorCheckOptions(margin=-0.1)
    with pytest.raises(TypeError):
        MirrorCheckOptions(hand=10)  # a typo raises


def test_the_mirror_set_is_a_function_of_its_seed_and_its_first_hands_of_nothing_else():
    a_seen, a_turned = render_mirror_set(3, seed=7)
    b_seen, b_turned = render_mirror_set(5, seed=7)
    assert a_seen.shape == (3, 30 * 45) and a_seen.dtype == np.uint8
    np.testing.assert_array_equal(a_seen, b_seen[:3])
    np.testing.assert_array_equal(a_turned, b_turned[:3])
    assert not np.array_equal(a_seen, a_turned)
    with pytest.raises(InvalidInputError, match="forearm_share"):
        render_mirror_set(2, forearm_share=-0.5)
    with pytest.raises(InvalidInputError, match="hands"):
        render_mirror_set(0)


@pytest.fixture(scope="module")
def held_out_rest():
    made = model_test_hands(1, seed=71, spread=1.5)[0].make()
    try:
        return made.mask(REST_POSTURES["relaxed"](np.random.default_rng(8)))
    finally:
        made.close()


def test_each_turn_of_a_rest_frame_is_named(perceptrons, held_out_rest, tmp_path):
    rest = held_out_rest
    seen = read_rest_frame(perceptrons, rest)
    assert (seen.low_confidence, seen.turn) == (False, None) and not seen.mirror.mirrored
    for turn, view in (("top to bottom", rest[::-1]), ("half a turn", rest[::-1, ::-1]),
                       ("left to right", rest[:, ::-1])):
        got = read_rest_frame(perceptrons, np.ascontiguousarray(view))
        assert got.turn == turn, (turn, got)
        assert turn in TURNS
        # the other hand's view and a camera upside down read as no hand learnt; a
        # mirrored one is told by the mirror check, not by that
        assert got.low_confidence == (turn != "left to right")
    # the left hand's estimator reads the left hand's view (the right's turned top to
    # bottom) as it is, and the right hand's view as turned
    left = learned_ensemble(tmp_path, members=LEARNED_PERCEPTRONS, side="left")
    assert read_rest_frame(left, np.ascontiguousarray(rest[::-1])).turn is None
    assert read_rest_frame(left, rest).turn == "top to bottom"


def test_no_mirror_check_is_asked_for_another_device_unless_given(perceptrons, held_out_rest,
                                                                  small, monkeypatch):
    from handsynth.estimate import _rest_view

    elsewhere = MirrorCheck(small._a, options=small.options,
                            mount=replace(CameraMount.paper(), height_mm=140.0), side="right",
                            cells=small.cells)
    monkeypatch.setattr(_rest_view, "mirror_check", lambda: elsewhere)
    got = read_rest_frame(perceptrons, held_out_rest)  # not the estimator's device: not asked
    assert got.mirror is None and got.turn is None
    got = read_rest_frame(perceptrons, held_out_rest, check=small)  # given: asked
    assert got.mirror == small.read(perceptrons, held_out_rest)
