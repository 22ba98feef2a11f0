"""The common output of every joint-centre estimator."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ._axis_filter import AxisFilterResult
from ._determinability import Determinability
from ._recording import Recording

__all__ = ["JointCentreResult", "centre_distance_mm"]


def centre_distance_mm(
    recording: Recording, centre_upper: np.ndarray, centre_lower: np.ndarray
) -> np.ndarray:
    """Per-frame distance between ``P_U`` and ``P_L`` in the transmitter frame.

    Parameters
    ----------
    recording : Recording
    centre_upper, centre_lower : (3,) ndarray of float64
        Centre in the upper and in the lower sensor frame, metres.

    Returns
    -------
    (n,) ndarray of float64
        ``|R_U P_U + t_U - (R_L P_L + t_L)|`` in millimetres.
    """
    pu = recording.rotations[:, 0] @ centre_upper + recording.positions[:, 0]
    pl = recording.rotations[:, 1] @ centre_lower + recording.positions[:, 1]
    return np.linalg.norm(pu - pl, axis=1) * 1e3


@dataclass(frozen=True)
class JointCentreResult:
    """Joint centre estimated from one recording.

    Attributes
    ----------
    method : str
        Estimator name (``"patent"``, ``"variance3d"``, ``"obrien"``,
        ``"score"``).
    frames_mode : str
        ``"all"`` or ``"filtered"`` (axis-angle filter).
    centre_upper : (3,) ndarray of float64
        ``P_U``: the centre in the upper sensor's frame, metres.
    centre_lower : (3,) ndarray of float64
        ``P_L``: the centre in the lower sensor's frame, metres.
    distance_mm : float
        ``|P_U - P_L|``: mean over the frames used of the distance between the
        two estimates mapped to the transmitter frame (the patent's quality
        measure, para. 0105), millimetres.
    residual_mm : float
        The method's own fit residual over the frames used, millimetres:
        RMS deviation of ``|v_LP|`` from its mean (sqrt of eq. 2, averaged
        over the ``P_U`` and ``P_L`` fits) for the variance methods; RMS of
        the linear system's residual vectors for O'Brien and SCoRE.
    frames : (k,) ndarray of int64
        Indices of the frames used.
    n_frames_total : int
    range_of_motion_deg : float
        Spread (1st-99th percentile) of the relative rotation about its main
        axis over the frames used.
    labels : (str, str)
        Segments carrying the upper and lower sensor.
    joint : str
    axis_filter : AxisFilterResult or None
        The filter's histogram when ``frames_mode == "filtered"``.
    determinability : Determinability or None
        Rotation spread, joint axis and expected error of the frames used.
    determined : {"point", "axis"}
        ``"axis"`` for a single-axis motion: only the joint axis is
        determined and the centre is the point of it nearest the sensors.
    warnings : tuple of str
        What the user must know with this centre (expected error, single
        axis, disagreement with the linear solution); empty when none.
    """

    method: str
    frames_mode: str
    centre_upper: np.ndarray
    centre_lower: np.ndarray
    distance_mm: float
    residual_mm: float
    frames: np.ndarray
    n_frames_total: int
    range_of_motion_deg: float
    labels: tuple[str, str]
    joint: str
    axis_filter: AxisFilterResult | None = None
    determinability: Determinability | None = None
    determined: str = "point"
    warnings: tuple[str, ...] = ()

    def error_mm(self, recording: Recording) -> np.ndarray:
        """Distance of ``P_U`` and ``P_L`` from the true centre, millimetres.

        The truth is the recording's
        :attr:`~handsynth.sensors.GroundTruth.reference_centre` (the centre
        of the extended joint).

        Returns
        -------
        (2,) ndarray of float64
            Error of ``P_U`` and of ``P_L``.

        Raises
        ------
        InvalidInputError
            If `recording` has no ground truth.
        """
        from ...errors import InvalidInputError

        if recording.truth is None:
            raise InvalidInputError("recording has no ground truth (not simulated)")
        est = np.stack([self.centre_upper, self.centre_lower])
        return np.linalg.norm(est - recording.truth.reference_centre, axis=1) * 1e3

    def to_dict(self) -> dict:
        """JSON-serialisable summary (centres in millimetres)."""
        d = {
            "method": self.method,
            "frames_mode": self.frames_mode,
            "joint": self.joint,
            "labels": list(self.labels),
            "centre_upper_mm": (self.centre_upper * 1e3).round(4).tolist(),
            "centre_lower_mm": (self.centre_lower * 1e3).round(4).tolist(),
            "distance_mm": round(float(self.distance_mm), 4),
            "residual_mm": round(float(self.residual_mm), 4),
            "n_frames_used": int(self.frames.size),
            "n_frames_total": int(self.n_frames_total),
            "range_of_motion_deg": round(float(self.range_of_motion_deg), 3),
            "determined": self.determined,
            "warnings": list(self.warnings),
        }
        if self.determinability is not None:
            d["determinability"] = self.determinability.to_dict()
        if self.axis_filter is not None:
            lo, hi = self.axis_filter.chosen_range
            d["axis_filter"] = {"bin": [round(lo, 6), round(hi, 6)],
                                "bins": int(self.axis_filter.counts.size)}
        return d
