import numpy as np
import pytest

from handsynth import CameraMount
from handsynth.errors import InvalidInputError
from handsynth.models import named_pose
from handsynth.render import SilhouetteRenderer, crop_resize, largest_component, preprocess

NO_CUT = CameraMount(wrist_cut_mm=None)


def test_keeps_largest_component_only():
    m = np.zeros((100, 120), bool)
    m[10:60, 10:40] = True   # big
    m[80:85, 100:105] = True  # small speck
    np.testing.assert_array_equal(largest_component(m), m & (np.arange(120) < 50)[None])


def test_aspect_ratio_is_kept_and_centred():
    m = np.zeros((100, 200), bool)
    m[20:40, 50:130] = True  # a 20 x 80 bar
    s = crop_resize(m, size=64)
    rows, cols = np.flatnonzero(s.any(1)), np.flatnonzero(s.any(0))
    assert cols.size == 64 and rows.size == 16
    assert rows[0] == 24  # centred vertically


def test_no_hand_gives_empty_silhouette():
    assert not preprocess(np.zeros((480, 720), bool), NO_CUT).any()
    assert not preprocess(np.zeros((48, 72, 3), np.uint8)).any()


def test_bgr_frame_gives_the_same_silhouette_as_its_mask():
    r = SilhouetteRenderer(width_px=360, height_px=240)
    mask = r.mask(named_pose("spread"))
    rng = np.random.default_rng(0)
    frame = np.where(mask[..., None], 200, 30).astype(np.uint8) + rng.integers(0, 20, (240, 360, 3), dtype=np.uint8)
    a, b = preprocess(mask, r.mount), preprocess(frame, r.mount)
    assert (a ^ b).sum() <= 10


def test_wrist_cut_removes_the_forearm():
    r = SilhouetteRenderer(width_px=360, height_px=240)
    m = r.mask(named_pose("fist"))
    assert m[:, 0].any()  # the forearm reaches the image border
    cut = preprocess(m, r.mount)
    nocut = preprocess(m, NO_CUT)
    assert cut.sum() != nocut.sum()


@pytest.mark.parametrize("frame, words", [
    (np.zeros((1, 1), np.uint8), "too small"),
    (np.zeros((64, 64), np.float32), "dtype float32"),
    (np.zeros((64, 64, 4), np.uint8), "shape"),
    ([[1, 2]], "numpy array"),
])
def test_garbage_frames_are_refused(frame, words):
    with pytest.raises(InvalidInputError, match=words):
        preprocess(frame)


def test_fast_preprocess_equals_the_reference_on_renders():
    from handsynth.models import natural_pose_set, paper_pose_set
    from handsynth.render import SilhouetteRasterizer, preprocess_reference

    poses = np.vstack([paper_pose_set(3000, seed=2)[::100], natural_pose_set(20, seed=3)])
    for side, mount in (("right", CameraMount()), ("left", CameraMount.whole_hand())):
        r = SilhouetteRasterizer(mount=mount, side=side, width_px=360, height_px=240)
        for m in r.masks(poses):
            np.testing.assert_array_equal(preprocess(m, mount, side=side),
                                          preprocess_reference(m, mount, side=side))


@pytest.mark.parametrize("seed", range(4))
def test_fast_preprocess_equals_the_reference_on_random_masks(seed):
    from handsynth.render import preprocess_reference

    rng = np.random.default_rng(seed)
    for _ in range(50):
        h, w = rng.integers(8, 70, size=2)
        m = rng.random((h, w)) < rng.uniform(0.05, 0.7)  # many components, ties, gaps
        for size in (8, 17, 64):
            np.testing.assert_array_equal(preprocess(m, NO_CUT, size=size),
                                          preprocess_reference(m, NO_CUT, size=size))


def test_resampling_is_continuous_across_resolutions():
    # the same view at 3x the resolution gives nearly the same silhouette
    from handsynth.render import SilhouetteRasterizer

    lo = SilhouetteRasterizer(width_px=240, height_px=160).mask(named_pose("spread"))
    hi = SilhouetteRasterizer(width_px=720, height_px=480).mask(named_pose("spread"))
    a, b = preprocess(lo), preprocess(hi)
    assert (a & b).sum() / (a | b).sum() > 0.97


def test_crop_resize_area_rule():
    # a 4x4 box scaled to 8x8: every cell fully covered; a box of 2 px height
    # in a 10 px wide mask covers rows 3.2-4.8 of 8: only row 4 reaches half
    m = np.zeros((20, 20), bool)
    m[5:9, 5:9] = True
    assert crop_resize(m, size=8).all()
    bar = np.zeros((20, 20), bool)
    bar[4:6, 0:10] = True
    s = crop_resize(bar, size=8)
    np.testing.assert_array_equal(np.flatnonzero(s.any(axis=1)), [3, 4])
