import re

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


class _Echo:
    """A lookup that answers each frame as its own angles, counting its calls."""

    def __init__(self):
        self.calls = 0

    def estimate(self, frame):
        self.calls += 1
        return type("E", (), {"angles": np.asarray(frame, float).ravel() + 2.0})()


@pytest.mark.parametrize("masks, poses, words", [
    # 12 frames, 10 poses: the error was broadcast or opaque
    (12, np.zeros((10, 20)), "poses must have shape (N, 20) with N = len(masks) = 12, got (10, 20)"),
    (3, np.zeros((3, 19)), "poses must have shape (N, 20) with N = len(masks) = 3, got (3, 19)"),
    (3, np.zeros(20), "poses must have shape (N, 20) with N = len(masks) = 3, got (20,)"),
    (1, np.zeros((1, 20, 1)), "poses must have shape (N, 20) with N = len(masks) = 1, got (1, 20, 1)"),
    (3, [["a"] * 20] * 3, "poses must be a real array of shape (N, 20) (degrees), got dtype <U1"),
    (3, None, "poses must be a real array of shape (N, 20) (degrees), got NoneType None"),
    (3, np.full((3, 20), np.nan), "poses must be finite, got nan at row 0, joint thumb_cmc_flex"),
    (0, np.zeros((0, 20)), "masks must hold at least one frame, got none"),
])
def test_lookup_errors_refuses_masks_and_poses_that_do_not_match(masks, poses, words):
    lookup = _Echo()
    with pytest.raises(InvalidInputError, match="^" + re.escape(words)):
        lookup_errors(lookup, [np.zeros(20)] * masks, poses)
    assert lookup.calls == 0  # refused before any frame is looked up


@pytest.mark.parametrize("lookup, masks, words", [
    (None, [np.zeros(20)], "lookup must have an estimate() method (a PoseLookup), got NoneType None"),
    (_Echo(), np.zeros((48, 72), bool), "masks must be a sequence of frames (ndarray, shape (H, W)), "
                                        "got an array of shape (48, 72)"),
    (_Echo(), "frames", "masks must be a sequence of frames (ndarray, shape (H, W)), got str 'frames'"),
    (_Echo(), 3, "masks must be a sequence of frames (ndarray, shape (H, W)), got int 3"),
])
def test_lookup_errors_names_a_lookup_or_masks_that_are_not_one(lookup, masks, words):
    with pytest.raises(InvalidInputError, match="^" + re.escape(words)):
        lookup_errors(lookup, masks, np.zeros((1, 20)))


def test_lookup_errors_takes_an_array_of_frames_and_integer_poses():
    truth = np.arange(2 * len(JOINT_NAMES)).reshape(2, -1)
    r = lookup_errors(_Echo(), truth[:, :, None], truth)
    assert r["mae_deg"] == 2.0


@pytest.mark.parametrize("sheet", [estimates_sheet, backgrounds_sheet])
def test_sheets_name_an_estimator_that_is_not_one_before_rendering(sheet):
    with pytest.raises(InvalidInputError, match=r"^estimator must have a calibrated\(\) method "
                                                r"\(a LearnedEstimator or EnsembleEstimator\), "
                                                r"got NoneType None"):
        sheet(None)
