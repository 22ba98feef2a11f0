"""The back-of-hand camera: its mount on the hand and its intrinsics."""

from __future__ import annotations

import math
from dataclasses import dataclass, fields, replace

import numpy as np

from .._checks import check_instance, check_number, check_side
from ..errors import InvalidCameraError
from ..models import DORSUM_Z_MM

__all__ = ["MAX_DISTANCE_MM", "MAX_IMAGE_SIDE_PX", "MAX_WRIST_CUT_MM", "CameraMount", "as_mount"]


#: Largest wrist cut, mm from the wrist joint centre along the hand.
MAX_WRIST_CUT_MM = 40.0
#: Farthest a camera worn on the hand is placed from it: the bound of ``height_mm`` and of
#: the size of ``thumb_offset_mm`` and ``along_mm``, mm.
MAX_DISTANCE_MM = 1000.0
#: Largest image side, pixels (a 16384 x 16384 mask is already 268 MB).
MAX_IMAGE_SIDE_PX = 16384


@dataclass(frozen=True)
class CameraMount:
    """Pose and optics of the camera on the back of the hand.

    Defaults are the device of the paper (SPEC.md section 1, seed 001 section
    2.1): a 90 deg lens, 720x480 frames, about 120 mm above the back of the
    hand, on the thumb side, optical axis perpendicular to the back of the
    hand.  Where the seed is silent (position along the hand, image
    orientation) the choice is documented per field.

    The camera frame follows OpenCV: x to the image's right, y down, z along
    the optical axis.  With ``tilt_deg = roll_deg = 0`` the camera looks
    straight down the hand frame's -z axis, the fingers point to the image's
    right (the long 720-pixel side runs along the hand) and the thumb side is
    at the top of the image.

    Parameters
    ----------
    height_mm : float
        Distance of the optical centre above the back of the hand (the dorsum
        over the metacarpal heads, ``DORSUM_Z_MM`` above the hand frame's
        x-y plane).  Paper: about 120 mm.  Above 0, at most
        :data:`MAX_DISTANCE_MM` (1000 mm).
    thumb_offset_mm : float
        Offset across the hand toward the thumb side (mirrored for a left
        hand), from the hand axis.  Default 25 mm: over the index metacarpal,
        "on the thumb side".  In [-1000, 1000] mm (:data:`MAX_DISTANCE_MM`).
    along_mm : float
        Offset along the hand from the wrist joint centre toward the
        fingers.  Default 60 mm: over the middle of the metacarpals, where a
        flexible arm from a wrist support reaches.  In [-1000, 1000] mm.
    tilt_deg : float
        Rotation of the optical axis toward the fingertips (about the hand
        x axis).  0 = perpendicular to the back of the hand.
    roll_deg : float
        Rotation of the image about the optical axis.
    fov_deg : float
        Horizontal field of view (across the 720-pixel side).
    width_px, height_px : int
        Frame size of the device, 1 to :data:`MAX_IMAGE_SIDE_PX` (16384)
        pixels a side.  Renders at other sizes keep the horizontal field of
        view and use square pixels.
    wrist_cut_mm : float
        Position along the hand (from the wrist joint centre) of the wrist
        cut: preprocessing removes what the camera sees of the hand frame's
        y < ``wrist_cut_mm`` at dorsum height (the forearm), identically for
        database renders and live frames, so a real forearm and the model's
        forearm stub do not enter the features.  ``None`` disables the cut.
        At most :data:`MAX_WRIST_CUT_MM` (the thumb's CMC joint lies about
        24 mm from the wrist, the MCP joints 69-83 mm: a cut much beyond
        them leaves no hand), at least -100 mm.

    Raises
    ------
    InvalidCameraError
        For a non-finite or out-of-range field, naming it.
    """

    height_mm: float = 120.0
    thumb_offset_mm: float = 25.0
    along_mm: float = 60.0
    tilt_deg: float = 0.0
    roll_deg: float = 0.0
    fov_deg: float = 90.0
    width_px: int = 720
    height_px: int = 480
    wrist_cut_mm: float | None = 10.0

    def __post_init__(self) -> None:
        for f in fields(self):
            v = getattr(self, f.name)
            if f.name == "wrist_cut_mm" and v is None:
                continue
            check_number(v, f"CameraMount.{f.name}", error=InvalidCameraError)
        if not 0.0 < self.height_mm <= MAX_DISTANCE_MM:
            raise InvalidCameraError(f"CameraMount.height_mm must be in (0, {MAX_DISTANCE_MM:g}] mm, "
                                     f"got {self.height_mm!r}")
        for n in ("thumb_offset_mm", "along_mm"):
            v = getattr(self, n)
            if not -MAX_DISTANCE_MM <= v <= MAX_DISTANCE_MM:
                raise InvalidCameraError(f"CameraMount.{n} must be in [-{MAX_DISTANCE_MM:g}, "
                                         f"{MAX_DISTANCE_MM:g}] mm, got {v!r}")
        if not 1.0 <= self.fov_deg <= 170.0:
            raise InvalidCameraError(f"CameraMount.fov_deg must be in [1, 170], got {self.fov_deg!r}")
        if self.wrist_cut_mm is not None and not -100.0 <= self.wrist_cut_mm <= MAX_WRIST_CUT_MM:
            raise InvalidCameraError(
                f"CameraMount.wrist_cut_mm must be in [-100, {MAX_WRIST_CUT_MM:g}] mm (beyond it "
                f"the cut removes the palm and every frame shows no hand), got {self.wrist_cut_mm!r}")
        if not -80.0 <= self.tilt_deg <= 80.0:
            raise InvalidCameraError(f"CameraMount.tilt_deg must be in [-80, 80], got {self.tilt_deg!r}")
        for n in ("width_px", "height_px"):
            v = getattr(self, n)
            if int(v) != v or not 1 <= v <= MAX_IMAGE_SIDE_PX:
                raise InvalidCameraError(f"CameraMount.{n} must be an integer in [1, "
                                         f"{MAX_IMAGE_SIDE_PX}] pixels, got {v!r}")
            object.__setattr__(self, n, int(v))

    # -- presets -----------------------------------------------------------------
    @classmethod
    def paper(cls) -> CameraMount:
        """The paper's device (the default): 120 mm, 90 deg, 720x480."""
        return cls()

    @classmethod
    def whole_hand(cls) -> CameraMount:
        """A mount high enough that the whole hand stays in the 720x480 frame.

        Same lens, centred over the hand and 190 mm above its back: open,
        spread and fist poses of all 81 grid shapes stay inside the frame
        (tested).  Fingertips and a spread little finger leave the paper's
        frame at 120 mm.
        """
        return cls(height_mm=190.0, thumb_offset_mm=10.0, along_mm=90.0)

    def replace(self, **changes) -> CameraMount:
        """A copy with some fields changed (validated again)."""
        return replace(self, **changes)

    def mirrored(self) -> CameraMount:
        """The device seen in the mirror: the roll turned the other way.

        A left hand's frame through this mount is the right hand's frame
        through ``mirrored()`` turned upside down (rows reversed), and the
        other way round; height, shifts and tilt keep their senses (the
        shift is toward the thumb on either hand).
        """
        return replace(self, roll_deg=0.0 - self.roll_deg)  # never -0.0: as_dict names caches

    def as_dict(self) -> dict:
        """The fields as a plain dict (for JSON and HDF5 attributes)."""
        return {f.name: getattr(self, f.name) for f in fields(self)}

    # -- geometry ----------------------------------------------------------------
    def pose_in_hand(self, *, side: str = "right") -> np.ndarray:
        """4x4 transform from the camera frame (OpenCV axes) to the hand frame, metres.

        Parameters
        ----------
        side : {"right", "left"}, keyword-only
            The thumb side is -x for a right hand and +x for a left hand.

        Returns
        -------
        ndarray, shape (4, 4), float64
            ``[[R, t], [0, 1]]`` with the camera centre ``t`` in metres and
            the columns of ``R`` the camera's x (image right), y (image down)
            and z (optical axis) axes in the hand frame.
        """
        check_side(side, error=InvalidCameraError)
        thumb_sign = -1.0 if side == "right" else 1.0
        t = np.array([thumb_sign * self.thumb_offset_mm, self.along_mm,
                      DORSUM_Z_MM + self.height_mm]) * 1e-3
        # Untilted: image right = +y (toward the fingers), optical axis = -z,
        # image down = z cross x = +x (away from a right hand's thumb).  A
        # left hand keeps the same axes, so its frames are the right hand's
        # frames flipped top to bottom through the mirrored device (mirrored()).
        r0 = np.array([[0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, -1.0]])
        # tilt about the hand x axis turns the optical axis from -z toward +y
        tilt = _axis_rot(np.array([1.0, 0.0, 0.0]), math.radians(self.tilt_deg))
        roll = _axis_rot(np.array([0.0, 0.0, 1.0]), math.radians(self.roll_deg))
        out = np.eye(4)
        out[:3, :3] = tilt @ r0 @ roll
        out[:3, 3] = t
        return out

    def intrinsics(self, width_px: int | None = None, height_px: int | None = None) -> np.ndarray:
        """3x3 pinhole matrix K (pixels) for a render of the given size.

        The horizontal field of view is kept, pixels are square and the
        principal point is the image centre (``(w - 1) / 2, (h - 1) / 2`` in
        pixel-centre coordinates).
        """
        w, h = self.size(width_px, height_px)
        f = 0.5 * w / math.tan(math.radians(self.fov_deg) / 2)
        return np.array([[f, 0.0, (w - 1) / 2], [0.0, f, (h - 1) / 2], [0.0, 0.0, 1.0]])

    def fovy_deg(self, width_px: int | None = None, height_px: int | None = None) -> float:
        """Vertical field of view of a render of the given size, degrees."""
        w, h = self.size(width_px, height_px)
        f = 0.5 * w / math.tan(math.radians(self.fov_deg) / 2)
        return math.degrees(2 * math.atan(0.5 * h / f))

    def size(self, width_px: int | None = None, height_px: int | None = None) -> tuple[int, int]:
        """Validated (width, height) of a render; the device's frame size by default.

        Raises
        ------
        InvalidCameraError
            A size that is not an integer in [1, :data:`MAX_IMAGE_SIDE_PX`] (16384), naming it.
        """
        w = self.width_px if width_px is None else width_px
        h = self.height_px if height_px is None else height_px
        for n, v in (("width_px", w), ("height_px", h)):
            if isinstance(v, bool) or not isinstance(v, (int, np.integer)) \
                    or not 1 <= v <= MAX_IMAGE_SIDE_PX:
                raise InvalidCameraError(f"image {n} must be a positive integer at most "
                                         f"{MAX_IMAGE_SIDE_PX}, got {v!r}")
        return int(w), int(h)

    def project(self, points_m: np.ndarray, *, side: str = "right",
                width_px: int | None = None, height_px: int | None = None) -> np.ndarray:
        """Project hand-frame points (N, 3) in metres to pixel coordinates (N, 2) (u, v)."""
        pose = self.pose_in_hand(side=side)
        pc = (np.asarray(points_m, float) - pose[:3, 3]) @ pose[:3, :3]
        uvw = pc @ self.intrinsics(width_px, height_px).T
        return uvw[:, :2] / uvw[:, 2:3]


def as_mount(mount, name: str = "mount", *, optional: bool = True) -> CameraMount:
    """`mount` checked to be a :class:`CameraMount`; the paper's device for ``None``
    when `optional`.

    Parameters
    ----------
    mount : object
        What was given.
    name : str
        The argument's name, for the message.
    optional : bool, keyword-only
        Read ``None`` as the paper's device (``CameraMount()``); refuse it
        when False.

    Returns
    -------
    CameraMount

    Raises
    ------
    InvalidCameraError
        Anything else (a falsy value too: ``mount=0`` is not the default),
        naming the argument `name`, the type received and its value.
    """
    if mount is None and optional:
        return CameraMount()
    return check_instance(mount, CameraMount, name=name, error=InvalidCameraError)


def _axis_rot(axis: np.ndarray, angle: float) -> np.ndarray:
    k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    return np.eye(3) + math.sin(angle) * k + (1 - math.cos(angle)) * (k @ k)
