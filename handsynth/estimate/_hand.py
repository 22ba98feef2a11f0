"""What counts as a hand in a frame: the least share of the view it covers."""

from ..errors import InvalidInputError

__all__ = ["MIN_HAND_COVERAGE"]

#: Least share of the device's view (after the wrist cut) that a hand covers.  The smallest
#: hand handsynth models (every ratio 0.5) covers at least 7.0 % of the paper's view in the
#: pose sets' most folded pose, a fist (the standard hand 13.9 %; 300 natural and 300 paper
#: poses and the named poses; `tests/estimate/test_learned.py` keeps this margin), so a
#: frame whose bright part covers less than a seventh of that (a lamp in a dark room, one
#: bright pixel, a speck) shows no hand rather than a confidently read one.
MIN_HAND_COVERAGE = 0.01


def no_hand_error(argument: str) -> InvalidInputError:
    """The error for a calibration frame `argument` that shows no hand (an empty silhouette,
    or one under :data:`MIN_HAND_COVERAGE` of the view)."""
    return InvalidInputError(f"{argument} shows no hand: nothing stands out, or what does covers "
                             f"less than {100 * MIN_HAND_COVERAGE:g} % of the view "
                             "(MIN_HAND_COVERAGE)")
