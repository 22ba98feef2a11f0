"""Joint-centre estimators: the patent's method and the classic baselines.

Every estimator is a frozen, keyword-only dataclass of its options (a typo in
an option name raises ``TypeError``) with one method,
``estimate(recording) -> JointCentreResult``; :class:`JointCentreEstimator`
is the runtime-checkable protocol they satisfy.  Frame selection (all frames
or the axis-angle filter) and the input checks are shared, so the methods
differ only in how they turn the selected frames into ``P_U`` and ``P_L``.

Notation (JP2010-88628, para. 0039): ``P`` is a point fixed in the upper
receiver's frame, ``v_UP`` its position there; ``v_LP(i)`` is its position
seen from the lower receiver in frame ``i``.  Because a rotation keeps
lengths, ``|v_LP(i)| = |v_UP - d(i)|`` with ``d(i)`` the lower receiver's
origin in the upper frame, so the patent's objective is evaluated on an
``(n, 3)`` point cloud with one vectorised norm per call.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Protocol, runtime_checkable

import numpy as np
from scipy.optimize import minimize
from scipy.spatial.transform import Rotation

from ...errors import EstimationError, InvalidInputError
from ..common import matrix_to_rotvec
from ._axis_filter import (
    AxisAngleFilter,
    AxisFilterResult,
    _reference_frames,
    principal_axis,
)
from ._checks import check_integer, check_number
from ._determinability import (
    Determinability,
    _fit_residual,
    _sensor_midpoint,
    assess_determinability,
    linear_centre,
)
from ._plane import foot_of_perpendicular, plane_coordinates, plane_point
from ._recording import Recording, relative_pose
from ._result import JointCentreResult, centre_distance_mm

__all__ = [
    "JointCentreEstimator",
    "OBrienEstimator",
    "PlaneVarianceEstimator",
    "VarianceEstimator",
]


@runtime_checkable
class JointCentreEstimator(Protocol):
    """What every joint-centre estimator provides."""

    name: str

    def estimate(self, recording: Recording) -> JointCentreResult:
        """Estimate the joint centre in both sensor frames."""
        ...


# --------------------------------------------------------------------------
# shared frame selection and checks


@dataclass(frozen=True)
class _Frames:
    """The frames an estimator works on, in both sensor frames."""

    recording: Recording  # restricted to the frames used
    index: np.ndarray  # (k,) into the original recording
    q: np.ndarray  # (k, 3, 3) lower -> upper sensor frame
    d: np.ndarray  # (k, 3) lower origin in the upper frame, m
    lateral_upper: np.ndarray  # (3,) finger width direction, upper sensor frame
    q0: np.ndarray  # (3, 3) relative rotation in the standard state
    rom_deg: float
    filter_result: AxisFilterResult | None
    det: Determinability
    single_axis: bool
    transposed: str  # why the rotations look transposed, or ""


def _check_frozen(recording: Recording) -> None:
    for s, role in enumerate(("upper", "lower")):
        p = recording.positions[:, s]
        r = recording.rotations[:, s]
        if np.ptp(p, axis=0).max() == 0 and np.ptp(r, axis=0).max() == 0:
            raise EstimationError(
                f"sensor {s} ({role}, on {recording.labels[s]!r}) reports exactly the "
                f"same pose in all {recording.n_frames} frames: it is frozen or "
                f"disconnected"
            )


# Rotations given the other way round (transmitter to sensor) are proper
# rotations too and pass every check of a Recording; the centre found from
# them is some 20-40 mm off.  They are told apart by the fit of a point fixed
# in both sensors: taking the transposes back, the fit becomes markedly
# better.  On simulated recordings of every configuration of
# handsynth.sensors.evaluate (10-75 deg range of motion, all error models) the
# transposed fit of correct rotations was never better than 0.95 times the
# fit as given, while on transposed rotations it is 2-180 times better when
# the motion is large enough -- but only 1.0-1.4 times for a pure hinge at
# Liberty accuracy noise, which this test therefore misses (docs/trackers.md).
_TRANSPOSED_FIT_RATIO = 0.5


def _transposed_rotations(recording: Recording, residual_mm: float) -> str:
    """A note when the transposed rotations fit markedly better, else ""."""
    if not residual_mm > 0:
        return ""
    q, d = relative_pose(np.swapaxes(recording.rotations, -1, -2), recording.positions)
    alt = float(np.sqrt((_fit_residual(q, d) ** 2).mean()) * 1e3)
    if not alt < _TRANSPOSED_FIT_RATIO * residual_mm:
        return ""
    return (
        f"rotations transposed? The point fixed in both sensors fits with "
        f"{residual_mm:.3g} mm RMS per coordinate as given but {alt:.3g} mm with every "
        f"rotation transposed: the rotations must map sensor-frame vectors to the "
        f"transmitter frame (sensor -> transmitter), not the reverse"
    )


def _range_of_motion(q: np.ndarray) -> float:
    """Spread of relative rotations about their main axis, degrees."""
    mean = Rotation.from_matrix(q).mean().as_matrix()
    rv = matrix_to_rotvec(q @ mean.T)
    axis = principal_axis(rv)
    proj = np.rad2deg(rv @ axis)
    lo, hi = np.percentile(proj, [1.0, 99.0])
    return float(hi - lo)


@dataclass(frozen=True, kw_only=True)
class _Estimator:
    """Options shared by all estimators.

    Parameters
    ----------
    frames : {"all", "filtered"}
        Use every frame, or only those kept by the axis-angle filter.
    axis_filter : AxisAngleFilter
        Filter options (patent: 100 bins of the lateral axis component).
    min_rom_deg : float
        Smallest range of motion (deg) accepted in the frames used, a floor
        below the data-driven checks.
    min_frames : int
        Smallest number of frames accepted after filtering.
    refuse_error_mm : float
        Refuse (:class:`EstimationError`) when the expected error of the
        centre across the joint axis exceeds this (see
        :mod:`~handsynth.sensors.trackers._determinability`).
    warn_error_mm : float
        Above this expected error the result carries a warning with it.
    axis_error_mm : float
        When the expected error *along* the best axis exceeds this, the
        motion counts as single-axis: only the axis is determined, and the
        centre reported is the point of the axis nearest the two sensors.
    max_distance_mm : float
        A centre farther than this from either sensor is not a finger joint
        centre; it is refused, never returned.
    max_residual_mm : float
        Refuse when no point is fixed in both sensors to within this RMS per
        coordinate (the sensors are not on the two sides of one joint, or
        the data are corrupt).
    """

    frames: str = "all"
    axis_filter: AxisAngleFilter = field(default_factory=AxisAngleFilter)
    min_rom_deg: float = 5.0
    min_frames: int = 30
    refuse_error_mm: float = 10.0
    warn_error_mm: float = 2.0
    axis_error_mm: float = 2.0
    max_distance_mm: float = 60.0
    max_residual_mm: float = 5.0

    name = "base"

    def __post_init__(self) -> None:
        if self.frames not in ("all", "filtered"):
            raise InvalidInputError(
                f"frames: expected 'all' or 'filtered', got {self.frames!r}"
            )
        if not isinstance(self.axis_filter, AxisAngleFilter):
            raise InvalidInputError(
                f"axis_filter: expected an AxisAngleFilter, got {self.axis_filter!r}"
            )
        self._set("min_rom_deg", check_number(self.min_rom_deg, "min_rom_deg", minimum=0.0))
        self._set("min_frames", check_integer(self.min_frames, "min_frames", minimum=3))
        for n in ("refuse_error_mm", "warn_error_mm", "axis_error_mm", "max_distance_mm",
                  "max_residual_mm"):
            self._set(n, check_number(getattr(self, n), n, above=0.0))
        if self.warn_error_mm > self.refuse_error_mm:
            raise InvalidInputError(
                f"warn_error_mm ({self.warn_error_mm!r}) must not exceed refuse_error_mm "
                f"({self.refuse_error_mm!r})"
            )

    def _set(self, name: str, value: object) -> None:
        """Store a checked option (a plain ``float`` or ``int``) in the frozen instance."""
        object.__setattr__(self, name, value)

    def _select(self, recording: Recording) -> _Frames:
        if not isinstance(recording, Recording):
            raise InvalidInputError(
                f"recording: expected a handsynth.sensors.Recording, got "
                f"{type(recording).__name__}"
            )
        _check_frozen(recording)
        filt = None
        index = np.arange(recording.n_frames)
        if self.frames == "filtered":
            filt = self.axis_filter.apply(recording)
            index = filt.frames
        if index.size < self.min_frames:
            raise EstimationError(
                f"{index.size} frames left after the axis-angle filter (bin "
                f"{filt.chosen_range[0]:.3f}-{filt.chosen_range[1]:.3f}); at least "
                f"min_frames={self.min_frames} are needed"
                if filt is not None
                else f"{index.size} frames; at least min_frames={self.min_frames} are needed"
            )
        sub = recording.take(index) if filt is not None else recording
        q, d = sub.relative()
        rom = _range_of_motion(q)
        where = "in the filtered frames" if filt is not None else "in the recording"
        if rom < self.min_rom_deg:
            raise EstimationError(
                f"range of motion {rom:.1f} deg {where} is below min_rom_deg="
                f"{self.min_rom_deg:g}: the joint barely moved, so a centre cannot "
                f"be fixed; flex the joint further"
            )
        det = assess_determinability(q, d)
        transposed = _transposed_rotations(sub, det.residual_mm)
        if det.residual_mm > self.max_residual_mm:
            raise EstimationError(
                f"no point is fixed in both sensors {where}: the best one moves by "
                f"{det.residual_mm:.1f} mm RMS per coordinate (> max_residual_mm="
                f"{self.max_residual_mm:g}); "
                + (transposed or "are both sensors on the two sides of one joint, and "
                   "the file read with the right columns and units?")
            )
        across = float(det.expected_error_mm[1])
        if not across <= self.refuse_error_mm:
            raise EstimationError(
                f"the motion {where} does not determine the joint centre: expected "
                f"error {across:.3g} mm > refuse_error_mm={self.refuse_error_mm:g} "
                f"(the directions across the joint axis turn by only {det.spread_deg[1]:.2f} "
                f"and {det.spread_deg[2]:.2f} deg RMS, range of motion {rom:.1f} deg, "
                f"residual {det.residual_mm:.2f} mm); "
                + (transposed or "flex the joint further or record longer")
            )
        single_axis = not float(det.expected_error_mm[0]) <= self.axis_error_mm
        q_all, _ = recording.relative()
        k = _reference_frames(recording, self.axis_filter.reference_s)
        q0 = Rotation.from_matrix(q_all[:k]).mean().as_matrix()
        if filt is not None:
            lateral = filt.lateral_axis
        else:
            rv = matrix_to_rotvec(q_all @ q0.T)
            lateral = self.axis_filter._lateral_axis(recording, rv)
        return _Frames(sub, index, q, d, lateral, q0, rom, filt, det, single_axis, transposed)

    def _finish(self, f: _Frames, cu: np.ndarray, cl: np.ndarray) -> tuple[
            np.ndarray, np.ndarray, list[str]]:
        """Single-axis convention, bounds and warnings shared by every method."""
        det = f.det
        notes = [f.transposed] if f.transposed else []
        if f.single_axis:
            # slide rigidly along the axis to the point nearest both sensors
            e = np.concatenate([det.axis_upper, det.axis_lower]) / np.sqrt(2)
            x = np.concatenate([cu, cl])
            m = _sensor_midpoint(f.q, f.d)
            x = x + (e @ (m - x)) * e
            cu, cl = x[:3], x[3:]
            notes.append(
                f"single-axis motion: only the joint axis is determined (the axis itself "
                f"turns by {det.spread_deg[0]:.2f} deg RMS, expected error along it "
                f"{min(det.expected_error_mm[0], 1e6):.3g} mm); the centre given is the "
                f"point of the axis nearest the two sensors"
            )
        if det.expected_error_mm[1] > self.warn_error_mm:
            notes.append(
                f"the centre is poorly determined: expected error {det.expected_error_mm[1]:.1f} "
                f"mm across the joint axis (directions across it turn by "
                f"{det.spread_deg[1]:.2f} deg RMS); "
                f"flex the joint further"
            )
        far = max(float(np.linalg.norm(cu)), float(np.linalg.norm(cl))) * 1e3
        if not far <= self.max_distance_mm:
            raise EstimationError(
                f"{self.name}: the centre found is {far:.3g} mm from a sensor (> "
                f"max_distance_mm={self.max_distance_mm:g}); that is not a finger joint "
                f"centre: the motion or this method does not determine it"
            )
        lu, ll = linear_centre(f.q, f.d, free_directions=int(f.single_axis))
        gap = float(np.linalg.norm(np.concatenate([cu - lu, cl - ll])) / np.sqrt(2)) * 1e3
        if gap > self.refuse_error_mm:
            raise EstimationError(
                f"{self.name}: its centre is {gap:.1f} mm from the linear least-squares "
                f"centre, whose expected error is {det.expected_error_mm[1]:.2g} mm "
                f"(> refuse_error_mm={self.refuse_error_mm:g} apart): this method's "
                f"objective does not determine the centre in this motion; use 'obrien'"
            )
        if gap > max(self.warn_error_mm, float(det.expected_error_mm[1])):
            notes.append(
                f"{self.name} differs from the linear least-squares centre by {gap:.1f} mm"
            )
        return cu, cl, notes

    def _result(self, f: _Frames, cu, cl, residual_mm: float,
                notes: list[str]) -> JointCentreResult:
        cu = np.asarray(cu, dtype=np.float64)
        cl = np.asarray(cl, dtype=np.float64)
        if not (np.isfinite(cu).all() and np.isfinite(cl).all()):
            raise EstimationError(f"{self.name}: the estimate is not finite")
        dist = centre_distance_mm(f.recording, cu, cl)
        return JointCentreResult(
            method=self.name,
            frames_mode=self.frames,
            centre_upper=cu,
            centre_lower=cl,
            distance_mm=float(dist.mean()),
            residual_mm=float(residual_mm),
            frames=f.index.astype(np.int64),
            n_frames_total=0,  # set by estimate()
            range_of_motion_deg=f.rom_deg,
            labels=f.recording.labels,
            joint=f.recording.joint,
            axis_filter=f.filter_result,
            determinability=f.det,
            determined="axis" if f.single_axis else "point",
            warnings=tuple(notes),
        )

    def _solve(self, f: _Frames) -> tuple[np.ndarray, np.ndarray, float]:
        raise NotImplementedError

    def estimate(self, recording: Recording) -> JointCentreResult:
        """Estimate ``P_U`` and ``P_L`` from `recording`.

        Parameters
        ----------
        recording : Recording

        Returns
        -------
        JointCentreResult
            With ``determined="axis"`` for a single-axis motion and its
            ``warnings`` (expected error, single axis, disagreement with the
            linear solution) to be shown with the centre.

        Raises
        ------
        EstimationError
            A frozen sensor, too few frames, a motion that does not
            determine the centre, no point fixed in both sensors, or a
            centre farther than ``max_distance_mm`` from a sensor.

        Notes
        -----
        When the rotations fit markedly better transposed (given
        transmitter -> sensor instead of sensor -> transmitter), the result's
        first warning, or the refusal, says so ("rotations transposed?").
        The test misses transposed rotations of small or hinge-like motions
        at Liberty accuracy noise; see docs/trackers.md.
        """
        f = self._select(recording)
        try:
            cu, cl, residual = self._solve(f)
            cu, cl, notes = self._finish(f, np.asarray(cu, float), np.asarray(cl, float))
        except EstimationError as exc:
            if not f.transposed:
                raise
            raise EstimationError(f"{exc}; {f.transposed}") from None
        res = self._result(f, cu, cl, residual, notes)
        object.__setattr__(res, "n_frames_total", recording.n_frames)
        return res


# --------------------------------------------------------------------------
# variance of |v_LP| (patent eqs. 1-2), plane-constrained and in 3-D


def _variance_mm2(p_mm: np.ndarray, points_mm: np.ndarray) -> float:
    """Eq. 2: ``s^2`` of ``|v_LP(i)|`` (eq. 1) for one candidate point."""
    r = np.sqrt(((points_mm - p_mm) ** 2).sum(axis=1))
    return float(r.var())


def _initial_point(points_mm: np.ndarray, rcond: float = 0.1) -> np.ndarray:
    """A point ``V`` for eq. 9: an algebraic sphere fit to the points.

    Solves ``2 m_i . q = |m_i|^2 - mean |m|^2`` (``m_i`` the centred points)
    with a truncated SVD, so that for a hinge (points on a circle) it returns
    the point of the axis nearest the points' centroid.
    """
    c = points_mm.mean(axis=0)
    m = points_mm - c
    rhs = (m**2).sum(axis=1)
    q, *_ = np.linalg.lstsq(2 * m, rhs - rhs.mean(), rcond=rcond)
    return c + q


def _side_data(f: _Frames, side: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Other sensor's origins (mm), the width direction and the linear
    centre (mm), in this sensor's frame."""
    lu, ll = linear_centre(f.q, f.d, free_directions=int(f.single_axis))
    if side == "upper":
        return f.d * 1e3, f.lateral_upper, lu * 1e3
    # lower frame: the upper origin is -Q^T d; the width direction is carried
    # over with the standard-state relative rotation (segments aligned there)
    pts = -np.einsum("nji,nj->ni", f.q, f.d) * 1e3
    return pts, f.q0.T @ f.lateral_upper, ll * 1e3


def _starts(points: np.ndarray, linear: np.ndarray) -> list[np.ndarray]:
    """Candidate points ``V`` (mm): the linear centre first, then the sphere
    fit and the midpoint of the two sensors."""
    cands = [linear, _initial_point(points), 0.5 * points.mean(axis=0)]
    return [c for c in cands if np.isfinite(c).all()]


def _bounded(objective, bound_mm: float):
    """`objective` of a point (mm), with a steep penalty beyond `bound_mm`
    from the sensor (the frame's origin)."""

    def f(p_mm: np.ndarray) -> float:
        r = float(np.linalg.norm(p_mm))
        val = objective(p_mm)
        if r > bound_mm:
            val += 1e3 * (r - bound_mm) ** 2 + 1e3
        return val

    return f


@dataclass(frozen=True, kw_only=True)
class _VarianceSearch(_Estimator):
    """Nelder-Mead search of eq. 2 from several starts, inside a bound."""

    xatol_mm: float = 1e-3
    fatol_mm2: float = 1e-9
    maxiter: int = 2000

    def __post_init__(self) -> None:
        super().__post_init__()
        for n in ("xatol_mm", "fatol_mm2"):
            self._set(n, check_number(getattr(self, n), n, above=0.0))
        self._set("maxiter", check_integer(self.maxiter, "maxiter", minimum=1))

    def _search(self, points: np.ndarray, axis: np.ndarray,
                linear: np.ndarray) -> tuple[np.ndarray, float]:
        raise NotImplementedError

    def _pick(self, found: list[tuple[np.ndarray, float]]) -> tuple[np.ndarray, float]:
        """Best of the restarts; a minimum at the bound is no answer."""
        p, v = min(found, key=lambda pv: pv[1])
        if np.linalg.norm(p) > self.max_distance_mm - 1.0:
            raise EstimationError(
                f"{self.name}: the variance of |v_LP| (eq. 2) keeps falling toward the "
                f"search bound ({self.max_distance_mm:g} mm from the sensor): this "
                f"motion does not fix its minimum; use 'obrien' or flex the joint further"
            )
        return p, v

    def _solve(self, f: _Frames):
        pu, vu = self._search(*_side_data(f, "upper"))
        pl, vl = self._search(*_side_data(f, "lower"))
        return pu * 1e-3, pl * 1e-3, float(np.sqrt(0.5 * (vu + vl)))


@dataclass(frozen=True, kw_only=True)
class PlaneVarianceEstimator(_VarianceSearch):
    """The patent's estimator (JP2010-88628, para. 0039-0074).

    For ``P_U``: minimise ``s^2`` (eq. 2) of ``|v_LP(i)|`` (eq. 1) over the
    point ``P(s, t)`` of a plane (eq. 4, the constraint of para. 0044-0057)
    with Nelder-Mead (scipy), starting from the foot of the perpendicular
    from a point ``V`` (eqs. 6-9).  ``P_L`` is the same with the roles of the
    receivers swapped (para. 0074).

    The patent leaves ``P1, P2, P3`` and ``V`` to the user ("任意の位置に配置
    した点V", para. 0061).  Here the plane is the finger's sagittal plane:
    normal to the finger's width direction (the ``y`` axis of the patent's
    segment frames; ``axis_filter.lateral_axis`` says how it is obtained)
    and through the midpoint of the two receivers, which the patent centres
    on the phalanges (para. 0103).  For a hinge the minimisers of eq. 2 form
    the whole joint axis, and this plane picks the point of the axis on the
    finger's midline.

    Robustness: eq. 2 is not bounded below along every direction (far from
    the sensors, ``|v_LP|`` varies only with the component of the other
    sensor's motion along the line of sight), so the search is run from
    three points ``V`` -- the linear least-squares centre
    (:func:`~handsynth.sensors.trackers._determinability.linear_centre`),
    an algebraic sphere fit and the midpoint of the two sensors -- inside a
    ball of radius ``max_distance_mm`` around the sensor, and the lowest
    minimum is kept.  A minimum at the ball's surface is refused.

    Parameters
    ----------
    plane_size_mm : float
        ``|P2 - P1| = |P3 - P1|``; sets the scale of ``(s, t)``.
    xatol_mm, fatol_mm2 : float
        Nelder-Mead tolerances on the point (mm) and on ``s^2`` (mm^2).
    maxiter : int
        Nelder-Mead iteration limit per start.

    Other parameters are those of every estimator (``frames``,
    ``axis_filter``, ``min_rom_deg``, ``min_frames``, the determinability
    thresholds and ``max_distance_mm``).
    """

    plane_size_mm: float = 10.0

    name = "patent"

    def __post_init__(self) -> None:
        super().__post_init__()
        self._set("plane_size_mm", check_number(self.plane_size_mm, "plane_size_mm", above=0.0))

    def _plane(self, points: np.ndarray, axis: np.ndarray):
        """``P1, P2, P3`` (mm): plane through the receivers' midpoint, normal `axis`."""
        mid = 0.5 * points.mean(axis=0)
        e1 = mid - axis * (mid @ axis)
        if np.linalg.norm(e1) < 1e-9:
            e1 = np.cross(axis, [1.0, 0.0, 0.0])
        e1 /= np.linalg.norm(e1)
        e2 = np.cross(axis, e1)
        h = self.plane_size_mm
        return mid, mid + h * e1, mid + h * e2

    def _search(self, points, axis, linear):
        p1, p2, p3 = self._plane(points, axis)
        objective = _bounded(lambda p: _variance_mm2(p, points), self.max_distance_mm)
        step = 1.0 / self.plane_size_mm  # 1 mm simplex
        found = []
        for v in _starts(points, linear):
            start = foot_of_perpendicular(p1, p2, p3, v)  # eqs. 6-9
            s0, t0 = plane_coordinates(p1, p2, p3, start)
            res = minimize(
                lambda w: objective(plane_point(p1, p2, p3, w[0], w[1])),  # eqs. 1-2, 4
                np.array([s0, t0]),
                method="Nelder-Mead",
                options={
                    "initial_simplex": np.array([[s0, t0], [s0 + step, t0], [s0, t0 + step]]),
                    "xatol": self.xatol_mm / self.plane_size_mm,
                    "fatol": self.fatol_mm2,
                    "maxiter": self.maxiter,
                },
            )
            found.append((plane_point(p1, p2, p3, res.x[0], res.x[1]), float(res.fun)))
        return self._pick(found)


@dataclass(frozen=True, kw_only=True)
class VarianceEstimator(_VarianceSearch):
    """Unconstrained 3-D minimisation of eq. 2 (the patent's starting point).

    Same objective, starts and bound as :class:`PlaneVarianceEstimator`
    (eqs. 1-2) but searched over all of 3-D space with Nelder-Mead.  The
    patent found it inaccurate (para. 0044): for a hinge-like joint every
    point of the axis minimises eq. 2, so the search drifts along the axis
    (a single-axis motion is then put back on the point nearest the sensors
    like every method's).

    Parameters
    ----------
    xatol_mm, fatol_mm2, maxiter
        As for :class:`PlaneVarianceEstimator`.
    """

    maxiter: int = 3000

    name = "variance3d"

    def _search(self, points, axis, linear):
        objective = _bounded(lambda p: _variance_mm2(p, points), self.max_distance_mm)
        found = []
        for v in _starts(points, linear):
            res = minimize(
                objective,
                v,
                method="Nelder-Mead",
                options={
                    "initial_simplex": v + np.vstack([np.zeros(3), np.eye(3)]),  # 1 mm
                    "xatol": self.xatol_mm,
                    "fatol": self.fatol_mm2,
                    "maxiter": self.maxiter,
                },
            )
            found.append((res.x, float(res.fun)))
        return self._pick(found)


# --------------------------------------------------------------------------
# O'Brien et al. (2000): linear least squares in the parent frame


@dataclass(frozen=True, kw_only=True)
class OBrienEstimator(_Estimator):
    """Linear least squares of O'Brien et al. (2000).

    O'Brien, Bodenheimer, Brostow & Hodgins, "Automatic joint parameter
    estimation from magnetic motion capture data", Graphics Interface 2000,
    pp. 53-60 (the patent's non-patent literature 1).  The centre is a point
    fixed in both segments: in the parent (upper) frame ``c_U = Q(i) c_L +
    d(i)`` for every frame, i.e. ``[I, -Q(i)] [c_U; c_L] = d(i)``, solved for
    the six unknowns in the least-squares sense in the eigenbasis of the
    normal matrix
    (:func:`~handsynth.sensors.trackers._determinability.linear_centre`).
    Every direction the data determine is solved for; along the joint axis
    of a single-axis motion (expected error above ``axis_error_mm``) the
    point nearest the two sensors is taken.
    """

    name = "obrien"

    def _solve(self, f: _Frames):
        cu, cl = linear_centre(f.q, f.d, free_directions=int(f.single_axis))
        resid = cu - np.einsum("nij,j->ni", f.q, cl) - f.d
        return cu, cl, float(np.sqrt((resid**2).sum(axis=1).mean()) * 1e3)
