import numpy as np
import pytest
from scipy import ndimage

from handsynth.db import hilditch_thinning
from handsynth.errors import InvalidInputError

EIGHT = np.ones((3, 3), bool)


def n_components(mask):
    return ndimage.label(mask, EIGHT)[1]


def n_holes(mask):
    """4-connected background components that do not touch the image border."""
    background = np.pad(~mask, 1, constant_values=True)
    return ndimage.label(background)[1] - 1


def blocks_2x2(mask):
    return mask[:-1, :-1] & mask[1:, :-1] & mask[:-1, 1:] & mask[1:, 1:]


def crossing_number(mask, r, c):
    p = np.pad(mask, 1)
    ring = [
        p[r + 1 + dr, c + 1 + dc]
        for dr, dc in ((0, 1), (-1, 1), (-1, 0), (-1, -1), (0, -1), (1, -1), (1, 0), (1, 1))
    ]
    b = [1 - int(v) for v in ring]
    return sum(b[k] * (1 - b[(k + 1) % 8] * b[(k + 2) % 8]) for k in (0, 2, 4, 6))


def test_shapes_thin_to_one_pixel_wide_subset_with_same_topology(shapes):
    for name, sil in shapes.items():
        ridge = hilditch_thinning(sil)
        assert ridge.dtype == bool and ridge.shape == (64, 64)
        assert not (ridge & ~sil).any(), name
        assert not blocks_2x2(ridge).any(), name
        assert n_components(ridge) == n_components(sil), name
        assert n_holes(ridge) == n_holes(sil), name
        if sil.sum() > 200:
            assert ridge.sum() < sil.sum() / 4, name


def test_thinning_is_idempotent(shapes):
    for name, sil in shapes.items():
        ridge = hilditch_thinning(sil)
        np.testing.assert_array_equal(hilditch_thinning(ridge), ridge, err_msg=name)


def test_topology_kept_on_noise_and_2x2_blocks_only_at_junctions():
    # Salt-and-pepper images are the hardest case for a sequential thinning.
    # Topology must survive; a 2x2 block may remain only where each of its
    # pixels is a junction (crossing number >= 2) or has no background
    # 4-neighbour, i.e. where Hilditch's conditions forbid any deletion.
    for seed in range(30):
        rng = np.random.default_rng(seed)
        sil = rng.random((64, 64)) < rng.uniform(0.3, 0.9)
        ridge = hilditch_thinning(sil)
        assert not (ridge & ~sil).any()
        assert n_components(ridge) == n_components(sil), seed
        assert n_holes(ridge) == n_holes(sil), seed
        padded = np.pad(ridge, 1)
        for r, c in np.argwhere(blocks_2x2(ridge)):
            for rr, cc in ((r, c), (r + 1, c), (r, c + 1), (r + 1, c + 1)):
                interior = (
                    padded[rr, cc + 1]
                    and padded[rr + 2, cc + 1]
                    and padded[rr + 1, cc]
                    and padded[rr + 1, cc + 2]
                )
                assert interior or crossing_number(ridge, rr, cc) >= 2


@pytest.mark.parametrize("width", [1, 3, 5, 7, 9])
@pytest.mark.parametrize("vertical", [False, True])
@pytest.mark.parametrize("row0, col0, col1", [(0, 0, 63), (5, 3, 40), (20, 10, 50), (40, 7, 20)])
def test_odd_bar_thins_to_centre_line(width, vertical, row0, col0, col1):
    # Exact result: the centre line of the bar, shortened by exactly the
    # half-width h = width // 2 at each end (Hilditch peels the ends too).
    h = width // 2
    bar = np.zeros((64, 64), bool)
    bar[row0 : row0 + width, col0 : col1 + 1] = True
    expected = np.zeros((64, 64), bool)
    expected[row0 + h, col0 + h : col1 - h + 1] = True
    if vertical:
        bar, expected = bar.T.copy(), expected.T.copy()
    np.testing.assert_array_equal(hilditch_thinning(bar), expected)


@pytest.mark.parametrize(
    "points",
    [
        [(30, c) for c in range(5, 60)],  # horizontal line
        [(r, 12) for r in range(2, 62)],  # vertical line
        [(10 + i, 10 + i) for i in range(40)],  # diagonal
        [(10, c) for c in range(10, 39)] + [(r, 39) for r in range(11, 50)],  # L, 8-connected
        [(32, c) for c in range(10, 54)] + [(r, 32) for r in range(10, 54) if r != 32],  # +
    ],
    ids=["horizontal", "vertical", "diagonal", "L", "plus"],
)
def test_one_pixel_lines_are_kept_with_their_end_points(points):
    line = np.zeros((64, 64), bool)
    for p in points:
        line[p] = True
    np.testing.assert_array_equal(hilditch_thinning(line), line)


def test_redundant_corner_of_a_4_connected_l_is_removed():
    # With 8-connected foreground the corner pixel of a 4-connected L is
    # simple (crossing number 1, two neighbours): Hilditch deletes it.
    line = np.zeros((64, 64), bool)
    line[10, 10:40] = True
    line[10:50, 39] = True
    expected = line.copy()
    expected[10, 39] = False
    np.testing.assert_array_equal(hilditch_thinning(line), expected)


def test_end_points_of_a_thick_t_survive():
    sil = np.zeros((64, 64), bool)
    sil[10:15, 5:60] = True  # bar, rows 10-14
    sil[10:58, 30:35] = True  # stem, cols 30-34
    ridge = hilditch_thinning(sil)
    rows, cols = np.nonzero(ridge)
    # extremities within the half-width (2) of the shape's own extremities
    assert cols.min() == 5 + 2 and cols.max() == 59 - 2
    assert rows.max() == 57 - 2
    assert ridge[12, 7] and ridge[12, 57] and ridge[55, 32]


def test_empty_and_full():
    assert not hilditch_thinning(np.zeros((64, 64), bool)).any()
    assert hilditch_thinning(np.ones((64, 64), bool)).sum() == 1


def test_rejects_wrong_shape():
    with pytest.raises(InvalidInputError, match=r"silhouette.*\(64, 64, 3\)"):
        hilditch_thinning(np.zeros((64, 64, 3), bool))
