import re

import numpy as np
import pytest

from handsynth.errors import EstimationError, OutputError, RecordingError
from handsynth.sensors.glove import (
    GloveRecording,
    GloveWarning,
    RangeNormalizer,
    apply_calibration,
    don_glove,
    range_readings,
    save_calibration,
    simulate_range_holds,
    simulate_session,
    write_angles_csv,
    write_glove_csv,
)


@pytest.fixture(scope="module")
def cal_file(tmp_path_factory, user, dg5, estimators):
    d = tmp_path_factory.mktemp("apply")
    ref = range_readings(simulate_range_holds(user, dg5, seed=4))
    return save_calibration(d / "cal.json", estimators, kind="dg5", range_reference=ref)


@pytest.fixture(scope="module")
def wear(tmp_path_factory, user):
    """A new wearing: one trial of each motion, then its range holds."""
    don = don_glove(user, "dg5", seed=8)
    rec = simulate_session(user, don, ["tripod", "standard"], trials=1, seed=21)
    holds = simulate_range_holds(user, don, seed=22, start_s=rec.time_s[-1] + 1)
    path = tmp_path_factory.mktemp("wear") / "wear.csv"
    return write_glove_csv(path, GloveRecording.concatenate([rec, holds]), with_angles=False)


def test_apply_writes_what_the_estimator_gives(tmp_path, cal_file, wear, estimators):
    from handsynth.sensors.glove import read_glove_csv

    out = tmp_path / "a.csv"
    with pytest.warns(GloveWarning):  # a new wearing without --range: off the range
        got = apply_calibration(cal_file, wear, out, model="model1")
    rec = read_glove_csv(wear)
    with pytest.warns(GloveWarning):
        want = estimators["model1"].predict(rec.sensors)
    np.testing.assert_allclose(got, want)
    expected = write_angles_csv(tmp_path / "b.csv", want, time_s=rec.time_s)
    assert out.read_bytes() == expected.read_bytes()


def test_apply_with_range_holds_maps_the_readings_first(tmp_path, cal_file, wear, estimators):
    from handsynth.sensors.glove import load_calibration, read_glove_csv

    got = apply_calibration(cal_file, wear, tmp_path / "a.csv", range_csv=wear)
    rec = read_glove_csv(wear)
    src = range_readings(rec)
    tgt = load_calibration(cal_file)["range_reference"]
    want = estimators["model4"].predict(RangeNormalizer(*src, *tgt).apply(rec.sensors))
    np.testing.assert_allclose(got, want)
    assert got.shape == (rec.n_samples, 20)


def _edit(path, dst, fn):
    lines = path.read_text().splitlines()
    head = lines[0].split(",")
    cols = [head.index(c) for c in head if c.startswith("sensor_")]
    rows = []
    for ln in lines[1:]:
        cells = ln.split(",")
        for k in cols:
            cells[k] = fn(cells[k], cells)
        rows.append(",".join(cells))
    dst.write_text("\n".join([lines[0], *rows]) + "\n")
    return dst


def test_all_saturated_or_all_nan_readings_are_refused_and_nothing_written(tmp_path, cal_file,
                                                                           wear):
    sat = _edit(wear, tmp_path / "sat.csv", lambda c, r: "4095")
    out = tmp_path / "a.csv"
    with pytest.warns(GloveWarning), pytest.raises(
            RecordingError, match=r"sat.csv: every reading is saturated or out of the converter's "
                                  r"range.*sensor_thumb saturated \(at 4095 counts\) in \d+ of \d+ "
                                  r"rows; sensor_index"):
        apply_calibration(cal_file, sat, out)
    assert not out.exists()
    blank = _edit(wear, tmp_path / "blank.csv", lambda c, r: "")
    with pytest.warns(GloveWarning), pytest.raises(
            RecordingError, match=r"blank.csv: none of the \d+ rows has all five readings"):
        apply_calibration(cal_file, blank, out)
    assert not out.exists()


def test_range_hold_problems_name_the_range_file(tmp_path, cal_file, wear):
    flat = _edit(wear, tmp_path / "flat.csv", lambda c, r: "1500" if r[1].startswith("range")
                 else c)
    with pytest.raises(EstimationError, match=r"^.*flat.csv: range calibration: sensor_thumb "
                                              r"reads the same"):
        apply_calibration(cal_file, wear, tmp_path / "a.csv", range_csv=flat)
    sat = _edit(wear, tmp_path / "fist.csv", lambda c, r: "4095" if r[1] == "range_fist"
                else c)
    with pytest.raises(RecordingError, match=r"fist.csv: sensor_thumb is saturated \(at 4095 "
                                             r"counts\) in 30 of the 30 rows labelled range_fist"):
        apply_calibration(cal_file, wear, tmp_path / "a.csv", range_csv=sat)
    assert not (tmp_path / "a.csv").exists()


def test_the_output_is_checked_before_anything_is_read(tmp_path, wear):
    with pytest.raises(OutputError, match="never replaces an input"):
        apply_calibration(tmp_path / "missing.json", wear, wear)


def test_an_empty_file_name_is_refused_by_name(tmp_path, cal_file, wear):
    from handsynth.errors import InvalidInputError

    # --range "" read the current folder as a file: "cannot read glove CSV '.'"
    with pytest.raises(InvalidInputError, match="range_csv must name a file, got ''"):
        apply_calibration(cal_file, wear, tmp_path / "a.csv", range_csv="")


def _retimed(wear, path, rename, scale):
    """`wear` with its time column renamed (None: dropped) and its values times `scale`."""
    lines = wear.read_text().splitlines()
    header = lines[0].split(",")
    k = header.index("time_s")
    rows = [ln.split(",") for ln in lines[1:]]
    if rename is None:
        header.pop(k)
        [r.pop(k) for r in rows]
    else:
        header[k] = rename
        for r in rows:
            r[k] = f"{float(r[k]) * scale:.3f}"
    path.write_text("\n".join(",".join(r) for r in [header, *rows]) + "\n")
    return path


def test_readings_without_a_time_column_give_row_numbers_not_seconds(tmp_path, cal_file, wear):
    # the row index was written as time_s: 0, 1, 2 ... s for samples 1/60 s apart
    src = _retimed(wear, tmp_path / "untimed.csv", None, 1.0)
    out = tmp_path / "a.csv"
    with pytest.warns(GloveWarning):  # a new wearing without --range: off the calibration
        apply_calibration(cal_file, src, out, model="model1")
    lines = out.read_text().splitlines()
    assert lines[0].split(",")[0] == "sample"
    assert [ln.split(",")[0] for ln in lines[1:4]] == ["0", "1", "2"]


@pytest.mark.parametrize("name", ["time_ms", "Time (ms)", "timestamp [ms]"])
def test_a_time_column_in_milliseconds_is_read_as_seconds(tmp_path, cal_file, wear, name):
    # it was ignored: the angles' time_s was then the row index
    from handsynth.sensors.glove import read_glove_csv

    want = read_glove_csv(wear).time_s
    src = _retimed(wear, tmp_path / "ms.csv", name, 1000.0)
    with pytest.warns(GloveWarning, match=re.escape(f"ms.csv: column '{name}' read as "
                                                    "time_s (milliseconds / 1000)")):
        got = read_glove_csv(src)
    np.testing.assert_allclose(got.time_s, want, atol=1e-6)
    assert got.meta["time_column"]
