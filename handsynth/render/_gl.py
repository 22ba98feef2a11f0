"""The one place that chooses the OpenGL backend for MuJoCo's renderer.

MuJoCo reads ``MUJOCO_GL`` when it is first imported.  On a machine without
a display handsynth defaults to ``egl`` (Mesa's software device, llvmpipe);
set ``MUJOCO_GL=osmesa`` before starting Python to use OSMesa instead, or
``glfw`` on a desktop.  Mesa's llvmpipe starts one rendering thread per core;
``LP_NUM_THREADS`` limits that (handsynth's batch jobs set it to 1 per
worker process).
"""

from __future__ import annotations

import os
import sys

__all__ = ["backend", "ensure_backend"]


def ensure_backend() -> str:
    """Set a headless default for ``MUJOCO_GL`` if none is set; return the backend."""
    if "mujoco" not in sys.modules and not os.environ.get("MUJOCO_GL") and not os.environ.get("DISPLAY"):
        os.environ["MUJOCO_GL"] = "egl"
    return backend()


def backend() -> str:
    """The backend MuJoCo uses (the value of ``MUJOCO_GL``, ``glfw`` when unset)."""
    return os.environ.get("MUJOCO_GL", "glfw")
