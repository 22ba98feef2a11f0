import numpy as np
import pytest

from handsynth import HandShape
from handsynth.errors import InvalidShapeError
from handsynth.models import KEYPOINT_SITES, HandModel


def test_grid_has_81_distinct_shapes():
    grid = HandShape.grid()
    assert len(grid) == 81 and len(set(grid)) == 81
    assert len({s.name for s in grid}) == 81
    assert HandShape() in grid and all(s.is_grid for s in grid)


def test_name_round_trip_and_nearest():
    s = HandShape(1.03, 0.92, 0.97, 1.08)
    assert HandShape.from_name(s.name) == s
    assert not s.is_grid
    assert s.nearest_grid() == HandShape(1.05, 0.9, 0.95, 1.1)


@pytest.mark.parametrize("field, value", [("length", 0), ("width", -1), ("palm", float("nan")),
                                          ("thumb", "big"), ("length", 5.0)])
def test_bad_ratio_names_the_field(field, value):
    with pytest.raises(InvalidShapeError, match=f"HandShape.{field}"):
        HandShape(**{field: value})


def _kp(shape):
    return dict(zip(KEYPOINT_SITES, HandModel(shape).keypoints() * 1000))


def _phalanges(k):
    segs = [("thumb_mcp", "thumb_ip"), ("thumb_ip", "thumb_tip")]
    for f in ("index", "middle", "ring", "little"):
        segs += [(f"{f}_mcp", f"{f}_pip"), (f"{f}_pip", f"{f}_dip"), (f"{f}_dip", f"{f}_tip")]
    return np.array([np.linalg.norm(k[a] - k[b]) for a, b in segs])


def test_length_ratio_scales_exactly_the_14_phalanges():
    std, big = _kp(HandShape()), _kp(HandShape(length=1.05))
    np.testing.assert_allclose(_phalanges(big) / _phalanges(std), 1.05, rtol=1e-6)
    assert len(_phalanges(std)) == 14
    # metacarpals and the palm stay put
    for f in ("index", "middle", "ring", "little"):
        np.testing.assert_allclose(big[f"{f}_mcp"], std[f"{f}_mcp"], atol=1e-9)
    np.testing.assert_allclose(big["thumb_mcp"], std["thumb_mcp"], atol=1e-9)


def test_palm_ratio_scales_horizontal_palm_width_only():
    std, wide = _kp(HandShape()), _kp(HandShape(palm=1.05))
    width = lambda k: k["little_mcp"][0] - k["index_mcp"][0]  # noqa: E731
    assert width(wide) / width(std) == pytest.approx(1.05, rel=1e-6)
    for f in ("index", "middle", "ring", "little"):
        assert wide[f"{f}_mcp"][1] == pytest.approx(std[f"{f}_mcp"][1])
    assert wide["thumb_cmc"][0] / std["thumb_cmc"][0] == pytest.approx(1.05)
    np.testing.assert_allclose(_phalanges(wide), _phalanges(std), rtol=1e-9)
    # the palm surface itself is wider across the hand, not longer
    e_std, e_wide = _extent(HandShape(), "palm"), _extent(HandShape(palm=1.05), "palm")
    assert e_wide[0] / e_std[0] == pytest.approx(1.05, rel=1e-6)
    assert e_wide[1:] == pytest.approx(e_std[1:], rel=1e-6)


def _extent(shape, geom):
    """Extent (x, y, z) in mm of a geom's mesh vertices in the hand frame of the built model."""
    h = HandModel(shape)
    m, d = h.model, h.data
    g = m.geom(geom).id
    mesh = m.geom_dataid[g]
    v = m.mesh_vert[m.mesh_vertadr[mesh]:m.mesh_vertadr[mesh] + m.mesh_vertnum[mesh]]
    world = d.geom_xpos[g] + v @ d.geom_xmat[g].reshape(3, 3).T
    return np.ptp(world, axis=0) * 1000


def test_thumb_ratio_scales_thumb_base_height():
    std, hi = _kp(HandShape()), _kp(HandShape(thumb=1.1))
    assert hi["thumb_cmc"][1] / std["thumb_cmc"][1] == pytest.approx(1.1, rel=1e-9)
    assert hi["thumb_cmc"][0] == pytest.approx(std["thumb_cmc"][0])
    np.testing.assert_allclose(hi["index_mcp"], std["index_mcp"])


def test_width_ratio_changes_finger_thickness_only():
    std, thick = _extent(HandShape(), "index_middle"), _extent(HandShape(width=1.1), "index_middle")
    # breadth (x) and depth (z) grow by the ratio; the length does not change
    assert thick[0] / std[0] == pytest.approx(1.1, rel=1e-6)
    assert thick[2] / std[2] == pytest.approx(1.1, rel=1e-6)
    assert _extent(HandShape(width=1.1), "palm") == pytest.approx(_extent(HandShape(), "palm"))
    ka, kb = _kp(HandShape()), _kp(HandShape(width=1.1))
    for k in ka:
        np.testing.assert_allclose(ka[k], kb[k], atol=1e-9)


@pytest.mark.parametrize("value", [True, False, np.bool_(True)])
def test_a_bool_is_not_a_ratio(value):
    # issue 16 item 19: HandShape(length=True) was accepted as 1.0
    with pytest.raises(InvalidShapeError, match=r"HandShape.length must be a number, got"):
        HandShape(length=value)


@pytest.mark.parametrize("name", ["L1.0__W1.0_P1.0", "_W1_P1_T1", "L1_W1_P1_", ""])
def test_a_malformed_name_is_an_invalid_shape(name):
    with pytest.raises(InvalidShapeError, match=r"is not of the form"):
        HandShape.from_name(name)
