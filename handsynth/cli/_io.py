"""Reading the images the commands take (photos, calibration frames)."""

from __future__ import annotations

from pathlib import Path

from ..errors import InvalidInputError


def read_image(path, *, what: str = "image"):
    """An image file as a uint8 grey (H, W) or BGR (H, W, 3) array.

    Raises
    ------
    InvalidInputError
        No such file, not an image OpenCV can decode, or pixels that are not
        8- or 16-bit (the message names the file and `what` it is).
    """
    import cv2
    import numpy as np

    path = Path(path)
    img = cv2.imread(str(path), cv2.IMREAD_UNCHANGED) if path.is_file() else None
    if img is None:
        raise InvalidInputError(f"cannot read the {what} {str(path)!r}: no such file or not an "
                                "image OpenCV can decode")
    if img.dtype == np.uint16:
        img = (np.asarray(img, dtype=np.uint16) >> 8).astype(np.uint8)  # asarray: the same array, typed
    if img.dtype != np.uint8:
        raise InvalidInputError(f"{what} {str(path)!r} has {img.dtype} pixels; give an 8- or "
                                "16-bit image")
    if img.ndim == 3 and img.shape[2] == 4:
        img = cv2.cvtColor(img, cv2.COLOR_BGRA2BGR)
    elif img.ndim == 3 and img.shape[2] == 1:
        img = img[..., 0]
    return img
