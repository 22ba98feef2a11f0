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


def _assert_points_land(intr: CameraIntrinsics) -> None:
    """Dots drawn where OpenCV's forward model puts the device's rays land, once corrected,
    on those rays' pixels of the device's view."""
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


@pytest.mark.parametrize("intr", [WIDE, FISHEYE], ids=["barrel", "fisheye"])
def test_a_point_lands_where_the_device_camera_sees_it(intr):
    _assert_points_land(intr)


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
@pytest.mark.parametrize("intr", [WIDE, CameraIntrinsics(720, 480, 302.0, 301.0, 367.0, 233.0)],
                         ids=["distorted", "undistorted"])
def test_opencv_calibration_files_read_back(tmp_path, suffix, intr):
    path = tmp_path / f"camera{suffix}"
    _opencv_file(path, intr)
    assert read_intrinsics(path) == intr


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
    _assert_refused_naming_the_file(tmp_path / "cam.yaml", text.encode(), match)


def _assert_refused_naming_the_file(path, content: bytes, match: str) -> None:
    path.write_bytes(content)
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


# --- calibration files as the tools write them ----------------------------------------------

#: A wide lens calibrated with OpenCV's rational model (8 coefficients; ROS's
#: ``rational_polynomial``, Basalt's ``pinhole-radtan8``).
RATIONAL = CameraIntrinsics(1280, 720, 560.0, 559.0, 641.5, 358.0,
                            distortion=(0.52, -0.05, 0.0004, -0.0003, 0.001, 0.88, 0.05, 0.002))


def _calibration_sample(path, intr: CameraIntrinsics, *, views: int = 25, board=(9, 6)) -> None:
    """As OpenCV's calibration sample (``camera_calibration.cpp``) saves its result: the board,
    the flags with a comment, ``fisheye_model``, the reprojection errors, extrinsics, the
    detected corners (``dt: 2f``) and the grid."""
    rng = np.random.default_rng(3)
    fisheye = intr.model == "fisheye"
    fs = cv2.FileStorage(str(path), cv2.FILE_STORAGE_WRITE)
    fs.write("calibration_time", "Fri Nov 27 04:44:04 2026")
    fs.write("nr_of_frames", views)
    fs.write("image_width", intr.width_px)
    fs.write("image_height", intr.height_px)
    fs.write("board_width", board[0])
    fs.write("board_height", board[1])
    fs.write("square_size", 50.0)
    if not fisheye:
        fs.write("fix_aspect_ratio", 1.0)
    fs.writeComment("flags:  +fix_k4 +fix_k5")
    fs.write("flags", 6144)
    fs.write("fisheye_model", int(fisheye))
    fs.write("camera_matrix", intr.matrix())
    fs.write("distortion_coefficients", np.asarray(intr.distortion, np.float64).reshape(-1, 1))
    fs.write("avg_reprojection_error", 0.39)
    fs.write("per_view_reprojection_errors", rng.random((views, 1)).astype(np.float32))
    fs.writeComment("a set of 6-tuples (rotation vector + translation vector) for each view")
    fs.write("extrinsic_parameters", rng.random((views, 6)))
    fs.write("image_points",
             (rng.random((views, board[0] * board[1], 2)) * 600).astype(np.float32))
    grid = np.array([[i * 50.0, j * 50.0, 0.0] for j in range(board[1]) for i in range(board[0])],
                    np.float32)
    fs.write("grid_points", grid.reshape(-1, 1, 3))
    fs.release()


@pytest.mark.parametrize("suffix", [".yml", ".xml", ".json"])
@pytest.mark.parametrize("intr", [WIDE, FISHEYE], ids=["pinhole", "fisheye"])
def test_opencv_calibration_sample_output_reads_back(tmp_path, suffix, intr):
    # fisheye_model: 1 once read its 4 coefficients as the pinhole k1, k2, p1, p2; the JSON,
    # with the flags' comment, was refused as not JSON
    path = tmp_path / f"out_camera_data{suffix}"
    _calibration_sample(path, intr)
    assert read_intrinsics(path) == intr


@pytest.mark.parametrize("suffix", [".yml", ".xml", ".json"])
def test_a_calibration_with_many_views_reads_fast(tmp_path, suffix):
    import time

    path = tmp_path / f"out_camera_data{suffix}"
    _calibration_sample(path, WIDE, views=200, board=(20, 15))  # 60 000 corners
    start = time.perf_counter()
    assert read_intrinsics(path) == WIDE
    assert time.perf_counter() - start < 0.3


def _ros_file(intr: CameraIntrinsics, model: str) -> str:
    """ROS camera_calibration's ``ost.yaml`` (numbers as it formats them, ``%f``)."""
    k = ", ".join(f"{v:f}" for v in intr.matrix().ravel())
    d = ", ".join(f"{v:f}" for v in intr.distortion)
    p = ", ".join(f"{v:f}" for v in np.column_stack([intr.matrix(), np.zeros(3)]).ravel())
    return (f"image_width: {intr.width_px}\nimage_height: {intr.height_px}\n"
            f"camera_name: narrow_stereo\ncamera_matrix:\n  rows: 3\n  cols: 3\n  data: [{k}]\n"
            f"distortion_model: {model}\ndistortion_coefficients:\n  rows: 1\n"
            f"  cols: {len(intr.distortion)}\n  data: [{d}]\n"
            f"rectification_matrix:\n  rows: 3\n  cols: 3\n"
            f"  data: [1.000000, 0.000000, 0.000000, 0.000000, 1.000000, 0.000000, 0.000000, "
            f"0.000000, 1.000000]\nprojection_matrix:\n  rows: 3\n  cols: 4\n  data: [{p}]\n")


def _basalt_file(cameras) -> str:
    """Basalt's ``calibration.json``: ``(camera_type, intrinsics, [w, h])`` per camera."""
    return json.dumps({"value0": {
        "T_imu_cam": [{"px": 0.01, "py": -0.02, "pz": 0.0, "qx": 0.0, "qy": 0.0, "qz": 0.0,
                       "qw": 1.0} for _ in cameras],
        "intrinsics": [{"camera_type": t, "intrinsics": p} for t, p, _ in cameras],
        "resolution": [list(r) for _, _, r in cameras],
        "calib_accel_bias": [0.0] * 9, "calib_gyro_bias": [0.0] * 12,
        "imu_update_rate": 200.0, "accel_noise_std": [0.016] * 3,
        "gyro_noise_std": [0.000282] * 3, "accel_bias_std": [0.001] * 3,
        "gyro_bias_std": [0.0001] * 3, "cam_time_offset_ns": 0, "vignette": []}}, indent=4)


def _basalt_params(intr: CameraIntrinsics, names) -> dict:
    return {"fx": intr.fx_px, "fy": intr.fy_px, "cx": intr.cx_px, "cy": intr.cy_px,
            **dict(zip(names, intr.distortion))}


def _orbslam_file(intr: CameraIntrinsics, camera_type: str, prefix: str = "Camera1.") -> str:
    """An ORB-SLAM3 settings file (``Camera1.*`` of its 1.0 format, ``Camera.*`` before)."""
    names = ("k1", "k2", "k3", "k4") if intr.model == "fisheye" else ("k1", "k2", "p1", "p2", "k3")
    dist = "".join(f"{prefix}{n}: {v!r}\n" for n, v in zip(names, intr.distortion))
    return (f'%YAML:1.0\n\nFile.version: "1.0"\n\n# Camera Parameters. Adjust them!\n'
            f'Camera.type: "{camera_type}"\n\n{prefix}fx: {intr.fx_px!r}\n{prefix}fy: {intr.fy_px!r}\n'
            f"{prefix}cx: {intr.cx_px!r}\n{prefix}cy: {intr.cy_px!r}\n\n{dist}\n"
            f"Camera.width: {intr.width_px}\nCamera.height: {intr.height_px}\n\n"
            f"Camera.newWidth: 600\nCamera.newHeight: 350\nCamera.fps: 20\nCamera.RGB: 1\n\n"
            f"IMU.T_b_c1: !!opencv-matrix\n   rows: 4\n   cols: 4\n   dt: f\n"
            f"   data: [1.0, 0.0, 0.0, 0.01, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0,\n"
            f"         0.0, 0.0, 0.0, 1.0]\n\nORBextractor.nFeatures: 1000\n")


KB4 = ("k1", "k2", "k3", "k4")
RADTAN8 = ("k1", "k2", "p1", "p2", "k3", "k4", "k5", "k6")
WIDE4 = CameraIntrinsics(720, 480, 302.0, 301.0, 367.0, 233.0,
                         distortion=(-0.30, 0.09, 0.001, -0.0008))

READ = {  # file name: (text, what it reads as)
    "ros_plumb_bob.yaml": (_ros_file(WIDE, "plumb_bob"), WIDE),
    "ros_rational.yaml": (_ros_file(RATIONAL, "rational_polynomial"), RATIONAL),
    "ros_equidistant.yaml": (_ros_file(FISHEYE, "equidistant"), FISHEYE),
    # a pinhole camera's 4 coefficients calibrated as a fisheye: legitimate, read as labelled
    "ros_pinhole_as_equidistant.yaml": (_ros_file(WIDE4, "equidistant"),
                                        CameraIntrinsics(720, 480, 302.0, 301.0, 367.0, 233.0,
                                                         distortion=WIDE4.distortion,
                                                         model="fisheye")),
    "kalibr_radtan.yaml": (KALIBR.replace("equidistant", "radtan"),
                           CameraIntrinsics(1280, 720, 420.0, 420.0, 645.0, 355.0,
                                            distortion=FISHEYE.distortion)),
    "basalt_kb4.json": (_basalt_file([("kb4", _basalt_params(FISHEYE, KB4), (1280, 720))]),
                        FISHEYE),
    "basalt_radtan8.json": (_basalt_file([("pinhole-radtan8",
                                           {**_basalt_params(RATIONAL, RADTAN8), "rpmax": 2.1},
                                           (1280, 720))]), RATIONAL),
    "basalt_pinhole.json": (_basalt_file([("pinhole", _basalt_params(WIDE, ()), (720, 480))]),
                            CameraIntrinsics(720, 480, 302.0, 301.0, 367.0, 233.0)),
    "orbslam3_pinhole.yaml": (_orbslam_file(WIDE, "PinHole"), WIDE),
    "orbslam3_kb8.yaml": (_orbslam_file(FISHEYE, "KannalaBrandt8"), FISHEYE),
    "orbslam_old_pinhole.yaml": (_orbslam_file(WIDE4, "PinHole", "Camera."), WIDE4),
}


@pytest.mark.parametrize("name", list(READ))
def test_calibration_files_of_ros_kalibr_basalt_and_orbslam_read(tmp_path, name):
    text, expected = READ[name]
    (tmp_path / name).write_text(text)
    assert read_intrinsics(tmp_path / name) == expected


@pytest.mark.parametrize("name", ["ros_rational.yaml", "basalt_kb4.json", "orbslam3_kb8.yaml"])
def test_a_point_lands_where_the_device_camera_sees_it_through_a_file(tmp_path, name):
    (tmp_path / name).write_text(READ[name][0])
    _assert_points_land(read_intrinsics(tmp_path / name))


def test_the_calibration_samples_fisheye_lands_points_where_the_device_sees_them(tmp_path):
    _calibration_sample(tmp_path / "out_camera_data.yml", FISHEYE)
    _assert_points_land(read_intrinsics(tmp_path / "out_camera_data.yml"))


def _kalibr_camera(model: str, intrinsics: str, distortion: str = "none", name: str = "cam0"):
    return (f"{name}:\n  cam_overlaps: []\n  camera_model: {model}\n  distortion_coeffs: []\n"
            f"  distortion_model: {distortion}\n  intrinsics: {intrinsics}\n"
            f"  resolution: [1280, 720]\n  rostopic: /{name}/image_raw\n")


@pytest.mark.parametrize("text, match", [
    (_kalibr_camera("omni", "[0.8, 420.0, 420.0, 645.0, 355.0]", "radtan"),
     "cam0.camera_model 'omni' is not a pinhole camera"),
    (_kalibr_camera("ds", "[-0.2, 0.57, 420.0, 420.0, 645.0, 355.0]"),
     "cam0.camera_model 'ds' is not a pinhole camera"),
    (_kalibr_camera("eucm", "[0.6, 1.1, 420.0, 420.0, 645.0, 355.0]"),
     "cam0.camera_model 'eucm' is not a pinhole camera"),
    (_kalibr_camera("pinhole", "[420.0, 420.0, 645.0, 355.0]", "fov"), "distortion_model 'fov'"),
    (_kalibr_camera("pinhole", "[1, 1, 1, 1]") + _kalibr_camera("pinhole", "[1, 1, 1, 1]", name="cam1")
     + "  T_cn_cnm1:\n  - [1, 0, 0, 0.1]\n  - [0, 1, 0, 0]\n  - [0, 0, 1, 0]\n  - [0, 0, 0, 1]\n",
     r"holds 2 cameras \(cam0, cam1\)"),
    (_basalt_file([("ds", {"fx": 420.0, "fy": 420.0, "cx": 645.0, "cy": 355.0, "xi": -0.2,
                           "alpha": 0.57}, (1280, 720))]),
     r"value0.intrinsics\[0\].camera_type 'ds' is not a camera handsynth reads \(it reads pinhole, "
     r"pinhole-radtan8, kb4\)"),
    (_basalt_file([("kb4", _basalt_params(FISHEYE, KB4), (1280, 720))] * 2),
     r"holds 2 cameras \(value0.intrinsics\[0\], value0.intrinsics\[1\]\)"),
    (_basalt_file([("kb4", _basalt_params(FISHEYE, KB4[:3]), (1280, 720))]),
     r"a kb4 camera needs value0.intrinsics\[0\].intrinsics.k4"),
    (_basalt_file([("kb4", _basalt_params(FISHEYE, KB4), (1280, 720))]).replace('"resolution"', '"res"'),
     "no frame size .*value0.resolution"),
    (_orbslam_file(WIDE, "Rectified"), "Camera.type 'Rectified' is not a camera handsynth reads"),
    (_orbslam_file(WIDE, "PinHole") + "Camera2.fx: 300.0\n", r"holds 2 cameras \(Camera1, Camera2\)"),
    (_orbslam_file(WIDE, "PinHole").replace("Camera.width", "Camera.w"),
     "no frame size .*Camera.width and Camera.height"),
    ("left:\n" + "".join("  " + line + "\n" for line in ROS.splitlines()) + "right:\n"
     + "".join("  " + line + "\n" for line in ROS.splitlines()), r"holds 2 cameras \(left, right\)"),
    (ROS.replace("distortion_model: plumb_bob", "fisheye_model: 1\ndistortion_model: plumb_bob"),
     "fisheye_model 1 and distortion_model 'plumb_bob' contradict each other"),
    (ROS.replace("distortion_model: plumb_bob", "fisheye_model: 2"), "'fisheye_model' must be 0 or 1"),
    (ROS.replace("image_width: 720", "image_width: 720.5"), "whole pixels, got 720.5 x 480"),
])
def test_cameras_not_read_are_refused_by_field_and_value(tmp_path, text, match):
    path = tmp_path / ("calibration.json" if text.startswith("{") else "camchain.yaml")
    path.write_text(text)
    with pytest.raises(InvalidInputError, match=match) as info:
        read_intrinsics(path)
    assert str(path) in str(info.value)


def test_ros_camera_info_as_topic_echo_prints_it_reads(tmp_path):
    k = ", ".join(repr(float(v)) for v in WIDE.matrix().ravel())
    ros1 = (f"header: \n  seq: 1043\n  stamp: \n    secs: 1700000000\n    nsecs: 12\n"
            f'  frame_id: "hand_cam"\nheight: 480\nwidth: 720\ndistortion_model: "plumb_bob"\n'
            f"D: {list(WIDE.distortion)}\nK: [{k}]\nR: [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0]\n"
            f"binning_x: 0\nbinning_y: 0\nroi: \n  x_offset: 0\n  do_rectify: False\n---\n")
    ros2 = (ros1.replace("D:", "d:").replace("K:", "k:").replace("R:", "r:"))
    for name, text in (("ros1.yaml", ros1), ("ros2.yaml", ros2)):
        (tmp_path / name).write_text(text)
        assert read_intrinsics(tmp_path / name) == WIDE
    (tmp_path / "twice.yaml").write_text(ros1 + ros1)
    with pytest.raises(InvalidInputError, match="holds 2 YAML documents"):
        read_intrinsics(tmp_path / "twice.yaml")


def test_files_as_editors_and_other_systems_save_them(tmp_path):
    _opencv_file(tmp_path / "camera.xml", WIDE)
    (tmp_path / "bom.xml").write_bytes(b"\xef\xbb\xbf" + (tmp_path / "camera.xml").read_bytes())
    (tmp_path / "bom.yaml").write_bytes(b"\xef\xbb\xbf" + ROS.encode())
    (tmp_path / "crlf.yaml").write_bytes(ROS.replace("\n", "\r\n").encode())
    _calibration_sample(tmp_path / "sample.yml", FISHEYE)
    (tmp_path / "crlf.yml").write_bytes((tmp_path / "sample.yml").read_bytes().replace(b"\n", b"\r\n"))
    for name in ("bom.xml", "bom.yaml", "crlf.yaml"):
        assert read_intrinsics(tmp_path / name) == WIDE, name
    assert read_intrinsics(tmp_path / "crlf.yml") == FISHEYE
    # a column vector of coefficients and a matrix of integers
    (tmp_path / "column.yaml").write_text(
        "%YAML:1.0\n---\nimage_width: 720\nimage_height: 480\ncamera_matrix: !!opencv-matrix\n"
        "   rows: 3\n   cols: 3\n   dt: i\n   data: [ 302, 0, 367, 0, 301, 233, 0, 0, 1 ]\n"
        "distortion_coefficients: [[-0.30], [0.09], [0.001], [-0.0008], [-0.012]]\n")
    assert read_intrinsics(tmp_path / "column.yaml") == WIDE


@pytest.mark.parametrize("content, match", [
    (b"", "the file is empty"), (b"\xef\xbb\xbf \r\n\r\n", "the file is empty"),
    (b"\x89PNG\r\n\x1a\n" + bytes(40), r"not a text file \(byte 0x89 at offset 0 is not UTF-8\)"),
    (ROS.replace("\n  ", "\n\t").encode(),
     "not valid YAML at line 5 .*YAML does not allow tabs there: indent with spaces"),
    (b"# oST version 5.0 parameters\n\n\n[image]\n\nwidth\n720\n\nheight\n480\n",
     "ROS camera_calibration's ost.txt; give the ost.yaml"),
    (b"# only a comment\n", "must be a map of fields .* got nothing"),
])
def test_empty_binary_and_misformatted_files_are_refused_clearly(tmp_path, content, match):
    _assert_refused_naming_the_file(tmp_path / "camera.yaml", content, match)


def test_a_half_size_correction_is_the_device_view_at_half_the_resolution():
    mount = CameraMount.paper()
    px, rays = _device_rays(mount, step=90)
    real = _forward(WIDE, rays)
    inside = ((real > 5) & (real < [WIDE.width_px - 6, WIDE.height_px - 6])).all(axis=1)
    half = LensCorrection(WIDE, mount, scale=0.5)
    assert half.size == (360, 240)
    out = half(_dots((WIDE.height_px, WIDE.width_px), real[inside]))
    assert out.shape == (240, 360)
    for u, v in px[inside]:
        # pixel centres: (u + 0.5) / 2 - 0.5
        cu, cv_ = (u + 0.5) / 2 - 0.5, (v + 0.5) / 2 - 0.5
        patch = out[int(cv_) - 4:int(cv_) + 6, int(cu) - 4:int(cu) + 6].astype(np.float64)
        assert patch.sum() > 0, (u, v)
        yy, xx = np.mgrid[int(cv_) - 4:int(cv_) + 6, int(cu) - 4:int(cu) + 6]
        assert np.hypot((patch * xx).sum() / patch.sum() - cu,
                        (patch * yy).sum() / patch.sum() - cv_) < 1.0, (u, v)
    with pytest.raises(InvalidInputError, match="scale"):
        LensCorrection(WIDE, mount, scale=0)
