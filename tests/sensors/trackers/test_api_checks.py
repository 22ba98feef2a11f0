"""Argument checks of the public API: units, labels, numbers, shapes, copies."""

import copy
import dataclasses
import pickle

import numpy as np
import pytest

from handsynth.errors import InvalidInputError
from handsynth.sensors.trackers import (
    NO_NOISE,
    ArcJoint,
    AxisAngleFilter,
    FieldDistortion,
    FingerJoint,
    FlexionMotion,
    OBrienEstimator,
    PlaneVarianceEstimator,
    Recording,
    ScoreEstimator,
    SensorMount,
    SensorNoise,
    assess_determinability,
    foot_of_perpendicular,
    linear_centre,
    plane_coordinates,
    read_polhemus,
    save_recording,
    segment_length_mm,
    segment_lengths_mm,
    simulate_recording,
)

# --------------------------------------------------------------------------
# segment lengths: units and labels


@pytest.fixture(scope="module")
def pip_dip():
    """O'Brien estimates of index PIP and DIP sharing the sensor on index_middle."""
    mount = SensorMount(pitch_deg=10.0)
    kw = dict(model="hinge", noise=NO_NOISE, geometry_source="table",
              motion=FlexionMotion(duration_s=4.0, wobble_deg=0.0), seed=0)
    pip = simulate_recording("index_pip", lower_mount=mount, **kw)
    dip = simulate_recording("index_dip", upper_mount=mount, **kw)
    return OBrienEstimator().estimate(pip), OBrienEstimator().estimate(dip)


def test_tip_in_millimetres_refused_with_unit_hint(pip_dip):
    rp, rd = pip_dip
    tip_m = rd.centre_lower + np.array([0.0, 0.015, 0.0])
    ok = segment_lengths_mm([rp, rd], tips={"index_distal": tip_m})
    assert 10 < ok[4] < 40  # index distal, L5
    with pytest.raises(InvalidInputError, match=r"tips\['index_distal'\].*metres"):
        segment_lengths_mm([rp, rd], tips={"index_distal": [0.0, 15.0, 0.0]})
    with pytest.raises(InvalidInputError, match=r"tips\['index_distal'\]"):
        segment_lengths_mm([rp, rd], tips={"index_distal": "0 0.015 0"})


def test_centres_in_millimetres_refused(pip_dip):
    rp, rd = pip_dip
    rd_mm = dataclasses.replace(rd, centre_upper=rd.centre_upper * 1e3)
    with pytest.raises(InvalidInputError, match="index_middle.*metres"):
        segment_length_mm(rp, rd_mm)
    with pytest.raises(InvalidInputError, match="metres"):
        segment_lengths_mm([rp, rd_mm])


@pytest.mark.parametrize("labels", [("upper", "lower"), ("Index_middle", "index_distal")])
def test_labels_that_are_not_segments_refused(pip_dip, labels):
    rp, rd = pip_dip
    bad = dataclasses.replace(rd, labels=labels)
    with pytest.raises(InvalidInputError, match=r"results\[1\].*not segment names.*index_middle"):
        segment_lengths_mm([rp, bad])


def test_palm_is_a_known_upper_label(pip_dip):
    rp, _ = pip_dip
    mcp = dataclasses.replace(rp, labels=("palm", "index_proximal"))
    assert np.isnan(segment_lengths_mm([mcp])).all()


# --------------------------------------------------------------------------
# Recording: pickle and deep copy


def _assert_same(a: Recording, b: Recording) -> None:
    for name in ("times", "positions", "rotations"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name))
        assert not getattr(b, name).flags.writeable
    assert (a.labels, a.joint, dict(a.metadata)) == (b.labels, b.joint, dict(b.metadata))
    assert (a.truth is None) == (b.truth is None)
    if a.truth is not None:
        for name in ("centre_world", "centre_sensor", "reference_centre"):
            np.testing.assert_array_equal(getattr(a.truth, name), getattr(b.truth, name))
            assert not getattr(b.truth, name).flags.writeable
        assert a.truth.joint_kind == b.truth.joint_kind


@pytest.mark.parametrize("clone", [lambda r: pickle.loads(pickle.dumps(r)), copy.deepcopy,
                                   copy.copy], ids=["pickle", "deepcopy", "copy"])
def test_recording_pickles_and_copies(finger_rec, clone):
    other = clone(finger_rec)
    _assert_same(finger_rec, other)
    assert other == finger_rec and other.truth == finger_rec.truth
    assert other != finger_rec.take(np.arange(50))
    assert other.metadata  # simulations carry provenance
    with pytest.raises(TypeError):
        other.metadata["noise"] = "none"  # type: ignore[index]
    plain = Recording(finger_rec.times, finger_rec.positions, finger_rec.rotations,
                      metadata={"source": "x.csv"})
    _assert_same(plain, clone(plain))
    assert clone(plain) == plain


# --------------------------------------------------------------------------
# numeric options


def test_numpy_numbers_accepted_and_stored_as_python_numbers():
    e = OBrienEstimator(warn_error_mm=np.float32(2.0), min_frames=np.int64(30),
                        refuse_error_mm=np.array(10.0))
    assert e.warn_error_mm == 2.0 and type(e.warn_error_mm) is float
    assert e.min_frames == 30 and type(e.min_frames) is int
    f = AxisAngleFilter(reference_s=np.float64(0.5), value_range=[0, 1], lateral_axis=np.ones(3))
    assert f.value_range == (0.0, 1.0) and f.lateral_axis == (1.0, 1.0, 1.0)
    assert ScoreEstimator(rcond=np.float32(0.1)).rcond == pytest.approx(0.1)


@pytest.mark.parametrize(
    "cls, kw, match",
    [
        (OBrienEstimator, dict(warn_error_mm=True), r"warn_error_mm must be a finite number > 0, got True"),
        (OBrienEstimator, dict(min_rom_deg="5"), r"min_rom_deg must be a finite .*got '5' \(str\)"),
        (OBrienEstimator, dict(min_rom_deg=None), r"min_rom_deg must be a finite number >= 0, got None"),
        (OBrienEstimator, dict(max_distance_mm=np.inf), r"max_distance_mm must be a finite number"),
        (OBrienEstimator, dict(warn_error_mm=np.float32(-1.0)), r"warn_error_mm must be .*> 0"),
        (OBrienEstimator, dict(min_frames=True), r"min_frames must be an integer"),
        (OBrienEstimator, dict(min_frames=30.0), r"min_frames must be an integer"),
        (ScoreEstimator, dict(rcond="0.1"), r"rcond must be a finite number"),
        (PlaneVarianceEstimator, dict(plane_size_mm=np.nan), r"plane_size_mm must be a finite number"),
        (PlaneVarianceEstimator, dict(maxiter=True), r"maxiter must be an integer"),
        (AxisAngleFilter, dict(reference_s="0.25"), r"reference_s must be a finite number .*got '0.25'"),
        (AxisAngleFilter, dict(reference_s=np.inf), r"reference_s must be a finite number"),
        (AxisAngleFilter, dict(value_range=1.0), r"value_range must be \(low, high\), two numbers, got 1.0"),
        (AxisAngleFilter, dict(value_range=(0.0, "1")), r"value_range must be \(low, high\)"),
        (AxisAngleFilter, dict(bins=True), r"bins must be an integer"),
        (AxisAngleFilter, dict(min_angle_deg=-1.0), r"min_angle_deg must be a finite number >= 0"),
        (AxisAngleFilter, dict(lateral_axis=("a", 0, 0)), r"lateral_axis: expected a non-zero"),
    ],
)
def test_bad_numeric_options_refused_naming_them(cls, kw, match):
    with pytest.raises(InvalidInputError, match=match):
        cls(**kw)


@pytest.mark.parametrize(
    "make, match",
    [
        (lambda: FlexionMotion(duration_s="10"), r"duration_s must be a finite number, got '10'"),
        (lambda: FlexionMotion(flexion_range_deg=75.0), r"flexion_range_deg must be \(low, high\)"),
        (lambda: SensorMount(along=None), r"along must be a finite number, got None"),
        (lambda: SensorNoise(position_sd_mm="0.76"), r"position_sd_mm must be a finite number"),
        (lambda: FieldDistortion(n_waves=True), r"n_waves must be an integer >= 1, got True"),
        (lambda: ArcJoint(arc_radius_mm=np.inf), r"arc_radius_mm must be a finite number"),
        (lambda: FingerJoint(slide_mm="1"), r"slide_mm must be a finite number"),
        (lambda: read_polhemus("missing.csv", rate_hz="240"), r"rate_hz must be a finite number"),
    ],
)
def test_simulation_and_reader_numbers_checked(make, match):
    with pytest.raises(InvalidInputError, match=match):
        make()


@pytest.mark.parametrize("free", [7, -1, True, 1.0])
def test_linear_centre_free_directions_checked(hinge_rec, free):
    q, d = hinge_rec.relative()
    with pytest.raises(InvalidInputError, match="free_directions must be an integer"):
        linear_centre(q, d, free_directions=free)


# --------------------------------------------------------------------------
# shapes and finiteness of the geometric helpers


def test_assess_determinability_checks_q_and_d(hinge_rec):
    q, d = hinge_rec.relative()
    qn = q.copy()
    qn[5, 0, 0] = np.nan
    with pytest.raises(InvalidInputError, match=r"q: 1 of \d+ frames contain NaN.*\[5\]"):
        assess_determinability(qn, d)
    with pytest.raises(InvalidInputError, match=r"d: expected shape \(n, 3\), got \(10, 4\)"):
        assess_determinability(q[:10], np.zeros((10, 4)))
    with pytest.raises(InvalidInputError, match=r"d: expected one row per frame of q"):
        assess_determinability(q[:10], d[:9])
    with pytest.raises(InvalidInputError, match=r"q: expected shape \(n, 3, 3\)"):
        linear_centre(q[:, :2], d)


def test_plane_helpers_check_their_points():
    p1, p2, p3 = [0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]
    assert plane_coordinates(p1, p2, p3, [0.1, 0.2, 0.0]) == pytest.approx((0.1, 0.2))
    with pytest.raises(InvalidInputError, match="collinear"):
        plane_coordinates(p1, p2, [2.0, 0.0, 0.0], [0.1, 0.2, 0.0])
    with pytest.raises(InvalidInputError, match=r"point: expected 3 finite numbers, got \[nan"):
        plane_coordinates(p1, p2, p3, [np.nan, 0.0, 0.0])
    with pytest.raises(InvalidInputError, match=r"v: expected 3 finite numbers, got \[1.0, 2.0\]"):
        foot_of_perpendicular(p1, p2, p3, [1.0, 2.0])


# --------------------------------------------------------------------------
# file suffix


@pytest.mark.parametrize("name", ["r.txt", "r", "r.h5.bak"])
def test_save_recording_refuses_other_suffixes(tmp_path, finger_rec, name):
    with pytest.raises(InvalidInputError, match=r"\.h5 or \.hdf5.*got '"):
        save_recording(tmp_path / name, finger_rec)
    assert not list(tmp_path.iterdir())
    assert save_recording(tmp_path / "R.HDF5", finger_rec).exists()


# --------------------------------------------------------------------------
# rotations in the transposed convention


def _transposed(rec: Recording) -> Recording:
    return Recording(rec.times, rec.positions, np.swapaxes(rec.rotations, -1, -2),
                     labels=rec.labels, joint=rec.joint)


@pytest.mark.parametrize("cls", [OBrienEstimator, ScoreEstimator])
def test_transposed_rotations_named_as_the_likely_cause(finger_rec, cls):
    assert not any("transposed" in w for w in cls().estimate(finger_rec).warnings)
    r = cls().estimate(_transposed(finger_rec))
    assert r.warnings[0].startswith("rotations transposed?")
    assert "sensor -> transmitter" in r.warnings[0]


def test_transposed_rotations_named_in_a_refusal(finger_rec):
    from handsynth.errors import EstimationError

    with pytest.raises(EstimationError, match=r"max_distance_mm.*rotations transposed\?"):
        OBrienEstimator(max_distance_mm=20.0).estimate(_transposed(finger_rec))
    with pytest.raises(EstimationError, match=r"max_residual_mm.*rotations transposed\?"):
        OBrienEstimator(max_residual_mm=2.0).estimate(_transposed(finger_rec))


def test_an_estimator_option_misspelt_is_named_with_the_options_there_are():
    from handsynth.sensors.trackers import make_estimator

    with pytest.raises(InvalidInputError, match=r"^patent has no option 'windw'; its options: .*frames"):
        make_estimator("patent", windw=3)
    with pytest.raises(InvalidInputError, match=r"^name: expected one of patent, "):
        make_estimator("kalman")
