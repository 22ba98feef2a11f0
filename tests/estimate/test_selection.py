"""Database selection: formulas (1)-(4) of SPEC.md on hand-made numbers."""

from __future__ import annotations

import json
import re

import numpy as np
import pytest

from handsynth.errors import InvalidShapeError
from handsynth.estimate import SelectionOptions, select_shape, shape_ratios
from handsynth.models import HandMeasurements, HandShape, model_measurements


def _meas(L=10.0, W=2.0, pw=80.0, ph=80.0, tw=20.0, th=25.0):
    return HandMeasurements(L=[L] * 14, W=[W] * 14, P_width=pw, P_height=ph, T_width=tw,
                            T_height=th)


STD = _meas()


def test_formulas_on_hand_made_numbers_paper_normalisation():
    # user palm 10 % wider -> s = 80 / 88; L'' = 11 * s = 10 -> r_length = 1.0
    user = HandMeasurements(L=[11.0] * 7 + [12.1] * 7, W=[2.2] * 14, P_width=88.0,
                            P_height=88.0, T_width=22.0, T_height=30.8)
    r = shape_ratios(user, STD)
    s = 80.0 / 88.0
    assert r.length == pytest.approx(np.mean([11 * s / 10] * 7 + [12.1 * s / 10] * 7))  # (1)
    assert r.length == pytest.approx(1.05)
    assert r.width == pytest.approx(1.0)  # (2)
    assert r.palm == pytest.approx((1.0 + 22 * s / 20) / (2 * 88 * s / 80))  # (3) = 1.0
    assert r.thumb == pytest.approx(30.8 * s / 25)  # (4) = 1.12


def test_formula_3_palm_width_against_height():
    user = _meas(pw=84.0, ph=80.0, tw=21.0)
    r = shape_ratios(user, STD, normalize="none")
    assert r.palm == pytest.approx((84 / 80 + 21 / 20) / 2)  # 1.05
    assert r.length == pytest.approx(1.0)
    # paper's normalisation: s = 80/84 -> (1 + 1) / (2 * 80/84) = 1.05 as well
    assert shape_ratios(user, STD).palm == pytest.approx(1.05)


def test_select_nearest_grid_level_per_ratio():
    std = model_measurements()
    target = HandShape(length=1.03, width=1.08, palm=0.97, thumb=1.06)
    user = model_measurements(target)
    sel = select_shape(user, options=SelectionOptions(normalize="none"))
    assert sel.ratios.length == pytest.approx(1.03, abs=1e-9)
    assert sel.ratios.thumb == pytest.approx(1.06, abs=1e-9)
    assert sel.ratios.palm == pytest.approx(0.97, abs=2e-3)
    assert sel.ratios.width == pytest.approx(1.08, abs=5e-3)
    assert sel.shape == HandShape(length=1.05, width=1.1, palm=0.95, thumb=1.1)
    assert sel.name == "L1.050_W1.100_P0.950_T1.100"
    # the standard model selects itself under both normalisations
    for norm in ("palm_width", "none"):
        assert select_shape(std, options=SelectionOptions(normalize=norm)).shape == HandShape()


def test_model_measurements_follow_the_shape():
    std = model_measurements()
    long = model_measurements(HandShape(length=1.05))
    np.testing.assert_allclose(np.array(long.L) / np.array(std.L), 1.05)
    assert long.P_width == pytest.approx(std.P_width)
    assert 70 < std.P_width < 95 and 15 < std.W[2] < 25 and 15 < std.L[-1] < 30


def test_files_json_and_csv(tmp_path):
    m = _meas(L=12.5)
    (tmp_path / "m.json").write_text(json.dumps(m.as_dict()))
    assert HandMeasurements.from_file(tmp_path / "m.json") == m
    rows = ["name,value_mm", "# a comment"]
    rows += [f"L{i},12.5" for i in range(1, 15)] + [f"W{i},2" for i in range(1, 15)]
    rows += ["P_width,80", "P_height,80", "T_width,20", "T_height,25"]
    (tmp_path / "m.csv").write_text("\n".join(rows))
    assert HandMeasurements.from_file(tmp_path / "m.csv") == m


@pytest.mark.parametrize("path, words", [
    (None, "path must be a file name (str or path), got None"),
    (12, "path must be a file name (str or path), got int 12"),
    ("", "path must name a file, got ''"),
])
def test_a_measurement_file_name_that_is_no_name_is_refused(path, words):
    # None gave pathlib's "expected str, bytes or os.PathLike object, not NoneType"
    with pytest.raises(InvalidShapeError, match=re.escape(words)):
        HandMeasurements.from_file(path)


@pytest.mark.parametrize(
    "kwargs, match",
    [
        ({"L": [10.0] * 13}, "L must hold 14"),
        ({"W": [2.0] * 13 + [float("nan")]}, "W14"),
        ({"P_width": -1.0}, "P_width"),
        ({"T_height": "x"}, "T_height"),
    ],
)
def test_bad_measurements_name_the_value(kwargs, match):
    base = _meas().as_dict()
    base.pop("units")
    base.update(kwargs)
    with pytest.raises(InvalidShapeError, match=match):
        HandMeasurements(**base)


def test_options_are_checked():
    with pytest.raises(InvalidShapeError, match="normalize"):
        SelectionOptions(normalize="palm")
    with pytest.raises(TypeError):
        SelectionOptions(normalise="none")  # typo
    with pytest.raises(InvalidShapeError, match="unknown keys"):
        HandMeasurements.from_dict({**_meas().as_dict(), "Pwidth": 3})


def test_select_shape_names_a_value_out_of_place():
    # measurements built in code: the error was "HandShape.length=0.105 is outside ..."
    m = model_measurements(HandShape()).as_dict()
    m.pop("units")
    m["P_width"] *= 10  # a misplaced decimal point
    with pytest.raises(InvalidShapeError, match=r"P_width .* times what the other values"):
        select_shape(HandMeasurements(**m))
