"""KeypointEstimator: a model hand posed by any estimator's angles."""

from __future__ import annotations

import numpy as np
import pytest

from handsynth.errors import InvalidInputError
from handsynth.estimate import KeypointEstimator, PoseEstimate, PoseEstimator, SmoothedEstimator
from handsynth.models import HandModel, HandShape, natural_pose_set


class _Fixed:
    """An estimator answering given angles in turn (NaN angles: no hand)."""

    def __init__(self, poses, *, side=None):
        self.poses = list(poses)
        self.calls = []
        if side is not None:
            self.side = side

    def estimate(self, frame):
        a = np.asarray(self.poses[len(self.calls) % len(self.poses)], float)
        self.calls.append(frame)
        none = bool(np.isnan(a).all())
        return PoseEstimate(angles=a, keypoints=np.full((21, 3), np.nan, np.float32),
                            confidence=0.0 if none else 0.7, entry=-1,
                            error=float("inf") if none else 1.0, low_confidence=none,
                            no_hand=none, moved=True)

    def calibrated(self, rest_frame, **kwargs):
        out = _Fixed(self.poses)
        out.rest, out.kwargs = rest_frame, kwargs
        return out


@pytest.mark.parametrize("side", ["right", "left"])
def test_keypoints_are_the_shapes_hand_posed_by_the_answered_angles(side):
    poses = natural_pose_set(6, seed=4)
    shape = HandShape(length=0.92, width=1.05, palm=1.04, thumb=0.96)
    est = KeypointEstimator(_Fixed(poses, side=side), shape=shape)
    assert isinstance(est, PoseEstimator) and est.side == side
    model = HandModel(shape, side=side)
    for p in poses:
        got = est.estimate(np.zeros((4, 4), np.uint8))
        model.set_pose(p)
        assert got.keypoints.dtype == np.float32 and got.keypoints.shape == (21, 3)
        np.testing.assert_allclose(got.keypoints, model.keypoints(), atol=1e-7)
        np.testing.assert_array_equal(got.angles, p)  # the rest is the estimator's
        assert (got.confidence, got.moved, got.entry) == (0.7, True, -1)


def test_the_shape_changes_the_keypoints_and_the_standard_hand_is_the_default():
    pose = natural_pose_set(3, seed=1)[2]
    standard = KeypointEstimator(_Fixed([pose])).estimate(None)
    model = HandModel(HandShape())
    model.set_pose(pose)
    np.testing.assert_allclose(standard.keypoints, model.keypoints(), atol=1e-7)
    longer = KeypointEstimator(_Fixed([pose]), shape=HandShape(length=1.15)).estimate(None)
    reach = [np.linalg.norm(e.keypoints[12] - e.keypoints[0]) for e in (standard, longer)]
    assert reach[1] > reach[0] * 1.05  # a longer hand's middle fingertip is farther out


def test_a_frame_without_a_hand_keeps_nan_keypoints():
    est = KeypointEstimator(_Fixed([np.full(20, np.nan), np.zeros(20)]))
    none, some = est.estimate(None), est.estimate(None)
    assert none.no_hand and np.isnan(none.keypoints).all()
    assert not some.no_hand and np.isfinite(some.keypoints).all()


def test_wrapping_a_smoothed_estimator_gives_the_keypoints_of_the_steadied_angles():
    poses = natural_pose_set(8, seed=2)
    smoothed = SmoothedEstimator(_Fixed(poses), rate_hz=30.0)
    est = KeypointEstimator(smoothed)
    model = HandModel()
    for _ in poses:
        got = est.estimate(None)
        model.set_pose(got.angles, check=False)
        np.testing.assert_allclose(got.keypoints, model.keypoints(), atol=1e-7)


def test_a_left_estimator_inside_a_wrapper_gives_a_left_hands_keypoints():
    # a SmoothedEstimator or an ensemble has no side of its own: the right hand was assumed
    from handsynth.estimate import EnsembleEstimator

    pose = natural_pose_set(2, seed=5)[1]
    left = HandModel(side="left")
    left.set_pose(pose)
    wrapped = (SmoothedEstimator(_Fixed([pose], side="left"), rate_hz=30.0),
               EnsembleEstimator([_Fixed([pose], side="left"), _Fixed([pose], side="left")]))
    for inner in wrapped:
        est = KeypointEstimator(inner)
        assert est.side == "left"
        np.testing.assert_allclose(est.estimate(None).keypoints, left.keypoints(), atol=1e-6)
        with pytest.raises(InvalidInputError, match="side 'right' differs from the estimator's"):
            KeypointEstimator(inner, side="right")


def test_calibrated_and_check_ready_reach_the_wrapped_estimator():
    inner = _Fixed([np.zeros(20)])
    ready = []
    inner.check_ready = lambda: ready.append(True)
    est = KeypointEstimator(inner, shape=HandShape(thumb=1.1))
    est.check_ready()
    assert ready == [True]
    cal = est.calibrated("rest", segment="colour")
    assert isinstance(cal, KeypointEstimator) and cal.shape == est.shape
    assert cal.estimator.rest == "rest" and cal.estimator.kwargs == {"segment": "colour"}


def test_bad_arguments_are_refused_by_name():
    with pytest.raises(InvalidInputError, match="has no estimate"):
        KeypointEstimator(object())
    with pytest.raises(InvalidInputError, match="shape must be a HandShape, got str"):
        KeypointEstimator(_Fixed([np.zeros(20)]), shape="L1.0")
    with pytest.raises(InvalidInputError, match="side must be 'right' or 'left', got 'up'"):
        KeypointEstimator(_Fixed([np.zeros(20)]), side="up")
    with pytest.raises(InvalidInputError, match="side 'left' differs from the estimator's"):
        KeypointEstimator(_Fixed([np.zeros(20)], side="right"), side="left")
    with pytest.raises(InvalidInputError, match="_NoCal cannot be calibrated"):
        KeypointEstimator(_NoCal()).calibrated("rest")


class _NoCal:
    def estimate(self, frame):  # pragma: no cover - never called
        raise AssertionError
