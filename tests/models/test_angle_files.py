"""Joint-angle files as the commands write them, read back and put at a constant frame rate."""

from __future__ import annotations

import json

import numpy as np
import pytest

from handsynth.errors import RecordingError
from handsynth.live import open_row_writer
from handsynth.models import JOINT_NAMES, read_angle_table


def _csv(path, header, rows) -> None:
    path.write_text("\n".join([",".join(header), *(",".join(str(v) for v in r) for r in rows)])
                    + "\n")


def _ramp(n: int) -> np.ndarray:
    return np.arange(n)[:, None] * 0.5 + np.arange(len(JOINT_NAMES))[None, :]


def test_time_s_table_kept_as_it_is(tmp_path):
    path = tmp_path / "angles.csv"
    t = np.arange(50) / 100.0
    _csv(path, ["time_s", *JOINT_NAMES], [[f"{ti:.6f}", *a] for ti, a in zip(t, _ramp(50))])
    table = read_angle_table(path)
    assert table.lines[0] == 2 and table.lines[-1] == 51
    values, rate = table.resampled()
    assert rate == 100.0
    np.testing.assert_allclose(values, _ramp(50), atol=1e-9)


def test_uneven_times_are_resampled_on_the_line_between_rows(tmp_path):
    path = tmp_path / "angles.csv"
    t = np.cumsum(np.random.default_rng(0).uniform(0.02, 0.05, 40))
    angles = 10.0 + 30.0 * t[:, None] * np.ones(len(JOINT_NAMES))   # linear in time
    _csv(path, ["time_s", *JOINT_NAMES], [[ti, *a] for ti, a in zip(t, angles)])
    values, rate = read_angle_table(path).resampled(50.0)
    assert rate == 50.0
    assert len(values) == int(np.floor((t[-1] - t[0]) * 50 + 1e-6)) + 1
    expected = 10.0 + 30.0 * (t[0] + np.arange(len(values)) / 50.0)
    np.testing.assert_allclose(values, expected[:, None] * np.ones(len(JOINT_NAMES)), atol=1e-9)


def test_live_rows_without_a_hand_take_their_neighbours_angles(tmp_path):
    """``estimate --out`` rows: a frame with no hand has empty angles."""
    rows = []
    for i in range(6):
        hand = i not in (0, 3)
        row = {"frame": i, "timestamp_s": round(i / 30.0, 6), "no_hand": not hand,
               "confidence": 1.0, "low_confidence": False, "moved": False, "entry": 0}
        row.update((n, float(i) if hand else None) for n in JOINT_NAMES)
        rows.append(row)
    for suffix in ("csv", "jsonl"):
        path = tmp_path / f"live.{suffix}"
        with open_row_writer(path) as writer:
            for row in rows:
                writer.write(row)
        table = read_angle_table(path)
        assert np.isnan(table.angles_deg[[0, 3]]).all()
        with pytest.warns(UserWarning, match=r"2 of 6 rows have no angles \(first at line "
                                             rf"{table.lines[0]}\)"):
            values, rate = table.resampled()
        assert rate == 30.0
        np.testing.assert_allclose(values[:, 0], [1.0, 1.0, 2.0, 3.0, 4.0, 5.0], atol=1e-3)


def test_a_table_without_times_needs_the_rate(tmp_path):
    path = tmp_path / "glove.csv"
    _csv(path, ["sample", *JOINT_NAMES], [[i, *a] for i, a in enumerate(_ramp(5))])
    table = read_angle_table(path)
    assert table.times_s is None
    with pytest.raises(RecordingError, match="no time column .*give the frame rate"):
        table.resampled()
    values, rate = table.resampled(60.0)
    assert rate == 60.0
    np.testing.assert_array_equal(values, _ramp(5))


@pytest.mark.parametrize(("header", "cells", "match"), [
    (["time_s", *JOINT_NAMES[:-2]], None, "no column little_pip_flex, little_dip_flex"),
    (["time_s", *JOINT_NAMES], {4: "x"}, r"line 3, index_mcp_flex: 'x' is not a number"),
    (["time_s", *JOINT_NAMES], {4: "1e9"}, "not an angle in degrees"),
    (["time_s", *JOINT_NAMES], {4: "inf"}, "not an angle"),
    (["time_s", *JOINT_NAMES], {"time": "0.0"}, r"line 3: time_s 0 does not come after"),
])
def test_refuses_cells_by_line_and_column(tmp_path, header, cells, match):
    path = tmp_path / "bad.csv"
    rows = [[i / 10, *a] for i, a in enumerate(_ramp(3))]
    for key, value in (cells or {}).items():
        if key == "time":
            rows[1][0] = value
        else:
            rows[1][1 + key] = value
    _csv(path, header, [r[:len(header)] for r in rows])
    with pytest.raises(RecordingError, match=match):
        read_angle_table(path)


def test_refuses_files_that_hold_no_angles(tmp_path):
    with pytest.raises(RecordingError, match="no such file"):
        read_angle_table(tmp_path / "none.csv")
    empty = tmp_path / "empty.csv"
    empty.write_text("")
    with pytest.raises(RecordingError, match="no rows"):
        read_angle_table(empty)
    header_only = tmp_path / "header.csv"
    _csv(header_only, ["time_s", *JOINT_NAMES], [])
    with pytest.raises(RecordingError, match="a header and no rows"):
        read_angle_table(header_only)
    lines = tmp_path / "bad.jsonl"
    lines.write_text(json.dumps(dict.fromkeys(JOINT_NAMES, 0)) + "\n[1, 2]\n")
    with pytest.raises(RecordingError, match="line 2: a JSON list"):
        read_angle_table(lines)
    lines.write_text("{not json\n")
    with pytest.raises(RecordingError, match="line 1: not JSON"):
        read_angle_table(lines)
    no_hand = tmp_path / "nohand.csv"
    _csv(no_hand, ["time_s", *JOINT_NAMES], [[0.0, *[""] * 20], [0.1, *[""] * 20]])
    with pytest.raises(RecordingError, match="no row has all 20 joint angles"):
        read_angle_table(no_hand).resampled()
