"""What the sensor systems share: rotation conventions and helpers.

Conventions used by every system in :mod:`handsynth.sensors`: a rotation
matrix ``R`` of a sensor maps sensor-frame coordinates to the reference
frame (``x_ref = R @ x_sensor + t``); rotation vectors are ``angle *
unit_axis`` in radians; quaternions are scalar-first ``(w, x, y, z)``.

Sensor packages import only :mod:`handsynth.models`, :mod:`handsynth.errors`
and this package.
"""

from ._rotations import (
    ROTATION_TOLERANCE,
    axis_angle_matrix,
    check_rotations,
    matrix_to_rotvec,
    rotation_error,
    rotvec_to_matrix,
)

__all__ = [
    "ROTATION_TOLERANCE",
    "axis_angle_matrix",
    "check_rotations",
    "matrix_to_rotvec",
    "rotation_error",
    "rotvec_to_matrix",
]
