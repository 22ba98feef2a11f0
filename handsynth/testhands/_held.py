"""An object held in the hand, for rendering test frames of grasps.

The device camera looks at the back of the hand; an object the fingers close around lies
on the palm's side, so the camera sees it where the hand does not cover it (its ends
beyond the hand's edges, between the fingers) and the fingers' tips may pass behind it.
:meth:`handsynth.testhands.MeshHandRenderer.mask_holding` renders a hand with such an
object; :func:`grasped_cylinder` places a cylinder where a power grasp's fingers close.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .._checks import check_array, check_number
from ..errors import InvalidInputError
from ..models import DEPTH_TO_BREADTH, FINGER_BREADTH_MM

__all__ = ["HeldObject", "grasped_cylinder"]

#: Half a finger's dorsal-palmar depth, mm, taken off the circle through the joint
#: centres: the mean breadth at the PIP of the four fingers times depth / breadth, both
#: from Greiner (1991) (:data:`handsynth.models.FINGER_BREADTH_MM`): 8.2 mm.
_FINGER_HALF_MM = 0.5 * DEPTH_TO_BREADTH * float(np.mean(
    [FINGER_BREADTH_MM[f][0] for f in ("index", "middle", "ring", "little")]))

#: Largest RMS distance, mm, of the finger joints from the circle fitted through them
#: for the fingers to be taken as closed around one cylinder.
_MAX_OFF_CIRCLE_MM = 6.0


@dataclass(frozen=True)
class HeldObject:
    """A cylinder held in the hand, in the hand frame.

    Parameters
    ----------
    centre_mm : tuple of 3 float
        The cylinder's centre in the hand frame (y toward the fingers, z out of the
        back of the hand; x across the palm, away from a right hand's thumb and
        toward a left hand's, as the renderer's ``keypoints`` give it), mm.
    axis : tuple of 3 float
        Its axis (normalised here); across the palm (x) by default.
    radius_mm, length_mm : float
        Its size, mm.
    bright : bool
        Drawn as bright as the hand (a white cup on a dark ground: it joins the
        hand's silhouette), or dark (only hiding what is behind it).

    Raises
    ------
    InvalidInputError
        A centre or axis that is not three finite numbers, an axis of length 0, a size
        that is not a finite number > 0.
    """

    centre_mm: tuple
    axis: tuple = (1.0, 0.0, 0.0)
    radius_mm: float = 30.0
    length_mm: float = 200.0
    bright: bool = True

    def __post_init__(self) -> None:
        for name in ("centre_mm", "axis"):
            v = check_array(getattr(self, name), name, (3,))
            if name == "axis":
                n = float(np.linalg.norm(v))
                if n == 0.0:
                    raise InvalidInputError("axis must not be of length 0")
                v = v / n
            object.__setattr__(self, name, tuple(float(x) for x in v))
        for name in ("radius_mm", "length_mm"):
            object.__setattr__(self, name, check_number(getattr(self, name), name, above=0.0))
        if not isinstance(self.bright, bool):
            raise InvalidInputError(f"bright must be True or False, got {self.bright!r}")

    def quat(self) -> np.ndarray:
        """The rotation (w, x, y, z) that turns a cylinder along z onto :attr:`axis`."""
        a = np.asarray(self.axis)
        c = float(a[2])
        if c < -1.0 + 1e-12:
            return np.array([0.0, 1.0, 0.0, 0.0])
        v = np.cross([0.0, 0.0, 1.0], a)  # sin(angle) * unit axis
        q = np.array([1.0 + c, *v])
        return q / np.linalg.norm(q)


def grasped_cylinder(keypoints_m: np.ndarray, *, length_mm: float = 200.0,
                     bright: bool = True) -> HeldObject | None:
    """The cylinder the four fingers of a grasp close around, or None.

    A circle is fitted (least squares) to the MCP, PIP and DIP centres and tips of the
    index to little fingers in the hand's y-z plane; the cylinder lies across the palm
    on that circle's centre, its radius the circle's less half a finger's depth
    (8.2 mm, Greiner 1991).

    Parameters
    ----------
    keypoints_m : ndarray, shape (21, 3)
        The hand's keypoints in the hand frame, metres, in the order of
        :meth:`handsynth.models.HandModel.keypoints` (wrist, thumb, then index to
        little: MCP, PIP, DIP, tip).
    length_mm : float, keyword-only
    bright : bool, keyword-only
        As :class:`HeldObject`.

    Returns
    -------
    HeldObject or None
        None where the fingers do not curl around a cylinder of 12-45 mm radius on the
        palm's side of the knuckles: the points more than 6 mm (RMS) off the circle, a
        cylinder reaching above the MCP centres (an open hand's circle), or one too
        large or too small (a fist's leaves no room).
    """
    kp = check_array(keypoints_m, "keypoints_m", (21, 3), rows="points")
    fingers = kp[5:21] * 1e3
    p = fingers[:, 1:]
    a = np.c_[2 * p, np.ones(len(p))]
    c, *_ = np.linalg.lstsq(a, (p**2).sum(axis=1), rcond=None)
    through = math.sqrt(max(c[2] + c[0] ** 2 + c[1] ** 2, 0.0))
    off = np.sqrt(np.mean((np.linalg.norm(p - c[:2], axis=1) - through) ** 2))
    radius = through - _FINGER_HALF_MM
    mcp_z = fingers[0::4, 2].mean()
    if not 12.0 <= radius <= 45.0 or off > _MAX_OFF_CIRCLE_MM or c[1] + radius > mcp_z:
        return None
    return HeldObject((float(fingers[:, 0].mean()), float(c[0]), float(c[1])),
                      radius_mm=radius, length_mm=length_mm, bright=bright)
