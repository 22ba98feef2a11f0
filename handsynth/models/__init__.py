"""Hand model: canonical joints, hand shapes, MJCF generation and pose sets."""

from ._joints import FINGERS, JOINT_LIMITS_DEG, JOINT_NAMES, joint_index

__all__ = ["FINGERS", "JOINT_LIMITS_DEG", "JOINT_NAMES", "joint_index"]
