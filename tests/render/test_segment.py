"""Telling the hand from an ordinary background by the colour of the user's skin."""

import cv2
import numpy as np
import pytest

from handsynth.errors import InvalidInputError
from handsynth.models import named_pose
from handsynth.render import (
    CameraMount,
    binarize,
    brightness_overlap,
    fit_skin_colour,
    palm_region,
    skin_mask,
)
from handsynth.render._segment import skin_inside
from handsynth.testhands import MeshHandRenderer, shipped_hand_path

SKIN = np.array([120, 150, 210], np.float32)  # BGR


def _photo(seed: int) -> np.ndarray:
    """A smooth random colour field, brighter than the hand in places (not a dark ground)."""
    rng = np.random.default_rng(seed)
    small = rng.integers(0, 256, (6, 9, 3)).astype(np.uint8)
    return cv2.resize(small, (720, 480), interpolation=cv2.INTER_CUBIC)


def _frame(mask, ground, rng, tone=SKIN):
    shade = np.linspace(0.55, 1.0, mask.shape[1], dtype=np.float32)[None, :, None]
    f = ground.astype(np.float32)
    f[mask] = (tone * shade * np.ones_like(f))[mask]
    return np.clip(f + rng.normal(0, 4, f.shape), 0, 255).astype(np.uint8)


def _small(mask, size):
    return cv2.resize(mask.astype(np.uint8), size, interpolation=cv2.INTER_AREA) > 0


def _iou(a, b):
    return (a & b).sum() / (a | b).sum()


@pytest.fixture(scope="module")
def mrtk():
    with MeshHandRenderer(path=shipped_hand_path("mrtk")) as r:
        yield r


def test_the_palm_region_is_hand_on_hands_it_was_not_drawn_from(mrtk):
    palm = palm_region()
    assert palm.shape == (120, 180) and 500 < palm.sum() < 0.3 * palm.size
    for pose in ("open", "fist", "point"):
        hand = _small(mrtk.mask(named_pose(pose)), (180, 120))
        assert (palm & ~hand).sum() < 0.1 * palm.sum()


def test_the_skin_is_told_over_a_bright_coloured_ground_where_brightness_fails(mrtk):
    rng = np.random.default_rng(0)
    skin = fit_skin_colour(_frame(mrtk.mask(named_pose("open")), _photo(1), rng))
    for k, pose in enumerate(("fist", "point", "pinch")):
        truth = mrtk.mask(named_pose(pose))
        frame = _frame(truth, _photo(2 + k), rng)
        got = skin_mask(frame, skin)
        assert got.shape == (120, 180)
        assert _iou(got, _small(truth, (180, 120))) > 0.9
        assert _iou(binarize(frame), truth) < 0.8  # Otsu's threshold takes in the ground


def test_a_second_skin_tone_and_a_dark_ground_are_told_as_well(mrtk):
    rng = np.random.default_rng(1)
    dark = np.full((480, 720, 3), 20, np.uint8)
    tone = np.array([60, 85, 125], np.float32)
    skin = fit_skin_colour(_frame(mrtk.mask(named_pose("open")), dark, rng, tone))
    truth = mrtk.mask(named_pose("grasp"))
    got = skin_mask(_frame(truth, dark, rng, tone), skin)
    assert _iou(got, _small(truth, (180, 120))) > 0.9


def test_the_look_up_table_answers_as_the_plain_test():
    f = np.zeros((480, 720, 3), np.uint8)
    f[:] = SKIN.astype(np.uint8)
    skin = fit_skin_colour(f)
    rng = np.random.default_rng(2)
    near = np.clip(SKIN * rng.uniform(0.15, 1.2, (50000, 1)) + rng.normal(0, 8, (50000, 3)),
                   0, 255).astype(np.uint8)
    colours = np.vstack([near, rng.integers(0, 256, (50000, 3)).astype(np.uint8)])
    q = (colours >> 2).astype(np.int32)
    table = skin._table[(q[:, 0] << 12) | (q[:, 1] << 6) | q[:, 2]]
    plain = skin_inside(colours, skin)
    assert plain[:50000].mean() > 0.5 and plain[50000:].mean() < 0.1
    assert (table == plain).mean() > 0.97  # they differ only within a 6-bit step of the edge


def test_a_left_hand_s_palm_region_is_the_right_s_upside_down_through_the_mirrored_device():
    mount = CameraMount(roll_deg=6.0)
    np.testing.assert_array_equal(palm_region(mount, side="left"),
                                  palm_region(mount.mirrored())[::-1])


@pytest.mark.parametrize(("frame", "message"), [
    (np.zeros((480, 720), np.uint8), "rest_frame must be a uint8 colour"),
    (np.zeros((480, 720), bool), "rest_frame must be a uint8 colour"),
    (np.zeros((480, 720, 3), np.uint8), "the back of the hand is dark"),
])
def test_frames_the_skin_cannot_be_taken_from_are_refused(frame, message):
    with pytest.raises(InvalidInputError, match=message):
        fit_skin_colour(frame)
    with pytest.raises(InvalidInputError, match="side must be 'right' or 'left'"):
        palm_region(side="both")


def test_a_change_of_white_balance_or_exposure_after_the_rest_frame_is_undone(mrtk):
    rng = np.random.default_rng(3)
    skin = fit_skin_colour(_frame(mrtk.mask(named_pose("open")), _photo(7), rng))
    truth = mrtk.mask(named_pose("point"))
    frame = _frame(truth, _photo(8), rng)
    for cast in ((0.85, 1.0, 1.15), (1.15, 1.0, 0.85), (0.7, 0.7, 0.7)):
        shifted = np.clip(frame * np.array(cast, np.float32), 0, 255).astype(np.uint8)
        assert _iou(skin_mask(shifted, skin), _small(truth, (180, 120))) > 0.9


def test_brightness_and_colour_agree_on_a_dark_ground_and_not_on_a_bright_one(mrtk):
    from handsynth.estimate import AUTO_OVERLAP

    rng = np.random.default_rng(4)
    mask = mrtk.mask(named_pose("open"))
    dark = _frame(mask, np.full((480, 720, 3), 20, np.uint8), rng)
    bright = _frame(mask, np.full((480, 720, 3), (200, 230, 240), np.uint8), rng)
    assert brightness_overlap(dark, fit_skin_colour(dark)) > AUTO_OVERLAP
    assert brightness_overlap(bright, fit_skin_colour(bright)) < 0.5


def test_a_skin_close_to_grey_says_that_colour_cannot_tell_it_from_grey(mrtk):
    rng = np.random.default_rng(5)
    mask = mrtk.mask(named_pose("open"))
    ground = np.full((480, 720, 3), 128, np.uint8)
    assert fit_skin_colour(_frame(mask, ground, rng)).tells_grey
    pale = fit_skin_colour(_frame(mask, ground, rng, tone=np.array([216, 247, 255], np.float32)))
    assert not pale.tells_grey  # overexposed: its channels clipped near white


def test_a_frame_whose_palm_region_is_not_the_skin_shows_no_hand(mrtk):
    rng = np.random.default_rng(6)
    skin = fit_skin_colour(_frame(mrtk.mask(named_pose("open")), _photo(9), rng))
    unlike = 0
    for k in range(10, 16):  # the colour fields alone: the hand gone from the view
        ground = _photo(k)
        gain = np.asarray(skin.palm_bgr) / np.maximum(
            np.median(cv2.resize(ground, (180, 120), interpolation=cv2.INTER_AREA)[palm_region()],
                      axis=0), 1.0)
        if gain.max() > 1.6 * gain.min():
            unlike += 1
            assert not skin_mask(ground, skin).any()
    assert unlike >= 3
    cast = np.clip(_frame(mrtk.mask(named_pose("fist")), _photo(16), rng)
                   * np.array([0.8, 1.0, 1.2], np.float32), 0, 255).astype(np.uint8)
    assert skin_mask(cast, skin).sum() > 1000  # a cast of 20 % is still undone
