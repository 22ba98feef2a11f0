"""The wrist cut on every mount CameraMount accepts, tilted and low ones included."""

import numpy as np
import pytest

from handsynth import CameraMount
from handsynth.errors import InvalidCameraError
from handsynth.models import DORSUM_Z_MM, named_pose
from handsynth.render import SilhouetteRenderer, coverage, preprocess, wrist_cut_keep
from handsynth.render._varied import MountVariation

W, H = 120, 80


def _projected_cut_keep(mount, side, w, h):
    """The cut through the projected points of the cut line, the forearm's side
    taken from the projected forearm point: right while all three are in front
    of the camera (the mounts in use)."""
    y_cut, z = mount.wrist_cut_mm * 1e-3, DORSUM_Z_MM * 1e-3
    (u0, v0), (u1, v1), (uf, vf) = mount.project(
        np.array([[-0.2, y_cut, z], [0.2, y_cut, z], [0.0, y_cut - 0.05, z]]),
        side=side, width_px=w, height_px=h)
    vv, uu = np.mgrid[0:h, 0:w]

    def side_of(u, v):
        return (u1 - u0) * (v - v0) - (v1 - v0) * (u - u0)

    return np.sign(side_of(uu, vv)) != np.sign(side_of(uf, vf))


def _mounts_in_use():
    rng = np.random.default_rng(7)
    out = [CameraMount.paper(), CameraMount.whole_hand()]
    for base in (CameraMount.paper(), CameraMount.whole_hand()):
        for factor in (0.5, 1.0, 2.0):
            out += [MountVariation().scaled(factor).sample(base, rng) for _ in range(15)]
    return out


def test_mounts_in_use_keep_the_same_pixels():
    for mount in _mounts_in_use():
        for side in ("right", "left"):
            for w, h in ((720, 480), (180, 120), (64, 64)):
                np.testing.assert_array_equal(
                    wrist_cut_keep(mount, side=side, width_px=w, height_px=h),
                    _projected_cut_keep(mount, side, w, h), err_msg=f"{mount} {side} {w}x{h}")


@pytest.mark.parametrize("tilt_deg, height_mm", [(52.0, 120.0), (60.0, 120.0), (30.0, 30.0),
                                                 (70.0, 60.0), (80.0, 20.0)])
def test_tilted_and_low_mounts_keep_the_hand(tilt_deg, height_mm):
    mount = CameraMount(tilt_deg=tilt_deg, height_mm=height_mm)
    with SilhouetteRenderer(mount=mount, width_px=360, height_px=240) as r:
        mask = r.mask(named_pose("pinch"))
    assert mask.sum() > 1000
    assert wrist_cut_keep(mount, width_px=360, height_px=240).mean() > 0.5
    assert preprocess(mask, mount).sum() > 100
    assert coverage(mask, mount).sum() > 1


def _visible_finger_pixels(r, mount, side):
    """Pixels (v, u) of the centres of the finger parts that lie beyond the cut,
    in front of the camera and inside the frame."""
    m, d = r.hand.model, r.hand.data
    fingers = [g for g in range(m.ngeom) if m.geom(g).name not in ("forearm", "palm")]
    pts = d.geom_xpos[fingers]
    pts = pts[pts[:, 1] > mount.wrist_cut_mm * 1e-3 + 0.02]
    pose = mount.pose_in_hand(side=side)
    depth = (pts - pose[:3, 3]) @ pose[:3, 2]
    uv = mount.project(pts[depth > 0.005], side=side, width_px=W, height_px=H)
    u, v = np.round(uv).astype(int).T
    inside = (u >= 0) & (u < W) & (v >= 0) & (v < H)
    return v[inside], u[inside]


@pytest.mark.parametrize("side", ["right", "left"])
def test_hand_seen_beyond_the_wrist_survives_the_cut_on_every_mount(side):
    poses = np.stack([named_pose("pinch"), named_pose("open")])
    seen = 0
    for height_mm in (20.0, 40.0, 120.0, 190.0):
        for tilt_deg in range(-80, 81, 20):
            mount = CameraMount(tilt_deg=float(tilt_deg), height_mm=height_mm)
            keep = wrist_cut_keep(mount, side=side, width_px=W, height_px=H)
            with SilhouetteRenderer(mount=mount, side=side, width_px=W, height_px=H) as r:
                for pose in poses:
                    mask = r.mask(pose)
                    v, u = _visible_finger_pixels(r, mount, side)
                    if v.size == 0:
                        continue
                    seen += 1
                    where = f"tilt_deg={tilt_deg} height_mm={height_mm}"
                    assert mask[v, u].all(), where
                    assert keep[v, u].all(), where
                    assert preprocess(mask, mount, side=side).any(), where
                    assert coverage(mask, mount, side=side).sum() > 0, where
    assert seen > 50


def test_cut_is_the_side_of_the_plane_through_the_camera_and_the_cut_line():
    # random mounts over every field's whole range; pixels whose ray lies in
    # the plane (to rounding) may go either way
    rng = np.random.default_rng(3)
    w, h = 97, 61
    vv, uu = np.mgrid[0:h, 0:w]
    pixels = np.stack([uu, vv, np.ones_like(uu)], -1).reshape(-1, 3)
    for i in range(150):
        mount = CameraMount(
            height_mm=float(rng.uniform(1, 400)), thumb_offset_mm=float(rng.uniform(-100, 100)),
            along_mm=float(rng.uniform(-100, 250)), tilt_deg=float(rng.uniform(-80, 80)),
            roll_deg=float(rng.uniform(-180, 180)), fov_deg=float(rng.uniform(1, 170)),
            wrist_cut_mm=float(rng.uniform(-100, 40)))
        side = ("right", "left")[i % 2]
        pose = mount.pose_in_hand(side=side)
        centre, y_cut, z = pose[:3, 3], mount.wrist_cut_mm * 1e-3, DORSUM_Z_MM * 1e-3
        normal = np.cross([1.0, 0.0, 0.0], np.array([0.0, y_cut, z]) - centre)
        forearm = np.sign(normal @ (np.array([0.0, y_cut - 0.05, z]) - centre))
        s = pixels @ np.linalg.inv(mount.intrinsics(w, h)).T @ pose[:3, :3].T @ normal
        clear = (np.abs(s) > 1e-9 * np.abs(s).max()).reshape(h, w)
        keep = wrist_cut_keep(mount, side=side, width_px=w, height_px=h)
        np.testing.assert_array_equal(keep[clear], (np.sign(s) != forearm).reshape(h, w)[clear],
                                      err_msg=str(mount))


def test_wrist_cut_keep_needs_a_mount():
    with pytest.raises(InvalidCameraError, match="mount must be a CameraMount, got NoneType"):
        wrist_cut_keep(None)
