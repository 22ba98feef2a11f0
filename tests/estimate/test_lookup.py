"""PoseLookup: self-match from a rendered frame, no hand, garbage input, threads."""

from __future__ import annotations

import re
from concurrent.futures import ThreadPoolExecutor

import numpy as np
import pytest

import handsynth
from handsynth.errors import DatabaseError, InvalidInputError
from handsynth.estimate import (
    PoseEstimator,
    PoseLookup,
    SearchOptions,
    SelectionOptions,
    select_shape,
)
from handsynth.models import JOINT_NAMES, HandShape, model_measurements
from handsynth.render import CameraMount, SilhouetteRenderer

RENDER_SIZE = (180, 120)  # render size of the shared small database (tests/conftest.py)


@pytest.fixture(scope="module")
def lookup(db_folder):
    return PoseLookup.open(db_folder, shape=HandShape(length=1.02, thumb=0.97))


def test_top_level_export_and_protocol(lookup):
    assert handsynth.PoseLookup is PoseLookup
    assert isinstance(lookup, PoseEstimator)


def test_frame_rendered_from_an_entry_returns_that_entry(db_folder, small_rows):
    lookup = PoseLookup.open(db_folder, shape=HandShape(length=1.02, thumb=0.97), ties="first")
    r = SilhouetteRenderer(HandShape(), CameraMount(), width_px=RENDER_SIZE[0],
                           height_px=RENDER_SIZE[1])
    for i in (3, 50, 200):
        mask = r.mask(small_rows["angles"][i])
        # a BGR frame: bright hand on a dark background
        bgr = np.where(mask[..., None], np.uint8([120, 160, 210]), np.uint8([15, 20, 25]))
        for frame in (mask, bgr):
            est = lookup.estimate(frame)
            assert not est.no_hand and est.error == 0.0 and est.confidence == 1.0
            np.testing.assert_array_equal(est.angles, lookup.database.angles[est.entry])
            np.testing.assert_allclose(est.angles, small_rows["angles"][i], atol=1e-4) \
                if est.entry == i else None
            assert est.entry == i or (lookup.database.hlac[est.entry]
                                      == small_rows["hlac"][i]).all()
            assert est.keypoints.shape == (21, 3)
    assert list(est.as_row())[4:] == list(JOINT_NAMES)


def test_no_hand_frame_gives_no_hand(lookup):
    for frame in (np.zeros((480, 720, 3), np.uint8), np.zeros((120, 180), bool),
                  np.full((60, 90, 3), 77, np.uint8)):
        est = lookup.estimate(frame)
        assert est.no_hand and est.entry == -1 and np.isnan(est.angles).all()
        assert est.confidence == 0.0


def _specks() -> list[np.ndarray]:
    """Dark 720x480 views where what stands out covers less than 1 % of the frame."""
    pixel = np.zeros((480, 720, 3), np.uint8)
    pixel[200, 300] = 255  # one white pixel, on the Otsu sample's grid: it stands out
    blob = np.zeros((480, 720, 3), np.uint8)
    blob[200:204, 300:340] = (120, 160, 210)  # 160 pixels of skin, 0.05 % of the view
    under = np.zeros((480, 720), bool)
    under[150:198, 300:372] = True  # 48 x 72 = 3456 pixels: 1 % of the view ...
    under[150, 300] = False  # ... less one
    return [pixel, blob, under]


@pytest.mark.parametrize("calibrated", [False, True])
def test_a_speck_is_no_hand(lookup, query_rows, calibrated):
    # one white pixel in a dark 720x480 view was read as a hand (no_hand=False)
    from handsynth.estimate import MIN_HAND_COVERAGE
    from handsynth.render import preprocess

    if calibrated:
        lookup = lookup.calibrated(_device_frames(query_rows["silhouette"])[-1])
    for frame in _specks():
        assert preprocess(frame, lookup.mount).any()  # it stands out, and the wrist cut keeps it
        est = lookup.estimate(frame)
        assert est.no_hand and est.entry == -1 and np.isnan(est.angles).all(), frame.dtype
        assert np.isnan(est.keypoints).all() and est.confidence == 0.0
        assert not lookup.silhouette(frame).any()
    at_limit = np.zeros((480, 720), bool)
    at_limit[150:198, 300:372] = True  # 3456 pixels: exactly MIN_HAND_COVERAGE of the view
    assert at_limit.sum() == MIN_HAND_COVERAGE * at_limit.size
    assert not lookup.estimate(at_limit).no_hand
    if calibrated:
        with pytest.raises(InvalidInputError, match="open_frame shows no hand"):
            lookup.calibrated(_specks()[0])


def test_the_smallest_hand_in_a_fist_covers_far_more_than_the_lookups_least():
    # what the lookup keeps of a database entry (its largest component after the wrist cut)
    # of the smallest modelled hand, every ratio 0.5, in the most folded poses
    from handsynth.estimate import MIN_HAND_COVERAGE
    from handsynth.models import named_pose
    from handsynth.render import SilhouetteRasterizer, preprocess

    mount = CameraMount.paper()
    r = SilhouetteRasterizer(HandShape(length=0.5, width=0.5, palm=0.5, thumb=0.5), mount)
    for m in r.masks(np.array([named_pose(n) for n in ("fist", "grasp", "pinch")])):
        assert preprocess(m, mount, min_coverage=6 * MIN_HAND_COVERAGE).any()


@pytest.mark.parametrize(
    "frame, match",
    [
        (np.zeros((1, 1, 3), np.uint8), "at least 8x8"),
        (np.full((64, 64), np.nan), "NaN"),
        (np.zeros((64, 64), np.float32), "dtype float32"),
        (np.zeros((64, 64), np.int64), "dtype int64"),
        (np.zeros((64, 64, 4), np.uint8), "shape"),
        ([[0, 1]], "numpy array"),
    ],
)
def test_garbage_input_raises_a_clear_error(lookup, frame, match):
    with pytest.raises(InvalidInputError, match=match):
        lookup.estimate(frame)


def test_open_by_measurements_and_missing_database(db_folder, tmp_path):
    lk = PoseLookup.open(db_folder, measurements=model_measurements(HandShape(width=1.03)))
    assert lk.shape == HandShape() and len(lk) == 240
    with pytest.raises(DatabaseError, match="L1.050"):
        PoseLookup.open(db_folder, shape=HandShape(length=1.05))
    with pytest.raises(DatabaseError, match="does not exist"):
        PoseLookup.open(tmp_path / "nope")


def _device_frames(silhouettes) -> list[np.ndarray]:
    """64x64 silhouettes as frames of the device's 3:2 view (black columns either side): a
    lookup refuses frames of another width-to-height ratio."""
    return [np.pad(s, ((0, 0), (16, 16))) for s in silhouettes]


@pytest.mark.parametrize("calibrated", [False, True])
def test_threads_share_one_lookup(lookup, query_rows, calibrated):
    frames = _device_frames(query_rows["silhouette"])
    if calibrated:
        lookup = lookup.calibrated(frames[-1])
    serial = [lookup.estimate(f) for f in frames]
    with ThreadPoolExecutor(4) as pool:
        parallel = list(pool.map(lookup.estimate, frames * 3))
    assert [e.entry for e in parallel] == [e.entry for e in serial] * 3
    np.testing.assert_array_equal(np.stack([e.angles for e in parallel]),
                                  np.stack([e.angles for e in serial] * 3))


def test_in_memory_rows(small_rows):
    lk = PoseLookup.from_rows(small_rows)
    r = SilhouetteRenderer(width_px=RENDER_SIZE[0], height_px=RENDER_SIZE[1])
    est = lk.estimate(r.mask(small_rows["angles"][9]))
    assert est.error == 0.0 and not est.low_confidence


def test_equally_good_entries_report_their_mean_pose(small_rows):
    # entry 9 repeated twice with other angles: the three match the frame equally well
    index = np.concatenate([np.arange(len(small_rows["angles"])), [9, 9]])
    rows = {k: np.asarray(v)[index] for k, v in small_rows.items()}
    rows["angles"] = rows["angles"].copy()
    rows["angles"][-2:] = small_rows["angles"][[20, 30]]  # other poses, within joint limits
    r = SilhouetteRenderer(width_px=RENDER_SIZE[0], height_px=RENDER_SIZE[1])
    mask = r.mask(small_rows["angles"][9])
    mean = PoseLookup.from_rows(rows).estimate(mask)
    first = PoseLookup.from_rows(rows, ties="first").estimate(mask)
    assert mean.entry == first.entry == 9 and mean.error == 0.0
    np.testing.assert_allclose(first.angles, rows["angles"][9])
    same = np.flatnonzero((rows["hlac"] == rows["hlac"][9]).all(1)
                          & (rows["sil_bits"] == rows["sil_bits"][9]).all(1)
                          & (rows["ridge_bits"] == rows["ridge_bits"][9]).all(1))
    assert {9, len(index) - 2, len(index) - 1} <= set(same.tolist())
    np.testing.assert_allclose(mean.angles, rows["angles"][same].mean(axis=0), atol=1e-4)
    assert not np.allclose(mean.angles, first.angles)
    with pytest.raises(InvalidInputError, match="ties"):
        PoseLookup.from_rows(rows, ties="median")


def test_approximate_lookup_probing_every_cell_equals_exact(db_folder, query_rows):
    from handsynth.estimate._ann import ApproximateOptions

    exact = PoseLookup.open(db_folder, shape=HandShape())
    approx = PoseLookup.open(db_folder, shape=HandShape(),
                             approximate=ApproximateOptions(nlist=8, nprobe=8, dims=16))
    assert approx.approximate is not None and exact.approximate is None
    for sil in _device_frames(query_rows["silhouette"][:8]):
        a, b = exact.estimate(sil), approx.estimate(sil)
        assert (a.entry, a.error, a.low_confidence) == (b.entry, b.error, b.low_confidence)
    with pytest.raises(InvalidInputError, match="approximate"):
        PoseLookup(exact.database, approximate="ivf")


def test_personal_database_is_built_once_for_the_hands_own_shape(tmp_path):
    from handsynth.db import BuildOptions

    shape = HandShape(length=1.0234, width=0.9712, palm=1.01, thumb=1.03)
    own = HandShape.from_name(shape.name)  # ratios to the 0.001 of the file name
    build = BuildOptions(count=60, render_size=(180, 120))
    lookup = PoseLookup.personal(tmp_path, shape=shape, build=build, workers=1)
    path = tmp_path / "L1.023_W0.971_P1.010_T1.030.h5"
    assert lookup.database.path == path and len(lookup) == 60 and lookup.shape == own
    built = path.stat().st_mtime_ns
    again = PoseLookup.personal(tmp_path, shape=own, build=build, workers=1)  # reused
    assert again.database.path == path and path.stat().st_mtime_ns == built
    # from millimetres: the ratios of formulas (1)-(4) without normalisation, no grid
    by_mm = PoseLookup.personal(tmp_path, measurements=model_measurements(own), build=build,
                                workers=1)
    ratios = select_shape(model_measurements(own), options=SelectionOptions(normalize="none"))
    assert by_mm.database.path == tmp_path / f"{ratios.ratios.name}.h5"
    assert by_mm.shape.name == ratios.ratios.name != ratios.shape.name
    mask = np.zeros((120, 180), bool)
    mask[40:80, 20:150] = True
    assert not again.estimate(mask).no_hand
    for kwargs, words in (({}, "exactly one"),
                          ({"shape": own, "measurements": model_measurements(own)}, "exactly one"),
                          ({"shape": "L1.000_W1.000_P1.000_T1.000"}, "shape must be a HandShape"),
                          ({"measurements": {"L": 1}}, "measurements must be HandMeasurements"),
                          ({"shape": own, "build": {"count": 5}}, "build must be a BuildOptions")):
        with pytest.raises(InvalidInputError, match=words):
            PoseLookup.personal(tmp_path, **kwargs)


def _open_frame() -> np.ndarray:
    r = SilhouetteRenderer(width_px=RENDER_SIZE[0], height_px=RENDER_SIZE[1])
    return r.mask(np.zeros(len(JOINT_NAMES)))


def test_defaults_are_the_natural_choice_of_each_mode(db_folder):
    from handsynth.estimate import ApproximateOptions

    exact = PoseLookup.open(db_folder, shape=HandShape())
    assert (exact.ties, exact.temporal) == ("mean", True)
    approx = PoseLookup.open(db_folder, shape=HandShape(),
                             approximate=ApproximateOptions(nlist=8, nprobe=8, dims=16))
    assert (approx.ties, approx.temporal) == ("first", True)
    calibrated = exact.calibrated(_open_frame())
    assert (calibrated.ties, calibrated.temporal) == ("mean", False)
    # temporal=False is what a calibrated lookup does anyway: accepted
    quiet = PoseLookup.open(db_folder, shape=HandShape(), temporal=False, ties="first")
    assert quiet.calibrated(_open_frame()).ties == "first"


@pytest.mark.parametrize("approximate", [True, "options"])
def test_ties_mean_with_the_approximate_index_is_refused(db_folder, approximate):
    from handsynth.estimate import ApproximateOptions

    if approximate == "options":
        approximate = ApproximateOptions(nlist=8, nprobe=8, dims=16)
    before = sorted(p.name for p in db_folder.iterdir())
    with pytest.raises(InvalidInputError,
                       match=r"ties='mean' cannot be honoured by the approximate index.*"
                             r"pass ties='first'"):
        PoseLookup.open(db_folder, shape=HandShape(), ties="mean", approximate=approximate)
    assert sorted(p.name for p in db_folder.iterdir()) == before  # refused before building


@pytest.mark.parametrize("kwargs, words", [
    ({"options": SearchOptions(c=0.1)},
     r"options=SearchOptions\(c=0.1, .*\) cannot be honoured by a calibrated lookup"),
    ({"options": SearchOptions()}, r"options=SearchOptions\(.*\) cannot be honoured"),
    ({"temporal": True}, r"temporal=True cannot be honoured by a calibrated lookup.*"
                         r"pass temporal=False"),
])
def test_calibrating_a_lookup_with_search_options_or_a_seed_is_refused(db_folder, kwargs, words):
    lookup = PoseLookup.open(db_folder, shape=HandShape(), **kwargs)
    with pytest.raises(InvalidInputError, match=words):
        lookup.calibrated(_open_frame())
    assert lookup.calibration is None


@pytest.mark.parametrize("kwargs, words", [
    ({"options": SearchOptions(c4=10.0)}, r"options=SearchOptions\(.*c4=10.0.*\) cannot be"),
    ({"temporal": True}, r"temporal=True cannot be honoured by a calibrated lookup"),
    ({"approximate": True}, r"needs the exact search, got approximate=True"),
])
def test_from_open_frame_refuses_what_it_cannot_honour_before_building(tmp_path, kwargs, words):
    with pytest.raises(InvalidInputError, match=words):
        PoseLookup.from_open_frame(tmp_path / "dbs", _open_frame(), shapes=[HandShape()],
                                   **kwargs)
    assert not (tmp_path / "dbs").exists()  # nothing was built


def test_mode_arguments_are_checked(small_rows):
    with pytest.raises(InvalidInputError, match=r"temporal must be True, False or None, got 'y"):
        PoseLookup.from_rows(small_rows, temporal="yes")
    with pytest.raises(InvalidInputError, match=r"ties must be 'mean', 'first' or None"):
        PoseLookup.from_rows(small_rows, ties="last")


def test_from_rows_checks_the_rows_as_write_database_does(small_rows):
    rows = {k: small_rows[k] for k in ("angles", "hlac", "sil_bits", "ridge_bits", "ridge_area",
                                       "keypoints")}
    mm = dict(rows, keypoints=rows["keypoints"] * 1000)  # millimetres: would overflow int16
    with pytest.raises(InvalidInputError, match=r"keypoints must lie within \+/-0\.32767 m"):
        PoseLookup.from_rows(mm)
    angles = rows["angles"].copy()
    angles[4, 7] = np.nan
    with pytest.raises(InvalidInputError, match=r"angles must be finite, got nan at index \(4, 7\)"):
        PoseLookup.from_rows(dict(rows, angles=angles))
    with pytest.raises(InvalidInputError, match=r"hlac must have shape \(10, 1600\), got .*\(240, "):
        PoseLookup.from_rows(dict(rows, angles=rows["angles"][:10]))
    with pytest.raises(InvalidInputError, match=r"rows must have the keys .*; missing hlac"):
        PoseLookup.from_rows({k: v for k, v in rows.items() if k != "hlac"})
    with pytest.raises(InvalidInputError, match=r"rows must be a mapping of arrays, got list"):
        PoseLookup.from_rows([rows])
    with pytest.raises(InvalidInputError, match=r"side must be 'right' or 'left', got 'Right'"):
        PoseLookup.from_rows(rows, side="Right")
    # valid rows: the same arrays as before the check
    lk = PoseLookup.from_rows(rows)
    assert np.array_equal(lk.database.keypoints_raw,
                          np.rint(rows["keypoints"] / 1e-5).astype(np.int16))
    assert np.array_equal(lk.database.angles, rows["angles"].astype(np.float32))


def test_open_checks_the_stored_hand_against_the_one_asked_for(tmp_path, db_folder, small_rows):
    from handsynth.db import database_meta, open_database, write_database
    from handsynth.errors import DatabaseMismatchError

    stored = ("angles", "hlac", "sil_bits", "ridge_bits", "ridge_area", "keypoints")
    rows = {k: small_rows[k] for k in stored}

    def write(name, shape, side):
        meta = database_meta(shape, CameraMount(), side=side, pose_set="paper", count=240,
                             seed=1, render_size=RENDER_SIZE)
        write_database(tmp_path / name, meta=meta, **rows)

    # a shape 0.0004 off under the standard hand's name (made before builds refused it)
    write(f"{HandShape().name}.h5", HandShape(length=1.0004), "right")
    with pytest.raises(DatabaseMismatchError, match=r"holds the right hand \(length=1.0004.*\) "
                                                    r"but the right hand \(length=1.0.*\) was"):
        PoseLookup.open(tmp_path, shape=HandShape())
    # a left hand's file under the right hand's name
    write(f"{HandShape().name}.h5", HandShape(), "left")
    with pytest.raises(DatabaseMismatchError, match=r"holds the left hand .* but the right hand"):
        PoseLookup.open(tmp_path, shape=HandShape())
    # the left hand's own file
    (tmp_path / f"{HandShape().name}.h5").rename(tmp_path / f"{HandShape().name}_left.h5")
    left = PoseLookup.open(tmp_path, shape=HandShape().name, side="left")
    assert left.side == "left" and left.shape == HandShape()
    with pytest.raises(DatabaseError, match=r"no database for the right hand"):
        PoseLookup.open(tmp_path, shape=HandShape())
    # the right hand's file of the shared fixture opens as before
    assert PoseLookup.open(db_folder, shape=HandShape()).shape == HandShape()
    assert open_database(tmp_path / f"{HandShape().name}_left.h5").meta["side"] == "left"


def _scaled(frame: np.ndarray, width: int, height: int) -> np.ndarray:
    """`frame` resized to `width` x `height` (nearest pixel): stretched unless the ratio is kept."""
    rows = np.arange(height) * frame.shape[0] // height
    cols = np.arange(width) * frame.shape[1] // width
    return frame[rows][:, cols]


def test_a_frame_of_another_width_to_height_ratio_is_refused_with_its_size(lookup, small_rows):
    # a portrait 480x720 frame or a 4:3 webcam frame for the 720x480 mount was stretched
    # silently (confidence down, low_confidence still False); the learnt estimator's rule
    r = SilhouetteRenderer(HandShape(), CameraMount(), width_px=RENDER_SIZE[0],
                           height_px=RENDER_SIZE[1])
    mask = r.mask(small_rows["angles"][50])
    assert lookup.estimate(mask).error == 0.0
    bgr = np.where(mask[..., None], np.uint8([120, 160, 210]), np.uint8([15, 20, 25]))
    for width, height in ((120, 180), (160, 120), (640, 480), (480, 720)):
        for frame in (_scaled(mask, width, height), _scaled(bgr, width, height)):
            with pytest.raises(InvalidInputError,
                               match=rf"^frame is {width}x{height} pixels; this lookup's database "
                                     r"holds the device's 720x480 view: give frames of that "
                                     r"width-to-height ratio \(scaled, not cropped\)$"):
                lookup.estimate(frame)
    # any size of the device's ratio is the same view: masks and camera frames alike
    for width, height in ((90, 60), (360, 240), (720, 480), (181, 120)):
        for frame in (_scaled(mask, width, height), _scaled(bgr, width, height)):
            est = lookup.estimate(frame)
            assert not est.no_hand and est.confidence > 0.3
    with pytest.raises(InvalidInputError, match=r"frame is 120x180 pixels"):
        lookup.calibrated(_scaled(_open_frame(), 120, 180))


def test_from_open_frame_refuses_a_frame_of_another_ratio_before_building(tmp_path):
    with pytest.raises(InvalidInputError, match=r"^frame is 160x120 pixels; .* 720x480 view"):
        PoseLookup.from_open_frame(tmp_path / "dbs", _scaled(_open_frame(), 160, 120),
                                   shapes=[HandShape()])
    assert not (tmp_path / "dbs").exists()  # nothing was built


def test_from_open_frame_refuses_a_speck_before_building(tmp_path):
    # one white pixel was upscaled to a 64x64 block and taken for a hand to choose a shape by
    for frame in _specks():
        with pytest.raises(InvalidInputError, match=r"^open_frame shows no hand: nothing stands "
                                                    r"out, or what does covers less than 1 % of "
                                                    r"the view \(MIN_HAND_COVERAGE\)$"):
            PoseLookup.from_open_frame(tmp_path / "dbs", frame, shapes=[HandShape()])
    assert not (tmp_path / "dbs").exists()  # nothing was built


@pytest.mark.parametrize("folder, words", [
    (None, "folder must be a folder name (str or path), got None"),
    (7, "folder must be a folder name (str or path), got int 7"),
    ("", "folder must name a folder, got ''"),
])
def test_open_names_a_folder_that_is_no_name(folder, words):
    # None gave pathlib's "expected str, bytes or os.PathLike object, not NoneType"
    with pytest.raises(InvalidInputError, match=re.escape(words)):
        PoseLookup.open(folder)


def test_arguments_that_the_lookup_does_not_take_are_named_with_the_method(db_folder, small_rows,
                                                                        tmp_path):
    # "PoseLookup.__init__() got an unexpected keyword argument 'mount'"
    with pytest.raises(InvalidInputError,
                       match=r"^PoseLookup\.open\(\) got an unexpected keyword argument 'mount'"):
        PoseLookup.open(db_folder, mount=CameraMount())
    with pytest.raises(InvalidInputError, match=r"^PoseLookup\.from_rows\(\) got an unexpected "
                                                r"keyword argument 'temporl'"):
        PoseLookup.from_rows(small_rows, temporl=False)
    with pytest.raises(InvalidInputError, match=r"^PoseLookup\.personal\(\) got an unexpected "
                                                r"keyword argument 'count'"):
        PoseLookup.personal(tmp_path / "dbs", shape=HandShape(), count=10)
    with pytest.raises(InvalidInputError, match=r"^PoseLookup\.from_open_frame\(\) got an "
                                                r"unexpected keyword argument 'side'"):
        PoseLookup.from_open_frame(tmp_path / "dbs", _open_frame(), side="left")
    assert not (tmp_path / "dbs").exists()  # refused before building
    assert PoseLookup.open(db_folder, ties="first", temporal=False).ties == "first"
