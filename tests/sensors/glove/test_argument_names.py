"""The glove readers and records name an argument that is not what they take."""

from __future__ import annotations

import pytest

from handsynth.errors import InvalidInputError
from handsynth.sensors.glove import read_glove_csv


@pytest.mark.parametrize("path, got", [(None, "None"), (3, "int 3"), ("  ", None)])
def test_read_glove_csv_names_a_path_that_is_not_one(path, got):
    # before: TypeError from pathlib (None, 3); a blank name read as the current folder
    match = (r"^path must be a file name \(str or path\), got " + got + "$" if got
             else r"^path must name a file, got '  '$")
    with pytest.raises(InvalidInputError, match=match):
        read_glove_csv(path)


def test_readings_that_are_not_an_array_of_numbers_are_named():
    # GloveRecording(sensors="abc") was numpy's "could not convert string to float";
    # check_sensors of one row an AxisError
    import numpy as np

    from handsynth.errors import RecordingError
    from handsynth.sensors.glove import GloveRecording, check_sensors

    with pytest.raises(RecordingError, match=r"sensors must be an \(N, 5\) array of readings, got str"):
        GloveRecording(sensors="abc")
    with pytest.raises(RecordingError, match=r"angles must be an \(2, 20\) array of angles, got str"):
        GloveRecording(sensors=np.zeros((2, 5)), angles="x")
    with pytest.raises(RecordingError, match=r"^wear.csv: sensors must be readings of shape \(N, 5\), "
                                             r"got shape \(5,\)$"):
        check_sensors(np.zeros(5), adc_max=4095, where="wear.csv")
