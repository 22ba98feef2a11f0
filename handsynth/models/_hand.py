"""A compiled hand: pose it with canonical angles, read bodies and keypoints."""

from __future__ import annotations

import numpy as np

from .._checks import check_instance
from ._joints import JOINT_NAMES
from ._mjcf import KEYPOINT_SITES, hand_mjcf
from ._pose import as_angles
from ._shape import HandShape

__all__ = ["HandModel", "compile_mjcf"]


def compile_mjcf(xml: str):
    """Compile an MJCF string, turning MuJoCo's errors into :class:`RenderError`.

    Parameters
    ----------
    xml : str
        A complete MJCF document (as :func:`hand_mjcf` writes), passed to
        ``mujoco.MjModel.from_xml_string``.

    Returns
    -------
    mujoco.MjModel

    Raises
    ------
    RenderError
        MuJoCo could not compile `xml` (its ``ValueError``, message kept).
    """
    import mujoco

    from ..errors import RenderError

    try:
        return mujoco.MjModel.from_xml_string(xml)
    except ValueError as exc:
        raise RenderError(f"MuJoCo could not compile the hand model: {exc}") from None


class HandModel:
    """The MuJoCo hand of one shape and side, posed by canonical joint angles.

    The world frame of the model *is* the hand frame: origin at the wrist
    joint centre, +y toward the middle-finger MCP joint, +z out of the back
    of the hand, x = y cross z (for a right hand +x points to the little
    finger; the left hand is the mirror image and its thumb lies at +x).
    Lengths are metres.

    Parameters
    ----------
    shape : HandShape, optional
        The standard hand by default.
    side : {"right", "left"}, keyword-only
    forearm : bool, keyword-only
        Include the forearm stub.
    xml : str, keyword-only
        Use this MJCF instead of generating one (it must have the same joint,
        body and site names, e.g. a scene that includes the hand).

    Raises
    ------
    InvalidShapeError
        `shape` is not a HandShape, or `xml` lacks one of the hand's joints or
        keypoint sites (naming it).
    RenderError
        MuJoCo could not compile `xml`.

    Attributes
    ----------
    model : mujoco.MjModel
    data : mujoco.MjData
    """

    def __init__(self, shape: HandShape | None = None, *, side: str = "right",
                 forearm: bool = True, xml: str | None = None) -> None:
        import mujoco

        self._mj = mujoco
        from ..errors import InvalidShapeError

        self.shape = HandShape() if shape is None else check_instance(
            shape, HandShape, name="shape", error=InvalidShapeError)
        self.side = side
        self.model = compile_mjcf(xml or hand_mjcf(self.shape, side=side, forearm=forearm))
        self.data = mujoco.MjData(self.model)
        for kind, names, find in (("joint", JOINT_NAMES, mujoco.mjtObj.mjOBJ_JOINT),
                                  ("site", KEYPOINT_SITES, mujoco.mjtObj.mjOBJ_SITE)):
            missing = [n for n in names if mujoco.mj_name2id(self.model, find, n) < 0]
            if missing:  # a model given as `xml` that is not a handsynth hand
                raise InvalidShapeError(f"xml: the model has no {kind} {missing[0]!r} ({len(missing)} "
                                        f"of the hand's {len(names)} {kind}s missing); give "
                                        "hand_mjcf()'s MJCF or one made from it")
        self._qadr = np.array(
            [self.model.joint(n).qposadr[0] for n in JOINT_NAMES], dtype=np.intp
        )
        self._sites = np.array([self.model.site(n).id for n in KEYPOINT_SITES], dtype=np.intp)
        self.set_pose(np.zeros(len(JOINT_NAMES)))

    def set_pose(self, angles, *, check: bool = True) -> None:
        """Pose the hand and update its kinematics.

        Parameters
        ----------
        angles : array_like, shape (20,), or mapping of str to float
            Degrees, canonical order (see :func:`as_angles`).
        check : bool, keyword-only
            Validate the angles (skip only for angles already validated).
        """
        a = as_angles(angles) if check else np.asarray(angles, dtype=np.float64)
        if a.ndim != 1:
            from ..errors import InvalidPoseError

            raise InvalidPoseError(f"set_pose takes one pose of shape (20,), got {a.shape}")
        self.data.qpos[self._qadr] = np.radians(a)
        self._mj.mj_kinematics(self.model, self.data)
        self._mj.mj_camlight(self.model, self.data)

    @property
    def angles(self) -> np.ndarray:
        """Current joint angles, degrees, canonical order, shape (20,)."""
        return np.degrees(self.data.qpos[self._qadr])

    def keypoints(self) -> np.ndarray:
        """The 21 keypoints in the hand frame, metres, shape (21, 3).

        Order: wrist, then thumb CMC, MCP, IP, tip, then for index, middle,
        ring, little: MCP, PIP, DIP, tip.
        """
        return self.data.site_xpos[self._sites].copy()

    def body_pose(self, name: str) -> tuple[np.ndarray, np.ndarray]:
        """Position (3,) in metres and rotation (3, 3) body-to-hand of body `name`.

        Raises
        ------
        InvalidInputError
            `name` is not a str (``3``, None: MuJoCo would raise its own error, or crash), or
            no body of the model, named with the value received.
        """
        b = self._body(name)
        return self.data.xpos[b].copy(), self.data.xmat[b].reshape(3, 3).copy()

    def joint_axis(self, name: str) -> tuple[np.ndarray, np.ndarray]:
        """Anchor (3,) in metres and unit axis (3,) of joint `name`, hand frame."""
        from ._joints import joint_index

        joint_index(name)
        j = self.model.joint(name).id
        return self.data.xanchor[j].copy(), self.data.xaxis[j].copy()

    def _body(self, name: str) -> int:
        from ..errors import InvalidInputError

        check_instance(name, str, name="name", error=InvalidInputError)
        b = self._mj.mj_name2id(self.model, self._mj.mjtObj.mjOBJ_BODY, name)
        if b < 0:
            names = [self.model.body(i).name for i in range(1, self.model.nbody)]
            raise InvalidInputError(f"unknown body {name!r}; expected one of {', '.join(names)}")
        return b
