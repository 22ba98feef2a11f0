"""What counts as a hand in a frame: the least share of the view it covers."""

__all__ = ["MIN_HAND_COVERAGE"]

#: Least share of the device's view (after the wrist cut) that a hand covers.  The smallest
#: hand handsynth models (every ratio 0.5) covers at least 7.0 % of the paper's view in the
#: pose sets' most folded pose, a fist (the standard hand 13.9 %; 300 natural and 300 paper
#: poses and the named poses; `tests/estimate/test_learned.py` keeps this margin), so a
#: frame whose bright part covers less than a seventh of that (a lamp in a dark room, one
#: bright pixel, a speck) shows no hand rather than a confidently read one.
MIN_HAND_COVERAGE = 0.01
