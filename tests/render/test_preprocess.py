import re

import numpy as np
import pytest

from handsynth import CameraMount
from handsynth.errors import InvalidInputError
from handsynth.models import named_pose
from handsynth.render import (
    SilhouetteRenderer,
    crop_resize,
    largest_component,
    preprocess,
    preprocess_reference,
    wrist_cut_keep,
)

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
    noise = rng.integers(0, 20, (240, 360, 3), dtype=np.uint8)
    frame = np.where(mask[..., None], 200, 30).astype(np.uint8) + noise
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
    (np.zeros((64, 64), np.float32), r"dtype float32; a float image in \[0, 1\] is \(frame \* 255\)"),
    (np.zeros((64, 64), np.uint16), "dtype uint16$"),
    (np.zeros((64, 64, 4), np.uint8), r"shape .*\(64, 64, 4\); drop the alpha channel: frame\[..., :3\]"),
    (np.zeros((64, 64, 2), np.uint8), r"got \(64, 64, 2\)$"),
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


# ---- binarization of uint8 frames (step 1): exact grey levels, Otsu on the sample

def _bright_hand_frame(mask, rng):
    """The mask as a camera frame: skin-coloured hand on a dark background, with noise."""
    img = np.where(mask[..., None], np.uint8([120, 160, 210]), np.uint8([15, 20, 25]))
    return np.ascontiguousarray(img + rng.integers(0, 12, img.shape, dtype=np.uint8))


def test_grey_levels_are_opencvs_bgr2gray_for_every_colour():
    import cv2

    from handsynth.render import binarize

    colours = np.arange(1 << 24, dtype=np.uint32).view(np.uint8).reshape(4096, 4096, 4)
    frame = np.ascontiguousarray(colours[..., :3])  # every (B, G, R) once
    grey = cv2.cvtColor(frame, cv2.COLOR_BGR2GRAY)
    for t in (0, 31, 32, 127, 128, 200, 254):
        np.testing.assert_array_equal(binarize(frame, threshold=t), grey > t)


def _bimodal_frames():
    rng = np.random.default_rng(11)
    out = []
    for h, w, frac, fg, bg, noise in [(480, 720, 0.35, (120, 160, 210), (15, 20, 25), 12),
                                      (37, 53, 0.5, (200, 200, 200), (30, 40, 50), 40),
                                      (100, 129, 0.1, (90, 130, 200), (60, 60, 60), 25),
                                      (64, 64, 0.8, (250, 240, 230), (0, 0, 0), 5)]:
        yy, xx = np.mgrid[0:h, 0:w]
        blob = (yy - h / 2) ** 2 / h ** 2 + (xx - w / 3) ** 2 / w ** 2 < frac / 3
        img = np.where(blob[..., None], np.uint8(fg), np.uint8(bg)).astype(np.int16)
        img += rng.integers(-noise // 2, noise // 2 + 1, img.shape).astype(np.int16)
        out.append(np.clip(img, 0, 255).astype(np.uint8))
    # overlapping modes: full image, this sample and a shifted one give different thresholds
    g = np.where(rng.random((90, 131)) < 0.4, rng.normal(150, 30, (90, 131)),
                 rng.normal(80, 30, (90, 131)))
    out.append(np.repeat(np.clip(g, 0, 255).astype(np.uint8)[..., None], 3, axis=2))
    return out


@pytest.mark.parametrize("k", range(5))
@pytest.mark.parametrize("grey_input", [False, True])
def test_sampled_otsu_threshold_is_opencvs_otsu_on_the_sample(k, grey_input):
    import cv2

    from handsynth.render import binarize
    from handsynth.render._preprocess import OTSU_STEP, otsu_threshold

    frame = _bimodal_frames()[k]
    grey = cv2.cvtColor(frame, cv2.COLOR_BGR2GRAY)
    sample = np.ascontiguousarray(grey[::OTSU_STEP, ::OTSU_STEP])
    expected, _ = cv2.threshold(sample, 0, 255, cv2.THRESH_BINARY + cv2.THRESH_OTSU)
    t = otsu_threshold(grey if grey_input else frame)
    assert t == int(expected)
    assert 0 < t < 255
    # (the whole image's Otsu threshold differs for some of these: the sample defines it)
    np.testing.assert_array_equal(binarize(grey if grey_input else frame), grey > t)


def test_otsu_of_a_uniform_histogram_is_opencvs_and_the_frame_is_empty():
    import cv2

    from handsynth.render import binarize
    from handsynth.render._preprocess import otsu_threshold
    from handsynth.render._runs import _grey_histogram, _otsu

    for level in (0, 77, 255):
        frame = np.full((48, 72, 3), level, np.uint8)
        grey = cv2.cvtColor(frame, cv2.COLOR_BGR2GRAY)
        hist = _grey_histogram(frame.reshape(-1), 48, 72, 3)
        cv_t, _ = cv2.threshold(grey[::4, ::4].copy(), 0, 255,
                                cv2.THRESH_BINARY + cv2.THRESH_OTSU)
        assert _otsu(hist) == int(cv_t)
        assert otsu_threshold(frame) == -1  # no hand: all samples at one level
        assert not binarize(frame).any()
        assert not preprocess(frame).any()
        assert not preprocess(frame[..., 0].copy()).any()


@pytest.mark.parametrize(("low", "high", "hand"), [
    (126, 128, False),   # a grey MJPG video's two levels: was split into a random silhouette
    (240, 251, False),   # an overexposed, almost white view
    (0, 11, False),
    (0, 1, True),        # a mask given as uint8 0 and 1
    (20, 32, True),      # MIN_CONTRAST levels apart: an image
    (20, 55, True),      # the dimmest hand of the imaging study against its background
])
def test_a_frame_of_fewer_than_min_contrast_grey_levels_shows_no_hand(low, high, hand):
    from handsynth.render import MIN_CONTRAST, binarize, preprocess_reference
    from handsynth.render._preprocess import otsu_threshold

    assert MIN_CONTRAST == 12
    frame = np.full((120, 180, 3), low, np.uint8)
    frame[30:90, 40:140] = high  # a patch where a hand would be
    for f in (frame, np.ascontiguousarray(frame[..., 0])):
        assert (otsu_threshold(f) >= 0) == hand
        assert binarize(f).any() == hand
        assert preprocess(f).any() == hand
        np.testing.assert_array_equal(preprocess(f), preprocess_reference(f))


def test_bright_hand_on_dark_frame_gives_the_silhouette_of_its_mask():
    import cv2

    from handsynth.models import paper_pose_set
    from handsynth.render import binarize, preprocess_reference

    r = SilhouetteRenderer(width_px=360, height_px=240)
    rng = np.random.default_rng(4)
    for pose in [named_pose("spread"), named_pose("fist"), *paper_pose_set(4, seed=1)]:
        mask = r.mask(pose)
        frame = _bright_hand_frame(mask, rng)
        np.testing.assert_array_equal(binarize(frame), mask)
        expected = preprocess(mask, r.mount)
        np.testing.assert_array_equal(preprocess(frame, r.mount), expected)
        np.testing.assert_array_equal(preprocess_reference(frame, r.mount), expected)
        grey = cv2.cvtColor(frame, cv2.COLOR_BGR2GRAY)
        np.testing.assert_array_equal(preprocess(grey, r.mount), expected)


def test_fixed_threshold_keyword():
    import cv2

    from handsynth.render import binarize, preprocess_reference

    rng = np.random.default_rng(5)
    frame = rng.integers(0, 256, (60, 90, 3), dtype=np.uint8)
    grey = cv2.cvtColor(frame, cv2.COLOR_BGR2GRAY)
    for t in (-1, 0, 100, 254, 255):
        np.testing.assert_array_equal(binarize(frame, threshold=t), grey > t)
        np.testing.assert_array_equal(binarize(grey, threshold=t), grey > t)
        for mount in (NO_CUT, CameraMount()):
            expected = preprocess(grey > t, mount)
            np.testing.assert_array_equal(preprocess(frame, mount, threshold=t), expected)
            np.testing.assert_array_equal(preprocess(grey, mount, threshold=t), expected)
            np.testing.assert_array_equal(preprocess_reference(frame, mount, threshold=t),
                                          expected)
    assert binarize(frame, threshold=-7).all() and not binarize(frame, threshold=300).any()
    flat = np.full((40, 40), 200, np.uint8)  # a fixed threshold skips the no-hand rule
    assert binarize(flat, threshold=100).all() and not binarize(flat).any()


@pytest.mark.parametrize("seed", range(3))
def test_fast_preprocess_equals_the_reference_on_random_frames(seed):
    from handsynth.render import preprocess_reference

    rng = np.random.default_rng(100 + seed)
    for i in range(40):
        h, w = rng.integers(8, 120, size=2)
        blocks = rng.integers(0, 256, (h // 4 + 1, w // 4 + 1, 3), dtype=np.uint8)
        frame = np.ascontiguousarray(np.repeat(np.repeat(blocks, 4, 0), 4, 1)[:h, :w])
        frame = frame if i % 2 else np.ascontiguousarray(frame[..., 1])
        mount = (NO_CUT, CameraMount(), CameraMount.whole_hand())[i % 3]
        side = ("right", "left")[i % 2]
        for size in (8, 64):
            np.testing.assert_array_equal(preprocess(frame, mount, side=side, size=size),
                                          preprocess_reference(frame, mount, side=side,
                                                               size=size))


def test_fast_preprocess_equals_the_reference_past_the_first_run_buffer():
    # ~22,000 runs: more than the kernels' first buffer of 4,096, so it must grow
    from handsynth.render import preprocess_reference

    rng = np.random.default_rng(7)
    mask = rng.random((300, 300)) < 0.5
    grey = np.where(mask, 200, 20).astype(np.uint8)
    for frame in (mask, grey):
        np.testing.assert_array_equal(preprocess(frame, NO_CUT, size=64),
                                      preprocess_reference(frame, NO_CUT, size=64))


def test_a_three_channel_bool_frame_is_refused():
    # issue 16 item 10: a bool (H, W, 3) frame passed check_frame and crashed later
    from handsynth.render import check_frame

    frame = np.zeros((48, 64, 3), bool)
    frame[10:30, 10:40] = True
    for fn in (check_frame, lambda f: preprocess(f, CameraMount())):
        with pytest.raises(InvalidInputError, match=r"a bool frame is a mask and must have shape "
                                                    r"\(H, W\), got \(48, 64, 3\)"):
            fn(frame)
    assert preprocess(frame[..., 0], CameraMount()).any()  # its one channel is fine


# ---- arguments of the plain steps

@pytest.mark.parametrize("mask, words", [
    (np.zeros((0, 5), bool), r"mask must not be empty .*got shape \(0, 5\)"),  # was: a segfault
    (np.zeros((5, 0), bool), r"mask must not be empty .*got shape \(5, 0\)"),
    (np.zeros((0, 0), bool), r"mask must not be empty .*got shape \(0, 0\)"),
    (np.zeros((5, 5, 3), np.uint8), r"mask must be a 2-D bool or uint8 numpy array, got dtype uint8 "
                                    r"shape \(5, 5, 3\)"),
    (np.zeros((5, 5, 3), bool), r"mask must be a 2-D .*got dtype bool shape \(5, 5, 3\)"),
    (np.zeros((5, 5), np.float64), r"mask must be a 2-D .*got dtype float64 shape \(5, 5\)"),
    ([[True, False]], r"mask must be a 2-D bool or uint8 numpy array, got list \[\[True, False\]\]"),
    (None, "mask must be a 2-D bool or uint8 numpy array, got NoneType None"),
])
def test_largest_component_and_crop_resize_refuse_a_mask_that_is_not_one(mask, words):
    # issue: an empty mask killed the interpreter in largest_component; a 3-D one gave a
    # raw cv2.error there, and crop_resize took a 3-D bool mask as a 64x64 silhouette
    for fn in (largest_component, crop_resize):
        with pytest.raises(InvalidInputError, match=words):
            fn(mask)


@pytest.mark.parametrize("size", [0, -4, 7, 4097, 100000, 8.0, "64", True, None])
def test_crop_resize_and_preprocess_share_one_size_rule(size):
    # issue: crop_resize(size=0) gave a (0, 0) array, size=-4 a raw numpy error, and
    # preprocess(size=100000) a raw MemoryError
    m = np.zeros((20, 20), bool)
    m[5:15, 5:15] = True
    for fn in (crop_resize, preprocess):
        with pytest.raises(InvalidInputError, match=rf"size must be an integer >= 8 and <= 4096, "
                                                    rf"got {size!r}"):
            fn(m, size=size)


def test_small_masks_and_the_size_bounds_are_accepted():
    m = np.zeros((3, 4), bool)
    m[1, 1:3] = True
    assert largest_component(m).sum() == 2
    assert crop_resize(m, size=8).sum() == 32  # a 1 x 2 bar fills half of 8 x 8
    assert crop_resize(m.astype(np.uint8) * 255, size=8).sum() == 32  # uint8: nonzero is hand
    assert crop_resize(m, size=np.int64(4096)).shape == (4096, 4096)


def _speck_and_hand(h: int = 120, w: int = 180):
    """A mask whose largest component covers 1 % of the view less one pixel, and one of
    exactly 1 % (``h * w / 100`` pixels), each with a smaller speck beside it."""
    exact = np.zeros((h, w), bool)
    exact[10:10 + h // 10, 20:20 + w // 10] = True  # a block of h * w / 100 pixels
    exact[-3:-1, -3:-1] = True  # a 4-pixel speck, apart
    under = exact.copy()
    under[10, 20] = False  # one pixel short
    return under, exact


@pytest.mark.parametrize("as_frame", [False, True])
def test_min_coverage_empties_a_component_under_that_share_of_the_frame(as_frame):
    # a speck (one bright pixel) is too little to be a hand; the lookup passes MIN_HAND_COVERAGE
    under, exact = _speck_and_hand()
    for mask, hand in ((under, False), (exact, True)):
        frame = np.where(mask[..., None], np.uint8(220), np.uint8(10)).repeat(3, 2) \
            if as_frame else mask
        got = preprocess(frame, NO_CUT, min_coverage=0.01)
        assert got.any() == hand
        np.testing.assert_array_equal(got, preprocess_reference(frame, NO_CUT, min_coverage=0.01))
        if hand:
            np.testing.assert_array_equal(got, preprocess(frame, NO_CUT))
        assert preprocess(frame, NO_CUT).any()  # no rule by default
    one = np.zeros((480, 720, 3), np.uint8)
    one[200, 300] = 255
    assert preprocess(one).any() and not preprocess(one, min_coverage=0.01).any()
    assert preprocess(one, min_coverage=1 / one[..., 0].size).any()


def test_min_coverage_counts_what_the_wrist_cut_keeps():
    r = SilhouetteRenderer(width_px=360, height_px=240)
    m = r.mask(named_pose("fist"))
    kept = largest_component(m & wrist_cut_keep(r.mount, width_px=360, height_px=240)).mean()
    assert preprocess(m, r.mount, min_coverage=kept).any()
    assert not preprocess(m, r.mount, min_coverage=kept + 1 / m.size).any()


@pytest.mark.parametrize("value, got", [
    (-0.1, "-0.1"), (1.5, "1.5"), (float("nan"), "nan"), ("1%", "'1%' (str)"), (None, "None (NoneType)"),
])
def test_min_coverage_is_checked(value, got):
    words = f"min_coverage must be a finite number >= 0 and <= 1, got {got}"
    with pytest.raises(InvalidInputError, match=re.escape(words)):
        preprocess(np.zeros((48, 72), bool), min_coverage=value)
    with pytest.raises(InvalidInputError, match=re.escape(words)):
        preprocess_reference(np.zeros((48, 72), bool), min_coverage=value)
