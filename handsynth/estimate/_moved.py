"""Has the device moved on the wrist since the rest frame was taken?

The learnt estimators read a frame against the user's rest frame and assume
the device has stayed where it was when that frame was taken; a strap that
slips costs them more than the constant answer (docs/camera_estimator.md, "The device slipping
after calibration").  The part of the hand next to the wrist cut -- the
back of the hand between the wrist and the thumb's base -- is rigid with the
device and moves with no finger: in the coverage grid its outline stays put
whatever the fingers do, and moves when the device does.  The thumb's base
reaches into one end of that band, so the band is cut in two halves along
the cut and the smaller of the halves' changes is kept: the device moving
changes both, the thumb one.  :class:`MoveCheck` measures that change of
coverage from the rest frame and calls the device moved when its median over
the last frames exceeds a limit.
"""

from __future__ import annotations

import copy
from collections import deque
from dataclasses import dataclass, field

import cv2
import numpy as np
from scipy import ndimage

from .._checks import check_integer, check_options
from ..errors import InvalidInputError
from ..render import CameraMount, wrist_cut_keep

__all__ = ["MoveCheck", "MoveCheckOptions", "MoveCheckState"]


@dataclass(frozen=True)
class MoveCheckOptions:
    """Options of :class:`MoveCheck`.

    Parameters
    ----------
    band_cells : int
        Width of the band, in grid cells from the wrist cut (2: 32 pixels of
        the 720x480 frame at the default 16-pixel cells).
    window : int
        Frames whose median change is compared with `limit`; the device is
        not called moved before that many frames were read.
    limit : float
        Median change (covered share of the band's cells changed, over the
        rest frame's covered share of them) above which the device is called
        moved: three times the largest median over 30-frame windows of frames
        seen from where the rest frame was (0.0055: four held-out model
        hands, fingers and thumb moving, outlines flickering; ``python
        scripts/study_camera.py moved``; docs/camera_estimator.md, "The device slipping after
        calibration").
    """

    band_cells: int = 2
    window: int = 30
    limit: float = 0.016

    def __post_init__(self) -> None:
        for name, lo in (("band_cells", 1), ("window", 1)):
            check_integer(getattr(self, name), f"MoveCheckOptions.{name}", minimum=lo)
        lim = self.limit
        if isinstance(lim, bool) or not isinstance(lim, (int, float)) or not 0 < lim < 1:
            raise InvalidInputError(f"MoveCheckOptions.limit must be in (0, 1), got {lim!r}")


@dataclass
class MoveCheckState:
    """The running part of a :class:`MoveCheck`: the last `window` changes."""

    changes: deque = field(default_factory=deque)


class MoveCheck:
    """Tells from coverage grids whether the device has moved since the rest frame.

    Parameters
    ----------
    rest_grid : ndarray, shape cells, uint8
        Coverage grid of the rest frame (255 = covered).
    mount : CameraMount
        The device whose wrist cut the grids were made with.
    side : {"right", "left"}, keyword-only
    options : MoveCheckOptions, keyword-only, optional

    Attributes
    ----------
    available : bool
        False when the grids have no wrist cut (``mount.wrist_cut_mm`` None)
        or the rest frame covers none of the band: :meth:`update` then
        never calls the device moved.
    """

    def __init__(self, rest_grid: np.ndarray, mount: CameraMount, *, side: str = "right",
                 options: MoveCheckOptions | None = None) -> None:
        self.options = check_options(options, MoveCheckOptions)
        self.state = MoveCheckState(deque(maxlen=self.options.window))
        rest = np.asarray(rest_grid)
        if rest.ndim != 2 or rest.dtype != np.uint8:
            raise InvalidInputError(f"rest_grid must be a 2-D uint8 coverage grid, got "
                                    f"{rest.dtype} of shape {rest.shape}")
        band = _band(rest, mount, side, self.options.band_cells)
        self._shape = rest.shape
        self._halves = [h for h in _halves(band, rest) if rest[h].any()]
        self._rest = [rest[h].astype(np.float32) for h in self._halves]
        self._area = [float(r.sum()) for r in self._rest]
        self.available = len(self._halves) == 2

    def fresh(self) -> MoveCheck:
        """This check with no frame seen yet (the rest frame's arrays shared, read only)."""
        out = copy.copy(self)
        out.state = MoveCheckState(deque(maxlen=self.options.window))
        return out

    def change(self, grid: np.ndarray) -> float:
        """Covered share of the band changed from the rest frame (NaN if not :attr:`available`).

        The smaller of the two halves' changes, each over the rest frame's
        covered share of its cells.

        Raises
        ------
        InvalidInputError
            `grid` is not a uint8 coverage grid of the rest frame's cells.
        """
        if not self.available:
            return float("nan")
        g = np.asarray(grid)
        if g.dtype != np.uint8 or g.size != self._shape[0] * self._shape[1]:
            raise InvalidInputError(f"grid must be a {self._shape[0]}x{self._shape[1]} uint8 "
                                    f"coverage grid, got {g.dtype} of shape {g.shape}")
        g = g.reshape(self._shape)
        return min(float(np.abs(g[h].astype(np.float32) - r).sum() / a)
                   for h, r, a in zip(self._halves, self._rest, self._area, strict=True))

    def update(self, grid: np.ndarray) -> bool:
        """Add a frame's grid; True when the device has moved by the last `window` frames."""
        if not self.available:
            return False
        self.state.changes.append(self.change(grid))
        return self.moved

    @property
    def moved(self) -> bool:
        """Whether the median change of the last `window` frames exceeds the limit."""
        c = self.state.changes
        return len(c) == self.options.window and float(np.median(c)) > self.options.limit


def _band(rest: np.ndarray, mount: CameraMount, side: str, width: int) -> np.ndarray:
    """Cells within `width` cells of the wrist cut and within 2 of the rest hand (bool, cells)."""
    rows, cols = rest.shape
    keep = wrist_cut_keep(mount, side=side)
    if keep is None:
        return np.zeros(rest.shape, bool)
    cut = cv2.resize((~keep).astype(np.float32), (cols, rows), interpolation=cv2.INTER_AREA) > 0
    if not cut.any():
        return np.zeros(rest.shape, bool)
    near_cut = ndimage.distance_transform_edt(~cut) <= width
    near_hand = ndimage.binary_dilation(rest > 0, iterations=2)
    return near_cut & near_hand & ~cut


def _halves(band: np.ndarray, rest: np.ndarray) -> list[np.ndarray]:
    """`band` cut in two along its long axis at the rest frame's covered median."""
    rr, cc = np.nonzero(band)
    if len(rr) < 2:
        return []
    xy = np.column_stack([rr, cc]).astype(float)
    xy -= xy.mean(axis=0)
    axis = np.linalg.svd(xy, full_matrices=False)[2][0]  # the band's long direction
    t = xy @ axis
    w = rest[rr, cc].astype(float)
    order = np.argsort(t)
    cum = np.cumsum(w[order])
    if cum[-1] <= 0:
        return []
    mid = t[order][np.searchsorted(cum, cum[-1] / 2)]
    out = []
    for part in (t <= mid, t > mid):
        h = np.zeros(band.shape, bool)
        h[rr[part], cc[part]] = True
        out.append(h)
    return out
