"""Kinematic models of a finger joint: where the lower segment is.

Both models give the pose of the *lower* segment frame in the *upper* segment
frame (frames as in :mod:`handsynth.sensors._geometry`: ``+y`` along the
bone, ``+z`` dorsal, flexion about ``-x``) as a function of the flexion angle
``theta`` and an abduction "wobble" ``psi``.  The lower frame's origin is the
lower bone's point at the joint centre.

:class:`HingeJoint` -- the patent's wooden mock (JP2010-88628, para. 0100:
two segments on a 4 mm pin): centre and axis fixed.

:class:`FingerJoint` -- a joint whose axis and centre move with flexion
(para. 0022, 0106: the lower phalanx, pulled by the tendon, slides on the
articular surface of the upper one).  With ``u = theta / 90 deg``:

* the centre moves by ``slide_mm * u**2`` in the upper frame, in the sagittal
  plane, along a direction ``slide_direction_deg`` from ``-y`` toward ``-z``
  (proximal and palmar: the base of the lower bone glides round the condyle);
* the flexion axis turns about the bone (``y``) by ``axis_tilt_deg * u**2``
  (the conjunct axial rotation of the finger joints).

Both effects grow quadratically, i.e. the joint is nearly a hinge near
extension and departs from one in deep flexion.  This is a modelling choice,
not a measurement: it is the simplest shape that reproduces the patent's two
observations (axis direction spread of a few degrees, Fig. 11; larger
|P_U - P_L| than the mock).  Defaults: 2.5 mm slide and 20 deg tilt at
90 deg flexion, i.e. 14 deg at 75 deg, so that the axes' lateral components
spread over about 0.96-1.0 as the patent's human DIP did (para. 0110).
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

from ..common import axis_angle_matrix
from ._checks import check_number

__all__ = ["ArcJoint", "FingerJoint", "HingeJoint"]

_X = np.array([1.0, 0.0, 0.0])
_Y = np.array([0.0, 1.0, 0.0])
_Z = np.array([0.0, 0.0, 1.0])


def _check_sliding_joint(joint) -> None:
    """Raise InvalidInputError unless every field of `joint` is finite and its slide >= 0."""
    for name, v in asdict(joint).items():
        check_number(v, name)
    check_number(joint.slide_mm, "slide_mm", minimum=0.0)


def _relative_rotation(axis: np.ndarray, theta: np.ndarray, psi: np.ndarray) -> np.ndarray:
    """Flexion by `theta` about `axis` after an abduction `psi` about ``+z``."""
    return axis_angle_matrix(axis, theta) @ axis_angle_matrix(_Z, psi)


@dataclass(frozen=True, kw_only=True)
class HingeJoint:
    """Single fixed axis through a fixed centre (the patent's mock)."""

    kind = "hinge"

    def pose(self, theta: np.ndarray, psi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Lower segment in the upper segment frame.

        Parameters
        ----------
        theta, psi : (n,) ndarray of float64
            Flexion and abduction wobble in radians.

        Returns
        -------
        rotation : (n, 3, 3) ndarray of float64
            Lower frame to upper frame.
        offset : (n, 3) ndarray of float64
            Displacement of the joint centre from its extended position, in
            the upper frame, metres (zero for the hinge).
        """
        theta = np.asarray(theta, dtype=np.float64)
        rot = _relative_rotation(np.broadcast_to(-_X, theta.shape + (3,)), theta, psi)
        return rot, np.zeros(theta.shape + (3,))

    def describe(self) -> dict:
        """JSON-serialisable parameters."""
        return {"kind": self.kind}


@dataclass(frozen=True, kw_only=True)
class FingerJoint:
    """Joint whose centre slides and axis tilts with flexion (see module doc).

    Parameters
    ----------
    slide_mm : float
        Centre displacement at 90 deg flexion, millimetres.
    slide_direction_deg : float
        Direction of that displacement in the sagittal plane, degrees from
        ``-y`` (proximal) toward ``-z`` (palmar).
    axis_tilt_deg : float
        Rotation of the flexion axis about the bone at 90 deg flexion.
    """

    slide_mm: float = 2.5
    slide_direction_deg: float = 45.0
    axis_tilt_deg: float = 20.0

    kind = "finger"

    def __post_init__(self) -> None:
        _check_sliding_joint(self)

    def pose(self, theta: np.ndarray, psi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Lower segment in the upper segment frame; see :meth:`HingeJoint.pose`."""
        theta = np.asarray(theta, dtype=np.float64)
        u2 = (theta / (np.pi / 2)) ** 2
        tilt = np.deg2rad(self.axis_tilt_deg) * u2
        axis = -axis_angle_matrix(np.broadcast_to(_Y, theta.shape + (3,)), tilt) @ _X
        rot = _relative_rotation(axis, theta, psi)
        a = np.deg2rad(self.slide_direction_deg)
        direction = -np.cos(a) * _Y - np.sin(a) * _Z
        offset = (self.slide_mm * 1e-3) * u2[..., None] * direction
        return rot, offset

    def describe(self) -> dict:
        """JSON-serialisable parameters."""
        return {"kind": self.kind, **asdict(self)}


@dataclass(frozen=True, kw_only=True)
class ArcJoint:
    """Joint whose centre rolls on an arc and whose axis tilts linearly.

    A second, independent finger-like model (a different shape from
    :class:`FingerJoint`, so that estimators are not tested only on the
    kinematics they were tuned on).  The lower bone's centre moves on a
    circular arc of radius `arc_radius_mm` in the sagittal plane: it travels
    the arc length ``slide_mm * theta / 90 deg`` (linear, not quadratic, in
    the flexion angle), starting tangentially toward palmar-proximal; the
    flexion axis turns about the dorsal axis (``z``, not the bone) by
    ``axis_tilt_deg * theta / 90 deg``.  Like :class:`FingerJoint` this is a
    modelling choice, not a measurement; defaults are the ones of the
    independent check reported in docs/trackers.md (1.5 mm slide, 4 deg tilt).

    Parameters
    ----------
    slide_mm : float
        Arc length travelled by the centre at 90 deg flexion, millimetres.
    arc_radius_mm : float
        Radius of the arc, millimetres (> 0).
    axis_tilt_deg : float
        Rotation of the flexion axis about ``z`` at 90 deg flexion, degrees.
    """

    slide_mm: float = 1.5
    arc_radius_mm: float = 4.0
    axis_tilt_deg: float = 4.0

    kind = "arc"

    def __post_init__(self) -> None:
        _check_sliding_joint(self)
        check_number(self.arc_radius_mm, "arc_radius_mm", above=0.0)

    def pose(self, theta: np.ndarray, psi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Lower segment in the upper segment frame; see :meth:`HingeJoint.pose`."""
        theta = np.asarray(theta, dtype=np.float64)
        u = theta / (np.pi / 2)
        tilt = np.deg2rad(self.axis_tilt_deg) * u
        axis = -axis_angle_matrix(np.broadcast_to(_Z, theta.shape + (3,)), tilt) @ _X
        rot = _relative_rotation(axis, theta, psi)
        r = self.arc_radius_mm * 1e-3
        phi = (self.slide_mm * 1e-3) * u / r  # angle travelled on the arc
        # arc tangent at the start: palmar (-z); it curves toward proximal (-y)
        offset = r * (-np.sin(phi)[..., None] * _Z - (1 - np.cos(phi))[..., None] * _Y)
        return rot, offset

    def describe(self) -> dict:
        """JSON-serialisable parameters."""
        return {"kind": self.kind, **asdict(self)}
