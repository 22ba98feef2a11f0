"""The GL backend is chosen before anything imports mujoco, whatever the user imported first.

These run in a fresh interpreter with ``MUJOCO_GL`` and the display variables
removed, as in a user's shell: the test suite itself sets ``MUJOCO_GL``
(conftest), which would hide a wrong order.
"""

import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def _run_bare(code: str, **extra_env) -> subprocess.CompletedProcess:
    env = {k: v for k, v in os.environ.items()
           if k not in ("MUJOCO_GL", "DISPLAY", "WAYLAND_DISPLAY", "PYOPENGL_PLATFORM")}
    env["PYTHONPATH"] = str(ROOT)
    env.update(extra_env)
    return subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True,
                          timeout=120, cwd=ROOT)


_RENDER = ("from handsynth.render import SilhouetteRenderer; "
           "r = SilhouetteRenderer(HandShape(), width_px=64, height_px=48); "
           "import os; print(int(r.mask({}).sum() > 100), os.environ['MUJOCO_GL'])")


@pytest.mark.parametrize("first", [
    "from handsynth import HandModel, HandShape; HandModel(HandShape())",   # the model loads mujoco
    "import mujoco; from handsynth import HandShape",                       # the user imported it
    "import mujoco, mujoco.renderer; from handsynth.models import HandShape",
])
def test_renders_headless_when_mujoco_is_imported_before_the_first_renderer(first):
    res = _run_bare(f"{first}; {_RENDER}")
    assert res.returncode == 0, res.stderr[-2000:]
    assert res.stdout.split() == ["1", "egl"]


def test_a_backend_the_user_chose_is_kept():
    res = _run_bare("import handsynth, os; print(os.environ['MUJOCO_GL'])", MUJOCO_GL="osmesa")
    assert res.returncode == 0, res.stderr[-2000:]
    assert res.stdout.strip() == "osmesa"


@pytest.mark.parametrize("backend", ["egl", "osmesa"])
def test_a_renderer_left_open_is_released_at_exit_without_a_traceback(backend):
    # MuJoCo's finaliser ran at interpreter teardown, found OSMesa's functions gone and
    # printed "Exception ignored in: Renderer.__del__" with a traceback
    res = _run_bare(f"from handsynth import HandShape; {_RENDER}", MUJOCO_GL=backend)
    assert res.returncode == 0, res.stderr[-2000:]
    assert res.stdout.split() == ["1", backend]
    assert "Exception" not in res.stderr and "Traceback" not in res.stderr, res.stderr[-2000:]
