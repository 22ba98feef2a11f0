"""Photos of the model hand for measurement: rendered top-down on a table beside a card."""

from __future__ import annotations

import math
import re
from dataclasses import dataclass

import numpy as np

from .._checks import check_number, check_options, check_side
from ..errors import InvalidInputError
from ..models import HandShape
from ._options import _positive

__all__ = ["MEASURE_POSE", "RenderedPhoto", "render_measurement_photo"]

#: The pose of the test photos: the open hand lying flat, fingers spread
#: (MCP abduction index +12, middle 0, ring -8, little -16 deg) and the thumb
#: swung away from the index in the palm plane (CMC flexion -15 deg, no
#: palmar abduction), degrees in the canonical joint order.
MEASURE_POSE: np.ndarray = np.array(
    [-15.0, 0.0, 0.0, 0.0, 0.0, 12.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0,
     0.0, -8.0, 0.0, 0.0, 0.0, -16.0, 0.0, 0.0])
MEASURE_POSE.setflags(write=False)


@dataclass(frozen=True)
class RenderedPhoto:
    """A synthetic top-down photo of the model hand (:func:`render_measurement_photo`).

    Attributes
    ----------
    image : ndarray, shape (H, W, 3), uint8
        BGR picture.
    mm_per_px : float
        Exact scale (orthographic camera).
    keypoints_px : ndarray, shape (21, 2), float64
        The model's 21 keypoints projected into the picture, (x, y) pixels.
    mask : ndarray, shape (H, W), bool
        The true silhouette of the hand and forearm (no table, no card).
    """

    image: np.ndarray
    mm_per_px: float
    keypoints_px: np.ndarray
    mask: np.ndarray


def render_measurement_photo(shape=None, angles=None, *, mm_per_px: float = 0.4,
                             size_mm: float = 300.0, roll_deg: float = 0.0,
                             side: str = "right", card: bool = False,
                             background_rgb=(0.30, 0.40, 0.60)) -> RenderedPhoto:
    """Render the model hand from straight above with an orthographic camera.

    The camera looks down the hand frame's -z axis (at the back of the hand),
    centred 15 mm toward the thumb and 75 mm along the hand from the wrist, so
    the hand lies inside a circle of 150 mm radius around the centre at any
    `roll_deg`; the forearm stub leaves the picture at the border, as a real
    forearm does.  The hand lies above a lit plane of `background_rgb` (the
    lighting makes the background a little uneven, as on a real table).

    Parameters
    ----------
    shape : HandShape, optional
        The standard hand by default.
    angles : array_like, shape (20,), or mapping, optional
        Degrees; :data:`MEASURE_POSE` by default.
    mm_per_px : float, keyword-only
        Pixel size, mm (square pixels, the same everywhere: orthographic).
    size_mm : float, keyword-only
        Side of the square field of view, mm.
    roll_deg : float, keyword-only
        Rotation of the picture; 0 puts the fingers to the right.
    side : {"right", "left"}, keyword-only
    card : bool, keyword-only
        Put a white ISO/IEC 7810 ID-1 card (85.60 x 53.98 mm) on the plane
        in the picture's lower left corner, 5 mm from the border, long side
        across the picture (clear of the hand for `roll_deg` near 0 and the
        default `size_mm`).
    background_rgb : tuple of 3 float, keyword-only
        Colour of the plane, 0-1.

    Returns
    -------
    RenderedPhoto

    Raises
    ------
    InvalidInputError
        A scale, size, roll or colour that is not a (finite) number -- a text
        such as ``"0.4"`` included -- or out of range; another `side`.
    """
    import mujoco

    from ..models import HandModel
    from ..render import ensure_backend, offscreen_renderer, scene_mjcf

    ensure_backend()
    shape = check_options(shape, HandShape, name="shape")
    mm_per_px = _positive(mm_per_px, "mm_per_px")
    size_mm = _positive(size_mm, "size_mm")
    roll_deg = check_number(roll_deg, "roll_deg")
    side = check_side(side)
    if isinstance(background_rgb, (str, bytes)) or np.shape(background_rgb) != (3,):
        raise InvalidInputError(f"background_rgb must be 3 numbers in [0, 1], got {background_rgb!r}")
    background_rgb = tuple(check_number(v, f"background_rgb[{i}]", minimum=0.0, maximum=1.0)
                           for i, v in enumerate(background_rgb))
    n_px = round(size_mm / mm_per_px)
    if not 32 <= n_px <= 4096:
        raise InvalidInputError(
            f"size_mm / mm_per_px must give 32 to 4096 pixels, got {size_mm} / {mm_per_px}")
    cx_mm, cy_mm = (15.0 if side == "left" else -15.0), 75.0
    c, s = math.cos(math.radians(roll_deg)), math.sin(math.radians(roll_deg))
    right = np.array([s, c, 0.0])       # image x axis in the hand frame
    down = np.array([c, -s, 0.0])       # image y axis (rows) in the hand frame
    up = -down

    def fmt(a):
        return " ".join(f"{v:.9g}" for v in a)

    extras = (
        f'    <camera name="measure" pos="{cx_mm / 1e3:.9g} {cy_mm / 1e3:.9g} 0.6" '
        f'xyaxes="{fmt(right)} {fmt(up)}" projection="orthographic" '
        f'fovy="{size_mm / 1e3:.9g}"/>\n'
        f'    <geom name="table" type="plane" size="2 2 0.01" pos="0 0 -0.05" '
        f'rgba="{fmt(background_rgb)} 1" material="cloth" contype="0" conaffinity="0"/>\n'
    )
    if card:
        # in the picture's lower left corner, long side across the picture, 5 mm from the border
        half = 0.5 * size_mm - 5.0
        at = np.array([cx_mm, cy_mm, 0.0]) - (half - 42.8) * right + (half - 27.0) * down
        extras += (f'    <geom name="card" type="box" size="0.02699 0.0428 0.0004" '
                   f'pos="{at[0] / 1e3:.9g} {at[1] / 1e3:.9g} -0.0496" '
                   f'xyaxes="{fmt(down)} {fmt(right)}" rgba="0.95 0.95 0.93 1" '
                   'contype="0" conaffinity="0"/>\n')
    xml = scene_mjcf(shape, None, side=side, width_px=n_px, height_px=n_px)
    xml = xml.replace("  </worldbody>", extras + "  </worldbody>", 1)
    # room light: a distant key light (even on the plane) instead of the scene's
    # spot light, a dimmer headlight, more ambient, and a matt table
    xml = re.sub(r'<light name="key"[^>]*/>',
                 '<light name="key" directional="true" dir="0.3 0.2 -1" diffuse="0.35 0.35 0.35" '
                 'specular="0 0 0" castshadow="false"/>', xml, count=1)
    xml = re.sub(r'<headlight [^>]*/>', '<headlight ambient="0.5 0.5 0.5" '
                 'diffuse="0.25 0.25 0.25" specular="0 0 0"/>', xml, count=1)
    xml = xml.replace("  <asset>\n", '  <asset>\n    <material name="cloth" specular="0" '
                      'shininess="0" reflectance="0"/>\n', 1)
    hand = HandModel(shape, side=side, xml=xml)
    hand.set_pose(MEASURE_POSE if angles is None else angles)
    r = offscreen_renderer(hand.model, n_px, n_px)
    try:
        r.update_scene(hand.data, camera="measure")
        rgb = r.render().copy()
        r.enable_segmentation_rendering()
        r.update_scene(hand.data, camera="measure")
        geom = r.render()[..., 0]
    finally:
        r.close()
    others = [mujoco.mj_name2id(hand.model, mujoco.mjtObj.mjOBJ_GEOM, g)
              for g in ("table", "card")]
    mask = (geom >= 0) & ~np.isin(geom, [g for g in others if g >= 0])
    rel = hand.keypoints() * 1e3 - np.array([cx_mm, cy_mm, 0.0])
    kp = np.stack([rel @ right, rel @ down], axis=1) / mm_per_px + (n_px / 2.0 - 0.5)
    return RenderedPhoto(image=np.ascontiguousarray(rgb[..., ::-1]), mm_per_px=mm_per_px,
                         keypoints_px=kp, mask=mask)
