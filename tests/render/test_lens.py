"""A real camera's frames remapped to the device's pinhole view (handsynth.render._lens).

The corrected frames are checked against OpenCV's *forward* models (``projectPoints`` and
``fisheye.projectPoints``: where a ray lands in the real camera's frame), which the
correction does not use (it builds the inverse map), and against the device's own render.
"""

from __future__ import annotations

import json

import cv2
import numpy as np
import pytest

from handsynth.errors import InvalidCameraError, InvalidInputError
from handsynth.render import CameraIntrinsics, CameraMount, LensCorrection, read_intrinsics

#: A wide-angle board camera: 100 deg across 720 px, barrel distortion, principal point
#: off centre (values of the size real calibrations of such lenses give).
WIDE = CameraIntrinsics(720, 480, 302.0, 301.0, 367.0, 233.0,
                        distortion=(-0.30, 0.09, 0.001, -0.0008, -0.012))
FISHEYE = CameraIntrinsics(1280, 720, 420.0, 420.0, 645.0, 355.0,
                           distortion=(0.05, -0.01, 0.003, -0.0005), model="fisheye")


def _device_rays(mount: CameraMount, step: int = 60) -> tuple[np.ndarray, np.ndarray]:
    """Pixels of the device's view on a grid and their rays (camera frame, z = 1)."""
    k = mount.intrinsics()
    u, v = np.meshgrid(np.arange(30, mount.width_px - 30, step),
                       np.arange(30, mount.height_px - 30, step))
    px = np.column_stack([u.ravel(), v.ravel()]).astype(np.float64)
    rays = np.column_stack([(px[:, 0] - k[0, 2]) / k[0, 0], (px[:, 1] - k[1, 2]) / k[1, 1],
                            np.ones(len(px))])
    return px, rays


def _forward(intr: CameraIntrinsics, rays: np.ndarray) -> np.ndarray:
    """Where each ray lands in the real camera's frame (OpenCV's forward models)."""
    d = np.asarray(intr.distortion, np.float64)
    if intr.model == "fisheye":
        pts, _ = cv2.fisheye.projectPoints(rays[:, None, :], np.zeros(3), np.zeros(3),
                                           intr.matrix(), d)
    else:
        pts, _ = cv2.projectPoints(rays, np.zeros(3), np.zeros(3), intr.matrix(), d)
    return pts.reshape(-1, 2)


def _dots(shape, centres: np.ndarray) -> np.ndarray:
    """A dark frame with a bright 5x5 square around each (rounded) centre."""
    frame = np.zeros(shape, np.uint8)
    for x, y in np.rint(centres).astype(int):
        frame[y - 2:y + 3, x - 2:x + 3] = 255
    return frame


@pytest.mark.parametrize("intr", [WIDE, FISHEYE], ids=["barrel", "fisheye"])
def test_a_point_lands_where_the_device_camera_sees_it(intr):
    mount = CameraMount.paper()
    px, rays = _device_rays(mount)
    real = _forward(intr, rays)
    inside = ((real > 5) & (real < [intr.width_px - 6, intr.height_px - 6])).all(axis=1)
    assert inside.sum() > 40
    out = LensCorrection(intr, mount)(_dots((intr.height_px, intr.width_px), real[inside]))
    assert out.shape == (480, 720)
    for u, v in px[inside]:
        patch = out[int(v) - 12:int(v) + 13, int(u) - 12:int(u) + 13].astype(np.float64)
        assert patch.sum() > 0, (u, v)
        yy, xx = np.mgrid[-12:13, -12:13]
        cu, cv_ = (patch * xx).sum() / patch.sum(), (patch * yy).sum() / patch.sum()
        # the dot was drawn at the rounded pixel: up to 0.5 px there, scaled by the lens
        assert np.hypot(cu, cv_) < 1.5, (u, v, cu, cv_)


def test_without_distortion_and_with_the_device_optics_the_frame_is_unchanged():
    mount = CameraMount.paper()
    k = mount.intrinsics()
    same = CameraIntrinsics(720, 480, k[0, 0], k[1, 1], k[0, 2], k[1, 2])
    rng = np.random.default_rng(0)
    frame = rng.integers(0, 256, (480, 720, 3), dtype=np.uint8)
    lens = LensCorrection(same, mount)
    assert lens.unseen_share == 0.0 and lens.fold_deg is None
    out = lens(frame)
    assert np.abs(out.astype(int) - frame).max() <= 1


def test_a_corrected_hand_matches_the_device_render():
    """The hand seen by the wide camera (made by sampling a wider pinhole render through the
    real camera's rays), corrected, is the device's own render of it."""
    from handsynth import HandShape
    from handsynth.models import named_pose
    from handsynth.render import SilhouetteRenderer

    mount = CameraMount.paper()
    wide = mount.replace(fov_deg=140.0, width_px=1800, height_px=1800)
    pose = named_pose("pinch")
    with SilhouetteRenderer(HandShape(), mount) as r:
        device = r.mask(pose)
    with SilhouetteRenderer(HandShape(), wide) as r:
        big = r.mask(pose).astype(np.uint8) * 255
    # the real camera's frame: each of its pixels looks along its own (undistorted) ray
    u, v = np.meshgrid(np.arange(WIDE.width_px, dtype=np.float64),
                       np.arange(WIDE.height_px, dtype=np.float64))
    pts = np.column_stack([u.ravel(), v.ravel()])[:, None, :]
    norm = cv2.undistortPoints(pts, WIDE.matrix(), np.asarray(WIDE.distortion), R=None, P=None,
                               criteria=(cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 40, 1e-9))
    kw = wide.intrinsics()
    mx = (norm[:, 0, 0] * kw[0, 0] + kw[0, 2]).reshape(u.shape).astype(np.float32)
    my = (norm[:, 0, 1] * kw[1, 1] + kw[1, 2]).reshape(u.shape).astype(np.float32)
    real = cv2.remap(big, mx, my, cv2.INTER_LINEAR) > 127
    assert (real != cv2.resize(device.astype(np.uint8), (720, 480)).astype(bool)).mean() > 0.02
    got = LensCorrection(WIDE, mount)(real)
    assert got.dtype == np.bool_
    iou = (got & device).sum() / (got | device).sum()
    assert iou > 0.97, iou


def test_a_narrower_camera_leaves_the_rest_of_the_view_black():
    mount = CameraMount.paper()
    narrow = CameraIntrinsics(640, 480, 395.0, 395.0, 319.5, 239.5)  # about 78 deg across
    lens = LensCorrection(narrow, mount)
    assert 0.2 < lens.unseen_share < 0.6
    out = lens(np.full((480, 640), 200, np.uint8))
    assert (out == 0).mean() == pytest.approx(lens.unseen_share, abs=0.01)
    assert out[240, 360] == 200 and out[240, 2] == 0


def test_a_lens_model_that_folds_back_is_cut_at_the_fold():
    # k1 strongly negative: the distorted radius stops growing well inside the device's view
    folding = CameraIntrinsics(720, 480, 300.0, 300.0, 359.5, 239.5, distortion=(-0.6, 0.0, 0, 0))
    lens = LensCorrection(folding, CameraMount.paper())
    assert lens.fold_deg is not None and 30 < lens.fold_deg < 45
    out = lens(np.full((480, 720), 200, np.uint8))
    assert out[0, 0] == 0 and out[240, 360] == 200


def test_frames_of_another_size_of_the_same_ratio_use_the_scaled_calibration():
    mount = CameraMount.paper()
    px, rays = _device_rays(mount, step=90)
    half = WIDE.scaled(360, 240)
    real = _forward(half, rays)
    inside = ((real > 3) & (real < [354, 234])).all(axis=1)
    lens = LensCorrection(WIDE, mount)
    out = lens(_dots((240, 360), real[inside]))
    assert out.shape == (480, 720)
    for u, v in px[inside]:
        assert out[int(v) - 6:int(v) + 7, int(u) - 6:int(u) + 7].any(), (u, v)
    with pytest.raises(InvalidInputError, match=r"640x480 pixels .* 720x480: the width-to-height ratio"):
        lens(np.zeros((480, 640, 3), np.uint8))


@pytest.mark.parametrize("field, value, match", [
    ("fx_px", 0.0, "fx_px"), ("cx_px", 900.0, "cx_px"), ("width_px", 7, "width_px"),
    ("distortion", (0.1, 0.2, 0.3), "distortion .* 3"), ("distortion", "abc", "distortion"),
    ("distortion", (float("nan"),) * 4, r"distortion\[0\]"), ("model", "kb", "model"),
])
def test_bad_intrinsics_are_refused_by_field(field, value, match):
    args = {"width_px": 720, "height_px": 480, "fx_px": 300.0, "fy_px": 300.0, "cx_px": 360.0,
            "cy_px": 240.0, field: value}
    with pytest.raises(InvalidCameraError, match=match):
        CameraIntrinsics(**args)


def test_fisheye_takes_four_coefficients():
    with pytest.raises(InvalidCameraError, match="fisheye .* 4"):
        CameraIntrinsics(720, 480, 300.0, 300.0, 360.0, 240.0, distortion=(0.1,) * 5,
                         model="fisheye")


# --- calibration files --------------------------------------------------------------------


def _opencv_file(path, intr: CameraIntrinsics) -> None:
    fs = cv2.FileStorage(str(path), cv2.FILE_STORAGE_WRITE)
    fs.write("image_width", intr.width_px)
    fs.write("image_height", intr.height_px)
    fs.write("camera_matrix", intr.matrix())
    fs.write("distortion_coefficients", np.asarray(intr.distortion).reshape(1, -1))
    fs.release()


@pytest.mark.parametrize("suffix", [".yaml", ".xml", ".json"])
def test_opencv_calibration_files_read_back(tmp_path, suffix):
    path = tmp_path / f"camera{suffix}"
    _opencv_file(path, WIDE)
    assert read_intrinsics(path) == WIDE


ROS = """image_width: 720
image_height: 480
camera_name: hand_cam
camera_matrix:
  rows: 3
  cols: 3
  data: [302.0, 0.0, 367.0, 0.0, 301.0, 233.0, 0.0, 0.0, 1.0]
distortion_model: plumb_bob
distortion_coefficients:
  rows: 1
  cols: 5
  data: [-0.30, 0.09, 0.001, -0.0008, -0.012]
rectification_matrix:
  rows: 3
  cols: 3
  data: [1, 0, 0, 0, 1, 0, 0, 0, 1]
"""

KALIBR = """cam0:
  camera_model: pinhole
  intrinsics: [420.0, 420.0, 645.0, 355.0]
  distortion_model: equidistant
  distortion_coeffs: [0.05, -0.01, 0.003, -0.0005]
  resolution: [1280, 720]
  rostopic: /cam0/image_raw
"""


def test_ros_and_kalibr_files_read(tmp_path):
    (tmp_path / "ros.yaml").write_text(ROS)
    (tmp_path / "kalibr.yaml").write_text(KALIBR)
    assert read_intrinsics(tmp_path / "ros.yaml") == WIDE
    assert read_intrinsics(tmp_path / "kalibr.yaml") == FISHEYE


def test_plain_json_with_nested_matrix_and_short_distortion(tmp_path):
    path = tmp_path / "cam.json"
    path.write_text(json.dumps({"width": 720, "height": 480,
                                "K": WIDE.matrix().tolist(), "D": [-0.3, 0.09]}))
    got = read_intrinsics(path)
    assert got.distortion == (-0.3, 0.09, 0.0, 0.0)
    assert (got.fx_px, got.cy_px) == (302.0, 233.0)


@pytest.mark.parametrize("text, match", [
    ("camera_matrix: [1, 2\n  : :", r"not valid YAML at line \d"),
    ("- 1\n- 2\n", "must be a map of fields"),
    ("image_width: 720\nimage_height: 480\ndistortion_coefficients: []\n",
     r"no camera matrix \(looked for camera_matrix.*found image_width"),
    ("image_width: 720\nimage_height: 480\ncamera_matrix: [300, 0, 360, 0, 300, 240, 0, 0, 1]\n",
     "no distortion coefficients"),
    ("camera_matrix: [300, 0, 360, 0, 300, 240, 0, 0, 1]\ndistortion_coefficients: []\n",
     "no frame size"),
    ("image_width: 720\nimage_height: 480\ncamera_matrix: [300, 0, 360, 0, 300, 240, 0, 0, 2]\n"
     "distortion_coefficients: []\n", "must be a camera matrix"),
    ("image_width: 720\nimage_height: 480\ncamera_matrix: [300, 2, 360, 0, 300, 240, 0, 0, 1]\n"
     "distortion_coefficients: []\n", "skew"),
    ("image_width: 720\nimage_height: 480\ncamera_matrix: [300, 0, 360, 0, 300, 240, 0, 0, 1]\n"
     "distortion_coefficients: [.nan, 0, 0, 0]\n", "NaN"),
    ("image_width: 720\nimage_height: 480\ncamera_matrix: [300, 0, 360, 0, 300, 240, 0, 0, 1]\n"
     "distortion_coefficients: []\ndistortion_model: double_sphere\n", "double_sphere"),
    ("image_width: 720\nimage_height: 480\ncamera_matrix: [300, 0, 900, 0, 300, 240, 0, 0, 1]\n"
     "distortion_coefficients: []\n", "cx_px"),
    ("cam0: {intrinsics: [1, 1, 1, 1], distortion_coeffs: [], resolution: [8, 8]}\n"
     "cam1: {intrinsics: [1, 1, 1, 1], distortion_coeffs: [], resolution: [8, 8]}\n",
     "2 cameras"),
])
def test_bad_calibration_files_name_the_file_and_the_problem(tmp_path, text, match):
    path = tmp_path / "cam.yaml"
    path.write_text(text)
    with pytest.raises(InvalidInputError, match=match) as info:
        read_intrinsics(path)
    assert str(path) in str(info.value)


def test_a_missing_or_damaged_file_is_refused(tmp_path):
    with pytest.raises(InvalidInputError, match="no such file"):
        read_intrinsics(tmp_path / "nope.yaml")
    bad = tmp_path / "cam.xml"
    bad.write_text("<opencv_storage><camera_matrix")
    with pytest.raises(InvalidInputError, match="cam.xml"):
        read_intrinsics(bad)
    with pytest.raises(InvalidInputError, match="camera intrinsics"):
        read_intrinsics("")
