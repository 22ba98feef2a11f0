"""Measurement files as people make them: Excel's BOM, other encodings, repeated rows (issue 16)."""

import json
import re
import warnings

import numpy as np
import pytest

from handsynth.errors import InvalidShapeError
from handsynth.models import HandMeasurements, HandShape, model_measurements


def _csv_lines(m: HandMeasurements) -> list[str]:
    lines = ["name,value_mm"]
    lines += [f"L{i},{v:.4f}" for i, v in enumerate(m.L, 1)]
    lines += [f"W{i},{v:.4f}" for i, v in enumerate(m.W, 1)]
    lines += [f"{n},{getattr(m, n):.4f}" for n in ("P_width", "P_height", "T_width", "T_height")]
    return lines


@pytest.fixture
def measured():
    return model_measurements(HandShape(length=1.05, width=0.95))


def test_a_byte_order_mark_is_not_part_of_the_first_name(tmp_path, measured):
    # item 13: Excel's "CSV UTF-8" was refused with an invisible character in the message
    path = tmp_path / "m.csv"
    path.write_bytes(b"\xef\xbb\xbf" + "\r\n".join(_csv_lines(measured)[1:]).encode())
    np.testing.assert_allclose(HandMeasurements.from_file(path).L, measured.L, atol=1e-4)
    path.write_bytes(b"\xef\xbb\xbf" + "\n".join(_csv_lines(measured)).encode())
    np.testing.assert_allclose(HandMeasurements.from_file(path).W, measured.W, atol=1e-4)


def test_a_file_that_is_not_utf8_is_one_clear_error(tmp_path, measured):
    # item 13: a UnicodeDecodeError traceback
    path = tmp_path / "m.csv"
    text = "\n".join(_csv_lines(measured)) + "\n# gemessen: Hände\n"
    path.write_bytes(text.encode("latin-1"))
    with pytest.raises(InvalidShapeError, match=r"m.csv is not UTF-8 text \(byte 0xe4 at offset"):
        HandMeasurements.from_file(path)


def test_a_name_given_twice_is_refused(tmp_path, measured):
    # item 13: a duplicate row silently overrode the first
    lines = _csv_lines(measured)
    lines.insert(5, "L2,99.0")
    path = tmp_path / "m.csv"
    path.write_text("\n".join(lines) + "\n")
    with pytest.raises(InvalidShapeError, match=r"line 6: L2 is given again \(line 3 gave it first\)"):
        HandMeasurements.from_file(path)


@pytest.mark.parametrize("header", ["name,value_cm", "name,value_in", "Name,Value"])
def test_a_csv_in_other_units_is_refused(tmp_path, measured, header):
    # defect 8: "name,value_cm" was read as millimetres (a hand ten times too small)
    lines = _csv_lines(measured)
    lines[0] = header
    path = tmp_path / "m.csv"
    path.write_text("\n".join(lines) + "\n")
    with pytest.raises(InvalidShapeError, match=r"m.csv line 1: the value column is .*"
                                                r"expected 'value_mm'"):
        HandMeasurements.from_file(path)


def test_the_csv_header_may_follow_comments_and_differ_in_case(tmp_path, measured):
    lines = _csv_lines(measured)
    lines[0] = "# measured by hand\nName, Value_MM"
    path = tmp_path / "m.csv"
    path.write_text("\n".join(lines) + "\n")
    np.testing.assert_allclose(HandMeasurements.from_file(path).L, measured.L, atol=1e-4)


@pytest.mark.parametrize("suffix", ["csv", "json"])
def test_an_absurd_value_is_blamed_by_name(tmp_path, measured, suffix):
    # defect 7: P_width ten times too large was reported as
    # "HandShape.length=0.1048... is outside the supported range [0.5, 2.0]"
    import json

    path = tmp_path / f"m.{suffix}"
    if suffix == "csv":
        lines = [f"P_width,{10 * measured.P_width:.3f}" if ln.startswith("P_width") else ln
                 for ln in _csv_lines(measured)]
        path.write_text("\n".join(lines) + "\n")
    else:
        path.write_text(json.dumps({**measured.as_dict(), "P_width": 1e9}))
    with pytest.raises(InvalidShapeError) as info:
        HandMeasurements.from_file(path)
    msg = str(info.value)
    assert msg.startswith(f"{path}: the measurements give a length ratio of "), msg
    assert "outside [0.5, 2.0]: P_width " in msg and "times what the other values suggest" in msg
    assert "HandShape" not in msg and "W1 " not in msg and "L1 " not in msg


def test_consistency_names_no_file_when_none_is_known(measured):
    values = {**measured.as_dict(), "L": [10 * v for v in measured.L]}
    with pytest.raises(InvalidShapeError, match=r"^the measurements give .*: L\d+ .* mm is 10.5 "
                                                r"times .*; and 11 more; check the values"):
        HandMeasurements.from_dict(values)


def test_extreme_but_supported_shapes_are_read(tmp_path):
    # the check must not refuse any hand of the supported range
    import itertools

    for ratios in itertools.product((0.5, 2.0), repeat=4):
        m = model_measurements(HandShape(*ratios))
        with pytest.warns(UserWarning, match="from the wrist to the middle fingertip") \
                if not 100 <= m.hand_length_mm <= 300 else _no_warning():
            assert HandMeasurements.from_dict(m.as_dict()) == m


def test_a_hand_in_centimetres_warns(tmp_path, measured):
    # defect 8 (JSON): centimetre-sized numbers without a "units" key were read as mm
    import json

    d = measured.as_dict()
    del d["units"]
    d = {k: [x / 10 for x in v] if isinstance(v, list) else v / 10 for k, v in d.items()}
    path = tmp_path / "m.json"
    path.write_text(json.dumps(d))
    with pytest.warns(UserWarning, match=r"m.json: the hand measures 19\.\d+ mm from the wrist .* "
                                         r"are the values in millimetres\?"):
        HandMeasurements.from_file(path)


def _no_warning():
    import contextlib
    import warnings

    @contextlib.contextmanager
    def ctx():
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            yield

    return ctx()


def test_check_consistent_blames_a_value_the_reader_lets_through(measured):
    # 4 times: no hand of the supported range is that far off, but the reader
    # leaves such values to select_shape; the check names them on request
    values = {**measured.as_dict(), "P_width": 4 * measured.P_width}
    m = HandMeasurements.from_dict(values)
    with pytest.raises(InvalidShapeError, match=r"^the measurements give .*: P_width .* is 4 "
                                                r"times what the other values suggest"):
        m.check_consistent()
    measured.check_consistent()


@pytest.mark.parametrize(("key", "value", "shown"), [
    ("P_width", "82", "'82' (str)"),       # text that reads as a number was taken as one
    ("T_height", True, "True (bool)"),
    ("P_height", -3.0, "-3.0"),
    ("L", [10.0] * 13, "got 13"),
])
def test_a_json_value_that_is_no_length_is_refused_naming_the_file(tmp_path, measured, key,
                                                                   value, shown):
    values = {**measured.as_dict(), key: value}
    path = tmp_path / "hand.json"
    path.write_text(json.dumps(values))
    with pytest.raises(InvalidShapeError, match=rf"hand.json: {key} .*{re.escape(shown)}"):
        HandMeasurements.from_file(path)


@pytest.mark.parametrize(("field", "value"), [
    ("T_width", "12"), ("T_width", b"12"), ("T_width", False), ("T_width", float("nan")),
    ("W", [10.0] * 13 + ["x"]),
])
def test_measurements_built_in_code_take_numbers_only(measured, field, value):
    fields = {k: v for k, v in measured.as_dict().items() if k != "units"}
    with pytest.raises(InvalidShapeError, match=field):
        HandMeasurements(**{**fields, field: value})


@pytest.mark.parametrize(("index", "factor"), [(3, 10.0), (3, 0.1), (5, 6.0)])
def test_one_length_far_off_the_others_is_refused_though_the_ratios_stay_in_range(
        measured, index, factor):
    # found by trying: L4 ten times too long was taken (the length ratio 1.725, in range)
    lengths = list(measured.L)
    lengths[index] *= factor
    values = {**measured.as_dict(), "L": lengths}
    with pytest.raises(InvalidShapeError, match=rf"^hand.json: L{index + 1} [\d.]+ mm is [\d.]+ "
                                                r"times what the other values suggest"):
        HandMeasurements.from_dict(values, source="hand.json")


@pytest.mark.parametrize("ratios", [(0.5, 2.0, 0.5, 2.0), (2.0, 0.5, 2.0, 0.5), (2.0, 2.0, 0.5, 0.5)])
def test_hands_at_the_corners_of_the_supported_range_are_read(ratios):
    shape = HandShape(length=ratios[0], width=ratios[1], palm=ratios[2], thumb=ratios[3])
    values = model_measurements(shape).as_dict()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)  # some are far from a person's size
        got = HandMeasurements.from_dict(values)
    np.testing.assert_allclose(got.L, model_measurements(shape).L)


def test_formula_ratios_refuses_a_normalization_it_does_not_know():
    # "palm-width" (a hyphen) was read as "none" without a word
    from handsynth.models import NORMALIZATIONS, formula_ratios, model_measurements

    std = model_measurements()
    user = HandMeasurements(L=std.L, W=std.W, P_width=std.P_width * 1.1, P_height=std.P_height,
                            T_width=std.T_width, T_height=std.T_height)
    assert formula_ratios(user, std, normalize="palm_width") != formula_ratios(user, std,
                                                                               normalize="none")
    for bad in ("palm-width", "None", None, 1):
        with pytest.raises(InvalidShapeError, match=r"normalize must be one of \('palm_width', "
                                                    r"'none'\), got"):
            formula_ratios(user, std, normalize=bad)
    with pytest.raises(InvalidShapeError, match="user must be a HandMeasurements, got NoneType"):
        formula_ratios(None, std)
    with pytest.raises(InvalidShapeError, match="standard must be a HandMeasurements, got dict"):
        formula_ratios(user, std.as_dict())
    assert NORMALIZATIONS == ("palm_width", "none")


@pytest.mark.parametrize("points, y, words", [
    ([[0, 0], [1, 0], [1, 1]], 0.5, None),
    ("abc", 0.5, "must be an (M, 2) array of numbers"),
    ([], 0.5, "shape (M, 2) with M >= 3 points, got shape (0,)"),
    ([1, 2, 3], 0.5, "got shape (3,)"),
    ([[0, 0], [1, 0]], 0.5, "got shape (2, 2)"),
    ([[0, 0], [1, np.nan], [1, 1]], 0.5, "finite, got NaN or inf at row 1"),
    ([[0, 0], [1, 0], [1, 1]], np.inf, "y must be"),
    ([[0, 0], [1, 0], [1, 1]], "half", "y must be"),
])
def test_hull_width_at_checks_its_points(points, y, words):
    from handsynth.errors import InvalidInputError
    from handsynth.models import hull_width_at

    if words is None:
        assert hull_width_at(points, y) == pytest.approx(0.5)  # the list is taken as an array
        return
    with pytest.raises(InvalidInputError) as err:
        hull_width_at(points, y)
    assert words in str(err.value)
