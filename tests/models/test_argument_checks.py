"""Arguments of the hand model's API refused by name and value."""

from __future__ import annotations

import pytest

from handsynth.errors import InvalidInputError, InvalidShapeError
from handsynth.models import HandModel, HandShape


@pytest.mark.parametrize("name, got", [(None, "NoneType None"), (1.0, "float 1.0")])
def test_from_name_refuses_a_name_that_is_not_text(name, got):
    # before: AttributeError ('NoneType' object has no attribute 'split')
    with pytest.raises(InvalidShapeError, match=f"^name must be a str, got {got}$"):
        HandShape.from_name(name)


@pytest.fixture(scope="module")
def model():
    return HandModel()


@pytest.mark.parametrize("name, got", [(3, "int 3"), (None, "NoneType None")])
def test_body_pose_refuses_a_name_that_is_not_text(model, name, got):
    # before: mujoco's TypeError for 3; None crashed the interpreter
    with pytest.raises(InvalidInputError, match=f"^name must be a str, got {got}$"):
        model.body_pose(name)


def test_body_pose_still_names_an_unknown_body(model):
    with pytest.raises(InvalidInputError, match="^unknown body 'palmm'"):
        model.body_pose("palmm")
    pos, rot = model.body_pose("palm")
    assert pos.shape == (3,) and rot.shape == (3, 3)


def test_a_model_that_is_not_a_hand_is_named():
    # HandModel(xml="<mujoco/>") was MuJoCo's KeyError "Invalid name 'thumb_cmc_flex'"
    with pytest.raises(InvalidShapeError, match=r"^xml: the model has no joint 'thumb_cmc_flex' "
                                                r"\(20 of the hand's 20 joints missing\)"):
        HandModel(xml="<mujoco/>")
