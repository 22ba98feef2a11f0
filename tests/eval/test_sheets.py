import numpy as np
import pytest

from handsynth.errors import InvalidInputError
from handsynth.eval import backgrounds_sheet, estimates_sheet, lookup_errors
from handsynth.models import JOINT_NAMES


@pytest.mark.parametrize("sheet", [estimates_sheet, backgrounds_sheet])
def test_sheets_check_their_sizes_before_rendering(sheet):
    with pytest.raises(InvalidInputError, match=r"^tile_width_px must be an integer >= 64, got 10"):
        sheet(None, tile_width_px=10)
    with pytest.raises(InvalidInputError, match=r"^count must be an integer >= 1, got 0"):
        sheet(None, count=0)


def test_lookup_errors_measures_against_the_true_angles():
    class Answer:  # a lookup that always answers 2 deg more than the truth of frame k
        def __init__(self):
            self.calls = 0

        def estimate(self, frame):
            self.calls += 1
            return type("E", (), {"angles": frame + 2.0})()

    truth = np.arange(3 * len(JOINT_NAMES), dtype=float).reshape(3, -1)
    lookup = Answer()
    r = lookup_errors(lookup, list(truth), truth)
    assert r["mae_deg"] == r["index_pip_mae_deg"] == r["thumb_cmc_flex_mae_deg"] == 2.0
    assert r["frames_per_s"] > 0 and lookup.calls == 4  # the first frame once more, untimed
