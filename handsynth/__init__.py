"""handsynth: a MuJoCo hand as ground truth for hand and finger pose measurement.

The flow of one frame: :mod:`handsynth.models` (hand model, shapes, poses) ->
:mod:`handsynth.render` (camera, renderer, preprocessing) ->
:mod:`handsynth.db` (features, database files) -> :mod:`handsynth.estimate`
(database selection, search, live loop).  :mod:`handsynth.sensors` feeds the
same hand to the sensor-based methods.
"""

from .estimate import PoseLookup
from .models import JOINT_NAMES, HandModel, HandShape
from .render import CameraMount

__version__ = "0.1.0"
__all__ = ["JOINT_NAMES", "CameraMount", "HandModel", "HandShape", "PoseLookup", "__version__"]
