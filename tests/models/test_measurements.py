"""Measurement files as people make them: Excel's BOM, other encodings, repeated rows (issue 16)."""

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
