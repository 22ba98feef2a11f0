"""A scene around the hand: the device camera, lights and off-screen settings."""

from __future__ import annotations

import numpy as np

from ..errors import InvalidInputError
from ..models import HandShape, hand_mjcf
from ._camera import CameraMount, as_mount

__all__ = ["mujoco_camera_xyaxes", "scene_include_mjcf", "scene_mjcf", "scene_parts", "standard_assets"]

#: Multisample counts of the off-screen buffer that OpenGL drivers offer (0: none).
MSAA_SAMPLES = (0, 2, 4, 8, 16)


def check_samples(samples) -> int:
    """`samples` checked to be one of :data:`MSAA_SAMPLES`.

    Raises
    ------
    InvalidInputError
        Anything else (a negative, odd or fractional count, a bool), naming
        the argument and the value received.
    """
    if isinstance(samples, bool) or not isinstance(samples, (int, np.integer)) \
            or samples not in MSAA_SAMPLES:
        raise InvalidInputError(
            f"samples must be one of {', '.join(map(str, MSAA_SAMPLES))} (multisample "
            f"anti-aliasing; 0: none), got {samples!r}")
    return int(samples)


def mujoco_camera_xyaxes(pose_cv: np.ndarray) -> np.ndarray:
    """MuJoCo ``xyaxes`` (6,) of a camera whose OpenCV-axes pose is `pose_cv` (4x4).

    MuJoCo cameras look along their -z axis with +y up; OpenCV's y points down.
    """
    r = pose_cv[:3, :3]
    return np.concatenate([r[:, 0], -r[:, 1]])


def scene_parts(mount: CameraMount | None, side: str, silhouette: bool,
                 width_px: int | None, height_px: int | None,
                 samples: int = 0) -> tuple[str, str]:
    """The ``<visual>`` element and the worldbody lights and cameras of a scene.

    Parameters
    ----------
    mount : CameraMount or None
        The device camera; the paper's device for ``None``.
    side : {"right", "left"}
        Hand side: the device camera sits on that hand's thumb side
        (:meth:`CameraMount.pose_in_hand`).
    silhouette : bool
        No lights (headlight off, no key light), for flat masks; a key light
        and a headlight when False.
    width_px, height_px : int or None
        Off-screen buffer size in pixels, which also sets the device camera's
        vertical field of view (:meth:`CameraMount.fovy_deg`); the mount's
        frame size for ``None``.
    samples : int
        Multisample anti-aliasing samples of the off-screen buffer, one of
        :data:`MSAA_SAMPLES` (0: none).

    Returns
    -------
    visual : str
        The ``<visual>`` element (buffer size, samples, headlight), indented
        for a child of ``<mujoco>``.
    world : str
        The key light (none with `silhouette`) and the cameras ``"device"``,
        ``"side"`` and ``"top"``, indented for children of ``<worldbody>``;
        positions in metres, ``fovy`` in degrees.

    Raises
    ------
    InvalidInputError
        A `mount` that is not a :class:`CameraMount`, or `samples` not one of
        :data:`MSAA_SAMPLES`, naming it.
    """
    mount = as_mount(mount)
    samples = check_samples(samples)
    w, h = mount.size(width_px, height_px)
    pose = mount.pose_in_hand(side=side)
    xy = mujoco_camera_xyaxes(pose)
    fmt = lambda a: " ".join(f"{v:.9g}" for v in a)  # noqa: E731
    light = "" if silhouette else (
        '    <light name="key" pos="0.05 0.05 0.5" dir="-0.1 -0.1 -1" diffuse="0.6 0.6 0.6" '
        'castshadow="false"/>\n')
    head = ('<headlight active="0" ambient="0 0 0" diffuse="0 0 0" specular="0 0 0"/>'
            if silhouette else '<headlight ambient="0.35 0.35 0.35" diffuse="0.45 0.45 0.45"/>')
    cameras = (
        f'    <camera name="device" pos="{fmt(pose[:3, 3])}" xyaxes="{fmt(xy)}" '
        f'fovy="{mount.fovy_deg(w, h):.9g}"/>\n'
        # a view from the thumb side (looking along +x), and one from far above
        '    <camera name="side" pos="-0.4 0.08 -0.01" xyaxes="0 -1 0 0 0 1" fovy="32"/>\n'
        '    <camera name="top" pos="0 0.08 0.45" xyaxes="0 1 0 -1 0 0" fovy="40"/>\n'
    )
    visual = (
        f'  <visual>\n    <global offwidth="{w}" offheight="{h}"/>\n'
        f'    <quality offsamples="{samples}" shadowsize="0"/>\n    {head}\n'
        '    <rgba haze="0 0 0 1"/>\n    <map znear="0.01" zfar="50"/>\n  </visual>\n'
    )
    return visual, light + cameras


def scene_mjcf(shape: HandShape | None = None, mount: CameraMount | None = None, *,
               side: str = "right", forearm: bool = True, silhouette: bool = False,
               width_px: int | None = None, height_px: int | None = None,
               samples: int = 0) -> str:
    """MJCF of the hand with the device camera ``"device"``, a side camera and lights.

    Parameters
    ----------
    shape, mount : optional
        Hand shape and camera mount (standard hand, paper device by default).
    side : {"right", "left"}, keyword-only
    forearm : bool, keyword-only
        Include the forearm stub.
    silhouette : bool, keyword-only
        Flat unlit white hand on black, no lights: a mask is one channel > 0.
    width_px, height_px : int, keyword-only
        Off-screen buffer size (the render size; the mount's frame size by default).
    samples : int, keyword-only
        Multisample anti-aliasing samples of the off-screen buffer: 0 (none),
        2, 4, 8 or 16.

    Returns
    -------
    str
        A complete MJCF document.
    """
    visual, world = scene_parts(mount, side, silhouette, width_px, height_px, samples)
    hand = hand_mjcf(shape, side=side, forearm=forearm, silhouette=silhouette)
    hand = hand.replace("  <compiler ", visual + "  <compiler ", 1)
    return hand.replace("  </worldbody>", world + "  </worldbody>", 1)


def scene_include_mjcf(hand_file: str, mount: CameraMount | None = None, *,
                       side: str = "right") -> str:
    """A scene document that includes the hand document `hand_file` (Menagerie layout).

    Parameters
    ----------
    hand_file : str
        The hand document's file name as the ``<include file=...>`` gives it
        (relative to the scene file, e.g. ``"right_hand.xml"``); written as
        given, not read or checked.
    mount : CameraMount, optional
        The device camera; the paper's device by default.
    side : {"right", "left"}, keyword-only
        Hand side: places the device camera and names the model
        ``"handsynth_<side>_scene"``.

    Returns
    -------
    str
        A complete MJCF document: lit (not a silhouette scene), the mount's
        frame size as off-screen buffer, no multisampling, with the cameras of
        :func:`scene_parts`.
    """
    visual, world = scene_parts(mount, side, False, None, None)
    return (f'<mujoco model="handsynth_{side}_scene">\n  <include file="{hand_file}"/>\n'
            f"{visual}  <worldbody>\n{world}  </worldbody>\n</mujoco>\n")


def standard_assets() -> dict[str, str]:
    """File name -> MJCF text of the standard right and left hands and their scenes.

    The files committed in ``assets/hand_mjcf/`` (Menagerie layout); a test
    checks that they equal this output (``scripts/write_mjcf_assets.py``
    writes them).
    """
    out = {}
    for side in ("right", "left"):
        out[f"{side}_hand.xml"] = hand_mjcf(HandShape(), side=side)
        out[f"scene_{side}.xml"] = scene_include_mjcf(f"{side}_hand.xml", side=side)
    return out
