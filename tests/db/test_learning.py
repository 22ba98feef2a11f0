import numpy as np
import pytest

from handsynth._cores import usable_cores
from handsynth.db import (
    LearningSetOptions,
    learning_poses,
    learning_set,
    learning_workers,
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


def test_worker_processes_render_the_same_set_to_the_byte():
    opts = LearningSetOptions(hands=10, poses_per_hand=3, seed=7, rest_slip=1.0,
                              rest_slip_share=0.5)
    said = {1: [], 2: []}
    one = render_learning_set(opts, progress=lambda *a: said[1].append(a))
    two = render_learning_set(opts, workers=2, progress=lambda *a: said[2].append(a))
    for k in ("grids", "rest_grids", "hand", "angles", "rest_angles"):
        assert np.array_equal(getattr(one, k), getattr(two, k)), k
    for lines in said.values():  # after each chunk of hands, up to all of them
        done = [d for d, _n in lines]
        assert len(done) > 1 and done == sorted(done) and lines[-1] == (10, 10)
    with pytest.raises(InvalidInputError, match="workers"):
        render_learning_set(SMALL, workers=0)
    # what the commands ask for: one process for small sets, every core (at most 8) for large
    assert learning_workers(399) == 1
    assert learning_workers(4000) == min(usable_cores(), 8)


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


def test_a_share_of_hands_rests_near_open():
    rng = np.random.default_rng(1)
    flex = list(range(4, 20))
    flex = [j for j in flex if (j - 4) % 4 != 1]
    near = np.stack([random_rest_posture(rng, near_open=True) for _ in range(200)])[:, flex]
    relaxed = np.stack([random_rest_posture(rng) for _ in range(200)])[:, flex]
    assert near.min() >= -3 and near.max() <= 8 and relaxed.max() > 20
    half = render_learning_set(LearningSetOptions(hands=40, poses_per_hand=1, seed=5,
                                                  open_rest_share=0.5))
    share = (half.rest_angles[:, flex].max(axis=1) <= 8).mean()
    assert 0.3 < share < 0.8
    # sets made before the option (share 0) keep their names; a share names its own
    assert LearningSetOptions(open_rest_share=0).digest() == "869345c1d0e4489c"
    assert LearningSetOptions(open_rest_share=0.5).digest() != LearningSetOptions().digest()
    with pytest.raises(InvalidInputError, match="open_rest_share"):
        LearningSetOptions(open_rest_share=1.5)


def test_bad_options_are_refused_by_name():
    with pytest.raises(InvalidInputError, match="hands"):
        LearningSetOptions(hands=0)
    with pytest.raises(InvalidInputError, match="mix"):
        LearningSetOptions(mix=(0.5, 0.5, 0.5))
    with pytest.raises(InvalidInputError, match="edge_px"):
        LearningSetOptions(edge_px=50)
    with pytest.raises(InvalidInputError, match="segment_width_sd"):
        LearningSetOptions(segment_width_sd=-0.1)
    with pytest.raises(InvalidInputError, match="flesh_offset_sd_mm"):
        LearningSetOptions(flesh_offset_sd_mm=11)
    with pytest.raises(InvalidInputError, match=r"breadth_follows_scale must be in \[0, 2\], got 3"):
        LearningSetOptions(breadth_follows_scale=3)


@pytest.mark.parametrize("kwargs, words", [
    ({"hand_spread": -1}, r"hand_spread must be a finite number >= 0, got -1"),
    ({"hand_spread": float("nan")}, r"hand_spread must be a finite number >= 0, got nan"),
    ({"seed": -1}, r"seed must be an integer >= 0, got -1"),
    ({"seed": 1.5}, r"seed must be an integer >= 0, got 1.5"),
    ({"cells": (10,)}, r"cells must be \(rows, cols\), two positive integers, got \(10,\)"),
    ({"cells": (10, 2.5)}, r"cells must be .* got \(10, 2.5\)"),
    ({"edge_px": 2.5}, r"edge_px must be an integer in \[0, 20\], got 2.5"),
    ({"mix": ("a", 0, 1)}, r"mix must be 3 shares summing to 1"),
    # 99999999999 hands: a MemoryError after the draw (12 PiB of learning frames)
    ({"hands": 100_001}, r"hands must be at most 100,000, got 100001"),
])
def test_options_that_would_fail_later_are_refused_by_name(kwargs, words):
    with pytest.raises(InvalidInputError, match=r"LearningSetOptions\." + words):
        LearningSetOptions(**kwargs)


def test_a_negative_device_variation_is_refused_by_name():
    from handsynth.render import MountVariation

    for bad in (-5, float("nan"), "4"):
        with pytest.raises(InvalidInputError, match=r"MountVariation.height_mm must be a finite "
                                                    r"s.d. >= 0, got "):
            MountVariation(height_mm=bad)
    with pytest.raises(InvalidInputError, match="mount_variation must be a MountVariation"):
        LearningSetOptions(mount_variation={"height_mm": 5})
    assert LearningSetOptions(seed=np.int64(3), cells=[30, 45]).cells == (30, 45)


def test_segment_widths_vary_the_learning_hands_and_name_their_own_set():
    opts = dict(hands=3, poses_per_hand=2, seed=2)
    same = render_learning_set(LearningSetOptions(**opts))
    varied = render_learning_set(LearningSetOptions(**opts, segment_width_sd=0.2))
    assert not np.array_equal(varied.grids, same.grids)
    assert np.array_equal(render_learning_set(LearningSetOptions(**opts, segment_width_sd=0.2)).grids,
                          varied.grids)
    assert LearningSetOptions(segment_width_sd=0).digest() == LearningSetOptions().digest()
    assert LearningSetOptions(segment_width_sd=0.1).digest() != LearningSetOptions().digest()
    assert LearningSetOptions(flesh_offset_sd_mm=0).digest() == LearningSetOptions().digest()
    assert LearningSetOptions(flesh_offset_sd_mm=1.5).digest() not in (
        LearningSetOptions().digest(), LearningSetOptions(segment_width_sd=0.1).digest())


def test_breadths_that_follow_the_scale_name_their_own_set():
    opts = dict(hands=3, poses_per_hand=2, seed=2)
    same = render_learning_set(LearningSetOptions(**opts))
    scaled = render_learning_set(LearningSetOptions(**opts, breadth_follows_scale=1.0))
    assert not np.array_equal(scaled.grids, same.grids)
    np.testing.assert_array_equal(scaled.angles, same.angles)  # the same draws otherwise
    assert LearningSetOptions(breadth_follows_scale=0).digest() == LearningSetOptions().digest()
    assert LearningSetOptions(breadth_follows_scale=1).digest() != LearningSetOptions().digest()


def test_a_rest_slip_moves_the_device_between_a_hand_s_rest_frame_and_its_other_frames():
    opts = dict(hands=2, poses_per_hand=3, seed=4)
    still = render_learning_set(LearningSetOptions(**opts))
    slipped = render_learning_set(LearningSetOptions(**opts, rest_slip=1.0))
    # the first hand is drawn alike up to its rest frame and poses; its frames are seen elsewhere
    assert np.array_equal(slipped.rest_grids[0], still.rest_grids[0])
    assert np.array_equal(slipped.angles[:3], still.angles[:3])
    assert not np.array_equal(slipped.grids[:3], still.grids[:3])
    none = render_learning_set(LearningSetOptions(**opts, rest_slip=1.0, rest_slip_share=0.0))
    assert np.array_equal(none.grids[:3], still.grids[:3])  # a share of hands does not slip
    # sets made before the option keep their names
    assert LearningSetOptions(rest_slip=0).digest() == LearningSetOptions().digest()
    assert LearningSetOptions(rest_slip=0.5).digest() != LearningSetOptions().digest()
    assert LearningSetOptions(rest_slip=0.5, rest_slip_share=0.5).digest() != \
        LearningSetOptions(rest_slip=0.5).digest()
    with pytest.raises(InvalidInputError, match="rest_slip"):
        LearningSetOptions(rest_slip=-1)
    with pytest.raises(InvalidInputError, match="rest_slip_share"):
        LearningSetOptions(rest_slip=1, rest_slip_share=2)


def test_the_folder_is_checked_before_the_set_is_rendered(tmp_path, monkeypatch):
    # a file in the way was found only after rendering the whole set (minutes by default)
    import re

    import handsynth._io
    import handsynth.db._learning
    from handsynth.errors import DatabaseError

    def no_rendering(*args, **kwargs):
        raise AssertionError("the learning set was rendered")

    monkeypatch.setattr(handsynth.db._learning, "render_learning_set", no_rendering)
    in_the_way = tmp_path / "some_file.h5"
    in_the_way.write_bytes(b"x")
    with pytest.raises(DatabaseError, match=r"cannot create the learning-set folder "
                                            rf"{re.escape(repr(str(in_the_way)))}"):
        learning_set(in_the_way, SMALL)
    with pytest.raises(DatabaseError, match=r"cannot create the learning-set folder"):
        learning_set(in_the_way / "below", SMALL)
    monkeypatch.setattr(handsynth._io, "_unwritable", lambda folder: "the file system is read-only")
    with pytest.raises(DatabaseError, match=r"cannot write into the learning-set folder .*"
                                            r"read-only"):
        learning_set(tmp_path / "sets", SMALL)
    for folder, words in ((None, "folder must be a folder name (str or path), got None"),
                          (3.5, "folder must be a folder name (str or path), got float 3.5"),
                          (" ", "folder must name a folder, got ' '")):
        with pytest.raises(InvalidInputError, match=re.escape(words)):
            learning_set(folder, SMALL)


def test_a_kept_set_is_read_from_a_folder_that_cannot_be_written(tmp_path, monkeypatch):
    import handsynth._io

    first = learning_set(tmp_path, SMALL)
    monkeypatch.setattr(handsynth._io, "_unwritable", lambda folder: "the file system is read-only")
    again = learning_set(tmp_path, SMALL)  # nothing to write: only read
    assert np.array_equal(first.grids, again.grids)
