import time

import numpy as np
import pytest

from handsynth.errors import EstimationError, InvalidInputError
from handsynth.sensors.trackers import (
    ESTIMATORS,
    NO_NOISE,
    AxisAngleFilter,
    FlexionMotion,
    JointCentreEstimator,
    OBrienEstimator,
    PlaneVarianceEstimator,
    Recording,
    ScoreEstimator,
    VarianceEstimator,
    foot_of_perpendicular,
    make_estimator,
    plane_coordinates,
    plane_point,
    simulate_recording,
)


def test_all_estimators_satisfy_protocol():
    for cls in ESTIMATORS.values():
        assert isinstance(cls(), JointCentreEstimator)
    assert not isinstance(object(), JointCentreEstimator)


def test_options_are_checked():
    with pytest.raises(TypeError):
        PlaneVarianceEstimator(plane_size=5.0)  # typo
    with pytest.raises(InvalidInputError, match="frames"):
        OBrienEstimator(frames="some")
    with pytest.raises(InvalidInputError, match="^name: expected one of"):
        make_estimator("sphere")
    with pytest.raises(InvalidInputError, match="bins"):
        AxisAngleFilter(bins=0)


def test_foot_of_perpendicular_eqs_6_to_9():
    p1, p2, p3 = np.array([0, 0, 1.0]), np.array([1, 0, 1.0]), np.array([0, 1, 1.0])
    np.testing.assert_allclose(foot_of_perpendicular(p1, p2, p3, [3, -2, 7]), [3, -2, 1])
    s, t = plane_coordinates(p1, p2, p3, [3, -2, 1])
    np.testing.assert_allclose(plane_point(p1, p2, p3, s, t), [3, -2, 1])
    with pytest.raises(InvalidInputError, match="collinear"):
        foot_of_perpendicular(p1, p1 * 2, p1 * 3, [0, 0, 0])


@pytest.mark.parametrize("cls", [PlaneVarianceEstimator, OBrienEstimator, ScoreEstimator])
def test_exact_hinge_is_recovered(cls):
    rec = simulate_recording("index_pip", model="hinge", noise=NO_NOISE, geometry_source="table",
                             motion=FlexionMotion(duration_s=5.0, wobble_deg=0.0), seed=1)
    r = cls().estimate(rec)
    # SCoRE has no hinge handling: exact data leaves it on the axis but anywhere
    tol = 5.0 if cls is ScoreEstimator else 0.01
    assert r.error_mm(rec).max() < tol
    assert r.distance_mm < 0.01


def test_unconstrained_variance_drifts_along_hinge_axis(hinge_rec):
    """The patent's motivation for the plane (para. 0044)."""
    plane = PlaneVarianceEstimator().estimate(hinge_rec).error_mm(hinge_rec).max()
    free = VarianceEstimator().estimate(hinge_rec).error_mm(hinge_rec).max()
    assert plane < 0.5 and free > 2 * plane


def _disagreement(r):
    return [w for w in r.warnings if "differs from the linear least-squares centre" in w]


def test_disagreement_warning_marks_the_answer_that_is_off(hinge_rec, finger_rec):
    """The warning against the linear centre fires where the method is the one
    that is off (its drift along the hinge axis) and not on a clean finger-like
    recording.  Over 10 seeds of every simulated configuration, 30 s and 15 s,
    variance3d was more than 2 mm off in 69 of the 73 answers that carried it
    (1.6-1.9 mm in the other 4), and the linear centre was the nearer of the
    two in all 73 (docs/trackers.md)."""
    r = VarianceEstimator().estimate(hinge_rec)
    linear = OBrienEstimator().estimate(hinge_rec).error_mm(hinge_rec).max()
    assert _disagreement(r) and r.error_mm(hinge_rec).min() > 2.0 > 0.5 > linear
    r = VarianceEstimator().estimate(finger_rec)
    assert not _disagreement(r) and r.error_mm(finger_rec).mean() < 2.0


def test_patent_method_meets_targets_on_finger_like_joint(finger_rec):
    # plane normal from the calibrated width direction, as in the patent
    r = PlaneVarianceEstimator(axis_filter=AxisAngleFilter(lateral_axis="recording")).estimate(finger_rec)
    assert r.error_mm(finger_rec).max() <= 1.5
    assert r.distance_mm <= 2.0
    assert r.frames.size == finger_rec.n_frames and r.range_of_motion_deg > 50


def test_filter_keeps_fullest_bin(finger_rec):
    f = AxisAngleFilter(lateral_axis="recording").apply(finger_rec)
    assert f.counts.sum() == finger_rec.n_frames and f.counts.size == 100
    assert f.frames.size == f.counts.max()
    lo, hi = f.chosen_range
    assert hi - lo == pytest.approx(0.01)
    assert np.all((f.lateral[f.frames] >= lo) & (f.lateral[f.frames] <= hi))
    # the finger-like joint spreads its axis: not every frame is in one bin
    assert f.frames.size < 0.8 * finger_rec.n_frames
    r = PlaneVarianceEstimator(frames="filtered",
                               axis_filter=AxisAngleFilter(lateral_axis="recording")).estimate(finger_rec)
    np.testing.assert_array_equal(r.frames, f.frames)


def test_obrien_and_score_minimise_the_same_residual(finger_rec):
    a = OBrienEstimator().estimate(finger_rec)
    b = ScoreEstimator().estimate(finger_rec)
    assert a.determined == b.determined
    np.testing.assert_allclose(a.centre_upper, b.centre_upper, atol=1e-7)
    assert a.residual_mm == pytest.approx(b.residual_mm, rel=1e-6)


def test_speed_30s_at_240hz_under_one_second():
    rec = simulate_recording(motion=FlexionMotion(duration_s=30.0), seed=2, geometry_source="table")
    est = PlaneVarianceEstimator(frames="filtered")
    est.estimate(rec)  # warm caches
    t0 = time.process_time()
    est.estimate(rec)
    assert time.process_time() - t0 < 1.0


def _frozen_lower(rec):
    pos = np.array(rec.positions)
    rot = np.array(rec.rotations)
    pos[:, 1], rot[:, 1] = pos[0, 1], rot[0, 1]
    return Recording(times=rec.times, positions=pos, rotations=rot, labels=rec.labels)


def test_frozen_sensor_is_named(finger_rec):
    with pytest.raises(EstimationError, match="sensor 1 .*lower.*index_distal.*frozen"):
        PlaneVarianceEstimator().estimate(_frozen_lower(finger_rec))


def test_small_range_of_motion_is_refused():
    rec = simulate_recording(motion=FlexionMotion(duration_s=4.0, flexion_range_deg=(0, 4),
                                                  wobble_deg=0.0), seed=1, geometry_source="table")
    with pytest.raises(EstimationError, match="range of motion .* below min_rom_deg"):
        OBrienEstimator().estimate(rec)


def test_wrong_input_type():
    with pytest.raises(InvalidInputError, match="Recording"):
        ScoreEstimator().estimate(np.zeros((10, 2, 3)))


def test_estimate_all_runs_every_method_and_mode_and_collects_refusals():
    from handsynth.sensors.trackers import estimate_all

    rec = simulate_recording(motion=FlexionMotion(duration_s=10.0), seed=3, geometry_source="table")
    results, refused = estimate_all(rec, ["obrien", "patent", "obrien"], frames_modes=("all", "filtered"))
    assert [(r.method, r.frames_mode) for r in results] == [
        ("obrien", "all"), ("obrien", "filtered"), ("patent", "all"), ("patent", "filtered")]
    assert refused == []
    results, refused = estimate_all(rec, ["obrien"], min_rom_deg=179.0)
    assert results == [] and refused[0]["method"] == "obrien" and "range of motion" in refused[0]["refused"]
