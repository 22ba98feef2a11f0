import numpy as np
import pytest

from handsynth import CameraMount, HandShape
from handsynth.errors import InvalidCameraError, InvalidPoseError
from handsynth.models import named_pose
from handsynth.render import SilhouetteRenderer, render_rgb, wrist_cut_keep


@pytest.fixture(scope="module")
def small():
    with SilhouetteRenderer(width_px=180, height_px=120) as r:
        yield r


def test_masks_are_non_empty_and_change_with_pose(small):
    masks = small.masks(np.stack([named_pose(p) for p in ("open", "fist", "pinch", "spread")]))
    assert masks.shape == (4, 120, 180) and masks.dtype == bool
    areas = masks.sum(axis=(1, 2))
    assert np.all(areas > 0.05 * 180 * 120)
    for i in range(4):
        for j in range(i + 1, 4):
            assert (masks[i] ^ masks[j]).sum() > 100
    # a flexed index finger hides part of itself: the mask shrinks
    bent = small.mask({"index_pip_flex": 90, "index_dip_flex": 60, "index_mcp_flex": 80})
    assert bent.sum() < areas[0] - 50


def test_rendering_is_deterministic(small):
    p = named_pose("pinch")
    np.testing.assert_array_equal(small.mask(p), small.mask(p))


def test_batch_equals_single(small):
    poses = np.stack([named_pose("grasp"), named_pose("point")])
    batch = small.masks(poses)
    for p, m in zip(poses, batch):
        np.testing.assert_array_equal(small.mask(p), m)


def _iou(a, b):
    return (a & b).sum() / (a | b).sum()


def test_left_hand_renders_as_the_mirror_image():
    r = SilhouetteRenderer(width_px=360, height_px=240)
    left = SilhouetteRenderer(width_px=360, height_px=240, side="left")
    for pose in ("open", "fist", "spread"):
        a, b = r.mask(named_pose(pose)), left.mask(named_pose(pose))
        assert _iou(a, b[::-1]) > 0.99
        assert _iou(a, b) < 0.9  # and not simply the same picture


@pytest.mark.slow
def test_whole_hand_preset_keeps_the_hand_inside_the_frame():
    mount = CameraMount.whole_hand()
    keep = wrist_cut_keep(mount, width_px=360, height_px=240)
    for shape in HandShape.grid():
        with SilhouetteRenderer(shape, mount, width_px=360, height_px=240) as r:
            for m in r.masks(np.stack([named_pose("open"), named_pose("fist"), named_pose("spread")])):
                hand = m & keep
                assert hand.sum() > 1000
                assert not (hand[0].any() or hand[-1].any() or hand[:, 0].any() or hand[:, -1].any())


def test_paper_mount_cuts_the_fingertips():
    # the geometry the issue warns about: at 120 mm an open hand leaves the frame
    with SilhouetteRenderer(HandShape(length=1.05), width_px=360, height_px=240) as r:
        m = r.mask(named_pose("spread"))
    assert m[:, -1].any()


@pytest.mark.parametrize("w, h", [(0, 120), (128, 0), (-5, 5), (1.5, 10)])
def test_zero_size_images_are_refused(w, h):
    with pytest.raises(InvalidCameraError, match="width_px|height_px"):
        SilhouetteRenderer(width_px=w, height_px=h)


def test_bad_pose_is_refused_before_rendering(small):
    with pytest.raises(InvalidPoseError, match="index_mcp_flex"):
        small.mask({"index_mcp_flex": float("nan")})


def test_rgb_views():
    img = render_rgb(named_pose("open"), width_px=96, height_px=64)
    side = render_rgb(named_pose("fist"), camera="side", width_px=96, height_px=64)
    assert img.shape == (64, 96, 3) and img.dtype == np.uint8
    assert img.std() > 10 and side.std() > 5
    with pytest.raises(InvalidCameraError, match="camera must be"):
        render_rgb(named_pose("open"), camera="back")
