"""Pictures and figures of what an estimator reads, for the demo and the docs.

:func:`estimates_sheet` and :func:`backgrounds_sheet` show a learned
estimator on the MRTK glTF hand (:mod:`handsynth.testhands`), which no
estimator learnt from, in natural poses from a relaxed rest (the protocol's
generators); :func:`lookup_errors` times a database lookup on rendered frames
and measures its error against their true angles.
"""

from __future__ import annotations

import time
from collections.abc import Sequence

import numpy as np

from .._checks import check_integer, short_repr
from ..errors import InvalidInputError
from ..models import JOINT_NAMES
from ..render import CameraMount, binarize, label_image, skin_mask
from ..testhands import MeshHandRenderer, shipped_hand_path
from ._backgrounds import background_photos
from ._protocol import JOINT_GROUPS
from ._testposes import natural_test_poses, relaxed_rest_posture

__all__ = ["backgrounds_sheet", "estimates_sheet", "lookup_errors"]


def _bordered(rows: list[list[np.ndarray]]) -> np.ndarray:
    """Tiles stacked in rows, in a 2-pixel white border."""
    import cv2

    sheet = np.vstack([np.hstack(r) for r in rows])
    return cv2.copyMakeBorder(sheet, 2, 2, 2, 2, cv2.BORDER_CONSTANT, value=(255, 255, 255))


def _tile_height(mount: CameraMount, tile_width_px: int) -> int:
    return round(tile_width_px * mount.height_px / mount.width_px)


def _sheet_poses(estimator, seed: int, tile_width_px: int, count: int):
    """The sheet's arguments checked; its generator, relaxed rest and `count` natural poses."""
    check_integer(tile_width_px, "tile_width_px", minimum=64)
    check_integer(count, "count", minimum=1)
    if not callable(getattr(estimator, "calibrated", None)):  # before anything is rendered
        raise InvalidInputError(f"estimator must have a calibrated() method (a LearnedEstimator "
                                f"or EnsembleEstimator), got {type(estimator).__name__} "
                                f"{short_repr(estimator)}")
    rng = np.random.default_rng(seed)
    rest = relaxed_rest_posture(rng)
    return rng, rest, natural_test_poses(rest, count, rng)[0]


def estimates_sheet(estimator, *, tile_width_px: int = 360, count: int = 4) -> np.ndarray:
    """What `estimator` reads on the MRTK glTF hand: the device's view, the truth and the reading.

    Natural poses from a relaxed rest (random generator seed 7); columns are
    frames; rows show the mesh hand as the device sees it, and from the
    thumb side at the true angles and at the estimated ones, each estimate
    labelled with its finger-flexion error.

    Parameters
    ----------
    estimator : LearnedEstimator or EnsembleEstimator
        Not yet calibrated: it is calibrated to the hand's rest frame here.
    tile_width_px : int, keyword-only
        Width of one picture, pixels (>= 64).
    count : int, keyword-only
        Frames (columns), >= 1.

    Returns
    -------
    ndarray, shape (3 H + 4, count W + 4, 3), uint8
        RGB, ``W = tile_width_px`` and ``H`` its height at the device's aspect.

    Raises
    ------
    InvalidInputError
        `tile_width_px` or `count` out of range, or `estimator` without a
        ``calibrated`` method, naming it, before anything is rendered.
    """
    _, rest, poses = _sheet_poses(estimator, 7, tile_width_px, count)
    flex = list(JOINT_GROUPS["finger_flexion"])
    mount = CameraMount.paper()
    hand = shipped_hand_path("mrtk")
    with MeshHandRenderer(mount, path=hand) as full:
        reader = estimator.calibrated(full.mask(rest))
        got = [reader.estimate(m).angles for m in full.masks(poses)]
    rows: list[list[np.ndarray]] = [[], [], []]
    with MeshHandRenderer(mount, width_px=tile_width_px, height_px=_tile_height(mount, tile_width_px),
                          path=hand) as mesh:
        for i, (truth, est) in enumerate(zip(poses, got)):
            mae = float(np.abs(est[flex] - truth[flex]).mean())
            rows[0].append(label_image(mesh.render_rgb(truth), f"frame {i + 1}: the device's view"))
            rows[1].append(label_image(mesh.render_rgb(truth, camera="side"), "true angles, side view"))
            rows[2].append(label_image(mesh.render_rgb(est, camera="side"),
                                       f"estimated: flexion error {mae:.1f} deg"))
    return _bordered(rows)


def backgrounds_sheet(estimator, *, tile_width_px: int = 360, count: int = 4) -> np.ndarray:
    """The MRTK glTF hand over photographs, told by brightness and by the skin's colour.

    Natural poses from a relaxed rest (random generator seed 11), the hand
    painted in a shaded skin colour over photographs bundled with
    scikit-image (:func:`background_photos`; the rest frame over one too);
    columns are frames; rows show the frame, the hand as Otsu's threshold
    tells it and as the skin's colour tells it, each with the finger-flexion
    error of `estimator` calibrated that way.

    Parameters
    ----------
    estimator : LearnedEstimator or EnsembleEstimator
        Not yet calibrated; calibrated here with ``segment="brightness"``
        and with ``segment="colour"``.
    tile_width_px : int, keyword-only
        Width of one picture, pixels (>= 64).
    count : int, keyword-only
        Frames (columns), >= 1.

    Returns
    -------
    ndarray, shape (3 H + 4, count W + 4, 3), uint8
        RGB, as :func:`estimates_sheet`.

    Raises
    ------
    InvalidInputError
        As :func:`estimates_sheet`, before anything is rendered.
    """
    import cv2

    rng, rest, poses = _sheet_poses(estimator, 11, tile_width_px, count)
    flex = list(JOINT_GROUPS["finger_flexion"])
    mount = CameraMount.paper()
    th = _tile_height(mount, tile_width_px)
    photos = background_photos()
    shade = np.linspace(0.55, 1.0, mount.width_px, dtype=np.float32)[None, :, None]
    skin = np.array([95, 125, 180], np.float32)  # BGR

    def paint(mask, photo):
        f = photo.astype(np.float32)
        f[mask] = (skin * shade * np.ones_like(f))[mask]
        return np.clip(f + rng.normal(0.0, 4.0, f.shape), 0, 255).astype(np.uint8)

    with MeshHandRenderer(mount, path=shipped_hand_path("mrtk")) as full:
        rest_frame = paint(full.mask(rest), photos[-1])
        frames = [paint(m, photos[i % (len(photos) - 1)]) for i, m in enumerate(full.masks(poses))]
    readers = {"brightness": estimator.calibrated(rest_frame, segment="brightness"),
               "colour": estimator.calibrated(rest_frame, segment="colour")}
    colour = readers["colour"].members[0].skin  # the skin its members tell the hand by

    def tile(image):  # the label's strip darkened, so that white text reads on white
        out = cv2.resize(image, (tile_width_px, th), interpolation=cv2.INTER_AREA)
        out[:24] //= 3
        return out

    rows: list[list[np.ndarray]] = [[], [], []]
    for i, (truth, frame) in enumerate(zip(poses, frames)):
        rows[0].append(label_image(tile(frame[..., ::-1]), f"frame {i + 1} over a photograph"))
        told = {"brightness": binarize(frame), "colour": skin_mask(frame, colour)}
        for r, (how, mask) in enumerate(told.items(), start=1):
            mae = float(np.abs(readers[how].estimate(frame).angles[flex] - truth[flex]).mean())
            grey = np.repeat(tile(mask.view(np.uint8) * 255)[..., None], 3, axis=2)
            rows[r].append(label_image(grey, f"by {how}: flexion error {mae:.1f} deg"))
    return _bordered(rows)


def _check_poses(poses, n: int) -> np.ndarray:
    """`poses` as float64, refused unless a finite real array of shape ``(n, 20)``."""
    joints = len(JOINT_NAMES)
    arr = np.asarray(poses) if isinstance(poses, (np.ndarray, Sequence)) else None
    if arr is None or arr.dtype.kind not in "iuf":
        got = (f"dtype {arr.dtype}" if arr is not None
               else f"{type(poses).__name__} {short_repr(poses)}")
        raise InvalidInputError(f"poses must be a real array of shape (N, {joints}) (degrees), "
                                f"got {got}")
    if arr.shape != (n, joints):
        raise InvalidInputError(f"poses must have shape (N, {joints}) with N = len(masks) = {n}, "
                                f"got {arr.shape}")
    arr = arr.astype(np.float64)
    if not np.isfinite(arr).all():
        bad = np.argwhere(~np.isfinite(arr))[0]
        raise InvalidInputError(f"poses must be finite, got {arr[tuple(bad)]} at row {bad[0]}, "
                                f"joint {JOINT_NAMES[bad[1]]}")
    return arr


def lookup_errors(lookup, masks, poses) -> dict:
    """Rate and error of `lookup` on rendered frames of known angles.

    The first frame is looked up once before the timing (it compiles the
    search on a fresh install).

    Parameters
    ----------
    lookup : PoseLookup
        Plain or calibrated.
    masks : sequence of ndarray, shape (H, W), bool
        The frames, at least one (a sequence, or an array of shape (N, H, W)).
    poses : ndarray, shape (N, 20), deg
        Their true joint angles, canonical order, finite; ``N = len(masks)``.

    Returns
    -------
    dict
        ``frames_per_s``; ``mae_deg`` over every joint; ``index_pip_mae_deg``
        and ``thumb_cmc_flex_mae_deg``.

    Raises
    ------
    InvalidInputError
        Before any frame is looked up: `lookup` has no ``estimate`` method;
        `masks` is not a sequence (or array) of frames, or holds none;
        `poses` is not a finite real array of shape ``(N, 20)`` with ``N =
        len(masks)``.  Each message names the argument and what it received.
        Each frame is then checked by ``lookup.estimate``.
    """
    if not callable(getattr(lookup, "estimate", None)):
        raise InvalidInputError(f"lookup must have an estimate() method (a PoseLookup), got "
                                f"{type(lookup).__name__} {short_repr(lookup)}")
    if isinstance(masks, (str, bytes)) or not isinstance(masks, (Sequence, np.ndarray)) \
            or (isinstance(masks, np.ndarray) and masks.ndim < 3):
        got = (f"an array of shape {masks.shape}" if isinstance(masks, np.ndarray)
               else f"{type(masks).__name__} {short_repr(masks)}")
        raise InvalidInputError(f"masks must be a sequence of frames (ndarray, shape (H, W)), "
                                f"got {got}")
    n = len(masks)
    if n == 0:
        raise InvalidInputError("masks must hold at least one frame, got none")
    poses = _check_poses(poses, n)
    lookup.estimate(masks[0])
    t = time.perf_counter()
    est = np.array([lookup.estimate(m).angles for m in masks])
    dt = time.perf_counter() - t
    err = np.abs(est - poses)
    return {"frames_per_s": len(masks) / dt if dt > 0 else float("inf"),
            "mae_deg": float(err.mean()),
            "index_pip_mae_deg": float(err[:, JOINT_NAMES.index("index_pip_flex")].mean()),
            "thumb_cmc_flex_mae_deg": float(err[:, JOINT_NAMES.index("thumb_cmc_flex")].mean())}
