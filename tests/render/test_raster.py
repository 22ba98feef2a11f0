"""SilhouetteRasterizer gives MuJoCo's renderer's masks."""

import numpy as np
import pytest

from handsynth.models import HandShape, natural_pose_set, paper_pose_set
from handsynth.render import (
    CameraMount,
    SilhouetteRasterizer,
    SilhouetteRenderer,
    preprocess,
)

POSES = np.vstack([paper_pose_set(2000, seed=4)[::100], natural_pose_set(10, seed=5)])


def _iou(a, b):
    return (a & b).sum(axis=(1, 2)) / np.maximum((a | b).sum(axis=(1, 2)), 1)


@pytest.mark.parametrize("shape, mount, side", [
    (HandShape(), CameraMount(), "right"),
    (HandShape(length=1.2, width=0.8, palm=1.1, thumb=0.9), CameraMount.whole_hand(), "left"),
])
def test_masks_match_mujoco_renderer(shape, mount, side):
    kw = dict(side=side, width_px=360, height_px=240)
    with SilhouetteRenderer(shape, mount, **kw) as gl:
        ref = gl.masks(POSES)
    ours = SilhouetteRasterizer(shape, mount, **kw).masks(POSES)
    iou = _iou(ours, ref)
    assert iou.min() > 0.999, iou.min()
    # at most a handful of edge pixels differ per mask (pixel-centre rule ties)
    assert (ours ^ ref).sum(axis=(1, 2)).max() <= 12
    sil_a = np.stack([preprocess(m, mount, side=side) for m in ours])
    sil_b = np.stack([preprocess(m, mount, side=side) for m in ref])
    assert _iou(sil_a, sil_b).mean() > 0.999


def test_mask_and_masks_agree_and_reuse_out():
    r = SilhouetteRasterizer(width_px=180, height_px=120)
    out = np.ones((2, 120, 180), bool)
    got = r.masks(POSES[:2], out=out)
    assert got is out
    np.testing.assert_array_equal(out[1], r.mask(POSES[1]))
    assert 0.05 < out.mean() < 0.9


def test_a_finger_flexion_changes_only_that_finger():
    r = SilhouetteRasterizer(width_px=360, height_px=240)
    a = np.zeros(20)
    b = a.copy()
    b[6] = 80.0  # index PIP
    ma, mb = r.mask(a), r.mask(b)
    assert (ma & ~mb).sum() > 200  # the bent finger's end left its place
