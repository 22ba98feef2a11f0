import numpy as np
import pytest

from handsynth.errors import InvalidShapeError
from handsynth.models import HandShape, named_pose
from handsynth.render import (
    CameraMount,
    HandVariation,
    MountVariation,
    SilhouetteRasterizer,
    VariedRasterizer,
)

W, H = 240, 160


@pytest.fixture(scope="module")
def varied():
    return VariedRasterizer(HandShape(length=1.02), width_px=W, height_px=H)


def test_no_variation_draws_the_built_hand(varied):
    varied.vary(HandVariation())
    varied.set_mount(CameraMount.paper())
    plain = SilhouetteRasterizer(HandShape(length=1.02), width_px=W, height_px=H)
    for pose in ("open", "fist", "pinch", "spread"):
        assert np.array_equal(varied.mask(named_pose(pose)), plain.mask(named_pose(pose)))


def test_a_variation_is_relative_to_the_built_hand_not_cumulative(varied):
    rng = np.random.default_rng(3)
    varied.vary(HandVariation.random(rng))
    first = varied.mask(named_pose("point"))
    varied.vary(HandVariation.random(rng))
    varied.vary(varied.variation)  # applying the same twice changes nothing
    again = varied.mask(named_pose("point"))
    varied.vary(HandVariation.random(np.random.default_rng(3)))
    assert np.array_equal(varied.mask(named_pose("point")), first)
    assert not np.array_equal(again, first)
    varied.vary(HandVariation())


def test_segment_length_moves_the_joints_and_tips_by_its_factor(varied):
    varied.vary(HandVariation())
    varied.hand.set_pose(np.zeros(20))
    kp0 = varied.hand.keypoints()
    lengths = [1.0] * 15
    lengths[3], lengths[5] = 1.3, 0.8  # index proximal and distal
    varied.vary(HandVariation(segment_length=tuple(lengths), palm_length=1.2))
    varied.hand.set_pose(np.zeros(20))
    kp = varied.hand.keypoints()
    # keypoints: 5 index MCP, 6 PIP, 7 DIP, 8 tip; the MCP moves with the palm length
    np.testing.assert_allclose(kp[5, 1], 1.2 * kp0[5, 1], rtol=1e-9)
    np.testing.assert_allclose(np.linalg.norm(kp[6] - kp[5]), 1.3 * np.linalg.norm(kp0[6] - kp0[5]),
                               rtol=1e-9)
    np.testing.assert_allclose(np.linalg.norm(kp[8] - kp[7]), 0.8 * np.linalg.norm(kp0[8] - kp0[7]),
                               rtol=1e-9)
    # and the drawn finger is longer: the open hand covers more pixels
    assert varied.mask(np.zeros(20)).sum() > SilhouetteRasterizer(
        HandShape(length=1.02), width_px=W, height_px=H).mask(np.zeros(20)).sum()
    varied.vary(HandVariation())


def test_a_segment_s_own_width_widens_only_that_segment(varied):
    varied.vary(HandVariation())
    pose = np.zeros(20)
    base = varied.mask(pose).astype(bool)
    widths = [1.0] * 15
    widths[3] = 1.4  # the index proximal phalanx
    varied.vary(HandVariation(segment_width=tuple(widths)))
    wide = varied.mask(pose).astype(bool)
    assert wide.sum() > base.sum() and not (base & ~wide).any()  # grows, nothing shrinks
    # the same factor on the whole digit covers more than on one segment of it
    varied.vary(HandVariation(digit_width=(1.0, 1.4, 1.0, 1.0, 1.0)))
    assert varied.mask(pose).sum() > wide.sum()
    # joints do not move: a width changes breadth and depth only
    varied.hand.set_pose(pose)
    kp0 = varied.hand.keypoints()
    varied.vary(HandVariation(segment_width=tuple(widths)))
    varied.hand.set_pose(pose)
    np.testing.assert_allclose(varied.hand.keypoints(), kp0, atol=1e-12)
    varied.vary(HandVariation())


def test_a_flesh_offset_moves_a_segment_s_surface_and_not_its_joints(varied):
    varied.vary(HandVariation())
    pose = named_pose("point")
    varied.hand.set_pose(pose)
    kp0 = varied.hand.keypoints()
    base = varied.mask(pose).astype(bool)
    offsets = [0.0] * 30
    offsets[6:8] = 4.0, 0.0  # the index proximal phalanx's flesh 4 mm toward its tip
    varied.vary(HandVariation(flesh_offset_mm=tuple(offsets)))
    varied.hand.set_pose(pose)
    np.testing.assert_allclose(varied.hand.keypoints(), kp0, atol=1e-12)
    moved = varied.mask(pose).astype(bool)
    assert (moved & ~base).any() and (base & ~moved).any()
    # undone by the next variation
    varied.vary(HandVariation())
    assert np.array_equal(varied.mask(pose).astype(bool), base)


def test_segment_widths_are_drawn_after_everything_else():
    plain = HandVariation.random(np.random.default_rng(8), spread=1.5)
    drawn = HandVariation.random(np.random.default_rng(8), spread=1.5, segment_width_sd=0.1)
    assert plain.segment_width == (1.0,) * 15
    assert drawn.segment_length == plain.segment_length and drawn.mcp_offset_mm == plain.mcp_offset_mm
    log_w = np.log(drawn.segment_width)
    assert 0.05 < log_w.std() < 0.3 and len(set(drawn.segment_width)) == 15
    with pytest.raises(InvalidShapeError, match="segment_width_sd"):
        HandVariation.random(np.random.default_rng(8), segment_width_sd=-0.1)
    flesh = HandVariation.random(np.random.default_rng(8), spread=1.5, segment_width_sd=0.1,
                                 flesh_offset_sd_mm=2.0)
    assert flesh.segment_width == drawn.segment_width and plain.flesh_offset_mm == (0.0,) * 30
    assert 1.5 < np.std(flesh.flesh_offset_mm) < 5.0
    with pytest.raises(InvalidShapeError, match="flesh_offset_sd_mm"):
        HandVariation.random(np.random.default_rng(8), flesh_offset_sd_mm=50.0)


def test_a_moved_mount_draws_what_a_rasterizer_built_with_it_draws(varied):
    varied.vary(HandVariation())
    mount = MountVariation().sample(CameraMount.paper(), np.random.default_rng(0))
    assert mount != CameraMount.paper()
    varied.set_mount(mount)
    other = SilhouetteRasterizer(HandShape(length=1.02), mount, width_px=W, height_px=H)
    assert np.array_equal(varied.mask(named_pose("grasp")), other.mask(named_pose("grasp")))
    varied.set_mount(CameraMount.paper())


def test_bad_variations_are_refused_by_name():
    with pytest.raises(InvalidShapeError, match="segment_length must have 15"):
        HandVariation(segment_length=(1.0,) * 14)
    with pytest.raises(InvalidShapeError, match="segment_width must have 15"):
        HandVariation(segment_width=(1.0,) * 5)
    with pytest.raises(InvalidShapeError, match="flesh_offset_mm out of range"):
        HandVariation(flesh_offset_mm=(0.0,) * 29 + (40.0,))
    with pytest.raises(InvalidShapeError, match="palm_length out of range"):
        HandVariation(palm_length=0.1)
    with pytest.raises(InvalidShapeError, match="mcp_offset_mm out of range"):
        HandVariation(mcp_offset_mm=(0.0,) * 7 + (np.nan,))
    with pytest.raises(InvalidShapeError, match="HandVariation"):
        VariedRasterizer(width_px=W, height_px=H).vary("long")


@pytest.mark.parametrize("spread", [-1.0, -1e-9, float("nan"), float("inf"), "1", None, True])
def test_a_random_hand_refuses_a_spread_that_is_not_a_finite_number_at_least_0(spread):
    # -1 was numpy's "ValueError: scale < 0"; NaN an error about an internal field
    import re

    named = rf"^spread must be a finite number >= 0, got {re.escape(repr(spread))}"
    with pytest.raises(InvalidShapeError, match=named):
        HandVariation.random(np.random.default_rng(0), spread=spread)
    with pytest.raises(InvalidShapeError, match=named):
        HandVariation().with_random_surface(np.random.default_rng(0), spread=spread,
                                            segment_width_sd=0.1)


def test_breadths_that_follow_the_scale_leave_the_lengths_and_scale_every_breadth_alike():
    plain = HandVariation.random(np.random.default_rng(4), spread=1.5)
    full = HandVariation.random(np.random.default_rng(4), spread=1.5, breadth_follows_scale=1.0)
    half = HandVariation.random(np.random.default_rng(4), spread=1.5, breadth_follows_scale=0.5)
    assert full.segment_length == plain.segment_length == half.segment_length
    assert full.palm_length == plain.palm_length and full.mcp_offset_mm == plain.mcp_offset_mm
    # every breadth takes the same factor, the common scale, which the segment lengths share:
    # their ratios to the plain hand's are exp(common) (1) and its square root (0.5)
    ratio = np.r_[full.digit_width, full.palm_width, full.palm_depth] / np.r_[
        plain.digit_width, plain.palm_width, plain.palm_depth]
    assert np.allclose(ratio, ratio[0]) and abs(np.log(ratio[0])) > 1e-3
    np.testing.assert_allclose(np.r_[half.digit_width, half.palm_width] / np.r_[
        plain.digit_width, plain.palm_width], np.sqrt(ratio[0]))
    for bad in (-0.1, 2.5, float("nan")):
        with pytest.raises(InvalidShapeError, match="breadth_follows_scale"):
            HandVariation.random(np.random.default_rng(4), breadth_follows_scale=bad)


def test_a_random_hand_of_spread_0_is_the_built_hand():
    rng = np.random.default_rng(5)
    assert HandVariation.random(rng, spread=0, segment_width_sd=0.1,
                                flesh_offset_sd_mm=2.0) == HandVariation()
    assert HandVariation.random(rng, spread=np.float32(0.5)) != HandVariation()
