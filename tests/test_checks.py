import pytest

from handsynth._checks import check_side
from handsynth.errors import InvalidCameraError, InvalidInputError


def test_a_side_is_right_or_left_and_named_otherwise():
    assert check_side("right") == "right" and check_side("left") == "left"
    with pytest.raises(InvalidInputError, match=r"^side must be 'right' or 'left', got 'Right'$"):
        check_side("Right")
    with pytest.raises(InvalidCameraError, match=r"^EvalOptions.side must be .*got None$"):
        check_side(None, name="EvalOptions.side", error=InvalidCameraError)


@pytest.mark.parametrize("mount", [0, "", False, [], "paper"])
def test_every_layer_refuses_a_mount_that_is_not_a_camera_mount_falsy_ones_too(mount, tmp_path):
    # `mount or CameraMount()` once read a falsy value (0, "", []) as the paper's device
    import numpy as np

    from handsynth.db import build_databases
    from handsynth.estimate import select_shape_from_frame
    from handsynth.eval import model_test_hands
    from handsynth.models import HandShape
    from handsynth.render import fit_skin_colour, palm_region, preprocess

    frame = np.zeros((480, 720, 3), np.uint8)
    frame[200:300, 300:400] = 200
    calls = {
        "render.preprocess": lambda: preprocess(frame, mount),
        "render.palm_region": lambda: palm_region(mount),
        "render.fit_skin_colour": lambda: fit_skin_colour(frame, mount),
        "db.build_databases": lambda: build_databases(tmp_path, [HandShape()], mount),
        "estimate.select_shape_from_frame": lambda: select_shape_from_frame(frame, mount=mount),
        "eval.model_test_hands": lambda: model_test_hands(1, mount=mount),
    }
    for where, call in calls.items():
        with pytest.raises(InvalidCameraError, match=rf"^mount must be a CameraMount, got "
                                                     rf"{type(mount).__name__} "):
            call()
        assert not any(tmp_path.iterdir()), where  # refused before anything was written
