"""Hand model: canonical joints, hand shapes, MJCF generation, pose sets and measurements.

The hand frame is public and used everywhere: origin at the wrist joint
centre, +y from the wrist toward the middle-finger MCP joint, +z out of the
back of the hand, x = y cross z.  Lengths in metres inside the model,
angles in degrees at every public interface.
"""

from ._angle_files import TIME_COLUMNS, AngleTable, read_angle_table
from ._anthropometry import (
    DEPTH_TO_BREADTH,
    DORSUM_Z_MM,
    FINGER_BREADTH_MM,
    HAND_BREADTH_MM,
    HAND_LENGTH_MM,
    SEGMENT_COEFFICIENTS,
    StandardLayout,
    standard_layout_mm,
)
from ._bvh import BVH_BONE_STARTS, BVH_BONES, BVH_CHANNELS, BVH_UNITS, bvh_text, write_bvh
from ._hand import HandModel, compile_mjcf
from ._joints import FINGERS, JOINT_LIMITS_DEG, JOINT_NAMES, joint_index
from ._measurements import (
    NORMALIZATIONS,
    SEGMENTS,
    HandMeasurements,
    formula_ratios,
    hull_width_at,
    model_measurements,
)
from ._mjcf import (
    KEYPOINT_SITES,
    SEGMENT_BODIES,
    THUMB_PITCH_DEG,
    THUMB_YAW_DEG,
    HandSpec,
    hand_mjcf,
    hand_spec,
)
from ._pose import NAMED_POSES, as_angles, named_pose
from ._posesets import MAX_POSES, PAPER_SIZE, POSE_SETS, natural_pose_set, paper_pose_set, pose_set
from ._shape import GRID_LEVELS, HandShape

__all__ = [
    "BVH_BONES",
    "BVH_BONE_STARTS",
    "BVH_CHANNELS",
    "BVH_UNITS",
    "DEPTH_TO_BREADTH",
    "DORSUM_Z_MM",
    "FINGERS",
    "FINGER_BREADTH_MM",
    "GRID_LEVELS",
    "HAND_BREADTH_MM",
    "HAND_LENGTH_MM",
    "JOINT_LIMITS_DEG",
    "JOINT_NAMES",
    "KEYPOINT_SITES",
    "MAX_POSES",
    "NAMED_POSES",
    "NORMALIZATIONS",
    "PAPER_SIZE",
    "POSE_SETS",
    "SEGMENTS",
    "SEGMENT_BODIES",
    "SEGMENT_COEFFICIENTS",
    "THUMB_PITCH_DEG",
    "THUMB_YAW_DEG",
    "TIME_COLUMNS",
    "AngleTable",
    "HandMeasurements",
    "HandModel",
    "HandShape",
    "HandSpec",
    "StandardLayout",
    "as_angles",
    "bvh_text",
    "compile_mjcf",
    "formula_ratios",
    "hand_mjcf",
    "hand_spec",
    "hull_width_at",
    "joint_index",
    "model_measurements",
    "named_pose",
    "natural_pose_set",
    "paper_pose_set",
    "pose_set",
    "read_angle_table",
    "standard_layout_mm",
    "write_bvh",
]
