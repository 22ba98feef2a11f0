import json

import numpy as np
import pytest

from handsynth.errors import RecordingError
from handsynth.sensors.imu import (
    ImuCalibration,
    ThumbCmcModel,
    segments_from_seconds,
    truth_chain_model,
)


def test_save_load_round_trip(tmp_path, ideal_rec):
    model = truth_chain_model(ideal_rec)
    cal = ImuCalibration(model, {s: np.eye(3) for s in model.own}, np.arange(20.0),
                         tuple(model.own))
    back = ImuCalibration.load(cal.save(tmp_path / "c.json"))
    assert back.sensors == cal.sensors and np.array_equal(back.zero, cal.zero)
    for k, v in cal.model.links.items():
        assert np.allclose(back.model.links[k], v)
    assert back.cmc is None  # a calibration without the thumb CMC axes (version 1 files)
    with_cmc = ImuCalibration(model, cal.frames, cal.zero, cal.sensors,
                              ThumbCmcModel(np.eye(3)[:2], np.eye(3)))
    again = ImuCalibration.load(with_cmc.save(tmp_path / "d.json"))
    assert np.array_equal(again.cmc.axes, np.eye(3)[:2]) and np.array_equal(again.cmc.rest,
                                                                            np.eye(3))


def test_bad_calibration_files(tmp_path):
    p = tmp_path / "c.json"
    p.write_text("{not json")
    with pytest.raises(RecordingError, match="not a calibration JSON file"):
        ImuCalibration.load(p)
    p.write_text(json.dumps({"format": "handsynth-imu-calibration", "sensors": []}))
    with pytest.raises(RecordingError, match="missing field\\(s\\) own_m"):
        ImuCalibration.load(p)


def test_track_needs_the_calibrated_sensors(ideal_rec):
    model = truth_chain_model(ideal_rec)
    cal = ImuCalibration(model, {}, np.zeros(20), tuple(model.own))
    with pytest.raises(RecordingError, match="lacks sensor\\(s\\) forearm_3, hand_radial"):
        cal.track(ideal_rec.subset(("index_distal",)))


def test_segments_from_seconds():
    assert segments_from_seconds({"static": [0, 2]}, 100.0, 500) == (("static", 0, 200),)
    with pytest.raises(RecordingError, match="must be \\[start_s, end_s\\]"):
        segments_from_seconds({"static": 3}, 100.0, 500)
