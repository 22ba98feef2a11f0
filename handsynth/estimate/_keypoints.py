"""Keypoints for estimators that read joint angles only (beyond the paper).

A database lookup reports the keypoints stored with the entry it matched;
the learnt estimators (:class:`~handsynth.estimate.LearnedEstimator`,
:class:`~handsynth.estimate.EnsembleEstimator`) read joint angles only, so
their keypoints are NaN.  A user who needs positions (a VR hand's
fingertips, a robot hand's targets) gets them here by forward kinematics:
the handsynth hand of a given :class:`~handsynth.models.HandShape` is posed
by the estimated angles and its 21 keypoints are read
(:meth:`handsynth.models.HandModel.keypoints`).  How far they are from a
hand's own keypoints depends on the angles and on how well the shape fits
the hand; both are measured in docs/camera_estimator.md ("Keypoints").
"""

from __future__ import annotations

import dataclasses

import numpy as np

from .._checks import check_instance
from ..errors import InvalidInputError
from ..models import HandModel, HandShape
from ._lookup import PoseEstimate

__all__ = ["KeypointEstimator"]

_SIDES = ("right", "left")


def _side_of(estimator, depth: int = 0) -> str | None:
    """The hand side an estimator reads: its own ``side``, or that of the estimator it wraps
    (``estimator``, as :class:`~handsynth.estimate.SmoothedEstimator`) or of its members
    (``members``, as :class:`~handsynth.estimate.EnsembleEstimator`); None if none says."""
    side = getattr(estimator, "side", None)
    if side in _SIDES or depth > 8:
        return side if side in _SIDES else None
    inner = getattr(estimator, "estimator", None)
    if inner is not None:
        return _side_of(inner, depth + 1)
    sides = {_side_of(m, depth + 1) for m in getattr(estimator, "members", ())} - {None}
    return sides.pop() if len(sides) == 1 else None


class KeypointEstimator:
    """Any pose estimator's answer with the keypoints of a model hand in its angles.

    Implements :class:`~handsynth.estimate.PoseEstimator`.  Each estimate's
    angles pose the handsynth hand of `shape`, whose 21 keypoints replace
    the estimate's (wrist, then thumb CMC, MCP, IP, tip, then MCP, PIP, DIP,
    tip of index, middle, ring and little; hand frame, metres, float32).  The
    rest of the estimate is the wrapped estimator's.  Frames without a hand
    keep NaN keypoints.

    Parameters
    ----------
    estimator : PoseEstimator
        Anything with ``estimate(frame) -> PoseEstimate`` (e.g. a calibrated
        :class:`~handsynth.estimate.EnsembleEstimator`, or one wrapped in a
        :class:`~handsynth.estimate.SmoothedEstimator` so that the keypoints
        follow the steadied angles).
    shape : HandShape, keyword-only, optional
        The hand whose keypoints are reported: the standard hand (187 mm from
        the wrist to the middle fingertip) by default; the user's from their
        measurements with :func:`~handsynth.estimate.select_shape`
        (``select_shape(m, options=SelectionOptions(normalize="none")).ratios``).
    side : {"right", "left"}, keyword-only, optional
        The hand's side; by default the estimator's: its ``side``, or that of
        the estimator it wraps or of its members (a
        :class:`~handsynth.estimate.SmoothedEstimator`, an
        :class:`~handsynth.estimate.EnsembleEstimator`), else ``"right"``.  A
        side other than the estimator's is refused.

    Raises
    ------
    InvalidInputError
        `estimator` without an ``estimate`` method, a `shape` that is not a
        :class:`HandShape`, or a `side` other than right / left or than the
        estimator's.
    """

    def __init__(self, estimator, *, shape: HandShape | None = None,
                 side: str | None = None) -> None:
        if not callable(getattr(estimator, "estimate", None)):
            raise InvalidInputError(f"estimator {estimator!r} has no estimate(frame) method")
        own = _side_of(estimator)
        if side is None:
            side = own if own in _SIDES else "right"
        if side not in _SIDES:
            raise InvalidInputError(f"side must be 'right' or 'left', got {side!r}")
        if own in _SIDES and own != side:
            raise InvalidInputError(f"side {side!r} differs from the estimator's ({own!r})")
        self.estimator = estimator
        self.shape = HandShape() if shape is None else check_instance(shape, HandShape,
                                                                      name="shape")
        self.side = side
        self._model = HandModel(self.shape, side=side, forearm=False)

    def calibrated(self, rest_frame: np.ndarray, **kwargs) -> KeypointEstimator:
        """A copy around the estimator calibrated to `rest_frame` (its ``calibrated``)."""
        inner = getattr(self.estimator, "calibrated", None)
        if not callable(inner):
            raise InvalidInputError(f"{type(self.estimator).__name__} cannot be calibrated")
        return KeypointEstimator(inner(rest_frame, **kwargs), shape=self.shape, side=self.side)

    def check_ready(self) -> None:
        """The wrapped estimator's ``check_ready()``, where it has one."""
        ready = getattr(self.estimator, "check_ready", None)
        if callable(ready):
            ready()

    def keypoints(self, angles) -> np.ndarray:
        """The 21 keypoints of the hand posed by `angles`.

        Parameters
        ----------
        angles : array_like, shape (20,)
            Degrees, canonical :data:`~handsynth.JOINT_NAMES` order.

        Returns
        -------
        ndarray, shape (21, 3), float32
            Hand frame, metres.
        """
        self._model.set_pose(angles)
        return self._model.keypoints().astype(np.float32)

    def estimate(self, frame: np.ndarray) -> PoseEstimate:
        """The wrapped estimator's answer with the model hand's keypoints."""
        got = self.estimator.estimate(frame)
        if got.no_hand or not np.isfinite(got.angles).all():
            return got
        self._model.set_pose(got.angles, check=False)  # an estimator's own angles
        return dataclasses.replace(got, keypoints=self._model.keypoints().astype(np.float32))
