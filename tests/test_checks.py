import pytest

from handsynth._checks import check_side
from handsynth.errors import InvalidCameraError, InvalidInputError


def test_a_side_is_right_or_left_and_named_otherwise():
    assert check_side("right") == "right" and check_side("left") == "left"
    with pytest.raises(InvalidInputError, match=r"^side must be 'right' or 'left', got 'Right'$"):
        check_side("Right")
    with pytest.raises(InvalidCameraError, match=r"^EvalOptions.side must be .*got None$"):
        check_side(None, name="EvalOptions.side", error=InvalidCameraError)
