"""handsynth: a MuJoCo hand as ground truth for hand and finger pose measurement."""

from .models import JOINT_NAMES

__version__ = "0.1.0"
__all__ = ["JOINT_NAMES", "__version__"]
