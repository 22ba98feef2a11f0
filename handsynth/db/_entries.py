"""Database entries: render poses, preprocess, extract features, record keypoints.

This is the one function that turns poses into database rows; the build job
(:mod:`handsynth.db._build`) and in-memory databases for tests and
evaluation both call it, so database rows and live frames go through exactly
the same preprocessing and features.
"""

from __future__ import annotations

import numpy as np

from ..errors import InvalidInputError
from ..models import HandShape, as_angles
from ..render import CameraMount, SilhouetteRasterizer, preprocess
from ._validation import IMAGE_SIZE
from .features import extract_features_batch

__all__ = ["DEFAULT_RENDER_SIZE", "database_meta", "render_entries"]

#: Render size (width, height) of database masks before preprocessing: the
#: device's own 720x480 frame, so database rows see what live frames see.
#: The masks come from :class:`~handsynth.render.SilhouetteRasterizer`
#: (the same masks as MuJoCo's renderer, tested, at a fraction of the cost).
DEFAULT_RENDER_SIZE: tuple[int, int] = (720, 480)


def check_render_size(size, name: str = "render_size") -> tuple[int, int]:
    """`size` as ``(width, height)``, two integers in [16, 4096] pixels.

    Raises
    ------
    InvalidInputError
        Anything else (``"720x480"``, three numbers, floats), naming `name` and the whole
        value.
    """
    try:
        w, h = (int(s) for s in size)
        ok = (w, h) == tuple(size) and 16 <= w <= 4096 and 16 <= h <= 4096
    except (TypeError, ValueError):
        ok = False
    if not ok:
        raise InvalidInputError(
            f"{name} must be (width, height) with integers in [16, 4096], got {size!r}")
    return w, h


def render_entries(angles, shape: HandShape | None = None, mount: CameraMount | None = None, *,
                   side: str = "right", render_size: tuple[int, int] = DEFAULT_RENDER_SIZE,
                   renderer=None) -> dict[str, np.ndarray]:
    """Database rows for the poses `angles`.

    Parameters
    ----------
    angles : array_like, shape (N, 20)
        Degrees, canonical order.
    shape, mount : optional
        Standard hand and paper device by default (ignored when `renderer` is given).
    side : {"right", "left"}, keyword-only
    render_size : (int, int), keyword-only
        (width, height) of the masks before preprocessing, pixels
        (:func:`check_render_size`; ignored when `renderer` is given).
    renderer : SilhouetteRasterizer or SilhouetteRenderer, keyword-only, optional
        Reuse an open mask maker (one model load for many calls); a new
        :class:`~handsynth.render.SilhouetteRasterizer` by default.

    Returns
    -------
    dict of str to ndarray
        ``angles`` (N, 20) float64, ``keypoints`` (N, 21, 3) float64 metres,
        ``silhouette`` (N, 64, 64) bool, and the fields of
        :func:`extract_features_batch` (``hlac``, ``sil_bits``, ``ridge_bits``,
        ``ridge_area``, ``contour``, ``ridge``).
    """
    a = as_angles(angles)
    if a.ndim == 1:
        a = a[None]
    if renderer is None:
        w, h = check_render_size(render_size)
        r = SilhouetteRasterizer(shape, mount, side=side, width_px=w, height_px=h)
    else:
        r = renderer
    sils = np.empty((len(a), IMAGE_SIZE, IMAGE_SIZE), dtype=bool)
    keypoints = np.empty((len(a), 21, 3))
    buf = np.zeros((1, r.height_px, r.width_px), dtype=bool)  # one mask buffer for all poses
    for i in range(len(a)):
        r.masks(a[i:i + 1], out=buf)
        keypoints[i] = r.hand.keypoints()
        sils[i] = preprocess(buf[0], r.mount, side=r.side, size=IMAGE_SIZE)
    out = extract_features_batch(sils)
    out.update(angles=a, keypoints=keypoints, silhouette=sils)
    return out


def database_meta(shape: HandShape, mount: CameraMount, *, side: str, pose_set: str,
                  count: int, seed: int, render_size: tuple[int, int]) -> dict:
    """The self-describing attributes of a database file (compared when it is opened).

    The arguments are not checked here (:class:`BuildOptions` checks them
    for a build).

    Parameters
    ----------
    shape : HandShape
        The database's hand shape (its four ratios and its name are stored).
    mount : CameraMount
        The device the masks were rendered for (every field is stored).
    side : {"right", "left"}, keyword-only
    pose_set : str, keyword-only
        Name of the pose set (a key of :data:`~handsynth.models.POSE_SETS`).
    count : int, keyword-only
        Poses in the database.
    seed : int, keyword-only
        Seed of the pose set.
    render_size : (int, int), keyword-only
        (width, height) in pixels of the masks before preprocessing.

    Returns
    -------
    dict
        JSON-able: ``shape`` (ratios), ``shape_name``, ``side``, ``mount``
        (:meth:`~handsynth.render.CameraMount.as_dict`), ``model`` (the hand model's generator
        and forearm), ``features`` (preprocessing and feature settings,
        `render_size` as a list), ``pose_set`` (``name``, ``count``,
        ``seed``) and ``handsynth_version``.
    """
    from .._version import __version__
    from .features import HLAC_SIZE

    return {
        "shape": shape.as_dict(),
        "shape_name": shape.name,
        "side": side,
        "mount": mount.as_dict(),
        "model": {"generator": "handsynth.models.hand_mjcf", "forearm": True},
        "features": {"image_size": IMAGE_SIZE, "hlac_size": HLAC_SIZE, "contour": "4-neighbour",
                     "thinning": "hilditch", "render_size": list(render_size),
                     "masks": "convex-hull raster", "resize": "continuous area"},
        "pose_set": {"name": pose_set, "count": int(count), "seed": int(seed)},
        "handsynth_version": __version__,
    }
