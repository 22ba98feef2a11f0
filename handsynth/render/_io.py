"""Image files written atomically (never a half-written picture under the final name)."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from .._io import write_bytes
from ..errors import InvalidInputError

__all__ = ["write_png"]


def write_png(path: str | os.PathLike, rgb: np.ndarray, *, inputs=()) -> Path:
    """Write an RGB (H, W, 3) or grey (H, W) uint8 image as PNG, atomically.

    Raises
    ------
    InvalidInputError
        Not a uint8 or bool image.
    OutputError
        `path` cannot be written (missing folder, full disk...) or is one of
        `inputs`; nothing is left under its name.
    """
    import cv2

    path = Path(path)
    img = np.asarray(rgb)
    if img.dtype == bool:
        img = img.astype(np.uint8) * 255
    if img.dtype != np.uint8 or img.ndim not in (2, 3):
        raise InvalidInputError(f"image for {path} must be uint8 (H, W[, 3]), got {img.dtype} {img.shape}")
    ok, buf = cv2.imencode(".png", img[..., ::-1] if img.ndim == 3 else img)
    if not ok:
        raise InvalidInputError(f"could not encode {path} as PNG")
    return write_bytes(path, buf.tobytes(), what="picture", inputs=inputs)
