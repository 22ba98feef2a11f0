"""The trackers' readers name themselves and their arguments, not the reader they forward to."""

from __future__ import annotations

import pytest

from handsynth.errors import InvalidInputError
from handsynth.sensors.trackers import read_recording


def test_read_recording_names_an_unknown_option_as_its_own(tmp_path):
    # before: "read_polhemus() got an unexpected keyword argument 'bogus'" (a TypeError)
    with pytest.raises(InvalidInputError, match=r"^read_recording\(\) got unknown options \['bogus'\]; "
                                                r"the options of a text export are columns, units"):
        read_recording(tmp_path / "take.txt", bogus=1)


def test_read_recording_names_a_path_that_is_not_one():
    # before: TypeError from pathlib
    with pytest.raises(InvalidInputError, match=r"^path must be a file name \(str or path\), got None$"):
        read_recording(None)


def test_load_recording_names_a_path_that_is_not_one():
    from handsynth.errors import RecordingError
    from handsynth.sensors.trackers import load_recording

    with pytest.raises(RecordingError, match=r"^path must be a file name \(str or path\), got None$"):
        load_recording(None)
