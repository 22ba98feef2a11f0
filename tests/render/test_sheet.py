import pytest

from handsynth.errors import InvalidInputError
from handsynth.models import HandShape
from handsynth.render import contact_sheet


@pytest.mark.parametrize(("kwargs", "message"), [
    (dict(shapes={}), r"^shapes must be a non-empty dict of label -> HandShape, got \{\}"),
    (dict(shapes=[HandShape()]), r"^shapes must be a non-empty dict"),
    (dict(shapes={"a": HandShape()}, poses=(), side_view=False), "at least one pose or the side view"),
    (dict(shapes={"a": HandShape()}, tile_width_px=0), r"^tile_width_px must be an integer >= 16, got 0"),
])
def test_contact_sheet_refuses_what_it_cannot_draw(kwargs, message):
    # before: numpy's "need at least one array to concatenate"
    with pytest.raises(InvalidInputError, match=message):
        contact_sheet(**kwargs)


def test_a_one_tile_sheet_has_the_documented_size():
    sheet = contact_sheet({"a": HandShape()}, poses=("open",), tile_width_px=90, side_view=False)
    assert sheet.shape == (round(90 * 480 / 720) + 4, 94, 3)
