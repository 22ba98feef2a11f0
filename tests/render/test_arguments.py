"""Arguments of the wrong type or value are refused with errors that name them."""

import numpy as np
import pytest

from handsynth import CameraMount
from handsynth.errors import InvalidCameraError, InvalidInputError, InvalidShapeError
from handsynth.models import HandModel, HandShape, named_pose
from handsynth.render import (
    SilhouetteRasterizer,
    SilhouetteRenderer,
    binarize,
    coverage,
    preprocess,
    preprocess_reference,
    render_rgb,
    scene_mjcf,
    wrist_cut_keep,
)


def _mask():
    m = np.zeros((40, 60), bool)
    m[10:30, 20:55] = True
    return m


@pytest.mark.parametrize("samples", [-1, 1, 3, 2.5, 64, True, "4", None])
def test_msaa_samples_outside_the_offered_counts_are_refused(samples):
    with pytest.raises(InvalidInputError, match=rf"samples .*got {samples!r}"):
        SilhouetteRenderer(width_px=60, height_px=40, samples=samples)
    with pytest.raises(InvalidInputError, match="samples"):
        scene_mjcf(samples=samples)


@pytest.mark.parametrize("samples", [0, 2, 4, np.int64(4)])
def test_offered_msaa_samples_render(samples):
    with SilhouetteRenderer(width_px=60, height_px=40, samples=samples) as r:
        assert r.mask(named_pose("open")).any()


@pytest.mark.parametrize("threshold", [float("nan"), float("inf"), -float("inf"), "100", True,
                                       [100], None])
def test_bad_thresholds_are_refused_by_name(threshold):
    mask = _mask()
    frame = mask.astype(np.uint8) * 200
    calls = [lambda: preprocess(frame, threshold=threshold),
             lambda: preprocess(mask, threshold=threshold),
             lambda: preprocess_reference(frame, threshold=threshold),
             lambda: binarize(frame, threshold=threshold),
             lambda: binarize(mask, threshold=threshold),
             lambda: coverage(frame, threshold=threshold)]
    if threshold is None:  # Otsu's threshold: accepted
        for call in calls:
            call()
        return
    for call in calls:
        with pytest.raises(InvalidInputError, match="threshold"):
            call()


def test_fixed_thresholds_of_any_real_number_type_agree():
    frame = _mask().astype(np.uint8) * 200
    ref = preprocess(frame, threshold=100)
    for t in (100.0, 100.7, np.uint8(100), np.float32(100.2), np.int64(100)):
        np.testing.assert_array_equal(preprocess(frame, threshold=t), ref)
    assert not preprocess(frame, threshold=1e9).any()  # finite and past 255: no hand


@pytest.mark.parametrize("mount", [HandShape(), {"height_mm": 120}, 120.0, "paper"])
def test_a_mount_that_is_not_a_camera_mount_is_refused_by_name(mount):
    name = type(mount).__name__
    for call in (lambda: SilhouetteRenderer(HandShape(), mount, width_px=60, height_px=40),
                 lambda: SilhouetteRasterizer(HandShape(), mount, width_px=60, height_px=40),
                 lambda: render_rgb(named_pose("open"), None, mount, width_px=60, height_px=40),
                 lambda: preprocess(_mask(), mount),
                 lambda: preprocess_reference(_mask(), mount),
                 lambda: coverage(_mask(), mount),
                 lambda: wrist_cut_keep(mount)):
        with pytest.raises(InvalidCameraError, match=rf"mount must be a CameraMount, got {name}"):
            call()


@pytest.mark.parametrize("shape", [CameraMount(), {}, 0, "standard"])
def test_a_shape_that_is_not_a_hand_shape_is_refused_by_name(shape):
    name = type(shape).__name__
    with pytest.raises(InvalidShapeError, match=rf"shape must be a HandShape, got {name}"):
        SilhouetteRenderer(shape, width_px=60, height_px=40)
    with pytest.raises(InvalidShapeError, match=rf"shape must be a HandShape, got {name}"):
        SilhouetteRasterizer(shape, width_px=60, height_px=40)
    with pytest.raises(InvalidShapeError, match=rf"shape must be a HandShape, got {name}"):
        HandModel(shape)


@pytest.mark.parametrize("maker", [SilhouetteRenderer, SilhouetteRasterizer])
@pytest.mark.parametrize("out, words", [([[0]], "got list"), (np.zeros((1, 40, 60)), "float64"),
                                        (np.zeros((2, 40, 60), bool), r"\(2, 40, 60\)")])
def test_masks_out_that_is_not_the_right_array_is_refused_by_name(maker, out, words):
    with maker(width_px=60, height_px=40) as r, \
            pytest.raises(InvalidInputError, match=rf"out must be a bool .*{words}"):
        r.masks(np.stack([named_pose("open")]), out=out)
