"""handsynth: a MuJoCo hand as ground truth for hand and finger pose measurement.

The flow of one frame: :mod:`handsynth.models` (hand model, shapes, poses,
measurements) -> :mod:`handsynth.render` (camera, renderer, preprocessing) ->
:mod:`handsynth.db` (features, database files) -> :mod:`handsynth.estimate`
(frame -> pose: database selection, search, calibration).  Around it:
:mod:`handsynth.measure` (hand measurements from a photo),
:mod:`handsynth.live` (frame sources, the live loop, writers),
:mod:`handsynth.testhands` (realistic glTF hands for testing),
:mod:`handsynth.eval` (the camera estimator's evaluation) and
:mod:`handsynth.cli`.  :mod:`handsynth.sensors` feeds the same hand to the
sensor-based methods.  Each layer imports only the layers below it (the
import contracts in ``pyproject.toml``).
"""

# First: chooses MuJoCo's OpenGL backend before anything imports mujoco.
import importlib
from typing import TYPE_CHECKING

from . import _gl  # noqa: F401
from ._version import __version__

if TYPE_CHECKING:
    from .estimate import PoseLookup
    from .models import JOINT_NAMES, HandModel, HandShape
    from .render import CameraMount

__all__ = ["JOINT_NAMES", "CameraMount", "HandModel", "HandShape", "PoseLookup", "__version__"]

#: Where each public name lives; imported on first use, so that ``import handsynth`` (and the
#: command line's entry point) does not load numpy, MuJoCo and the rest before it is needed.
_LAZY = {"JOINT_NAMES": "models", "HandModel": "models", "HandShape": "models",
         "CameraMount": "render", "PoseLookup": "estimate"}


def __getattr__(name: str):
    if name not in _LAZY:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(importlib.import_module(f".{_LAZY[name]}", __name__), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted({*globals(), *_LAZY})
