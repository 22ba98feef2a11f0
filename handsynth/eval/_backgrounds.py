"""Photographs to composite test frames over (the camera's view is not always dark).

The device's estimators binarize the frame by Otsu's threshold, which suits a
hand brighter than a dark background.  :func:`background_photos` gives
ordinary photographs, bundled with scikit-image (no download), to composite
the hand over, as the studies of backgrounds and the speed benchmark do.
"""

from __future__ import annotations

import numpy as np

from ..errors import InvalidInputError

__all__ = ["BACKGROUND_PHOTOS", "background_photos"]

#: The photographs of :mod:`skimage.data` used, by name: people, objects,
#: text and textures, colour and gray.
BACKGROUND_PHOTOS: tuple[str, ...] = ("astronaut", "coffee", "chelsea", "rocket", "camera",
                                      "coins", "page", "moon", "text", "clock")


def background_photos(*, width_px: int = 720, height_px: int = 480) -> list[np.ndarray]:
    """The photographs of :data:`BACKGROUND_PHOTOS`, resized to the frame.

    Parameters
    ----------
    width_px, height_px : int, keyword-only
        Frame size, pixels (default the paper's device, 720x480).

    Returns
    -------
    list of ndarray, each shape (height_px, width_px, 3) uint8
        BGR (OpenCV's order), gray photographs repeated over the channels.

    Raises
    ------
    InvalidInputError
        A size that is not a positive integer.
    """
    for name, v in (("width_px", width_px), ("height_px", height_px)):
        if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or v < 1:
            raise InvalidInputError(f"{name} must be a positive integer, got {v!r}")
    import cv2
    import skimage.data

    out = []
    for name in BACKGROUND_PHOTOS:
        im = getattr(skimage.data, name)()
        if im.ndim == 2:
            im = np.stack([im] * 3, -1)
        out.append(cv2.resize(cv2.cvtColor(np.ascontiguousarray(im[..., :3]), cv2.COLOR_RGB2BGR),
                              (int(width_px), int(height_px))))
    return out
