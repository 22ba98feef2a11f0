"""A two-sensor 6-DOF recording across one finger joint, and its ground truth.

A :class:`Recording` holds what a Polhemus Liberty (or a simulation of one)
delivers for the two receivers glued on the phalanges either side of a joint:
per frame, each sensor's position and orientation in the transmitter frame.
Sensor 0 is the *upper* (proximal) sensor, sensor 1 the *lower* (distal)
one, as in the patent JP2010-88628 (upper receiver 1a, lower receiver 1b).

Arrays are validated on construction and made read-only, so a recording that
exists is usable: finite, strictly increasing times, proper rotations.  Both
classes pickle and deep-copy by constructing anew from their fields, so a
copy (sent to another process, say) is checked and read-only like the
original, and compare equal when their fields are (arrays by value).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Any

import numpy as np

from ...errors import RecordingError
from ..common import check_rotations

__all__ = ["GroundTruth", "Recording"]


def _frozen(a: np.ndarray) -> np.ndarray:
    a = np.array(a, dtype=np.float64, copy=True)
    a.setflags(write=False)
    return a


def relative_pose(rotations: np.ndarray, positions: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(q, d)`` of :meth:`Recording.relative` from ``(n, 2, 3, 3)`` rotations
    and ``(n, 2, 3)`` positions."""
    ru, rl = rotations[:, 0], rotations[:, 1]
    q = np.einsum("nji,njk->nik", ru, rl)
    d = np.einsum("nji,nj->ni", ru, positions[:, 1] - positions[:, 0])
    return q, d


def _rebuild(cls: type, fields: dict[str, Any]) -> Any:
    """Construct `cls` from `fields` (used by pickle and copy)."""
    return cls(**fields)


def _field_values(record: Any) -> dict[str, Any]:
    """Field name to value of the dataclass instance `record`."""
    return {f.name: getattr(record, f.name) for f in dataclasses.fields(record)}


class _ByValue:
    """Equality by field values (arrays compared by value), and pickling and copying
    by building anew from the fields, so that a copy is checked as the original was.

    Subclasses are dataclasses declared with ``eq=False`` (the decorator would
    otherwise replace this ``__eq__``).
    """

    def __eq__(self, other: object) -> bool:
        if other.__class__ is not self.__class__:
            return NotImplemented
        theirs = _field_values(other)
        for name, x in _field_values(self).items():
            y = theirs[name]
            if not (np.array_equal(x, y) if isinstance(x, np.ndarray) else bool(x == y)):
                return False
        return True

    def __reduce__(self) -> tuple[Any, ...]:
        # a read-only mapping view does not pickle: hand over a plain copy
        fields = {k: dict(v) if isinstance(v, MappingProxyType) else v
                  for k, v in _field_values(self).items()}
        return (_rebuild, (type(self), fields))


def _check_shape(name: str, a: np.ndarray, shape: tuple[int | None, ...]) -> None:
    ok = a.ndim == len(shape) and all(
        s is None or s == d for s, d in zip(shape, a.shape)
    )
    if not ok:
        want = "(" + ", ".join("n" if s is None else str(s) for s in shape) + ")"
        raise RecordingError(f"{name}: expected shape {want}, got {a.shape}")


@dataclass(frozen=True, eq=False)
class GroundTruth(_ByValue):
    """Known joint centre of a simulated recording.

    Attributes
    ----------
    centre_world : (n, 3) ndarray of float64
        Instantaneous joint centre per frame in the transmitter frame, metres.
    centre_sensor : (n, 2, 3) ndarray of float64
        The same point in the upper (``[:, 0]``) and lower (``[:, 1]``) sensor
        frames, metres.  Constant for a hinge; it moves in the upper frame for
        the finger-like joint (the lower bone slides on the upper one).
    reference_centre : (2, 3) ndarray of float64
        The joint centre that estimates are scored against, in the upper and
        lower sensor frames (metres): the centre of the *extended* joint, which
        is the one that segment lengths measured on an open hand refer to.
    joint_kind : str
        ``"hinge"`` or ``"finger"``.
    """

    centre_world: np.ndarray
    centre_sensor: np.ndarray
    reference_centre: np.ndarray
    joint_kind: str

    def __post_init__(self) -> None:
        for name in ("centre_world", "centre_sensor", "reference_centre"):
            object.__setattr__(self, name, _frozen(getattr(self, name)))
        n = self.centre_world.shape[0]
        _check_shape("centre_world", self.centre_world, (n, 3))
        _check_shape("centre_sensor", self.centre_sensor, (n, 2, 3))
        _check_shape("reference_centre", self.reference_centre, (2, 3))

    def take(self, index: np.ndarray) -> GroundTruth:
        """Ground truth restricted to the frames `index`."""
        return dataclasses.replace(
            self,
            centre_world=self.centre_world[index],
            centre_sensor=self.centre_sensor[index],
        )


@dataclass(frozen=True, eq=False)
class Recording(_ByValue):
    """Poses of two 6-DOF sensors across one joint.

    Parameters
    ----------
    times : (n,) array_like of float
        Sample times in seconds, strictly increasing.
    positions : (n, 2, 3) array_like of float
        Sensor origins in the transmitter frame, metres; ``[:, 0]`` is the
        upper (proximal) sensor, ``[:, 1]`` the lower (distal) one.
    rotations : (n, 2, 3, 3) array_like of float
        Sensor orientations, mapping sensor-frame vectors to the transmitter
        frame.  Each must be a proper rotation (see
        :data:`~handsynth.sensors.common.ROTATION_TOLERANCE`).  Transposed
        rotations (transmitter -> sensor) are proper rotations too and cannot
        be refused here; the estimators warn when they look transposed.
    labels : tuple of str, optional
        Names of the segments carrying the upper and lower sensor, e.g.
        ``("index_middle", "index_distal")``; used to chain joints into
        segment lengths.
    joint : str, optional
        Name of the joint between them, e.g. ``"index_dip"``.
    metadata : mapping, optional
        Free-form, JSON-serialisable provenance (source file, units, noise);
        kept as a read-only copy.
    truth : GroundTruth, optional
        Present for simulated recordings.

    Raises
    ------
    RecordingError
        Wrong shapes, non-finite values (naming the frames), non-increasing
        times, fewer than 10 frames, or matrices that are not rotations.
    """

    times: np.ndarray
    positions: np.ndarray
    rotations: np.ndarray
    labels: tuple[str, str] = ("upper", "lower")
    joint: str = "joint"
    metadata: Mapping[str, Any] = field(default_factory=dict)
    truth: GroundTruth | None = None

    def __post_init__(self) -> None:
        for name in ("times", "positions", "rotations"):
            object.__setattr__(self, name, _frozen(getattr(self, name)))
        object.__setattr__(self, "metadata", MappingProxyType(dict(self.metadata)))
        object.__setattr__(self, "labels", tuple(str(s) for s in self.labels))
        n = self.times.shape[0] if self.times.ndim == 1 else -1
        _check_shape("times", self.times, (None,))
        _check_shape("positions", self.positions, (n, 2, 3))
        _check_shape("rotations", self.rotations, (n, 2, 3, 3))
        if len(self.labels) != 2:
            raise RecordingError(f"labels: expected 2 names, got {self.labels!r}")
        if n < 10:
            raise RecordingError(f"recording has {n} frames; at least 10 are needed")
        bad = ~np.isfinite(self.times)
        bad |= ~np.isfinite(self.positions).all(axis=(1, 2))
        bad |= ~np.isfinite(self.rotations).all(axis=(1, 2, 3))
        if bad.any():
            where = np.flatnonzero(bad)
            raise RecordingError(
                f"{where.size} frames contain NaN or inf (first frames "
                f"{where[:5].tolist()}); read the file with on_invalid='drop' "
                f"to skip them"
            )
        dt = np.diff(self.times)
        if not (dt > 0).all():
            i = int(np.flatnonzero(~(dt > 0))[0])
            raise RecordingError(
                f"times must increase strictly; times[{i + 1}] = "
                f"{self.times[i + 1]!r} <= times[{i}] = {self.times[i]!r}"
            )
        check_rotations(self.rotations, name="rotations")
        if self.truth is not None and self.truth.centre_world.shape[0] != n:
            raise RecordingError(
                f"truth has {self.truth.centre_world.shape[0]} frames, recording {n}"
            )

    # -- convenience -----------------------------------------------------
    @property
    def n_frames(self) -> int:
        """Number of frames ``n``."""
        return int(self.times.shape[0])

    @property
    def rate_hz(self) -> float:
        """Sampling rate in Hz: one over the mean step between frames.

        Steps beyond 1.5 times the median (frames dropped) are left out.  A
        mean rather than the median, because exported stamps are rounded: at
        240 Hz with four decimals the steps alternate 0.0042 and 0.0041 s,
        whose median read 238 Hz.
        """
        steps = np.diff(self.times)
        typical = steps[steps <= 1.5 * np.median(steps)]
        return float(1.0 / np.mean(typical))

    @property
    def duration_s(self) -> float:
        """``times[-1] - times[0]`` in seconds."""
        return float(self.times[-1] - self.times[0])

    def relative(self) -> tuple[np.ndarray, np.ndarray]:
        """Pose of the lower sensor in the upper sensor's frame.

        Returns
        -------
        q : (n, 3, 3) ndarray of float64
            ``R_U^T R_L``: lower-sensor vectors to upper-sensor vectors.
        d : (n, 3) ndarray of float64
            ``R_U^T (t_L - t_U)``: lower-sensor origin in the upper frame, m.
        """
        return relative_pose(self.rotations, self.positions)

    def take(self, index: np.ndarray) -> Recording:
        """A new recording with only the frames `index` (sorted, unique)."""
        index = np.unique(np.asarray(index, dtype=np.int64))
        return dataclasses.replace(
            self,
            times=self.times[index],
            positions=self.positions[index],
            rotations=self.rotations[index],
            truth=None if self.truth is None else self.truth.take(index),
        )
