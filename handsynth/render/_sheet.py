"""Contact sheets of rendered hands (the demo's pictures)."""

from __future__ import annotations

import numpy as np

from .._checks import check_integer, short_repr
from ..errors import InvalidInputError
from ..models import HandShape, named_pose
from ._camera import CameraMount, as_mount
from ._renderer import render_rgb

__all__ = ["contact_sheet"]


def contact_sheet(shapes: dict[str, HandShape], poses: tuple[str, ...] = ("open", "fist", "pinch"),
                  mount: CameraMount | None = None, *, tile_width_px: int = 360,
                  side_view: bool = True) -> np.ndarray:
    """A labelled grid of device-camera pictures: one row per shape, one column per pose.

    With `side_view`, a last column shows the pinch from the thumb side.

    Parameters
    ----------
    shapes : dict of str to HandShape
        Row label to hand shape, one row each in the dict's order; every hand
        is rendered as a right hand.
    poses : tuple of str
        Names of :data:`~handsynth.models.NAMED_POSES`
        (:func:`~handsynth.models.named_pose`), one column each, in order.
    mount : CameraMount, optional
        The device camera; the paper's device by default.  Its frame's aspect
        ratio sets the tiles' height.
    tile_width_px : int, keyword-only
        Width of one tile in pixels; its height is
        ``round(tile_width_px * mount.height_px / mount.width_px)``.
    side_view : bool, keyword-only
        Add the last column: the ``"pinch"`` pose seen by the ``"side"``
        camera (:func:`render_rgb`).

    Returns
    -------
    ndarray, shape (H, W, 3), uint8
        RGB.  Each tile is labelled ``"<label>: <pose>"`` and framed
        (:func:`label_image`); the grid has a 2-pixel white border, so
        ``H = len(shapes) * tile height + 4`` and
        ``W = (len(poses) + side_view) * tile_width_px + 4``.

    Raises
    ------
    InvalidInputError
        `shapes` empty or not a dict, no pose and no side view, or
        `tile_width_px` not an integer >= 16; a pose name
        :func:`~handsynth.models.named_pose` does not know.
    """
    import cv2

    mount = as_mount(mount)
    if not isinstance(shapes, dict) or not shapes:
        raise InvalidInputError(f"shapes must be a non-empty dict of label -> HandShape, got "
                                f"{short_repr(shapes)}")
    if not poses and not side_view:
        raise InvalidInputError("contact_sheet needs at least one pose or the side view")
    tw = check_integer(tile_width_px, "tile_width_px", minimum=16)
    th = round(tw * mount.height_px / mount.width_px)
    rows = []
    for label, shape in shapes.items():
        tiles = []
        for p in poses:
            img = render_rgb(named_pose(p), shape, mount, width_px=tw, height_px=th)
            tiles.append(label_image(img, f"{label}: {p}"))
        if side_view:
            img = render_rgb(named_pose("pinch"), shape, mount, camera="side", width_px=tw, height_px=th)
            tiles.append(label_image(img, f"{label}: pinch, side view"))
        rows.append(np.hstack(tiles))
    sheet = np.vstack(rows)
    return cv2.copyMakeBorder(sheet, 2, 2, 2, 2, cv2.BORDER_CONSTANT, value=(255, 255, 255))


def label_image(img: np.ndarray, text: str) -> np.ndarray:
    """A copy of `img` with `text` written in its top left corner and a grey frame.

    Parameters
    ----------
    img : ndarray, shape (H, W, 3) or (H, W), uint8
        A picture; it is not modified.
    text : str

    Returns
    -------
    ndarray, same shape and dtype as `img`
        A new array.

    Raises
    ------
    InvalidInputError
        `img` is not a uint8 image of one of those shapes (the message names
        it, its dtype and shape), or `text` is not a string.
    """
    import cv2

    if not isinstance(img, np.ndarray) or img.dtype != np.uint8 or not (
            img.ndim == 2 or (img.ndim == 3 and img.shape[2] == 3)) or 0 in img.shape:
        raise InvalidInputError(
            "img must be a non-empty uint8 numpy array of shape (H, W, 3) or (H, W), got "
            + (f"dtype {img.dtype} shape {img.shape}" if isinstance(img, np.ndarray)
               else type(img).__name__))
    if not isinstance(text, str):
        raise InvalidInputError(f"text must be a str, got {type(text).__name__}")
    img = np.array(img, order="C")  # a copy: the caller's picture is left as it is
    cv2.putText(img, text, (6, 18), cv2.FONT_HERSHEY_SIMPLEX, 0.5, (255, 255, 255), 1, cv2.LINE_AA)
    cv2.rectangle(img, (0, 0), (img.shape[1] - 1, img.shape[0] - 1), (90, 90, 90), 1)
    return img
