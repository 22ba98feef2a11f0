import numpy as np
import pytest

from handsynth.errors import InvalidInputError
from handsynth.models import named_pose
from handsynth.render import CameraMount, SilhouetteRasterizer, coverage, wrist_cut_keep


def test_coverage_is_the_covered_share_of_each_cell_after_the_wrist_cut():
    mount = CameraMount.paper()
    mask = SilhouetteRasterizer(mount=mount).mask(named_pose("spread"))
    cov = coverage(mask, mount, cells=(30, 45))
    assert cov.shape == (30, 45) and cov.dtype == np.float32
    kept = mask & wrist_cut_keep(mount)
    # 16x16-pixel cells: each cell's share is its pixel count / 256
    expect = kept.reshape(30, 16, 45, 16).mean(axis=(1, 3))
    np.testing.assert_allclose(cov, expect, atol=1e-6)


def test_a_grey_frame_gives_the_mask_s_coverage():
    mask = SilhouetteRasterizer().mask(named_pose("fist"))
    frame = np.where(mask, 200, 20).astype(np.uint8)
    np.testing.assert_allclose(coverage(frame), coverage(mask), atol=1e-6)


def test_one_finger_changes_only_the_cells_it_crosses():
    r = SilhouetteRasterizer()
    a = np.zeros(20)
    b = a.copy()
    b[6] = 60.0  # index PIP
    changed = np.abs(coverage(r.mask(a)) - coverage(r.mask(b))) > 0
    assert 0 < changed.sum() < 0.1 * changed.size


def test_bad_cells_are_refused():
    with pytest.raises(InvalidInputError, match="cells"):
        coverage(np.zeros((48, 72), bool), cells=(1, 45))
    with pytest.raises(InvalidInputError, match="cells"):
        coverage(np.zeros((48, 72), bool), cells="big")
