"""Fixed-frame coverage: how much of each cell of the camera's whole view the hand covers.

The paper's preprocessing crops a frame to the hand's bounding box and
rescales it to 64x64 (:func:`~handsynth.render.preprocess`).  The camera is
fixed to the wrist, so a pixel's place already means something: a change of
one finger then moves the whole cropped silhouette, and a hand whose other
fingers rest a few degrees elsewhere matches nothing.  :func:`coverage` keeps
the camera's frame: the binarized frame, less the wrist cut, averaged over a
fixed grid of cells of the full view (16x16 pixels of a 720x480 frame by
default).  A finger changes only the cells it crosses.
"""

from __future__ import annotations

from functools import lru_cache

import cv2
import numpy as np

from ..errors import InvalidInputError
from ._camera import CameraMount, as_mount
from ._preprocess import binarize, wrist_cut_keep

__all__ = ["DEFAULT_CELLS", "coverage"]

#: Default grid: (rows, columns) of cells over the whole frame.
DEFAULT_CELLS: tuple[int, int] = (30, 45)


@lru_cache(maxsize=16)
def _keep_u8(mount: CameraMount, side: str, w: int, h: int) -> np.ndarray | None:
    keep = wrist_cut_keep(mount, side=side, width_px=w, height_px=h)
    if keep is None:
        return None
    out = keep.astype(np.uint8)
    out.setflags(write=False)
    return out


def coverage(frame: np.ndarray, mount: CameraMount | None = None, *, side: str = "right",
             cells: tuple[int, int] = DEFAULT_CELLS, threshold: int | None = None) -> np.ndarray:
    """Share of each cell of the camera's view that the hand covers.

    Parameters
    ----------
    frame : ndarray, shape (H, W) bool, or (H, W) / (H, W, 3) uint8
        A mask or camera frame of the whole view (binarized as
        :func:`~handsynth.render.binarize`: Otsu's threshold for images).
    mount : CameraMount, optional
        The device whose wrist cut is applied (the paper's by default).
    side : {"right", "left"}, keyword-only
    cells : (int, int), keyword-only
        Rows and columns of the grid over the whole frame; a pixel straddling
        two cells is shared by area (:func:`cv2.resize` ``INTER_AREA``).
    threshold : int, keyword-only, optional
        Grey threshold of :func:`~handsynth.render.binarize`.

    Returns
    -------
    ndarray, shape cells, float32
        In [0, 1]: the covered share of each cell.

    Raises
    ------
    InvalidInputError
        A frame that is not an image (:func:`~handsynth.render.check_frame`),
        a bad `cells` or `threshold`, or a `mount` that is not a
        :class:`~handsynth.render.CameraMount`
        (:class:`~handsynth.errors.InvalidCameraError`).
    """
    rows, cols = _check_cells(cells)
    mask = binarize(frame, threshold=threshold)
    h, w = mask.shape
    keep = _keep_u8(as_mount(mount), side, w, h)
    m8 = mask.view(np.uint8)
    if keep is not None:
        m8 = m8 & keep
    return cv2.resize(m8.astype(np.float32), (cols, rows), interpolation=cv2.INTER_AREA)


def _check_cells(cells) -> tuple[int, int]:
    try:
        rows, cols = (int(c) for c in cells)
        ok = all(int(c) == c for c in cells)
    except (TypeError, ValueError):
        ok = False
    if not ok or not 2 <= rows <= 480 or not 2 <= cols <= 720:
        raise InvalidInputError(f"cells must be two integers (rows, columns) of 2-480 and 2-720, "
                                f"got {cells!r}")
    return rows, cols
