import numpy as np
import pytest
from scipy import ndimage

from handsynth.db import contour
from handsynth.errors import InvalidInputError


def test_contour_matches_erosion_definition(shapes):
    cross = ndimage.generate_binary_structure(2, 1)
    for name, sil in shapes.items():
        expected = sil & ~ndimage.binary_erosion(sil, cross, border_value=0)
        np.testing.assert_array_equal(contour(sil), expected, err_msg=name)


def test_contour_of_square_and_border():
    sil = np.zeros((64, 64), bool)
    sil[10:15, 20:30] = True
    c = contour(sil)
    assert c.sum() == 2 * 10 + 2 * 3
    assert not c[11:14, 21:29].any()
    full = contour(np.ones((64, 64), bool))
    assert full.sum() == 4 * 63 and full[0].all() and not full[1:-1, 1:-1].any()


def test_contour_rejects_values_other_than_0_1():
    bad = np.zeros((64, 64))
    bad[3, 4] = 0.5
    with pytest.raises(InvalidInputError, match=r"silhouette.*0\.5.*\(3, 4\)"):
        contour(bad)
