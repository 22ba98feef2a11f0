"""An object held in a glTF test hand: its placement and how the device sees it."""

import dataclasses

import numpy as np
import pytest

from handsynth.errors import InvalidCameraError, InvalidInputError
from handsynth.models import named_pose
from handsynth.testhands import HeldObject, MeshHandRenderer, grasped_cylinder

W, H = 360, 240


@pytest.fixture(scope="module")
def holding():
    with MeshHandRenderer(width_px=W, height_px=H, holding=True) as r:
        yield r


def test_a_cylinder_is_placed_only_where_the_fingers_close_around_one(holding):
    assert grasped_cylinder(holding.keypoints(named_pose("open"))) is None
    assert grasped_cylinder(holding.keypoints(named_pose("spread"))) is None
    kp = holding.keypoints(named_pose("fist"))
    held = grasped_cylinder(kp)
    assert isinstance(held, HeldObject) and 12.0 <= held.radius_mm <= 45.0
    mcp = kp[[5, 9, 13, 17]] * 1e3
    # across the palm, under the knuckles and among the fingers
    assert held.axis == (1.0, 0.0, 0.0)
    assert held.centre_mm[2] + held.radius_mm <= mcp[:, 2].mean()
    assert mcp[:, 0].min() < held.centre_mm[0] < mcp[:, 0].max()
    with pytest.raises(InvalidInputError, match="keypoints_m"):
        grasped_cylinder(kp[:20])


def test_the_object_joins_the_hand_or_hides_what_is_behind_it(holding):
    pose = named_pose("fist")
    held = grasped_cylinder(holding.keypoints(pose))
    with MeshHandRenderer(width_px=W, height_px=H) as plain:
        hand = plain.mask(pose)
    assert np.array_equal(holding.mask(pose), hand)  # the scene's object is out of view
    bright = holding.mask_holding(pose, held)
    beyond = bright & ~hand
    assert beyond.sum() > 0.05 * hand.sum()
    # a cylinder across the palm is seen beyond both edges of the hand (image rows)
    rows = np.nonzero(hand.any(axis=1))[0]
    assert beyond[: rows.min()].any() and beyond[rows.max() + 1:].any()
    dark = holding.mask_holding(pose, dataclasses.replace(held, bright=False))
    assert not (dark & ~hand).any()  # a dark object adds nothing ...
    in_front = dataclasses.replace(held, centre_mm=(held.centre_mm[0], held.centre_mm[1], 60.0),
                                   bright=False)
    assert (hand & ~holding.mask_holding(pose, in_front)).sum() > 0.05 * hand.sum()  # ... it hides
    assert np.array_equal(holding.mask(pose), hand)  # and leaves the scene as it was


def test_a_left_hand_holds_the_mirror_image():
    pose = named_pose("fist")
    kw = {"width_px": W, "height_px": H, "holding": True}
    with MeshHandRenderer(**kw) as right, MeshHandRenderer(side="left", **kw) as left:
        held = grasped_cylinder(right.keypoints(pose))
        theirs = grasped_cylinder(left.keypoints(pose))  # in the left hand's own frame
        assert theirs.centre_mm[0] == pytest.approx(-held.centre_mm[0])
        a, b = right.mask_holding(pose, held), left.mask_holding(pose, theirs)
    assert (a & b[::-1]).sum() / (a | b[::-1]).sum() > 0.97


def test_bad_objects_and_renderers_are_refused(holding):
    with MeshHandRenderer(width_px=W, height_px=H) as plain, \
            pytest.raises(InvalidCameraError, match="holding=True"):
        plain.mask_holding(named_pose("fist"), HeldObject((0, 90, -20)))
    with pytest.raises(InvalidCameraError, match="HeldObject"):
        holding.mask_holding(named_pose("fist"), (0, 90, -20))
    with pytest.raises(InvalidCameraError, match="holding"):
        MeshHandRenderer(width_px=W, height_px=H, holding="yes")
    for bad, match in (({"centre_mm": (0, 1)}, "centre_mm"),
                       ({"centre_mm": (0, np.nan, 1)}, "centre_mm"),
                       ({"centre_mm": "abc"}, "centre_mm"),
                       ({"centre_mm": (0, 0, 0), "axis": (0, 0, 0)}, "axis"),
                       ({"centre_mm": (0, 0, 0), "radius_mm": 0}, "radius_mm"),
                       ({"centre_mm": (0, 0, 0), "length_mm": -5}, "length_mm"),
                       ({"centre_mm": (0, 0, 0), "bright": 1}, "bright")):
        with pytest.raises(InvalidInputError, match=match):
            HeldObject(**bad)
    h = HeldObject((0, 0, 0), axis=(0, 0, 2))
    assert h.axis == (0.0, 0.0, 1.0)
    np.testing.assert_allclose(h.quat(), [1, 0, 0, 0])
    np.testing.assert_allclose(HeldObject((0, 0, 0), axis=(0, 0, -1)).quat(), [0, 1, 0, 0])
