import dataclasses

import numpy as np
import pytest

from handsynth.errors import RecordingError
from handsynth.sensors.imu import (
    EVAL_NOISE,
    check_recording,
    free_motion,
    read_imu_csv,
    simulate_imu,
    write_imu_csv,
)


def _with(rec, **arrays):
    return dataclasses.replace(rec, truth=None, **arrays)


def test_clean_recording_passes(free_rec):
    assert check_recording(free_rec) == []


def test_nan_is_named(free_rec):
    gyr = free_rec.gyr.copy()
    gyr[4, 321, 1] = np.nan
    with pytest.raises(RecordingError, match=r"sensor 'little_proximal' gyr axis y .* sample 321"):
        check_recording(_with(free_rec, gyr=gyr))


def test_saturation_is_named(free_rec):
    acc = free_rec.acc.copy()
    acc[7, 500:520, 2] = 16 * 9.80665
    with pytest.raises(RecordingError, match=r"'ring_proximal' acc axis z is saturated .* 20 samples"):
        check_recording(_with(free_rec, acc=acc))


def test_wrong_units_are_caught(free_rec):
    start = free_rec.slice(0, 150)
    with pytest.raises(RecordingError, match="deg/s given as rad/s"):
        check_recording(_with(start, gyr=np.degrees(start.gyr) + 1.0))
    with pytest.raises(RecordingError, match="given in g"):
        check_recording(_with(free_rec, acc=free_rec.acc / 9.80665))


def test_magnetic_disturbance_is_reported(imu_hand):
    rec = simulate_imu(free_motion(20.0, seed=1), hand=imu_hand,
                       noise=dataclasses.replace(EVAL_NOISE), seed=1)
    warnings = check_recording(rec)
    assert warnings and "magnetic disturbance" in warnings[0]
    assert "t=14" in warnings[0] or "t=13" in warnings[0]


def test_csv_round_trip_and_units(tmp_path, free_rec):
    p = tmp_path / "rec.csv"
    small = free_rec.subset(("forearm_1", "index_distal")).slice(0, 300)
    write_imu_csv(small, p)
    back = read_imu_csv(p)
    assert back.sensors == ("forearm_1", "index_distal")
    assert back.rate_hz == pytest.approx(100.0)
    assert np.allclose(back.gyr, small.gyr, atol=1e-8)
    # the same file read as deg/s gives values 57x too small
    slow = read_imu_csv(p, gyr_units="deg/s")
    assert np.allclose(slow.gyr * 180 / np.pi, small.gyr, atol=1e-6)


def test_csv_as_a_spreadsheet_writes_it(tmp_path, free_rec):
    """The same recording saved by a spreadsheet in a decimal-comma locale (';'
    between the fields, quoted names, a byte-order mark, CRLF) reads the same."""
    p = tmp_path / "rec.csv"
    small = free_rec.subset(("forearm_1",)).slice(0, 100)
    write_imu_csv(small, p)
    lines = [ln for ln in p.read_text().splitlines() if not ln.startswith("#")]
    out = [";".join(f'"{c}"' for c in lines[0].split(","))]
    out += [";".join(c.replace(".", ",") for c in ln.split(",")) for ln in lines[1:]]
    sheet = tmp_path / "sheet.csv"
    sheet.write_bytes(("\ufeff" + "\r\n".join(out) + "\r\n").encode("utf-8"))
    back = read_imu_csv(sheet)
    assert back.sensors == ("forearm_1",) and back.rate_hz == pytest.approx(100.0)
    assert np.allclose(back.acc, small.acc, rtol=1e-8) and np.allclose(back.gyr, small.gyr, atol=1e-8)


def test_csv_gap_and_bad_cells(tmp_path, free_rec):
    p = tmp_path / "rec.csv"
    write_imu_csv(free_rec.subset(("forearm_1",)).slice(0, 50), p)
    lines = p.read_text().splitlines()
    gapped = tmp_path / "gap.csv"
    gapped.write_text("\n".join(lines[:20] + lines[25:]) + "\n")
    with pytest.raises(RecordingError, match="gap.*missing samples"):
        read_imu_csv(gapped)
    bad = tmp_path / "bad.csv"
    bad.write_text("\n".join(lines[:5] + [lines[5].replace(",", ",x", 1)] + lines[6:]) + "\n")
    with pytest.raises(RecordingError, match=r"bad.csv, line 6: forearm_1_acc_x is 'x.*not a number"):
        read_imu_csv(bad)
    with pytest.raises(RecordingError, match="unknown gyr units 'rpm'"):
        read_imu_csv(p, gyr_units="rpm")
    with pytest.raises(RecordingError, match="no such file"):
        read_imu_csv(tmp_path / "missing.csv")


def test_a_recording_is_written_whole_or_not_at_all(tmp_path, free_rec, full_disk):
    # issue 16: every output goes through the atomic writer (a missing folder or a full
    # disk is one clear error; nothing half-written is left)
    from handsynth.errors import OutputError

    small = free_rec.subset(("forearm_1",)).slice(0, 50)
    with pytest.raises(OutputError, match=r"folder .*nowhere' does not exist"):
        write_imu_csv(small, tmp_path / "nowhere" / "r.csv")
    (full_disk / "filler").write_bytes(b"\0" * (256 * 1024 - 2048))
    with pytest.raises(OutputError, match=r"no space left"):
        write_imu_csv(free_rec, full_disk / "r.csv")
    assert sorted(p.name for p in full_disk.iterdir()) == ["filler"]
