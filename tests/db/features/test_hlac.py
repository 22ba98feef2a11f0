import itertools

import numpy as np
import pytest

from handsynth.db import HLAC_PATTERNS, HLAC_SIZE, contour, hlac
from handsynth.db.features._hlac import _hlac_reference, hlac_from_contour
from handsynth.errors import InvalidInputError

NEIGHBOURS = [(dr, dc) for dr in (-1, 0, 1) for dc in (-1, 0, 1) if (dr, dc) != (0, 0)]


def canonical(points):
    """Translation class of a pixel set: shift so the min row and min col are 0."""
    r0 = min(p[0] for p in points)
    c0 = min(p[1] for p in points)
    return frozenset((r - r0, c - c0) for r, c in points)


def test_patterns_are_the_translation_classes_of_centre_plus_two_neighbours():
    classes = set()
    for size in range(3):
        for subset in itertools.combinations(NEIGHBOURS, size):
            classes.add(canonical({(0, 0), *subset}))
    assert len(classes) == 25

    spec = [canonical({(0, 0), *offsets}) for offsets in HLAC_PATTERNS]
    assert len(HLAC_PATTERNS) == 25
    assert len(set(spec)) == 25, "two SPEC patterns fall in the same class"
    assert set(spec) == classes
    for offsets in HLAC_PATTERNS:
        assert all(o in NEIGHBOURS for o in offsets)
        assert len(set(offsets)) == len(offsets)


def test_order_counts_match_spec():
    orders = [len(p) for p in HLAC_PATTERNS]
    assert orders == [0] + [1] * 4 + [2] * 20
    assert HLAC_SIZE == 1600


def _index(block_row, block_col, pattern):
    return (block_row * 8 + block_col) * 25 + pattern


def test_single_pixel_counts_only_order_zero_of_its_block():
    img = np.zeros((64, 64), bool)
    img[13, 42] = True  # block (1, 5)
    h = hlac_from_contour(img)
    expected = np.zeros(1600, np.uint8)
    expected[_index(1, 5, 0)] = 1
    np.testing.assert_array_equal(h, expected)


def test_block_border_reference_pixel_owns_the_count():
    # Horizontal pair straddling the border of blocks (0, 0) and (0, 1):
    # the (0, 1) mask is counted at the left pixel, i.e. in block (0, 0).
    img = np.zeros((64, 64), bool)
    img[7, 7] = img[7, 8] = True
    h = hlac_from_contour(img)
    expected = np.zeros(1600, np.uint8)
    expected[_index(0, 0, 0)] = 1
    expected[_index(0, 1, 0)] = 1
    expected[_index(0, 0, HLAC_PATTERNS.index(((0, 1),)))] = 1
    # the right pixel sees its left neighbour: mask ((0, -1),) is not one of
    # the 25 (it is the same class as (0, 1)), so nothing else is counted.
    np.testing.assert_array_equal(h, expected)


def test_image_border_is_zero():
    img = np.zeros((64, 64), bool)
    img[0, :] = True  # top row: no pixel above, so no upward masks
    h = hlac_from_contour(img).reshape(8, 8, 25)
    up = [k for k, p in enumerate(HLAC_PATTERNS) if any(dr == -1 for dr, _ in p)]
    assert h[..., up].sum() == 0
    assert h[0, :, 0].tolist() == [8] * 8
    assert h[0, :, HLAC_PATTERNS.index(((0, 1),))].tolist() == [8] * 7 + [7]


@pytest.mark.parametrize("density", [0.05, 0.3, 0.7, 1.0])
def test_compiled_matches_reference_on_random_images(density):
    rng = np.random.default_rng(int(density * 100))
    for _ in range(20):
        img = rng.random((64, 64)) < density
        np.testing.assert_array_equal(hlac_from_contour(img), _hlac_reference(img))


def test_compiled_matches_reference_on_shapes(shapes):
    for name, sil in shapes.items():
        got = hlac(sil)
        np.testing.assert_array_equal(got, _hlac_reference(contour(sil)), err_msg=name)


def test_full_image_counts():
    # All-ones contour image: every pixel counts every mask whose offsets are
    # inside the image, so block (3, 3) (interior) has 64 of each mask.
    h = hlac_from_contour(np.ones((64, 64), bool)).reshape(8, 8, 25)
    assert (h[3, 3] == 64).all()
    assert h.dtype == np.uint8


def test_hlac_of_silhouette_uses_contour():
    sil = np.zeros((64, 64), bool)
    sil[16:32, 16:32] = True
    h = hlac(sil).reshape(8, 8, 25)
    # the 16x16 square has a 60-pixel contour; its interior blocks count nothing
    assert h[..., 0].sum() == 60
    assert h[..., 0].tolist()[2] == [0, 0, 15, 15, 0, 0, 0, 0]


def test_hlac_rejects_bad_input():
    with pytest.raises(InvalidInputError, match=r"silhouette.*\(32, 32\)"):
        hlac(np.zeros((32, 32), bool))
