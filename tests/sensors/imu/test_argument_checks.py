"""Arguments of the IMU API refused by name and value: motions, placement, CSV reading, static start."""

from __future__ import annotations

import re

import numpy as np
import pytest

from handsynth.errors import InvalidInputError, RecordingError
from handsynth.models import named_pose
from handsynth.sensors.imu import (
    MAX_MOTION_S,
    MODEL_JOINTS,
    ImuPlacement,
    ImuRecording,
    StaticStart,
    azimuth_correction,
    calibration_motion,
    check_static_fits,
    gyro_bias,
    initial_attitude,
    read_imu_csv,
    static_motion,
)

_SHAPES = "(29,) (MODEL_JOINTS) or (20,) (canonical hand angles, deg)"


# static_motion ------------------------------------------------------------------------------

def test_static_motion_takes_the_20_canonical_angles():
    # before: "could not broadcast input array from shape (20,) into shape (200,29)"
    fist = named_pose("fist")
    m = static_motion(2.0, pose=fist)
    assert m.q.shape == (200, len(MODEL_JOINTS))
    assert np.array_equal(m.q[:, len(MODEL_JOINTS) - 20:], np.broadcast_to(fist, (200, 20)))
    assert not m.q[:, :len(MODEL_JOINTS) - 20].any()
    full = np.arange(len(MODEL_JOINTS), dtype=float)
    assert np.array_equal(static_motion(0.5, pose=full).q[0], full)  # 29 positions unchanged


@pytest.mark.parametrize("pose, named", [
    # before: "could not convert string to float: 'fist'"
    ("fist", f"pose must be an array of shape {_SHAPES}, got str 'fist' "
             "(a named pose: handsynth.models.named_pose(name))"),
    (np.zeros(7), f"pose must be an array of shape {_SHAPES}, got shape (7,)"),
    ([np.nan] * 20, "pose must be finite, got"),
    ({"a": 1}, f"pose must be an array of shape {_SHAPES} of numbers, got dict"),
])
def test_static_motion_refuses_a_pose_that_is_not_joint_positions(pose, named):
    with pytest.raises(InvalidInputError, match=f"^{re.escape(named)}"):
        static_motion(1.0, pose=pose)


def test_calibration_motion_checks_its_rest_pose_alike():
    with pytest.raises(InvalidInputError, match=r"^rest_pose must be an array of shape"):
        calibration_motion(rest_pose="open")


@pytest.mark.parametrize("duration", [1e9, MAX_MOTION_S + 1, float("nan"), -1.0, "2"])
def test_static_motion_bounds_the_duration(duration):
    # before: 1e9 gave a raw MemoryError
    with pytest.raises(InvalidInputError, match=r"^duration_s must be a finite number > 0 and <= 3600, got"):
        static_motion(duration)


def test_static_motion_refuses_a_rate_that_is_not_a_number():
    with pytest.raises(InvalidInputError, match=r"^rate_hz must be a finite number >= 10 and <= 1000, got"):
        static_motion(1.0, rate_hz="100")


# ImuPlacement -------------------------------------------------------------------------------

@pytest.mark.parametrize("kwargs, named", [
    # before: TypeError "'<=' not supported between instances of 'float' and 'str'"
    ({"height_mm": "4"}, "ImuPlacement.height_mm must be a finite number >= 0 and < 50, got '4' (str)"),
    ({"height_mm": float("nan")}, "ImuPlacement.height_mm must be a finite number >= 0 and < 50, got nan"),
    ({"along": None}, "ImuPlacement.along must be a finite number > 0 and < 1, got None (NoneType)"),
    ({"along": 1.5}, "ImuPlacement.along must be a finite number > 0 and < 1, got 1.5"),
    ({"forearm_length_mm": "250"},
     "ImuPlacement.forearm_length_mm must be a finite number >= 100 and <= 400, got '250' (str)"),
    # before: "Value after * must be an iterable, not int"
    ({"offsets_mm": 3}, "ImuPlacement.offsets_mm must be a Mapping, got int 3"),
    ({"tilts_deg": 2.0}, "ImuPlacement.tilts_deg must be a Mapping, got float 2.0"),
    ({"tilts_deg": {"index_distal": 30}},
     "ImuPlacement.tilts_deg['index_distal'] must be 3 finite numbers (x, y, z), got int 30"),
    ({"offsets_mm": {"index_distal": (1, 2)}},
     "ImuPlacement.offsets_mm['index_distal'] must be 3 finite numbers (x, y, z), got tuple (1, 2)"),
    ({"offsets_mm": {"index_distal": "123"}},
     "ImuPlacement.offsets_mm['index_distal'] must be 3 finite numbers (x, y, z), got str '123'"),
])
def test_placement_checks_every_field_by_type_and_range(kwargs, named):
    with pytest.raises(InvalidInputError, match=f"^{re.escape(named)}"):
        ImuPlacement(**kwargs)


def test_placement_keeps_valid_fields():
    p = ImuPlacement(height_mm=0, along=0.25, forearm_length_mm=400,
                     tilts_deg={"index_distal": np.array([1.0, 0.0, 0.0])},
                     offsets_mm={"forearm_1": (0, 0, 1)})
    assert p.height_mm == 0 and p.tilts_deg["index_distal"][0] == 1.0


# read_imu_csv -------------------------------------------------------------------------------

def test_read_imu_csv_names_a_path_that_is_not_one():
    # before: TypeError from pathlib
    with pytest.raises(InvalidInputError, match=r"^path must be a file name \(str or path\), got None$"):
        read_imu_csv(None)


@pytest.mark.parametrize("gap", [float("nan"), 0.0, "2"])
def test_read_imu_csv_refuses_a_max_gap_that_is_not_a_positive_number(tmp_path, gap):
    # before: NaN turned the gap check off
    with pytest.raises(InvalidInputError, match=r"^max_gap must be a finite number > 0, got"):
        read_imu_csv(tmp_path / "rec.csv", max_gap=gap)


# static start -------------------------------------------------------------------------------

def _still(seconds: float, rate: float = 100.0) -> ImuRecording:
    n = int(round(seconds * rate))
    acc = np.tile([0.0, 0.0, 9.81], (2, n, 1))
    mag = np.tile([20.0, 0.0, -40.0], (2, n, 1))
    return ImuRecording(rate, ("forearm_1", "index_distal"), acc, np.zeros((2, n, 3)), mag)


def test_a_static_start_longer_than_the_recording_is_refused():
    # before: gyro_bias accepted StaticStart(static_s=100) on 3 s
    rec = _still(3.0)
    static = StaticStart(static_s=100.0)
    for fn in (gyro_bias, azimuth_correction, initial_attitude):
        with pytest.raises(RecordingError, match=r"the static start static_s=100 s is longer than the "
                                                 r"recording \(300 samples, 3 s\)"):
            fn(rec, static)
    assert gyro_bias(rec, StaticStart(static_s=3.0, align_start_s=None)).shape == (2, 3)


def test_check_static_fits_allows_half_a_sample():
    rec = _still(2.0)
    check_static_fits(rec, 2.004)
    with pytest.raises(RecordingError, match=r"^rec\.csv: the static start static_s=2\.01 s"):
        check_static_fits(rec, 2.01, source="rec.csv")
