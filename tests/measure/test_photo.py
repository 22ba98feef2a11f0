"""measure_photo on rendered photos of model hands of known shape."""

from __future__ import annotations

import numpy as np
import pytest

from handsynth.errors import InvalidInputError
from handsynth.estimate import SelectionOptions, select_shape
from handsynth.measure import (
    MEASURE_POSE,
    MODEL_CALIBRATION,
    MODEL_SHAPE_CORRECTION,
    NO_CALIBRATION,
    NO_SHAPE_CORRECTION,
    MeasureCalibration,
    MeasureOptions,
    ShapeCorrection,
    annotate_measurement,
    calibrate_on_model,
    fit_shape_correction,
    measure_photo,
    render_measurement_photo,
    write_measurement_file,
)
from handsynth.models import HandMeasurements, HandShape, model_measurements, named_pose

MM = 0.5  # mm per pixel of the test photos (600 x 600 pixels)
RATIOS = ("length", "width", "palm", "thumb")


def _errors(result, shape):
    return np.array([getattr(result.selection.ratios, n) - getattr(shape, n) for n in RATIOS])


@pytest.fixture(scope="module")
def standard():
    return render_measurement_photo(HandShape(), mm_per_px=MM)


@pytest.fixture(scope="module")
def standard_result(standard):
    return measure_photo(standard.image, mm_per_px=MM)


def test_standard_hand_gives_the_models_measurements(standard, standard_result):
    got, true = standard_result.measurements, model_measurements(HandShape())
    np.testing.assert_allclose(got.L, true.L, rtol=0.03)
    np.testing.assert_allclose(got.W, true.W, rtol=0.03)
    for name in ("P_width", "P_height", "T_width", "T_height"):
        assert abs(getattr(got, name) - getattr(true, name)) < 1.0, name
    assert standard_result.selection.shape == HandShape()
    # the joints found lie on the model's joints (fingers: MCP, PIP, DIP, tip)
    kp = standard.keypoints_px
    for k, finger in enumerate(standard_result.fingers[1:]):
        rows = [5 + 4 * k + j for j in range(4)]
        dist_mm = np.hypot(*(finger.joints_px - kp[rows]).T) * MM
        assert dist_mm.max() < 1.5, (finger.name, dist_mm)
    assert np.hypot(*(standard_result.cmc_px - kp[1])) * MM < 1.5
    assert standard_result.wrist_rule == "narrowest" and standard_result.warnings == ()


@pytest.mark.parametrize("shape, roll_deg, side", [
    (HandShape(length=0.95, width=1.1, palm=1.05, thumb=0.9), 70.0, "right"),
    (HandShape(length=1.05, width=0.9, palm=0.95, thumb=1.1), -150.0, "left"),
    (HandShape(length=0.96, width=1.07, palm=1.04, thumb=0.92), 25.0, "right"),   # off the grid
    (HandShape(length=1.04, width=0.93, palm=0.96, thumb=1.08), 200.0, "left"),   # off the grid
])
def test_ratios_and_selection_of_known_shapes(shape, roll_deg, side):
    photo = render_measurement_photo(shape, mm_per_px=MM, roll_deg=roll_deg, side=side)
    result = measure_photo(photo.image, mm_per_px=MM)
    err = np.abs(_errors(result, shape))
    assert np.all(err < [0.012, 0.012, 0.015, 0.05]), err
    assert result.selection.shape == shape.nearest_grid()


def test_perspective_top_camera_of_the_scene():
    """The scene's own "top" camera (perspective, 450 mm up, spot-lit, black background)."""
    import math

    from handsynth.render import render_rgb

    shape = HandShape(width=1.1, thumb=0.9)
    rgb = render_rgb(MEASURE_POSE, shape, camera="top", width_px=800, height_px=800)
    # scale at the plane of the finger joints (z = 0), 450 mm below the camera, fovy 40 deg
    mm_per_px = 450.0 * 2.0 * math.tan(math.radians(20.0)) / 800
    result = measure_photo(np.ascontiguousarray(rgb[..., ::-1]), mm_per_px=mm_per_px)
    # parts nearer the lens (back of the palm) or farther (the thumb, 12 deg below
    # the palm) are scaled differently: errors are larger than with an orthographic view
    assert np.all(np.abs(_errors(result, shape)) < [0.03, 0.04, 0.02, 0.06])
    assert result.selection.shape == shape


def test_without_calibration_the_thumb_is_off(standard):
    raw = measure_photo(standard.image, mm_per_px=MM,
                        options=MeasureOptions(calibration=NO_CALIBRATION))
    # the thumb seen from above is narrower than its breadth, and the wrist line
    # lies below the narrowest section: the corrections are needed and do something
    true = model_measurements(HandShape())
    assert raw.measurements.W[0] < 0.95 * true.W[0]
    assert raw.measurements.W[1] < 0.95 * true.W[1]
    assert raw.measurements.P_height < true.P_height - 0.8


def test_model_calibration_agrees_with_the_model():
    # two of the five scales MODEL_CALIBRATION averages over: agreement to the
    # scatter between scales (the wrist's narrowest section moves with the pixel grid)
    found = calibrate_on_model(mm_per_px=(0.25, 0.5))
    assert abs(found.wrist_offset_mm - MODEL_CALIBRATION.wrist_offset_mm) < 0.5
    assert abs(found.thumb_axis_shift - MODEL_CALIBRATION.thumb_axis_shift) < 0.01
    np.testing.assert_allclose(found.thumb_width_factors, MODEL_CALIBRATION.thumb_width_factors,
                               atol=0.015)
    assert abs(found.thumb_length_factor - MODEL_CALIBRATION.thumb_length_factor) < 0.01


def test_grey_and_mask_give_the_colour_result(standard, standard_result):
    import cv2

    dark = render_measurement_photo(HandShape(), mm_per_px=MM, background_rgb=(0.0, 0.0, 0.0))
    grey = measure_photo(cv2.cvtColor(dark.image, cv2.COLOR_BGR2GRAY), mm_per_px=MM)
    mask = measure_photo(standard.mask, mm_per_px=MM)
    ref = standard_result.selection.ratios
    for other in (grey, mask):
        diff = np.abs([getattr(other.selection.ratios, n) - getattr(ref, n) for n in RATIOS])
        assert np.all(diff < [0.005, 0.005, 0.005, 0.02]), diff


def test_grey_on_a_light_background_gives_the_colour_result(standard_result):
    import cv2

    light = render_measurement_photo(HandShape(), mm_per_px=MM, background_rgb=(0.9, 0.9, 0.9))
    grey = measure_photo(cv2.cvtColor(light.image, cv2.COLOR_BGR2GRAY), mm_per_px=MM)
    ref = standard_result.selection.ratios
    diff = np.abs([getattr(grey.selection.ratios, n) - getattr(ref, n) for n in RATIOS])
    assert np.all(diff < [0.005, 0.005, 0.005, 0.02]), diff


@pytest.mark.parametrize("background_rgb", [None, (0.3, 0.3, 0.3), (0.8, 0.8, 0.8)])
def test_grey_photo_on_a_background_like_the_hand_is_refused(background_rgb):
    # defect 3: the grey of the blue test background is that of the hand's shaded rim:
    # the rim was taken for background and every breadth came out ~2 mm too small
    # (width ratio 0.79 for 0.90), silently; as a JPEG, fingertips were lost
    import cv2

    kw = {} if background_rgb is None else {"background_rgb": background_rgb}
    photo = render_measurement_photo(HandShape(width=0.9), mm_per_px=MM, **kw)
    grey = cv2.cvtColor(photo.image, cv2.COLOR_BGR2GRAY)
    jpeg = cv2.imdecode(cv2.imencode(".jpg", grey)[1], cv2.IMREAD_UNCHANGED)
    for image in (grey, jpeg, cv2.cvtColor(grey, cv2.COLOR_GRAY2BGR)):
        with pytest.raises(InvalidInputError, match=r"a colour photo is needed: in this grey "
                                                    r"photo the background \(grey level \d+\)"):
            measure_photo(image, mm_per_px=MM)
    assert measure_photo(photo.image, mm_per_px=MM).selection.shape == HandShape(width=0.9)


def test_segmentation_is_the_true_silhouette(standard, standard_result):
    wrong = standard_result.mask ^ standard.mask
    assert wrong.sum() < 0.001 * standard.mask.sum()


def test_reference_card_gives_the_scale():
    photo = render_measurement_photo(HandShape(width=1.1), mm_per_px=MM, card=True)
    result = measure_photo(photo.image, reference_width_mm=85.60)
    assert result.scale_source == "reference"
    assert abs(result.mm_per_px - MM) < 0.005 * MM
    assert result.selection.shape == HandShape(width=1.1)
    assert result.reference_px.shape == (4, 2)


def test_result_serialises_and_annotates(tmp_path, standard, standard_result):
    import json

    data = json.loads(json.dumps(standard_result.as_dict()))
    assert data["selection"]["shape"] == HandShape().name
    assert len(data["diagnostics"]["fingers"]) == 5 and len(data["L"]) == 14
    for suffix in (".json", ".csv"):
        path = write_measurement_file(tmp_path / f"m{suffix}", standard_result.measurements)
        back = HandMeasurements.from_file(path)
        np.testing.assert_allclose(back.L, standard_result.measurements.L, atol=1e-3)
        assert abs(back.T_height - standard_result.measurements.T_height) < 1e-3
    pic = annotate_measurement(standard.image, standard_result)
    assert pic.shape == standard.image.shape and pic.dtype == np.uint8
    changed = np.any(pic != standard.image, axis=2)
    assert 0.005 < changed.mean() < 0.2
    with pytest.raises(InvalidInputError, match="not the measured photo"):
        annotate_measurement(standard.image[:100], standard_result)


# -- bad input ------------------------------------------------------------------------


@pytest.mark.parametrize("kwargs, words", [
    ({}, "exactly one of mm_per_px"),
    ({"mm_per_px": MM, "reference_width_mm": 85.6}, "exactly one of mm_per_px"),
    ({"mm_per_px": -1.0}, "mm_per_px"),
    ({"mm_per_px": float("nan")}, "mm_per_px"),
    ({"reference_width_mm": 85.6}, "no reference object"),
])
def test_scale_errors(standard, kwargs, words):
    with pytest.raises(InvalidInputError, match=words):
        measure_photo(standard.image, **kwargs)


def test_no_hand_and_bad_images():
    with pytest.raises(InvalidInputError, match="no hand found"):
        measure_photo(np.full((200, 300, 3), 90, np.uint8), mm_per_px=MM)
    speck = np.full((200, 300), 40, np.uint8)
    speck[90:110, 140:160] = 200
    with pytest.raises(InvalidInputError, match="no hand found"):
        measure_photo(speck, mm_per_px=MM)
    with pytest.raises(InvalidInputError, match="dtype"):
        measure_photo(np.zeros((200, 300), np.float32), mm_per_px=MM)
    with pytest.raises(InvalidInputError, match="shape"):
        measure_photo(np.zeros((200, 300, 4), np.uint8), mm_per_px=MM)


def test_two_hands_are_refused(standard):
    two = np.hstack([standard.image, standard.image[:, ::-1]])
    with pytest.raises(InvalidInputError, match="two hand-sized blobs"):
        measure_photo(two, mm_per_px=MM)


def test_hand_touching_the_border_is_refused(standard):
    # cut the picture through the fingers: the forearm may leave the photo, fingers may not
    tips_x = standard.keypoints_px[[8, 12, 16], 0]
    cut = standard.image[:, : int(tips_x.min()) - 20]
    with pytest.raises(InvalidInputError, match="border"):
        measure_photo(cut, mm_per_px=MM)
    thumb_y = standard.keypoints_px[4, 1]
    cut = standard.image[int(thumb_y) + 15:]
    with pytest.raises(InvalidInputError, match="border"):
        measure_photo(cut, mm_per_px=MM)


def test_reference_touching_the_border_is_refused():
    photo = render_measurement_photo(mm_per_px=MM, card=True)
    with pytest.raises(InvalidInputError, match="reference object .* touches"):
        measure_photo(photo.image[:-20], reference_width_mm=85.6)


def test_raised_thumb_is_refused():
    # "spread": the thumb is abducted out of the palm's plane and hidden under the palm
    photo = render_measurement_photo(mm_per_px=MM, angles=named_pose("spread"))
    with pytest.raises(InvalidInputError, match="thumb"):
        measure_photo(photo.image, mm_per_px=MM)


def test_fist_is_refused():
    photo = render_measurement_photo(mm_per_px=MM, angles=named_pose("fist"))
    with pytest.raises(InvalidInputError, match="fingertip"):
        measure_photo(photo.image, mm_per_px=MM)


@pytest.mark.parametrize("kwargs, word", [
    ({"tip_arc_mm": 0}, "tip_arc_mm"),
    ({"max_finger_width_mm": "wide"}, "max_finger_width_mm"),
    ({"normalize": "paper"}, "normalize"),
    ({"calibration": None}, "calibration"),
])
def test_options_validate(kwargs, word):
    with pytest.raises(InvalidInputError, match=word):
        MeasureOptions(**kwargs)


@pytest.mark.parametrize("kwargs, word", [
    ({"wrist_offset_mm": float("inf")}, "wrist_offset_mm"),
    ({"thumb_width_factors": (1.0,)}, "thumb_width_factors"),
    ({"thumb_length_factor": 3.0}, "thumb_length_factor"),
])
def test_calibration_validates(kwargs, word):
    with pytest.raises(InvalidInputError, match=word):
        MeasureCalibration(**kwargs)


def test_measure_pose_is_read_only_and_valid():
    from handsynth.models import as_angles

    assert not MEASURE_POSE.flags.writeable
    as_angles(MEASURE_POSE)


# -- the model shape: measured ratios corrected for the method -----------------------


def _shape_errors(shape_found, shape):
    return np.array([getattr(shape_found, n) - getattr(shape, n) for n in RATIOS])


def test_shape_correction_on_hands_it_was_not_fitted_on():
    # MODEL_SHAPE_CORRECTION was fitted on random hands of seed 1000; these are hand-made
    raw_total = corrected_total = 0.0
    for shape, roll in ((HandShape(length=0.97, width=1.04, palm=1.03, thumb=0.93), 30.0),
                        (HandShape(length=1.04, width=0.94, palm=0.97, thumb=1.07), -120.0)):
        photo = render_measurement_photo(shape, mm_per_px=0.25, roll_deg=roll)
        found = measure_photo(photo.image, mm_per_px=0.25)
        raw = measure_photo(photo.image, mm_per_px=0.25,
                            options=MeasureOptions(shape_correction=NO_SHAPE_CORRECTION))
        # without the correction the shape is the formulas' ratios, no normalisation
        assert raw.shape == select_shape(raw.measurements,
                                         options=SelectionOptions(normalize="none")).ratios
        err = _shape_errors(found.shape, shape)
        assert np.all(np.abs(err) < [0.006, 0.005, 0.005, 0.015]), err
        raw_total += np.abs(_shape_errors(raw.shape, shape)).sum()
        corrected_total += np.abs(err).sum()
        assert found.as_dict()["shape"]["name"] == found.shape.name
    assert corrected_total < 0.6 * raw_total, (corrected_total, raw_total)


def test_shape_correction_applies_its_matrix_and_validates():
    c = ShapeCorrection(coefficients=[[1, 0, 0, 0, 0.01], [0, 2, 0, 0, -1], [0, 0, 1, 0, 0],
                                      [0, 0, -0.5, 1, 0.5]])
    got = c.apply(HandShape(length=1.0, width=0.95, palm=1.04, thumb=1.1))
    assert got.as_dict() == pytest.approx({"length": 1.01, "width": 0.9, "palm": 1.04,
                                           "thumb": 1.08}, abs=1e-12)
    assert NO_SHAPE_CORRECTION.apply(HandShape(palm=1.037)) == HandShape(palm=1.037)
    for bad in ([[1, 0, 0, 0]] * 4, [[1, 0, 0, 0, float("nan")]] * 4, "matrix"):
        with pytest.raises(InvalidInputError, match="ShapeCorrection.coefficients"):
            ShapeCorrection(coefficients=bad)
    with pytest.raises(InvalidInputError, match="shape_correction"):
        MeasureOptions(shape_correction="none")
    with pytest.raises(InvalidInputError, match="HandShape.width"):
        c.apply(HandShape(width=1.6))  # 2 * 1.6 - 1 = 2.2: beyond the ratios a hand may have


@pytest.mark.slow
def test_fit_shape_correction_fits_what_it_measures():
    from handsynth.eval import random_hand_shapes

    shapes = random_hand_shapes(12, seed=7, margin=0.5)
    fitted = fit_shape_correction(shapes, mm_per_px=0.4, seed=3)
    # the committed correction's strongest terms show up in a fit on other hands:
    # the palm ratio is under-read (slope 1.11), and the hidden thumb CMC moves
    # with the palm (-0.45)
    m = np.array(fitted.coefficients)
    assert abs(m[2, 2] - MODEL_SHAPE_CORRECTION.coefficients[2][2]) < 0.1, m
    assert abs(m[3, 2] - MODEL_SHAPE_CORRECTION.coefficients[3][2]) < 0.25, m
    with pytest.raises(InvalidInputError, match="at least 10"):
        fit_shape_correction(shapes[:9])


def test_a_photo_can_be_given_as_the_path_of_its_image_file(tmp_path, standard, standard_result):
    import cv2

    png = tmp_path / "hand.png"
    assert cv2.imwrite(str(png), standard.image)  # BGR, lossless
    bgra = tmp_path / "hand_alpha.png"
    assert cv2.imwrite(str(bgra), cv2.cvtColor(standard.image, cv2.COLOR_BGR2BGRA))
    for path in (str(png), png, bgra):
        got = measure_photo(path, mm_per_px=MM)
        assert got.shape == standard_result.shape
        assert got.selection.ratios == standard_result.selection.ratios
        assert got.measurements == standard_result.measurements


def test_a_path_that_is_not_a_readable_image_is_named(tmp_path):
    missing = tmp_path / "no_such_hand.jpg"
    with pytest.raises(InvalidInputError, match=r"photo .*no_such_hand\.jpg.*no such file"):
        measure_photo(str(missing), mm_per_px=MM)
    text = tmp_path / "notes.png"
    text.write_text("not a picture")
    with pytest.raises(InvalidInputError, match=r"photo .*notes\.png"):
        measure_photo(text, mm_per_px=MM)
    with pytest.raises(InvalidInputError, match=r"photo .*"):
        measure_photo(tmp_path, mm_per_px=MM)  # a folder


@pytest.mark.parametrize("width", [-5.0, 0.0, float("nan")])
def test_a_bad_reference_width_is_named_before_the_photo_is_read(width):
    # before: a blank image gave "the reference object is ambiguous" instead
    blank = np.zeros((200, 300), np.uint8)
    with pytest.raises(InvalidInputError, match="reference_width_mm must be a finite number > 0"):
        measure_photo(blank, reference_width_mm=width)


@pytest.mark.parametrize("kwargs, named", [
    ({"mm_per_px": "0.5"}, "mm_per_px must be a finite number > 0 and <= 1000, got '0.5' (str)"),
    ({"mm_per_px": "12mm"}, "mm_per_px must be a finite number > 0 and <= 1000, got '12mm' (str)"),
    ({"mm_per_px": True}, "mm_per_px must be a finite number > 0 and <= 1000, got True (bool)"),
    ({"mm_per_px": [0.5]}, "mm_per_px must be a finite number > 0 and <= 1000, got [0.5] (list)"),
    ({"mm_per_px": 1e300}, "mm_per_px must be a finite number > 0 and <= 1000, got 1e+300"),
    ({"reference_width_mm": "85.6"},
     "reference_width_mm must be a finite number > 0 and <= 10000, got '85.6' (str)"),
    ({"reference_width_mm": np.True_},
     "reference_width_mm must be a finite number > 0 and <= 10000, got np.True_ (bool)"),
    ({"reference_width_mm": 1e308},
     "reference_width_mm must be a finite number > 0 and <= 10000, got 1e+308"),
])
def test_a_scale_that_is_not_a_number_is_refused_by_name(standard, kwargs, named):
    # before: float() read "0.5" and True as numbers and measured on; "12mm" said "a positive
    # number"; 1e300 mm/px overflowed (OverflowError traceback from the command line)
    import re

    with pytest.raises(InvalidInputError, match=f"^{re.escape(named)}$"):
        measure_photo(standard.image, **kwargs)
    assert measure_photo(standard.image, mm_per_px=np.float32(MM)).mm_per_px == MM  # numbers pass


@pytest.mark.parametrize("kwargs, named", [
    ({"tip_arc_mm": "22"}, "MeasureOptions.tip_arc_mm must be a finite number > 0, got '22' (str)"),
    ({"min_hand_area_mm2": True}, "MeasureOptions.min_hand_area_mm2 must be a finite number > 0, "
                                  "got True (bool)"),
])
def test_options_that_are_text_or_bool_are_refused_by_name(kwargs, named):
    import re

    with pytest.raises(InvalidInputError, match=f"^{re.escape(named)}$"):
        MeasureOptions(**kwargs)


@pytest.mark.parametrize("kwargs, named", [
    ({"wrist_offset_mm": "1.2"}, "MeasureCalibration.wrist_offset_mm must be a finite number, "
                                 "got '1.2' (str)"),
    ({"thumb_axis_shift": False}, "MeasureCalibration.thumb_axis_shift must be a finite number, "
                                  "got False (bool)"),
    ({"thumb_width_factors": ("1.1", "1.2")}, "MeasureCalibration.thumb_width_factors must be 2 "
                                              "numbers, got ('1.1', '1.2')"),
    ({"thumb_width_factors": "12"}, "MeasureCalibration.thumb_width_factors must be 2 numbers, "
                                    "got '12'"),
    ({"thumb_length_factor": "1.04"}, "MeasureCalibration.thumb_length_factor must be a finite "
                                      "number > 0.5 and < 2, got '1.04' (str)"),
])
def test_calibration_values_that_are_text_or_bool_are_refused_by_name(kwargs, named):
    import re

    with pytest.raises(InvalidInputError, match=f"^{re.escape(named)}$"):
        MeasureCalibration(**kwargs)


@pytest.mark.parametrize("call, named", [
    (lambda: render_measurement_photo(mm_per_px="0.4"), "mm_per_px must be a finite number > 0, "
                                                         "got '0.4' (str)"),
    (lambda: render_measurement_photo(size_mm=True), "size_mm must be a finite number > 0, "
                                                      "got True (bool)"),
    (lambda: render_measurement_photo(roll_deg="90"), "roll_deg must be a finite number, "
                                                       "got '90' (str)"),
    (lambda: calibrate_on_model(mm_per_px="0.25"), "mm_per_px must be a finite number > 0, "
                                                    "got '0.25' (str)"),
    (lambda: calibrate_on_model(mm_per_px=(0.25, "0.3")), "mm_per_px[1] must be a finite number "
                                                           "> 0, got '0.3' (str)"),
    (lambda: fit_shape_correction([HandShape()] * 10, mm_per_px=["0.25"]),
     "mm_per_px[0] must be a finite number > 0, got '0.25' (str)"),
])
def test_photo_scales_that_are_text_are_refused_before_any_render(call, named):
    # before: np.asarray(mm_per_px, float) and float() read the texts as numbers
    import re

    with pytest.raises(InvalidInputError, match=f"^{re.escape(named)}$"):
        call()


def test_write_measurement_file_names_what_is_not_measurements(tmp_path):
    # measurements=None was an AttributeError ('NoneType' object has no attribute 'as_dict')
    from handsynth.measure import write_measurement_file

    with pytest.raises(InvalidInputError, match="measurements must be a HandMeasurements, got NoneType"):
        write_measurement_file(tmp_path / "m.json", None)
    with pytest.raises(InvalidInputError, match="path must be a file name"):
        write_measurement_file(None, None)
    assert list(tmp_path.iterdir()) == []
