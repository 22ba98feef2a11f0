"""A real camera's lens undone: its frames remapped to the device's pinhole view.

The databases and the learnt estimators hold renders of an ideal pinhole
camera (:class:`CameraMount`: horizontal field of view ``fov_deg``, principal
point at the frame's centre, square pixels, no distortion).  A real camera
differs: another focal length, an off-centre principal point, and a lens that
bends straight lines (a wide-angle lens's barrel distortion, a fisheye).
:class:`LensCorrection` gives each frame the view the device's pinhole camera
would have from the same place: for each pixel of the device's view, the ray
through it (:meth:`CameraMount.intrinsics`) is taken through the real camera's
intrinsics and distortion to a point of the frame, which is sampled there
(bilinear; OpenCV's ``initUndistortRectifyMap`` and ``remap``, or their fisheye
versions).  Where the device's view reaches beyond what the real camera sees,
the corrected frame is black: background (:attr:`LensCorrection.unseen_share`).

The distortion models are OpenCV's (Bradski & Kaehler, *Learning OpenCV*,
2008, ch. 11; OpenCV documentation "Camera Calibration and 3D
Reconstruction"): the Brown-Conrady model with 4, 5, 8, 12 or 14 coefficients
``(k1, k2, p1, p2[, k3[, k4, k5, k6[, s1, s2, s3, s4[, tx, ty]]]])`` and the
equidistant fisheye model ``(k1, k2, k3, k4)`` (Kannala & Brandt 2006).  A
polynomial fitted to a calibration's field of view can fold back beyond it
(the distorted radius stops growing with the ray's angle); rays past the fold
would sample the wrong part of the frame, so they are counted unseen.

The calibration files are read by :func:`~handsynth.render.read_intrinsics`
(:mod:`handsynth.render._calibration_files`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .._checks import check_instance, check_integer, check_number, short_repr
from ..errors import InvalidCameraError, InvalidInputError
from ._camera import MAX_IMAGE_SIDE_PX, CameraMount, as_mount
from ._preprocess import check_frame

__all__ = ["CameraIntrinsics", "LensCorrection"]

#: Distortion coefficient counts OpenCV's models take.
_PINHOLE_COUNTS = (0, 4, 5, 8, 12, 14)
_MODELS = ("pinhole", "fisheye")
#: Relative difference of width-to-height ratios below which a frame of another size is
#: taken as the calibrated camera's view scaled (a calibration at 1280x720 used at 640x360).
_RATIO_TOLERANCE = 0.01


@dataclass(frozen=True)
class CameraIntrinsics:
    """A real camera's intrinsics and lens distortion, as a calibration gives them.

    Parameters
    ----------
    width_px, height_px : int
        Frame size the calibration was made at, pixels.
    fx_px, fy_px : float
        Focal lengths, pixels (> 0).
    cx_px, cy_px : float
        Principal point, pixels from the top-left pixel's centre (OpenCV's
        convention), within the frame.
    distortion : tuple of float, keyword-only
        OpenCV's coefficients: for ``"pinhole"`` 0, 4, 5, 8, 12 or 14
        (``k1, k2, p1, p2[, k3[, ...]]``), for ``"fisheye"`` 4
        (``k1, k2, k3, k4``).  Empty: no distortion.
    model : {"pinhole", "fisheye"}, keyword-only
        The distortion model.

    Raises
    ------
    InvalidCameraError
        A field of the wrong type, out of range or not finite, or a
        distortion of a length the model does not take, naming it.
    """

    width_px: int
    height_px: int
    fx_px: float
    fy_px: float
    cx_px: float
    cy_px: float
    distortion: tuple[float, ...] = field(default=(), kw_only=True)
    model: str = field(default="pinhole", kw_only=True)

    def __post_init__(self) -> None:
        for name in ("width_px", "height_px"):
            object.__setattr__(self, name, check_integer(
                getattr(self, name), f"CameraIntrinsics.{name}", minimum=8,
                maximum=MAX_IMAGE_SIDE_PX, error=InvalidCameraError))
        for name in ("fx_px", "fy_px"):
            object.__setattr__(self, name, check_number(
                getattr(self, name), f"CameraIntrinsics.{name}", above=0.0,
                error=InvalidCameraError))
        for name, side in (("cx_px", self.width_px), ("cy_px", self.height_px)):
            object.__setattr__(self, name, check_number(
                getattr(self, name), f"CameraIntrinsics.{name}", minimum=-0.5,
                maximum=side - 0.5, error=InvalidCameraError))
        if self.model not in _MODELS:
            raise InvalidCameraError(f"CameraIntrinsics.model must be one of {', '.join(_MODELS)}, "
                                     f"got {short_repr(self.model)}")
        d = self.distortion
        if isinstance(d, (str, bytes)) or not hasattr(d, "__len__"):
            raise InvalidCameraError(f"CameraIntrinsics.distortion must be a sequence of numbers, "
                                     f"got {short_repr(d)}")
        coeffs = tuple(check_number(v, f"CameraIntrinsics.distortion[{i}]",
                                    error=InvalidCameraError) for i, v in enumerate(d))
        counts = _PINHOLE_COUNTS if self.model == "pinhole" else (0, 4)
        if len(coeffs) not in counts:
            raise InvalidCameraError(
                f"CameraIntrinsics.distortion of the {self.model} model must hold "
                f"{', '.join(map(str, counts))} coefficients, got {len(coeffs)}")
        object.__setattr__(self, "distortion", coeffs)

    def matrix(self) -> np.ndarray:
        """The 3x3 camera matrix ``K`` (float64)."""
        return np.array([[self.fx_px, 0.0, self.cx_px], [0.0, self.fy_px, self.cy_px],
                         [0.0, 0.0, 1.0]])

    @property
    def fov_deg(self) -> float:
        """Horizontal field of view of the camera matrix without its distortion, degrees."""
        return math.degrees(2.0 * math.atan(0.5 * self.width_px / self.fx_px))

    def scaled(self, width_px: int, height_px: int) -> CameraIntrinsics:
        """The same camera streaming at another frame size of the same width-to-height ratio.

        Raises
        ------
        InvalidInputError
            A size whose ratio differs from the calibration's by more than
            1 % (a camera that crops its sensor differently at that size
            cannot be corrected from this calibration).
        """
        w = check_integer(width_px, "width_px", minimum=8)
        h = check_integer(height_px, "height_px", minimum=8)
        if (w, h) == (self.width_px, self.height_px):
            return self
        ratio, own = w / h, self.width_px / self.height_px
        if abs(ratio / own - 1.0) > _RATIO_TOLERANCE:
            raise InvalidInputError(
                f"frames of {w}x{h} pixels cannot be corrected with intrinsics calibrated at "
                f"{self.width_px}x{self.height_px}: the width-to-height ratio differs "
                f"({ratio:.3f} against {own:.3f}); calibrate the camera at the size it streams")
        sx, sy = w / self.width_px, h / self.height_px
        # pixel centres: x_new + 0.5 = (x + 0.5) * s
        return CameraIntrinsics(w, h, self.fx_px * sx, self.fy_px * sy,
                                (self.cx_px + 0.5) * sx - 0.5, (self.cy_px + 0.5) * sy - 0.5,
                                distortion=self.distortion, model=self.model)


def _radial_fold(intrinsics: CameraIntrinsics, radius_max: float) -> float:
    """The undistorted radius (normalised image coordinates) where the lens model folds back.

    ``inf`` when the distorted radius keeps growing up to `radius_max`.  For
    the pinhole model the radial factor ``(1 + k1 r^2 + k2 r^4 + k3 r^6) /
    (1 + k4 r^2 + k5 r^4 + k6 r^6)`` times ``r``; for the fisheye model
    ``theta (1 + k1 theta^2 + ... + k4 theta^8)`` of the ray's angle
    ``theta = atan(r)``.
    """
    d = np.zeros(14)
    d[:len(intrinsics.distortion)] = intrinsics.distortion
    r = np.linspace(0.0, radius_max, 4096)[1:]
    if intrinsics.model == "fisheye":
        t = np.arctan(r)
        rd = t * (1 + d[0] * t**2 + d[1] * t**4 + d[2] * t**6 + d[3] * t**8)
    else:
        k1, k2, _, _, k3, k4, k5, k6 = d[:8]
        r2 = r * r
        rd = r * (1 + k1 * r2 + k2 * r2**2 + k3 * r2**3) / (1 + k4 * r2 + k5 * r2**2 + k6 * r2**3)
    falls = np.flatnonzero(np.diff(rd) <= 0)
    return float(r[falls[0]]) if falls.size else math.inf


class LensCorrection:
    """Frames of a real camera remapped to the device's pinhole view.

    Parameters
    ----------
    intrinsics : CameraIntrinsics
        The real camera's calibration (:func:`read_intrinsics`).
    mount : CameraMount, optional
        The device whose view the frames are given (the paper's by default):
        its field of view and frame size.  The real camera is taken to sit
        where the mount's camera sits and to look where it looks.
    scale : float, keyword-only
        The corrected frames' size as a share of the mount's frame size (same
        field of view): 1 by default; 0.5 gives 360x240 frames of the paper's
        device at a quarter of the remap's cost (the learnt estimators read a
        frame at half the resolution as at full, docs/camera_estimator.md).

    Attributes
    ----------
    size : tuple of int
        (width, height) of the corrected frames, pixels.
    unseen_share : float
        Share of the device's view the real camera does not see (a narrower
        lens, a frame cut off, or rays beyond the fold of its lens model),
        at the calibration's frame size: black in every corrected frame.
    fold_deg : float or None
        Angle from the optical axis beyond which the lens model folds back
        (None: it does not within the device's view).

    Examples
    --------
    >>> lens = LensCorrection(read_intrinsics("camera.yaml"))      # doctest: +SKIP
    >>> estimator.estimate(lens(frame))                            # doctest: +SKIP
    """

    def __init__(self, intrinsics: CameraIntrinsics, mount: CameraMount | None = None, *,
                 scale: float = 1.0) -> None:
        self.intrinsics = check_instance(intrinsics, CameraIntrinsics, name="intrinsics")
        self.mount = as_mount(mount)
        f = check_number(scale, "scale", above=0.0, maximum=4.0)
        self.size = (max(8, round(self.mount.width_px * f)), max(8, round(self.mount.height_px * f)))
        self._maps: dict[tuple[int, int], tuple[np.ndarray, np.ndarray]] = {}
        k = self.mount.intrinsics(*self.size)
        w, h = self.size
        corners = np.array([[0.0, 0.0], [w - 1.0, h - 1.0], [0.0, h - 1.0], [w - 1.0, 0.0]])
        r_max = float(np.max(np.hypot((corners[:, 0] - k[0, 2]) / k[0, 0],
                                      (corners[:, 1] - k[1, 2]) / k[1, 1])))
        self._fold_r = _radial_fold(self.intrinsics, r_max)
        self.fold_deg = None if math.isinf(self._fold_r) else math.degrees(math.atan(self._fold_r))
        self.unseen_share = self._build(self.intrinsics.width_px, self.intrinsics.height_px)

    def _build(self, width_px: int, height_px: int) -> float:
        """Make and keep the maps for frames of this size; the share of the view unseen."""
        import cv2

        intr = self.intrinsics.scaled(width_px, height_px)
        k_new = self.mount.intrinsics(*self.size)
        w, h = self.size
        k = intr.matrix()
        d = np.asarray(intr.distortion, np.float64)
        if intr.model == "fisheye":
            mx, my = cv2.fisheye.initUndistortRectifyMap(k, d, np.eye(3), k_new, (w, h),
                                                         cv2.CV_32FC1)
        else:
            mx, my = cv2.initUndistortRectifyMap(k, d if d.size else None, None, k_new, (w, h),
                                                 cv2.CV_32FC1)
        # a pixel's footprint reaches half a pixel beyond its centre: sampled at the edge
        unseen = ~((mx >= -0.5) & (mx <= width_px - 0.5) & (my >= -0.5) & (my <= height_px - 0.5))
        np.clip(mx, 0.0, width_px - 1.0, out=mx)
        np.clip(my, 0.0, height_px - 1.0, out=my)
        if not math.isinf(self._fold_r):
            u, v = np.meshgrid(np.arange(w), np.arange(h))
            r = np.hypot((u - k_new[0, 2]) / k_new[0, 0], (v - k_new[1, 2]) / k_new[1, 1])
            unseen |= r >= self._fold_r
        mx[unseen] = -10.0  # sampled outside the frame: black
        my[unseen] = -10.0
        self._maps[(width_px, height_px)] = cv2.convertMaps(mx, my, cv2.CV_16SC2)
        return float(unseen.mean())

    def __call__(self, frame: np.ndarray) -> np.ndarray:
        """The device's view of `frame`.

        Parameters
        ----------
        frame : ndarray, shape (H, W) or (H, W, 3)
            A BGR or grey uint8 frame or a bool mask of the real camera, at
            the calibration's size or another of the same width-to-height
            ratio.

        Returns
        -------
        ndarray, shape (size[1], size[0][, 3])
            Same dtype; black (False) where the real camera does not see.

        Raises
        ------
        InvalidInputError
            A frame that is not an image (:func:`check_frame`), or of a
            width-to-height ratio other than the calibration's.
        """
        import cv2

        frame = check_frame(frame)
        h, w = frame.shape[:2]
        if (w, h) not in self._maps:
            self._build(w, h)
        m1, m2 = self._maps[(w, h)]
        src = frame.view(np.uint8) * np.uint8(255) if frame.dtype == np.bool_ else frame
        out = cv2.remap(src, m1, m2, cv2.INTER_LINEAR, borderMode=cv2.BORDER_CONSTANT,
                        borderValue=0)
        return out > 127 if frame.dtype == np.bool_ else out
