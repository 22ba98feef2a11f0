"""Off-screen rendering of masks and pictures with MuJoCo's own renderer."""

from __future__ import annotations

import atexit
import contextlib
import os
import weakref

import numpy as np

from .._gl import ensure_backend
from ..errors import InvalidCameraError, RenderError
from ..models import HandModel, HandShape
from ._camera import CameraMount, as_mount
from ._masks import MaskMaker
from ._scene import check_samples, scene_mjcf

__all__ = ["GLContextOwner", "SilhouetteRenderer", "offscreen_renderer", "render_rgb"]


#: Off-screen renderers not yet closed, closed at exit while the GL library is still there
#: (at interpreter teardown MuJoCo's own finaliser found OSMesa's functions gone and printed
#: a traceback for every renderer its user had not closed).
_OPEN_RENDERERS: weakref.WeakSet = weakref.WeakSet()


@atexit.register
def _close_open_renderers() -> None:
    for renderer in list(_OPEN_RENDERERS):
        with contextlib.suppress(Exception):
            renderer.close()


def offscreen_renderer(model, w: int, h: int):
    """A MuJoCo off-screen renderer of `model`, `w` by `h` pixels.

    Parameters
    ----------
    model : mujoco.MjModel
        The scene to draw; its off-screen buffer (``<visual><global
        offwidth offheight>``, as :func:`scene_mjcf` writes it) must be at
        least `w` by `h`.
    w, h : int
        Width and height of the images, in pixels.

    Returns
    -------
    mujoco.Renderer
        Holding a GL context of its own: release it with its ``close()``
        when done (or hold it in a :class:`GLContextOwner`).  Any not closed
        is closed at interpreter exit, while the GL library is still loaded.

    Raises
    ------
    RenderError
        The renderer could not be made (no GL backend for ``MUJOCO_GL``, a
        size larger than the model's off-screen buffer), with the reason and
        what to install on a machine without a display.
    """
    import mujoco

    try:
        renderer = mujoco.Renderer(model, height=h, width=w)
        _OPEN_RENDERERS.add(renderer)
        return renderer
    except Exception as exc:  # GL context creation failures come in many types
        raise RenderError(
            f"could not create a {w}x{h} off-screen renderer with MUJOCO_GL="
            f"{os.environ.get('MUJOCO_GL')!r}: {exc}. On a machine without a "
            "display install Mesa (libegl1 libgl1-mesa-dri) and use MUJOCO_GL=egl or osmesa."
        ) from None


class GLContextOwner:
    """Base of the classes that hold a MuJoCo off-screen renderer in ``_renderer``:
    :meth:`close` releases its GL context; also a context manager."""

    _renderer = None

    def close(self) -> None:
        """Release the GL context (idempotent)."""
        if self._renderer is not None:
            self._renderer.close()
            self._renderer = None

    def __enter__(self):
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def __del__(self) -> None:
        with contextlib.suppress(Exception):
            self.close()


class SilhouetteRenderer(GLContextOwner, MaskMaker):
    """Boolean hand masks as the device camera sees them.

    One compiled model and one GL context are reused for every pose, so a
    batch of masks costs one model load.  Rendering is deterministic: the
    same pose gives the same mask, bit for bit, on the same machine.

    Parameters
    ----------
    shape : HandShape, optional
        The standard hand by default.
    mount : CameraMount, optional
        The paper's device by default.
    side : {"right", "left"}, keyword-only
    width_px, height_px : int, keyword-only
        Render size (the mount's 720x480 by default); the horizontal field of
        view is kept and pixels are square.
    forearm : bool, keyword-only
        Render the forearm stub behind the wrist, as the real camera sees it.
    samples : int, keyword-only
        Multisample anti-aliasing: 0 (none), 2, 4, 8 or 16 (Mesa's llvmpipe
        gives the same masks for every count above 0); a pixel is hand when
        at least half of its samples are (a high-quality reference).

    Raises
    ------
    InvalidInputError
        An argument of the wrong type or value, naming it: a `mount` that
        is not a :class:`CameraMount` (:class:`~handsynth.errors.InvalidCameraError`),
        a `shape` that is not a :class:`~handsynth.models.HandShape`
        (:class:`~handsynth.errors.InvalidShapeError`), `samples` not one of
        those counts, a bad `side` or image size.
    RenderError
        No off-screen renderer could be created (no GL library).

    Examples
    --------
    >>> r = SilhouetteRenderer(width_px=180, height_px=120)
    >>> r.mask(named_pose("fist")).shape
    (120, 180)
    """

    def __init__(self, shape: HandShape | None = None, mount: CameraMount | None = None, *,
                 side: str = "right", width_px: int | None = None, height_px: int | None = None,
                 forearm: bool = True, samples: int = 0) -> None:
        check_samples(samples)  # before the GL context, whose failure would be blamed on GL
        ensure_backend()
        import mujoco

        self._load_hand(shape, mount, side=side, width_px=width_px, height_px=height_px,
                        forearm=forearm, samples=samples)
        self._renderer = offscreen_renderer(self.hand.model, self.width_px, self.height_px)
        self._cam = mujoco.mj_name2id(self.hand.model, mujoco.mjtObj.mjOBJ_CAMERA, "device")
        self._buf = np.empty((self.height_px, self.width_px, 3), dtype=np.uint8)

    def _draw(self, pose: np.ndarray, out: np.ndarray) -> None:
        if self._renderer is None:
            raise RenderError("this SilhouetteRenderer is closed")
        self.hand.set_pose(pose, check=False)
        self._renderer.update_scene(self.hand.data, camera=self._cam)
        self._renderer.render(out=self._buf)
        np.greater(self._buf[:, :, 0], 127, out=out)



def render_rgb(angles, shape: HandShape | None = None, mount: CameraMount | None = None, *,
               side: str = "right", camera: str = "device", width_px: int | None = None,
               height_px: int | None = None, forearm: bool = True) -> np.ndarray:
    """A lit colour picture of the posed hand.

    Parameters
    ----------
    angles : array_like, shape (20,), or mapping
        Degrees, canonical order.
    shape, mount : optional
    side : {"right", "left"}, keyword-only
    camera : {"device", "side", "top"}, keyword-only
        The device camera, a view from the thumb side, or a view from far above.
    width_px, height_px : int, keyword-only

    Returns
    -------
    ndarray, shape (height_px, width_px, 3), uint8
        RGB.
    """
    if camera not in ("device", "side", "top"):
        raise InvalidCameraError(f"camera must be 'device', 'side' or 'top', got {camera!r}")
    mount = as_mount(mount)
    ensure_backend()
    w, h = mount.size(width_px, height_px)
    xml = scene_mjcf(shape, mount, side=side, forearm=forearm, width_px=w, height_px=h)
    hand = HandModel(shape, side=side, xml=xml)
    hand.set_pose(angles)
    r = offscreen_renderer(hand.model, w, h)
    try:
        r.update_scene(hand.data, camera=camera)
        return r.render().copy()
    finally:
        r.close()
