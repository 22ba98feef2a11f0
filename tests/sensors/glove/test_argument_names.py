"""read_glove_csv names an argument that is not a file name."""

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
