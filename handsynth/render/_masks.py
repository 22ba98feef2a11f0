"""The interface shared by every maker of hand masks (MuJoCo renders, raster, mesh hand)."""

from __future__ import annotations

import numpy as np

from ..errors import InvalidInputError, InvalidPoseError
from ..models import as_angles

__all__ = ["MaskMaker"]


class MaskMaker:
    """Base class: boolean masks of posed hands as the device camera sees them.

    Subclasses set ``width_px`` and ``height_px`` (the model hands through
    :meth:`_load_hand`) and implement :meth:`_draw`, which poses the hand and
    writes one mask.
    """

    width_px: int
    height_px: int

    def _load_hand(self, shape, mount, *, side: str, width_px: int | None,
                   height_px: int | None, forearm: bool, samples: int = 0) -> None:
        """Set ``shape, mount, side, width_px, height_px`` and ``hand``: the model hand
        in its silhouette scene (flat white, device camera at the mask size)."""
        from ..models import HandModel, HandShape
        from ._camera import as_mount
        from ._scene import scene_mjcf

        self.shape = HandShape() if shape is None else shape
        self.mount = as_mount(mount)
        self.side = side
        self.width_px, self.height_px = self.mount.size(width_px, height_px)
        xml = scene_mjcf(self.shape, self.mount, side=side, forearm=forearm, silhouette=True,
                         width_px=self.width_px, height_px=self.height_px, samples=samples)
        self.hand = HandModel(self.shape, side=side, xml=xml)

    def _draw(self, pose: np.ndarray, out: np.ndarray) -> None:
        """Write the mask of `pose` ((20,) validated degrees) into `out` ((H, W) bool)."""
        raise NotImplementedError

    def mask(self, angles) -> np.ndarray:
        """Mask of one pose.

        Parameters
        ----------
        angles : array_like, shape (20,), or mapping of str to float
            Joint angles, degrees, canonical order.

        Returns
        -------
        ndarray, shape (height_px, width_px), bool
            True where the camera sees the hand.

        Raises
        ------
        InvalidPoseError
            Unknown joints, NaN, or angles outside the joint limits.
        """
        a = as_angles(angles)
        if a.ndim != 1:
            raise InvalidPoseError(f"angles must be one pose of shape (20,), got {a.shape}")
        out = np.zeros((self.height_px, self.width_px), dtype=bool)
        self._draw(a, out)
        return out

    def masks(self, angles, *, out: np.ndarray | None = None) -> np.ndarray:
        """Masks of many poses.

        Parameters
        ----------
        angles : array_like, shape (N, 20)
            Degrees, canonical order; all validated before drawing starts.
        out : ndarray, shape (N, height_px, width_px), bool, optional
            Written in place and returned.

        Returns
        -------
        ndarray, shape (N, height_px, width_px), bool

        Raises
        ------
        InvalidPoseError
            Unknown joints, NaN, or angles outside the joint limits.
        InvalidInputError
            An `out` that is not a bool numpy array of that shape.
        """
        a = as_angles(angles)
        if a.ndim != 2:
            a = a[None]
        shape = (len(a), self.height_px, self.width_px)
        if out is None:
            out = np.zeros(shape, dtype=bool)
        elif not isinstance(out, np.ndarray):
            raise InvalidInputError(f"out must be a bool numpy array of shape {shape}, "
                                    f"got {type(out).__name__}")
        elif out.shape != shape or out.dtype != bool:
            raise InvalidInputError(f"out must be a bool array of shape {shape}, "
                                    f"got {out.dtype} {out.shape}")
        for i, pose in enumerate(a):
            self._draw(pose, out[i])
        return out
