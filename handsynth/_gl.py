"""The one place that chooses the OpenGL backend of MuJoCo's renderer.

MuJoCo chooses its OpenGL backend from ``MUJOCO_GL`` once, when ``mujoco``
is first imported, and uses GLFW (which needs a display) when the variable
is unset.  handsynth therefore chooses before anything of its own imports
``mujoco``: ``handsynth/__init__.py`` imports this module first, and on a
machine without a display (no ``DISPLAY`` or ``WAYLAND_DISPLAY``) and without
``MUJOCO_GL`` it sets ``MUJOCO_GL=egl`` (Mesa's software device, llvmpipe).
A ``MUJOCO_GL`` set by the user is never changed: ``osmesa`` uses OSMesa,
``glfw`` a desktop's display.

When ``mujoco`` was imported before handsynth, with ``MUJOCO_GL`` unset and
no display, it holds a GLFW backend that cannot work; :func:`ensure_backend`
(called before every renderer is made) then re-runs MuJoCo's backend choice
with ``MUJOCO_GL=egl``.  Mesa's llvmpipe starts one rendering thread per core;
``LP_NUM_THREADS`` limits that (handsynth's batch jobs set it to 1 per
worker process).
"""

from __future__ import annotations

import importlib
import os
import sys

__all__ = ["HEADLESS_BACKEND", "backend", "ensure_backend"]

#: Backend chosen when there is no display and ``MUJOCO_GL`` is unset.
HEADLESS_BACKEND = "egl"
_GL_CONTEXT_MODULE = "mujoco.rendering.classic.gl_context"


def _has_display() -> bool:
    return bool(os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"))


def _choose() -> bool:
    """Set the headless default if needed; True when it was set now."""
    if os.environ.get("MUJOCO_GL") or _has_display():
        return False
    os.environ["MUJOCO_GL"] = HEADLESS_BACKEND
    return True


def ensure_backend() -> str:
    """Make sure MuJoCo renders with a backend that can work here; return its name.

    Sets ``MUJOCO_GL=egl`` when it is unset and there is no display.  If
    ``mujoco`` is already imported and chose its backend without the
    variable, its choice is made again with it (MuJoCo reads the variable
    only on import).  A value set by the user is never changed.
    """
    if _choose():
        gl_context = sys.modules.get(_GL_CONTEXT_MODULE)
        if gl_context is not None and getattr(gl_context, "_MUJOCO_GL", None) == "":
            importlib.reload(gl_context)  # mujoco was imported first, with GLFW
    return backend()


def backend() -> str:
    """The backend MuJoCo uses (the value of ``MUJOCO_GL``, ``glfw`` when unset)."""
    return os.environ.get("MUJOCO_GL", "glfw")


# Chosen on import: handsynth/__init__.py imports this module before any other.
ensure_backend()
