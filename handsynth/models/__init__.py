"""Hand model: canonical joints, hand shapes, MJCF generation and pose sets.

The hand frame is public and used everywhere: origin at the wrist joint
centre, +y from the wrist toward the middle-finger MCP joint, +z out of the
back of the hand, x = y cross z.  Lengths in metres inside the model,
angles in degrees at every public interface.
"""

from ._anthropometry import DORSUM_Z_MM, HAND_BREADTH_MM, HAND_LENGTH_MM
from ._hand import HandModel, compile_mjcf
from ._joints import FINGERS, JOINT_LIMITS_DEG, JOINT_NAMES, joint_index
from ._mjcf import KEYPOINT_SITES, SEGMENT_BODIES, hand_mjcf
from ._pose import NAMED_POSES, as_angles, named_pose
from ._posesets import POSE_SETS, natural_pose_set, paper_pose_set, pose_set
from ._shape import GRID_LEVELS, HandShape

__all__ = [
    "DORSUM_Z_MM",
    "FINGERS",
    "GRID_LEVELS",
    "HAND_BREADTH_MM",
    "HAND_LENGTH_MM",
    "HandModel",
    "HandShape",
    "JOINT_LIMITS_DEG",
    "JOINT_NAMES",
    "KEYPOINT_SITES",
    "NAMED_POSES",
    "POSE_SETS",
    "SEGMENT_BODIES",
    "as_angles",
    "compile_mjcf",
    "hand_mjcf",
    "joint_index",
    "named_pose",
    "natural_pose_set",
    "paper_pose_set",
    "pose_set",
]
