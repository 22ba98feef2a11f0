"""Bad arguments of the evaluation's public functions are refused, naming the argument and value."""

from __future__ import annotations

import re
from types import SimpleNamespace

import numpy as np
import pytest

from handsynth.errors import InvalidInputError
from handsynth.eval import ProtocolOptions, _hands, joint_stats, random_hand_shapes, silhouette_ambiguity


# before: margin=-1 looped forever, nan raised OverflowError, 5 was accepted
@pytest.mark.parametrize("kwargs, named", [
    ({"margin": -1}, "margin must be a finite number >= 0 and <= 4, got -1"),
    ({"margin": float("nan")}, "margin must be a finite number >= 0 and <= 4, got nan"),
    ({"margin": 5}, "margin must be a finite number >= 0 and <= 4, got 5"),
    ({"margin": "0.5"}, "margin must be a finite number >= 0 and <= 4, got '0.5' (str)"),
    ({"seed": -1}, "seed must be an integer >= 0, got -1"),
])
def test_random_hand_shapes_refuses_bad_arguments(kwargs, named):
    with pytest.raises(InvalidInputError, match=f"^{re.escape(named)}$"):
        random_hand_shapes(3, **kwargs)


def test_random_hand_shapes_refuses_a_bad_count():
    with pytest.raises(InvalidInputError, match=r"^n must be an integer >= 0, got 2\.5"):
        random_hand_shapes(2.5)


def test_random_hand_shapes_keeps_the_extreme_margins():
    for margin in (0, 4):
        assert len(random_hand_shapes(5, margin=margin)) == 5


def test_random_hand_shapes_redraws_a_bounded_number_of_times():
    class OnLevel:  # a generator that always lands on a level
        calls = 0

        def uniform(self, a, b):
            OnLevel.calls += 1
            return 1.0

    with pytest.raises(InvalidInputError, match="no length ratio off the grid levels"):
        _hands._draw_off_levels(OnLevel(), (0.95, 1.0, 1.05), 0.5, "length")
    assert OnLevel.calls == _hands._MAX_REDRAWS


def test_protocol_options_refuse_an_unhashable_rest():
    # before: TypeError "unhashable type: 'list'"
    with pytest.raises(InvalidInputError, match=r"^ProtocolOptions.rest must be one of .*got \['open'\]$"):
        ProtocolOptions(rest=["open"])


def _db():
    a = np.arange(64, dtype=np.uint64)
    return SimpleNamespace(sil_bits=np.stack([a, a]), angles=np.zeros((2, 20)))


@pytest.mark.parametrize("spread", [-5, 0, float("nan"), "20"])
def test_silhouette_ambiguity_refuses_a_non_positive_spread(spread):
    # before: spread_deg=-5 marked every entry ambiguous
    with pytest.raises(InvalidInputError, match=r"^spread_deg must be a finite number > 0, got"):
        silhouette_ambiguity(_db(), spread_deg=spread)


def test_joint_stats_refuses_no_rows():
    # before: NaN statistics
    with pytest.raises(InvalidInputError, match=re.escape("errors_deg must have at least one row (frame), "
                                                          "got shape (0, 20)")):
        joint_stats(np.zeros((0, 20)))


def test_ratio_distance_names_what_is_not_a_hand_shape():
    # ratio_distance("a", ...) was an AttributeError
    from handsynth.eval import ratio_distance
    from handsynth.models import HandShape

    with pytest.raises(InvalidInputError, match="shape must be a HandShape, got str 'a'"):
        ratio_distance("a", HandShape())
    with pytest.raises(InvalidInputError, match="grid must be a HandShape, got NoneType"):
        ratio_distance(HandShape(), None)
    assert ratio_distance(HandShape(), HandShape()) == 0.0


def test_condition_stats_refuses_rows_that_do_not_pair():
    # estimates and truth of different lengths were numpy's broadcast error
    from handsynth.eval import condition_stats

    with pytest.raises(InvalidInputError, match=r"estimates and truth must both have shape \(N, 20\), "
                                                r"got \(3, 20\) and \(4, 20\)"):
        condition_stats(np.zeros((3, 20)), np.zeros((4, 20)), np.zeros(20))
    with pytest.raises(InvalidInputError, match=r"rest must have shape \(20,\) or \(3, 20\), got \(5,\)"):
        condition_stats(np.zeros((3, 20)), np.zeros((3, 20)), np.zeros(5))
    assert condition_stats(np.zeros((3, 20)), np.ones((3, 20)), np.zeros(20))["skill"]["all"] == 0.0
