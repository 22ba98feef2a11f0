"""Image files: read as the frames handsynth takes, written atomically (never a
half-written picture under the final name)."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from .._checks import check_path
from .._io import write_bytes
from ..errors import InvalidInputError

__all__ = ["read_image", "write_png"]


def read_image(path: str | os.PathLike, *, what: str = "image") -> np.ndarray:
    """An image file as a uint8 grey (H, W) or BGR (H, W, 3) array, read with OpenCV.

    Parameters
    ----------
    path : str or os.PathLike
        Any format OpenCV decodes (PNG, JPEG, BMP, TIFF...).  16-bit pixels
        keep their top 8 bits, an alpha channel is dropped.
    what : str, keyword-only
        What the file is, for the messages ("photo", "calibration image").

    Returns
    -------
    ndarray, shape (H, W) or (H, W, 3), uint8

    Raises
    ------
    InvalidInputError
        `path` is not a file name (None, a number, an empty name), no such
        file, not an image OpenCV can decode, or pixels that are not 8- or
        16-bit (the message names the file and `what` it is).
    """
    import cv2

    path = check_path(path, "path")
    img = cv2.imread(str(path), cv2.IMREAD_UNCHANGED) if path.is_file() else None
    if img is None:
        raise InvalidInputError(f"cannot read the {what} {str(path)!r}: no such file or not an "
                                "image OpenCV can decode")
    if img.dtype == np.uint16:
        img = (np.asarray(img, dtype=np.uint16) >> 8).astype(np.uint8)
    if img.dtype != np.uint8:
        raise InvalidInputError(f"{what} {str(path)!r} has {img.dtype} pixels; give an 8- or "
                                "16-bit image")
    if img.ndim == 3 and img.shape[2] == 4:
        img = cv2.cvtColor(img, cv2.COLOR_BGRA2BGR)
    elif img.ndim == 3 and img.shape[2] == 1:
        img = img[..., 0]
    return img


def write_png(path: str | os.PathLike, rgb: np.ndarray, *, inputs=()) -> Path:
    """Write an RGB (H, W, 3), RGBA (H, W, 4) or grey (H, W) uint8 image as PNG, atomically.

    A bool image is written as black and white; an RGBA image keeps its
    alpha channel.

    Parameters
    ----------
    path : str or os.PathLike
        The file, whose name must end in ``.png`` (any case); its folder must exist.
        The image appears under this name only when complete (written under
        ``<path>.tmp-<pid>`` first, then renamed); a symbolic link is written
        through to the file it names.
    rgb : array_like, shape (H, W, 3), (H, W, 4) or (H, W), uint8 or bool
        RGB, RGBA or grey pixels (channels in that order, not OpenCV's BGR);
        bool pixels are written as 0 and 255.
    inputs : iterable of path-like, keyword-only
        Files the caller reads; `path` must be none of them (``None`` items
        are skipped).

    Returns
    -------
    pathlib.Path
        `path` as given.

    Raises
    ------
    InvalidInputError
        `path` is not a file name (None, a number, an empty name) or does not
        end in ``.png`` (a PNG under a ``.jpg`` name would mislead its readers),
        naming it; `rgb` is not a uint8 or bool image of one of those shapes
        (the message names it, its dtype and its shape).
    OutputError
        `path` cannot be written (missing folder, full disk...) or is one of
        `inputs`; nothing is left under its name.
    """
    import cv2

    path = check_path(path, "path")
    if path.suffix.lower() != ".png":
        raise InvalidInputError(f"path must name a .png file (write_png writes PNG), got "
                                f"{str(path)!r}")
    img = np.asarray(rgb)
    if img.dtype == bool:
        img = img.astype(np.uint8) * 255
    if img.dtype != np.uint8 or not (img.ndim == 2 or (img.ndim == 3 and img.shape[2] in (3, 4))) \
            or 0 in img.shape:
        raise InvalidInputError(
            f"rgb (the image for {path}) must be a non-empty uint8 or bool image of shape (H, W), "
            f"(H, W, 3) or (H, W, 4), got dtype {img.dtype} shape {img.shape}")
    if img.ndim == 3:
        img = img[..., _TO_OPENCV[img.shape[2]]]  # RGB(A) -> OpenCV's BGR(A)
    ok, buf = cv2.imencode(".png", img)
    if not ok:
        raise InvalidInputError(f"could not encode {path} as PNG")
    return write_bytes(path, buf.tobytes(), what="picture", inputs=inputs)


#: Channel order that turns an RGB or RGBA image into OpenCV's BGR or BGRA, by channel count.
_TO_OPENCV = {3: [2, 1, 0], 4: [2, 1, 0, 3]}
