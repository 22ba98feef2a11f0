"""The mean of several estimators' answers (beyond the paper).

Learnt estimators of different kinds err differently: the per-digit
nearest neighbours of :class:`~handsynth.estimate.LearnedEstimator`
(``kind="fingers"``) average what similar learning frames did, the
perceptron (``kind="mlp"``) interpolates between them.  Their mean is more
accurate than either on the model hands of the evaluation protocol
(README, "Camera estimator for unseen hands").
"""

from __future__ import annotations

import numpy as np

from ..errors import InvalidInputError
from ._learned import LearnedEstimator
from ._lookup import PoseEstimate

__all__ = ["EnsembleEstimator"]


class EnsembleEstimator:
    """Reports the (weighted) mean of its members' angles.

    Implements :class:`~handsynth.estimate.PoseEstimator`.

    Parameters
    ----------
    members : sequence of PoseEstimator
        At least one.  Members with a ``calibrated(rest_frame)`` method are
        calibrated together by :meth:`calibrated`.
    weights : sequence of float, keyword-only, optional
        Non-negative, one per member (equal by default).

    Raises
    ------
    InvalidInputError
        No members, or weights that do not match them.
    """

    def __init__(self, members, *, weights=None) -> None:
        self.members = list(members)
        if not self.members:
            raise InvalidInputError("an EnsembleEstimator needs at least one member")
        for m in self.members:
            if not callable(getattr(m, "estimate", None)):
                raise InvalidInputError(f"ensemble member {m!r} has no estimate(frame) method")
        w = np.ones(len(self.members)) if weights is None else np.asarray(weights, float)
        if w.shape != (len(self.members),) or not np.all(np.isfinite(w)) or np.any(w < 0) \
                or w.sum() <= 0:
            raise InvalidInputError(f"weights must be {len(self.members)} non-negative numbers "
                                    f"with a positive sum, got {weights!r}")
        self.weights = w / w.sum()

    def calibrated(self, rest_frame: np.ndarray) -> EnsembleEstimator:
        """A copy whose members are calibrated to `rest_frame` (those that calibrate)."""
        members = [m.calibrated(rest_frame) if callable(getattr(m, "calibrated", None)) else m
                   for m in self.members]
        return EnsembleEstimator(members, weights=self.weights)

    def estimate(self, frame: np.ndarray) -> PoseEstimate:
        """Every member's estimate of `frame`, averaged.

        Returns
        -------
        PoseEstimate
            ``angles``: the weighted mean of the members' (NaN when any finds
            no hand); ``keypoints`` the mean of those given (NaN if none);
            ``confidence`` the weighted mean; ``entry`` -1.  Learnt members
            of the same mount, side and cells share one coverage grid of the
            frame (:meth:`LearnedEstimator.estimate_grid`).
        """
        grids: dict = {}  # learnt members of one mount, side and cells read one grid
        got = []
        for m in self.members:
            if isinstance(m, LearnedEstimator):
                key = (m.mount, m.side, m.cells)
                if key not in grids:
                    grids[key] = m.grid(frame)
                got.append(m.estimate_grid(grids[key]))
            else:
                got.append(m.estimate(frame))
        if any(e.no_hand for e in got):
            return PoseEstimate(angles=np.full(20, np.nan), keypoints=np.full((21, 3), np.nan,
                                np.float32), confidence=0.0, entry=-1, error=float("inf"),
                                low_confidence=True, no_hand=True)
        angles = self.weights @ np.stack([e.angles for e in got])
        kps = [e.keypoints for e in got if np.isfinite(e.keypoints).all()]
        keypoints = (np.mean(kps, axis=0).astype(np.float32) if kps
                     else np.full((21, 3), np.nan, np.float32))
        return PoseEstimate(angles=angles, keypoints=keypoints,
                            confidence=float(self.weights @ [e.confidence for e in got]),
                            entry=-1, error=float(self.weights @ [e.error for e in got]),
                            low_confidence=any(e.low_confidence for e in got), no_hand=False)
