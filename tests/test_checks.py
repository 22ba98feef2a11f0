import pytest

from handsynth._checks import check_side
from handsynth.errors import InvalidCameraError, InvalidInputError


def test_a_side_is_right_or_left_and_named_otherwise():
    assert check_side("right") == "right" and check_side("left") == "left"
    with pytest.raises(InvalidInputError, match=r"^side must be 'right' or 'left', got 'Right'$"):
        check_side("Right")
    with pytest.raises(InvalidCameraError, match=r"^EvalOptions.side must be .*got None$"):
        check_side(None, name="EvalOptions.side", error=InvalidCameraError)


@pytest.mark.parametrize("mount", [0, "", False, [], "paper"])
def test_every_layer_refuses_a_mount_that_is_not_a_camera_mount_falsy_ones_too(mount, tmp_path):
    # `mount or CameraMount()` once read a falsy value (0, "", []) as the paper's device
    import numpy as np

    from handsynth.db import build_databases
    from handsynth.estimate import select_shape_from_frame
    from handsynth.eval import model_test_hands
    from handsynth.models import HandShape
    from handsynth.render import fit_skin_colour, palm_region, preprocess

    frame = np.zeros((480, 720, 3), np.uint8)
    frame[200:300, 300:400] = 200
    calls = {
        "render.preprocess": lambda: preprocess(frame, mount),
        "render.palm_region": lambda: palm_region(mount),
        "render.fit_skin_colour": lambda: fit_skin_colour(frame, mount),
        "db.build_databases": lambda: build_databases(tmp_path, [HandShape()], mount),
        "estimate.select_shape_from_frame": lambda: select_shape_from_frame(frame, mount=mount),
        "eval.model_test_hands": lambda: model_test_hands(1, mount=mount),
    }
    for where, call in calls.items():
        with pytest.raises(InvalidCameraError, match=rf"^mount must be a CameraMount, got "
                                                     rf"{type(mount).__name__} "):
            call()
        assert not any(tmp_path.iterdir()), where  # refused before anything was written


def test_options_are_checked_to_be_the_options_class_and_none_is_the_defaults():
    from dataclasses import dataclass

    from handsynth._checks import check_options

    @dataclass(frozen=True)
    class Options:
        k: int = 3

    assert check_options(None, Options) == Options()
    given = Options(k=5)
    assert check_options(given, Options) is given
    with pytest.raises(InvalidInputError, match=r"^options must be an Options, got dict \{\} "
                                                r"\(make one: Options\(\*\*fields\)\)$"):
        check_options({}, Options)  # not the defaults: a dict of fields is not options
    with pytest.raises(InvalidCameraError, match=r"^selection must be an Options, got str "):
        check_options("x" * 100, Options, name="selection", error=InvalidCameraError)


@pytest.mark.parametrize("bad", [{}, {"k": 3}, "fast", 0])
def test_every_options_argument_refuses_what_is_not_its_class(bad):
    # `options or XOptions()` once read {} or 0 as the defaults, and a dict of fields
    # failed later with an AttributeError
    import numpy as np

    from handsynth.estimate import OneEuroFilter, one_euro, select_shape
    from handsynth.eval import run_protocol
    from handsynth.models import model_measurements
    from handsynth.sensors import glove, imu

    calls = {
        "OneEuroFilter": lambda: OneEuroFilter(30.0, options=bad),
        "one_euro": lambda: one_euro(np.zeros((3, 2)), rate_hz=30.0, options=bad),
        "select_shape": lambda: select_shape(model_measurements(), options=bad),
        "run_protocol": lambda: run_protocol([object()], [], options=bad),
        "glove evaluate": lambda: glove.evaluate(options=bad),
        "glove calibrate": lambda: glove.calibrate(object(), options=bad),
        "gated_orientation": lambda: imu.gated_orientation(object(), bad),
    }
    for where, call in calls.items():
        with pytest.raises(InvalidInputError, match=rf"^options must be an? \w+Options, got "
                                                    rf"{type(bad).__name__} "):
            call()
            pytest.fail(f"{where} took options={bad!r}")


def test_numbers_are_finite_real_numbers_within_bounds_and_named_otherwise():
    import numpy as np

    from handsynth._checks import check_integer, check_number

    for v in (2, 2.5, np.float32(2.5), np.int64(2), np.array(2.5)):
        assert check_number(v, "x", above=0) == float(v)
        assert type(check_number(v, "x")) is float
    assert check_number(None, "x", allow_none=True) is None
    for v, words in ((True, r"got True \(bool\)"), ("2", r"got '2' \(str\)"),
                     (None, r"got None \(NoneType\)"), ([2], r"got \[2\] \(list\)"),
                     (float("nan"), "got nan$"), (np.inf, "got inf$"), (0, "got 0$")):
        with pytest.raises(InvalidInputError, match=rf"^fps must be a finite number > 0, {words}"):
            check_number(v, "fps", above=0)
    with pytest.raises(InvalidInputError, match=r"^x must be a finite number >= 0 and < 1, got 1$"):
        check_number(1, "x", minimum=0, below=1)
    assert check_integer(np.int32(3), "n", minimum=1) == 3
    assert type(check_integer(np.int32(3), "n")) is int
    for v in (2.0, True, "3", None):  # a count is not a measurement
        with pytest.raises(InvalidInputError, match=r"^n must be an integer >= 1 and <= 5, got "):
            check_integer(v, "n", minimum=1, maximum=5)
    with pytest.raises(InvalidCameraError, match=r"^n must be an integer >= 1, got 0$"):
        check_integer(0, "n", minimum=1, error=InvalidCameraError)


def test_an_integer_too_large_for_a_float_is_not_finite():
    from handsynth._checks import check_number

    with pytest.raises(InvalidInputError, match=r"^x must be a finite number, got 1000"):
        check_number(10 ** 400, "x")


def test_a_long_value_is_cut_in_messages():
    from handsynth._checks import short_repr

    assert short_repr("ab") == "'ab'"
    assert short_repr("x" * 100, 10) == "'xxxxxx..." and len(short_repr("x" * 100)) == 60


def test_what_is_a_number():
    import numpy as np

    from handsynth._checks import is_number

    assert all(is_number(v) for v in (1, 2.5, np.float32(1), np.int8(3), np.array(2.0), np.nan))
    assert not any(is_number(v) for v in (True, np.bool_(False), "1", b"1", None, [1], np.ones(2)))


def test_an_instance_of_the_wrong_class_is_named_with_its_value():
    from handsynth._checks import check_instance
    from handsynth.errors import InvalidShapeError
    from handsynth.models import HandModel, HandShape
    from handsynth.sensors.imu import ChainEKF

    shape = HandShape()
    assert check_instance(shape, HandShape, name="shape") is shape
    with pytest.raises(InvalidInputError, match=r"^data must be an? HandShape, got dict \{\}$"):
        check_instance({}, HandShape, name="data")
    with pytest.raises(InvalidShapeError, match=r"^shape must be a HandShape, got str 'L1\.0'$"):
        HandModel("L1.0")
    with pytest.raises(InvalidInputError, match=r"^ChainEKF\.model must be a ChainModel, got "
                                                r"NoneType None$"):
        ChainEKF(model=None)


@pytest.mark.parametrize("bad", [0, "", {}])
def test_a_falsy_shape_or_placement_is_refused_not_read_as_the_default(bad):
    # `shape or HandShape()` once read 0, "" or {} as the standard hand
    from handsynth.db import build_database
    from handsynth.measure import render_measurement_photo
    from handsynth.models import model_measurements
    from handsynth.sensors.imu import ImuHand

    calls = {
        "model_measurements": (lambda: model_measurements(bad), "shape must be a HandShape"),
        "build_database": (lambda: build_database("/nonexistent/never-made", bad),
                           "shape must be a HandShape"),
        "ImuHand shape": (lambda: ImuHand(bad), "shape must be a HandShape"),
        "ImuHand placement": (lambda: ImuHand(placement=bad), "placement must be an ImuPlacement"),
        "render_measurement_photo": (lambda: render_measurement_photo(bad),
                                     "shape must be a HandShape"),
    }
    for where, (call, message) in calls.items():
        with pytest.raises(InvalidInputError, match=rf"^{message}, got {type(bad).__name__} "):
            call()
            pytest.fail(f"{where} took {bad!r}")


def test_an_empty_or_blank_path_name_is_refused_by_name():
    from pathlib import Path

    from handsynth._checks import check_path_names
    from handsynth.errors import OutputError

    check_path_names([("--out", "rows.csv"), ("--json", None), ("path", Path("x"))])
    with pytest.raises(InvalidInputError, match=r"^--out must name a folder, got ''$"):
        check_path_names([("--db", "dbs"), ("--out", "")], kind="folder")
    with pytest.raises(OutputError, match=r"^out must name a file, got ' '$"):
        check_path_names([("out", " ")], error=OutputError)


def test_a_path_argument_must_be_a_name():
    from pathlib import Path

    from handsynth._checks import check_path

    assert check_path("a.csv", "path") == Path("a.csv")
    assert check_path(Path("dbs"), "folder", kind="folder") == Path("dbs")
    with pytest.raises(InvalidInputError, match=r"^path must be a file name \(str or path\), got None$"):
        check_path(None, "path")
    with pytest.raises(InvalidInputError, match=r"^folder must be a folder name .*, got int 3$"):
        check_path(3, "folder", kind="folder")
    with pytest.raises(InvalidInputError, match="got bytes"):
        check_path(b"a.csv", "path")
    with pytest.raises(InvalidInputError, match=r"^path must name a file, got ''$"):
        check_path("", "path")
