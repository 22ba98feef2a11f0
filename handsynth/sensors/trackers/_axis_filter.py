"""The patent's axis-angle frame filter (JP2010-88628, para. 0083-0091, 0110).

A finger joint is not single-axis: its axis moves during flexion.  The patent
expresses the rotation of the lower segment relative to the upper one as
axis-angle, takes the axis component along the finger's width (the ``y``
axis of its segment frames), splits that component into 100 equal bins and
keeps the frames of the fullest bin, i.e. the frames during which the joint
axis pointed (nearly) the same way.

Here, with ``Q(i) = R_U(i)^T R_L(i)`` the lower sensor's orientation in the
upper sensor's frame and ``Q0`` its mean over the standard state (the static
first ``reference_s`` seconds, para. 0084), the change of relative orientation
is ``dR(i) = Q(i) Q0^T``.  This is the patent's ``R_ULS(i) = R_US(i)^-1
R_LS(i)`` (eqs. 10-12, with segment frames equal to the transmitter frame at
the standard state) expressed in the upper sensor's frame instead of the
transmitter's: the same rotation, axis seen from a different frame.  The
width direction ``lateral_axis`` is given as the patent does it (para. 0084):
a direction in the transmitter frame, read in the standard state, here
mapped into the upper sensor's frame with the sensor's mean orientation over
the standard state (eq. 11).  ``"recording"`` takes that direction from the
recording's metadata (simulations store the finger's true width direction);
``"auto"`` uses the principal direction of the rotation vectors, i.e. the
mean flexion axis, for recordings without a calibrated standard state.  Axes are flipped so
that their lateral component is >= 0
(para. 0090).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial.transform import Rotation

from ...errors import EstimationError, InvalidInputError
from ..common import matrix_to_rotvec
from ._checks import check_integer, check_interval, check_number, check_vector3
from ._recording import Recording

__all__ = ["AxisAngleFilter", "AxisFilterResult", "relative_rotation_vectors"]


def relative_rotation_vectors(recording: Recording, *, reference_s: float = 0.25) -> np.ndarray:
    """Rotation vectors of ``dR(i) = Q(i) Q0^T`` in the upper sensor frame.

    ``dR(i)`` is the patent's ``R_ULS(i)`` of eqs. 10-12 expressed in the
    upper sensor's frame (module docstring).

    Parameters
    ----------
    recording : Recording
    reference_s : float
        Length of the standard state at the start, seconds (at least one
        frame is used).

    Returns
    -------
    (n, 3) ndarray of float64
        ``angle * axis``, radians.
    """
    q, _ = recording.relative()
    k = _reference_frames(recording, reference_s)
    q0 = Rotation.from_matrix(q[:k]).mean().as_matrix()
    return matrix_to_rotvec(q @ q0.T)


def _reference_frames(recording: Recording, reference_s: float) -> int:
    """Number of frames in the standard state (at least 1)."""
    return max(1, int(np.searchsorted(recording.times, recording.times[0] + reference_s)))


def principal_axis(rotvecs: np.ndarray) -> np.ndarray:
    """Unit principal direction of rotation vectors ``(n, 3)`` (sign: +x-ish)."""
    _w, v = np.linalg.eigh(rotvecs.T @ rotvecs)
    a = v[:, -1]
    return a if a[np.argmax(np.abs(a))] > 0 else -a


@dataclass(frozen=True)
class AxisFilterResult:
    """What the axis-angle filter saw and kept.

    Attributes
    ----------
    lateral : (n,) ndarray of float64
        Lateral (width) component of each frame's unit axis, flipped >= 0.
    angle_deg : (n,) ndarray of float64
        Rotation angle of each frame from the standard state, degrees.
    lateral_axis : (3,) ndarray of float64
        Width direction used, upper sensor frame.
    edges : (bins + 1,) ndarray of float64
        Bin edges over ``value_range``.
    counts : (bins,) ndarray of int64
    chosen_bin : int
        Index of the fullest bin (lowest index on ties).
    frames : (k,) ndarray of int64
        Frames whose lateral component falls in the chosen bin.
    """

    lateral: np.ndarray
    angle_deg: np.ndarray
    lateral_axis: np.ndarray
    edges: np.ndarray
    counts: np.ndarray
    chosen_bin: int
    frames: np.ndarray

    @property
    def chosen_range(self) -> tuple[float, float]:
        """Lower and upper edge of the chosen bin."""
        return float(self.edges[self.chosen_bin]), float(self.edges[self.chosen_bin + 1])


@dataclass(frozen=True, kw_only=True)
class AxisAngleFilter:
    """Options of the axis-angle filter (patent claims 4-5, 9-10).

    Parameters
    ----------
    bins : int
        Number of equal bins of the lateral component (patent: 100; SPEC.md
        section 2, "split the y component of the axis into 100 equal bins").
    value_range : (float, float)
        Range binned; ``(0, 1)`` covers every flipped unit axis, giving the
        patent's 0.01-wide bins such as 0.97-0.98 (para. 0110).
    lateral_axis : "auto", "recording" or (3,) sequence of float
        Width direction of the finger: a vector (in the frame named by
        `lateral_frame`), ``"recording"`` for
        ``recording.metadata["lateral_axis"]`` (transmitter frame at the
        standard state), or ``"auto"`` for the mean flexion axis (see
        module docstring), which is fixed to the finger.
    lateral_frame : {"transmitter", "upper"}
        Frame of a vector `lateral_axis`: the transmitter's at the standard
        state (the patent's calibration, para. 0084), or the upper sensor's
        own frame -- a direction fixed to the finger, as the patent's
        segment ``y`` axis is, that needs no standard state.
    reference_s : float
        Duration of the standard state at the start of the recording, s.
    min_angle_deg : float
        Frames rotated less than this from the standard state are not
        binned (their axis is noise).  The patent bins all frames (0).
    """

    bins: int = 100
    value_range: tuple[float, float] = (0.0, 1.0)
    lateral_axis: str | tuple[float, float, float] = "auto"
    lateral_frame: str = "transmitter"
    reference_s: float = 0.25
    min_angle_deg: float = 0.0

    def __post_init__(self) -> None:
        set_ = object.__setattr__  # frozen: store the checked values
        set_(self, "bins", check_integer(self.bins, "bins", minimum=1))
        set_(self, "value_range", check_interval(self.value_range, "value_range"))
        if isinstance(self.lateral_axis, str):
            if self.lateral_axis not in ("auto", "recording"):
                raise InvalidInputError(
                    f"lateral_axis must be 'auto', 'recording' or 3 numbers, got "
                    f"{self.lateral_axis!r}"
                )
        else:
            a = check_vector3(self.lateral_axis, "lateral_axis", nonzero=True)
            set_(self, "lateral_axis", tuple(float(v) for v in a))
        if self.lateral_frame not in ("transmitter", "upper"):
            raise InvalidInputError(
                f"lateral_frame must be 'transmitter' or 'upper', got {self.lateral_frame!r}"
            )
        set_(self, "reference_s", check_number(self.reference_s, "reference_s", minimum=0.0))
        set_(self, "min_angle_deg",
             check_number(self.min_angle_deg, "min_angle_deg", minimum=0.0, below=180.0))

    def _lateral_axis(self, recording: Recording, rv: np.ndarray) -> np.ndarray:
        """Width direction in the upper sensor frame, unit."""
        if isinstance(self.lateral_axis, str) and self.lateral_axis == "auto":
            return principal_axis(rv)
        if isinstance(self.lateral_axis, str):
            if "lateral_axis" not in recording.metadata:
                raise InvalidInputError(
                    "lateral_axis='recording' but the recording's metadata has no "
                    "'lateral_axis'; give the axis in the transmitter frame or 'auto'"
                )
            a = np.asarray(recording.metadata["lateral_axis"], dtype=np.float64)
            if a.shape != (3,) or not np.isfinite(a).all() or not np.linalg.norm(a) > 0:
                raise InvalidInputError(
                    f"recording metadata lateral_axis must be a non-zero 3-vector, "
                    f"got {recording.metadata['lateral_axis']!r}"
                )
        else:
            a = np.asarray(self.lateral_axis, dtype=np.float64)
            if self.lateral_frame == "upper":  # already fixed to the finger
                return a / np.linalg.norm(a)
        k = _reference_frames(recording, self.reference_s)
        r0 = Rotation.from_matrix(recording.rotations[:k, 0]).mean().as_matrix()
        a = r0.T @ a  # transmitter -> upper sensor frame (eq. 11)
        return a / np.linalg.norm(a)

    def apply(self, recording: Recording) -> AxisFilterResult:
        """Bin the frames of `recording` and select the fullest bin.

        Raises
        ------
        EstimationError
            If no frame rotates more than `min_angle_deg`.
        """
        rv = relative_rotation_vectors(recording, reference_s=self.reference_s)
        angle = np.linalg.norm(rv, axis=1)
        lateral_axis = self._lateral_axis(recording, rv)
        with np.errstate(invalid="ignore", divide="ignore"):
            lateral = np.abs(rv @ lateral_axis) / angle  # flip: component >= 0
        lateral = np.where(angle > 0, lateral, 0.0)
        usable = np.rad2deg(angle) >= self.min_angle_deg
        if not usable.any():
            raise EstimationError(
                f"axis-angle filter: no frame rotates more than min_angle_deg="
                f"{self.min_angle_deg:g} from the standard state"
            )
        edges = np.linspace(*self.value_range, self.bins + 1)
        idx = np.clip(np.searchsorted(edges, lateral, side="right") - 1, 0, self.bins - 1)
        inside = usable & (lateral >= edges[0]) & (lateral <= edges[-1])
        counts = np.bincount(idx[inside], minlength=self.bins).astype(np.int64)
        chosen = int(np.argmax(counts))
        frames = np.flatnonzero(inside & (idx == chosen)).astype(np.int64)
        return AxisFilterResult(
            lateral=lateral,
            angle_deg=np.rad2deg(angle),
            lateral_axis=lateral_axis,
            edges=edges,
            counts=counts,
            chosen_bin=chosen,
            frames=frames,
        )
