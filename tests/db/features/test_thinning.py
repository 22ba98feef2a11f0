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


# --- The fast thinning gives exactly the reference's result -----------------


def thin_both(sil):
    """Ridge lines of `sil` by the fast `_thin_into` and by the reference."""
    from handsynth.db.features._thinning import _DC, _DR, _thin_into, _thin_into_reference

    sil = np.ascontiguousarray(sil, dtype=bool)
    results = []
    for thin in (_thin_into, _thin_into_reference):
        out = np.empty_like(sil)
        work = np.empty((sil.shape[0] + 2, sil.shape[1] + 2), np.int8)
        thin(sil, out, work, _DR, _DC)
        results.append(out)
    return results


def assert_same_as_reference(sil, msg=""):
    fast, reference = thin_both(sil)
    np.testing.assert_array_equal(fast, reference, err_msg=msg)


def special_images(h, w):
    """Lines, checkerboards, border pixels and isolated pixels on an (h, w) image."""
    yy, xx = np.mgrid[:h, :w]
    images = {
        "empty": np.zeros((h, w), bool),
        "full": np.ones((h, w), bool),
        "checkerboard": (yy + xx) % 2 == 0,
        "checkerboard_2x2": (yy // 2 + xx // 2) % 2 == 0,
        "stripes_1px": yy % 2 == 0,
        "stripes_2px": yy % 4 < 2,
        "columns_2px": xx % 3 < 2,
        "border_frame": (yy == 0) | (yy == h - 1) | (xx == 0) | (xx == w - 1),
        "border_frame_2px": (yy < 2) | (yy >= h - 2) | (xx < 2) | (xx >= w - 2),
        "corners": ((yy == 0) | (yy == h - 1)) & ((xx == 0) | (xx == w - 1)),
        "isolated": (yy % 3 == 1) & (xx % 4 == 2),
        "diagonal_1px": yy == xx,
        "diagonal_2px": (xx - yy >= 0) & (xx - yy < 2),
        "anti_diagonal_2px": (xx + yy >= w // 2) & (xx + yy < w // 2 + 2),
        "full_minus_centre": (yy != h // 2) | (xx != w // 2),
    }
    cross = np.zeros((h, w), bool)
    cross[h // 2 : h // 2 + 2, :] = True
    cross[:, w // 2 : w // 2 + 2] = True
    images["cross_2px"] = cross
    return images


@pytest.mark.parametrize(
    "h, w", [(64, 64), (1, 1), (1, 64), (64, 1), (2, 2), (3, 7), (17, 64), (64, 40), (40, 63), (5, 33)]
)
def test_fast_thinning_matches_reference_on_special_images(h, w):
    for name, sil in special_images(h, w).items():
        assert_same_as_reference(sil, f"{name} {h}x{w}")


@pytest.mark.parametrize("density", [0.05, 0.2, 0.4, 0.5, 0.6, 0.8, 0.95])
def test_fast_thinning_matches_reference_on_noise(density):
    rng = np.random.default_rng(int(density * 100))
    for h, w in [(64, 64)] * 20 + [(7, 64), (64, 9), (33, 50), (3, 3), (1, 20), (20, 1)]:
        sil = rng.random((h, w)) < density
        assert_same_as_reference(sil, f"{h}x{w}")


@pytest.mark.parametrize("sigma", [0.7, 1.5, 3.0, 6.0])
def test_fast_thinning_matches_reference_on_blobs(sigma):
    rng = np.random.default_rng(int(sigma * 10))
    for i in range(25):
        h, w = (64, 64) if i < 18 else tuple(int(n) for n in rng.integers(2, 65, 2))
        field = ndimage.gaussian_filter(rng.standard_normal((h, w)), sigma)
        sil = field > rng.uniform(-1.0, 1.0) * field.std()
        if i % 3 == 0:  # speckle: isolated pixels and pinholes
            sil ^= rng.random((h, w)) < 0.02
        assert_same_as_reference(sil, f"{i} {h}x{w}")


def test_fast_thinning_matches_reference_on_rectangles_and_lines():
    # Overlapping bars of width 1..6 and 1-px lines, many touching the border.
    rng = np.random.default_rng(7)
    for i in range(200):
        sil = np.zeros((64, 64), bool)
        for _ in range(rng.integers(1, 8)):
            r0, c0 = rng.integers(-4, 64, 2)
            height, width = rng.integers(1, 7), rng.integers(1, 64)
            if rng.random() < 0.5:
                height, width = width, height
            sil[max(r0, 0) : r0 + height, max(c0, 0) : c0 + width] = True
        assert_same_as_reference(sil, str(i))


def test_fast_thinning_matches_reference_on_test_shapes(shapes):
    for name, sil in shapes.items():
        assert_same_as_reference(sil, name)
        assert_same_as_reference(sil.T, name + " transposed")
        assert_same_as_reference(sil[::-1, ::-1], name + " rotated")
        np.testing.assert_array_equal(hilditch_thinning(sil), thin_both(sil)[1], err_msg=name)


@pytest.fixture(scope="module")
def hand_silhouettes():
    from handsynth.db import render_entries
    from handsynth.models import paper_pose_set

    return render_entries(paper_pose_set(24, seed=11), render_size=(180, 120))["silhouette"]


def test_fast_thinning_matches_reference_on_rendered_hands(hand_silhouettes):
    assert hand_silhouettes.sum(axis=(1, 2)).min() > 200
    for i, sil in enumerate(hand_silhouettes):
        assert_same_as_reference(sil, str(i))
        np.testing.assert_array_equal(hilditch_thinning(sil), thin_both(sil)[1], err_msg=str(i))


def test_wide_images_fall_back_to_the_reference():
    from handsynth.db.features._thinning import _thin

    rng = np.random.default_rng(3)
    field = ndimage.gaussian_filter(rng.standard_normal((40, 100)), 2.0)
    sil = field > 0
    np.testing.assert_array_equal(_thin(sil), thin_both(sil)[1])
    assert_same_as_reference(sil)
