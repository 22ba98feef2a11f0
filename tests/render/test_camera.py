import numpy as np
import pytest

from handsynth import CameraMount, HandModel
from handsynth.errors import InvalidCameraError
from handsynth.models import DORSUM_Z_MM


def test_paper_device_defaults():
    m = CameraMount.paper()
    assert (m.fov_deg, m.width_px, m.height_px, m.height_mm) == (90.0, 720, 480, 120.0)
    pose = m.pose_in_hand()
    # optical axis perpendicular to the back of the hand, looking down at it
    np.testing.assert_allclose(pose[:3, 2], [0, 0, -1], atol=1e-12)
    assert pose[2, 3] == pytest.approx((DORSUM_Z_MM + 120) * 1e-3)
    assert pose[0, 3] < 0  # thumb side of a right hand
    assert np.linalg.det(pose[:3, :3]) == pytest.approx(1.0)


def test_intrinsics_match_field_of_view():
    m = CameraMount()
    k = m.intrinsics()
    assert k[0, 0] == pytest.approx(360.0)  # 90 deg across 720 px
    assert k[0, 2] == pytest.approx(359.5) and k[1, 2] == pytest.approx(239.5)
    assert m.fovy_deg() == pytest.approx(2 * np.degrees(np.arctan(240 / 360)))


def test_projection_puts_the_hand_where_the_renderer_does():
    from handsynth.models import named_pose
    from handsynth.render import SilhouetteRenderer

    m = CameraMount.whole_hand()
    r = SilhouetteRenderer(mount=m, width_px=360, height_px=240, forearm=False)
    mask = r.mask(named_pose("spread"))
    h = HandModel()
    h.set_pose(named_pose("spread"))
    uv = m.project(h.keypoints(), width_px=360, height_px=240)
    for u, v in np.round(uv).astype(int):  # every joint centre lies on the hand
        assert mask[v - 1:v + 2, u - 1:u + 2].any()


def test_tilt_turns_the_axis_toward_the_fingers():
    pose = CameraMount(tilt_deg=20).pose_in_hand()
    assert pose[1, 2] > 0.3 and pose[2, 2] < -0.9


def test_left_mount_is_mirrored():
    r, l = CameraMount().pose_in_hand(side="right"), CameraMount().pose_in_hand(side="left")
    assert l[0, 3] == -r[0, 3] and l[1, 3] == r[1, 3]


def test_a_left_frame_is_the_right_frame_through_the_mirrored_device_upside_down():
    from handsynth.models import named_pose
    from handsynth.render import SilhouetteRasterizer

    mount = CameraMount(height_mm=110.0, thumb_offset_mm=18.0, tilt_deg=5.0, roll_deg=7.0)
    assert mount.mirrored().roll_deg == -7.0 and mount.mirrored().mirrored() == mount
    assert CameraMount.paper().mirrored().as_dict() == CameraMount.paper().as_dict()  # no -0.0
    for pose in ("open", "pinch"):
        left = SilhouetteRasterizer(mount=mount, side="left").mask(named_pose(pose))
        right = SilhouetteRasterizer(mount=mount.mirrored()).mask(named_pose(pose))
        np.testing.assert_array_equal(left, right[::-1])
        # without the mirrored roll the frames differ
        assert (left != SilhouetteRasterizer(mount=mount).mask(named_pose(pose))[::-1]).sum() > 1000


@pytest.mark.parametrize("field, value", [("height_mm", 0), ("fov_deg", 180), ("width_px", 0),
                                          ("height_px", 2.5), ("tilt_deg", float("nan"))])
def test_bad_mount_names_the_field(field, value):
    with pytest.raises(InvalidCameraError, match=f"CameraMount.{field}"):
        CameraMount(**{field: value})


@pytest.mark.parametrize("cut", [1e6, 41.0, -101.0])
def test_a_wrist_cut_that_removes_the_hand_is_refused(cut):
    # issue 16 item 19: wrist_cut_mm=1e6 was accepted, then every frame was "no hand"
    with pytest.raises(InvalidCameraError, match=r"wrist_cut_mm must be in \[-100, 40\] mm"):
        CameraMount(wrist_cut_mm=cut)
    assert CameraMount(wrist_cut_mm=40.0).wrist_cut_mm == 40.0
    assert CameraMount(wrist_cut_mm=None).wrist_cut_mm is None


@pytest.mark.parametrize("field, value, words", [
    ("width_px", 10**30, r"width_px must be an integer in \[1, 16384\] pixels, got 10{30}"),
    ("width_px", 10**8, r"width_px must be an integer in \[1, 16384\] pixels, got 100000000"),
    ("height_px", 16385, r"height_px must be an integer in \[1, 16384\] pixels, got 16385"),
    ("height_mm", 1000.5, r"height_mm must be in \(0, 1000\] mm, got 1000.5"),
    ("height_mm", 0, r"height_mm must be in \(0, 1000\] mm, got 0"),
    ("thumb_offset_mm", -1e4, r"thumb_offset_mm must be in \[-1000, 1000\] mm, got -10000.0"),
    ("along_mm", 1e6, r"along_mm must be in \[-1000, 1000\] mm, got 1000000.0"),
])
def test_mount_sizes_and_distances_have_upper_bounds(field, value, words):
    # issue: width_px=10**30 was stored as a 31-digit integer, 10**8 gave a raw MemoryError
    # in the rasterizer; no distance had an upper bound
    with pytest.raises(InvalidCameraError, match=rf"CameraMount\.{words}"):
        CameraMount(**{field: value})


def test_mount_bounds_themselves_are_accepted():
    m = CameraMount(width_px=16384, height_px=1, height_mm=1000.0, thumb_offset_mm=-1000.0,
                    along_mm=1000.0)
    assert (m.width_px, m.height_px, m.height_mm) == (16384, 1, 1000.0)
    assert m.size(16384, 16384) == (16384, 16384)


@pytest.mark.parametrize("size", [(10**8, 480), (720, 16385)])
def test_a_render_size_past_the_largest_image_side_is_refused(size):
    with pytest.raises(InvalidCameraError, match=r"_px must be a positive integer at most 16384, "
                                                 rf"got {max(size)}"):
        CameraMount().size(*size)
