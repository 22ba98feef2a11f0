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
