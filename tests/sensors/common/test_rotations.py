"""The shared rotation helpers refuse arrays they cannot turn into rotations, by name and value."""

from __future__ import annotations

import re

import numpy as np
import pytest

from handsynth.errors import InvalidInputError, RecordingError
from handsynth.sensors.common import (
    axis_angle_matrix,
    check_rotations,
    matrix_to_rotvec,
    rotation_error,
    rotvec_to_matrix,
)


def test_valid_input_gives_the_same_rotations():
    r = axis_angle_matrix(np.array([0.0, 0.0, 2.0]), np.array(0.5))
    c, s = np.cos(0.5), np.sin(0.5)
    assert np.allclose(r, [[c, -s, 0], [s, c, 0], [0, 0, 1]])
    assert axis_angle_matrix([0.0, 0.0, 1.0], np.zeros(4)).shape == (4, 3, 3)
    v = np.array([[0.1, -0.2, 0.3], [0.0, 0.0, 0.0]])
    assert np.allclose(matrix_to_rotvec(rotvec_to_matrix(v)), v)
    assert rotvec_to_matrix(np.zeros((2, 5, 3))).shape == (2, 5, 3, 3)
    check_rotations(np.eye(3)[None])


@pytest.mark.parametrize("call, named", [
    # before: a NaN matrix and a RuntimeWarning
    (lambda: axis_angle_matrix(np.zeros(3), np.array(0.5)),
     "axis must be nonzero with a finite length, got [0.0, 0.0, 0.0] at index ()"),
    (lambda: axis_angle_matrix(np.array([1.0, np.nan, 0.0]), 0.5),
     "axis must be finite, got nan at index (1,)"),
    (lambda: axis_angle_matrix([1.0, 0.0, 0.0], np.inf), "angle must be finite, got inf at index ()"),
    (lambda: axis_angle_matrix(np.ones(2), 0.5), "axis must have shape (..., 3), got shape (2,)"),
    (lambda: axis_angle_matrix(np.ones((2, 3)), np.ones(3)),
     "angle of shape (3,) does not broadcast against axis[..., 0] of shape (2,)"),
    # before: a NaN matrix
    (lambda: rotvec_to_matrix(np.full(3, 1e300)), "rotvec must have a finite length (radians)"),
    (lambda: rotvec_to_matrix(np.zeros(4)), "rotvec must have shape (..., 3), got shape (4,)"),
    (lambda: rotvec_to_matrix("x"), "rotvec must be a (..., 3) array of numbers, got str 'x'"),
    # before: LinAlgError, scipy's ValueError, a raw reshape error
    (lambda: matrix_to_rotvec(np.full((3, 3), np.nan)), "rotations must be finite, got nan at index (0, 0)"),
    (lambda: matrix_to_rotvec(np.ones((3, 3))),
     "rotations must have a positive determinant, got 0 at index ()"),
    (lambda: matrix_to_rotvec(np.stack([np.eye(3), -np.eye(3)])),
     "rotations must have a positive determinant, got -1 at index (1,)"),
    (lambda: matrix_to_rotvec(np.zeros(9)), "rotations must have shape (..., 3, 3), got shape (9,)"),
    # before: einsum's ValueError
    (lambda: rotation_error(np.zeros(9)), "rotations must have shape (..., 3, 3), got shape (9,)"),
])
def test_helpers_refuse_what_is_not_a_rotation(call, named):
    with pytest.raises(InvalidInputError, match=f"^{re.escape(named)}"):
        call()


def test_check_rotations_names_a_wrong_shape():
    # before: einsum's ValueError
    with pytest.raises(RecordingError, match=re.escape("poses must have shape (..., 3, 3), got shape (9,)")):
        check_rotations(np.zeros(9), name="poses")
