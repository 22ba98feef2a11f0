"""Image files written atomically (never a half-written picture under the final name)."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from ..errors import InvalidInputError

__all__ = ["write_png"]


def write_png(path: str | os.PathLike, rgb: np.ndarray) -> Path:
    """Write an RGB (H, W, 3) or grey (H, W) uint8 image as PNG, atomically."""
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
    tmp = path.with_name(f".{path.name}.tmp-{os.getpid()}")
    tmp.write_bytes(buf.tobytes())
    os.replace(tmp, path)
    return path
