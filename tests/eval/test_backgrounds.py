import numpy as np
import pytest

from handsynth.errors import InvalidInputError
from handsynth.eval import BACKGROUND_PHOTOS, background_photos


def test_background_photos_are_bgr_frames_of_the_size_asked():
    photos = background_photos(width_px=72, height_px=48)
    assert len(photos) == len(BACKGROUND_PHOTOS) == 10
    for p in photos:
        assert p.shape == (48, 72, 3) and p.dtype == np.uint8
    # colour photographs keep their colour (BGR order), gray ones repeat one channel
    astronaut = photos[BACKGROUND_PHOTOS.index("astronaut")]
    assert not np.array_equal(astronaut[..., 0], astronaut[..., 2])
    camera = photos[BACKGROUND_PHOTOS.index("camera")]
    assert np.array_equal(camera[..., 0], camera[..., 2])
    # not dark like the device's background: a hand binarized over them is hard
    assert np.mean([p.mean() for p in photos]) > 60


@pytest.mark.parametrize("kw", [{"width_px": 0}, {"height_px": 2.5}, {"width_px": True}])
def test_background_photos_refuse_a_size_that_is_not_a_positive_integer(kw):
    name = next(iter(kw))
    with pytest.raises(InvalidInputError, match=f"{name} must be a positive integer"):
        background_photos(**kw)
