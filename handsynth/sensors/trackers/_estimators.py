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
from ._plane import foot_of_perpendicular, plane_coordinates, plane_point
from ._recording import Recording
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
        Smallest range of motion (deg) accepted in the frames used; below it
        the centre is not determined and :class:`EstimationError` is raised.
    min_frames : int
        Smallest number of frames accepted after filtering.
    """

    frames: str = "all"
    axis_filter: AxisAngleFilter = field(default_factory=AxisAngleFilter)
    min_rom_deg: float = 10.0
    min_frames: int = 30

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
        if not (np.isfinite(self.min_rom_deg) and self.min_rom_deg >= 0):
            raise InvalidInputError(f"min_rom_deg must be >= 0, got {self.min_rom_deg!r}")
        if not (isinstance(self.min_frames, (int, np.integer)) and self.min_frames >= 3):
            raise InvalidInputError(f"min_frames must be an integer >= 3, got {self.min_frames!r}")

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
        if rom < self.min_rom_deg:
            where = "in the filtered frames" if filt is not None else "in the recording"
            raise EstimationError(
                f"range of motion {rom:.1f} deg {where} is below min_rom_deg="
                f"{self.min_rom_deg:g}: the joint barely moved, so a centre cannot "
                f"be fixed; flex the joint further"
            )
        q_all, _ = recording.relative()
        k = _reference_frames(recording, self.axis_filter.reference_s)
        q0 = Rotation.from_matrix(q_all[:k]).mean().as_matrix()
        if filt is not None:
            lateral = filt.lateral_axis
        else:
            rv = matrix_to_rotvec(q_all @ q0.T)
            lateral = self.axis_filter._lateral_axis(recording, rv)
        return _Frames(sub, index, q, d, lateral, q0, rom, filt)

    def _result(self, f: _Frames, cu, cl, residual_mm: float) -> JointCentreResult:
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

        Raises
        ------
        EstimationError
            A frozen sensor, too few frames, or too small a range of motion.
        """
        f = self._select(recording)
        cu, cl, residual = self._solve(f)
        res = self._result(f, cu, cl, residual)
        object.__setattr__(res, "n_frames_total", recording.n_frames)
        return res


# --------------------------------------------------------------------------
# variance of |v_LP| (patent eqs. 1-2), plane-constrained and in 3-D


def _variance_mm2(p_mm: np.ndarray, points_mm: np.ndarray) -> float:
    """Eq. 2: ``s^2`` of ``|v_LP(i)|`` (eq. 1) for one candidate point."""
    r = np.sqrt(((points_mm - p_mm) ** 2).sum(axis=1))
    return float(r.var())


def _initial_point(points_mm: np.ndarray, rcond: float = 0.1) -> np.ndarray:
    """Point ``V`` for eq. 9: an algebraic sphere fit to the points.

    Solves ``2 m_i . q = |m_i|^2 - mean |m|^2`` (``m_i`` the centred points)
    with a truncated SVD, so that for a hinge (points on a circle) it returns
    the point of the axis nearest the points' centroid.
    """
    c = points_mm.mean(axis=0)
    m = points_mm - c
    rhs = (m**2).sum(axis=1)
    q, *_ = np.linalg.lstsq(2 * m, rhs - rhs.mean(), rcond=rcond)
    return c + q


def _side_data(f: _Frames, side: str) -> tuple[np.ndarray, np.ndarray]:
    """Other sensor's origins (mm) and the width direction, in this sensor's frame."""
    if side == "upper":
        return f.d * 1e3, f.lateral_upper
    # lower frame: the upper origin is -Q^T d; the width direction is carried
    # over with the standard-state relative rotation (segments aligned there)
    pts = -np.einsum("nji,nj->ni", f.q, f.d) * 1e3
    return pts, f.q0.T @ f.lateral_upper


@dataclass(frozen=True, kw_only=True)
class PlaneVarianceEstimator(_Estimator):
    """The patent's estimator (JP2010-88628, para. 0039-0074).

    For ``P_U``: minimise ``s^2`` (eq. 2) of ``|v_LP(i)|`` (eq. 1) over the
    point ``P(s, t)`` of a plane (eq. 4, the constraint of para. 0044-0057)
    with Nelder-Mead (scipy), starting from the foot of the perpendicular
    from a point ``V`` (eqs. 6-9).  ``P_L`` is the same with the roles of the
    receivers swapped (para. 0074).

    The patent leaves ``P1, P2, P3`` and ``V`` to the user.  Here the plane
    is the finger's sagittal plane: normal to the finger's width direction
    (the ``y`` axis of the patent's segment frames; ``axis_filter.lateral_axis``
    says how it is obtained) and through the midpoint of the two receivers,
    which the patent centres on the phalanges (para. 0103).  For a hinge the
    minimisers of eq. 2 form the whole joint axis, and this plane picks the
    point of the axis on the finger's midline.  ``V`` is an algebraic sphere
    fit of the other receiver's positions.

    Parameters
    ----------
    plane_size_mm : float
        ``|P2 - P1| = |P3 - P1|``; sets the scale of ``(s, t)``.
    xatol_mm, fatol_mm2 : float
        Nelder-Mead tolerances on the point (mm) and on ``s^2`` (mm^2).
    maxiter : int
        Nelder-Mead iteration limit.

    Other parameters are those of every estimator (``frames``,
    ``axis_filter``, ``min_rom_deg``, ``min_frames``).
    """

    plane_size_mm: float = 10.0
    xatol_mm: float = 1e-3
    fatol_mm2: float = 1e-9
    maxiter: int = 2000

    name = "patent"

    def __post_init__(self) -> None:
        super().__post_init__()
        for n in ("plane_size_mm", "xatol_mm", "fatol_mm2"):
            v = getattr(self, n)
            if not (np.isfinite(v) and v > 0):
                raise InvalidInputError(f"{n} must be > 0, got {v!r}")
        if not (isinstance(self.maxiter, (int, np.integer)) and self.maxiter > 0):
            raise InvalidInputError(f"maxiter must be a positive integer, got {self.maxiter!r}")

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

    def _fit_side(self, points: np.ndarray, axis: np.ndarray) -> tuple[np.ndarray, float]:
        p1, p2, p3 = self._plane(points, axis)
        start = foot_of_perpendicular(p1, p2, p3, _initial_point(points))  # eqs. 6-9
        s0, t0 = plane_coordinates(p1, p2, p3, start)
        step = 1.0 / self.plane_size_mm  # 1 mm simplex
        simplex = np.array([[s0, t0], [s0 + step, t0], [s0, t0 + step]])

        def objective(w: np.ndarray) -> float:
            return _variance_mm2(plane_point(p1, p2, p3, w[0], w[1]), points)  # eqs. 1-2

        res = minimize(
            objective,
            np.array([s0, t0]),
            method="Nelder-Mead",
            options={
                "initial_simplex": simplex,
                "xatol": self.xatol_mm / self.plane_size_mm,
                "fatol": self.fatol_mm2,
                "maxiter": self.maxiter,
            },
        )
        return plane_point(p1, p2, p3, res.x[0], res.x[1]), float(res.fun)

    def _solve(self, f: _Frames):
        pu, vu = self._fit_side(*_side_data(f, "upper"))
        pl, vl = self._fit_side(*_side_data(f, "lower"))
        return pu * 1e-3, pl * 1e-3, float(np.sqrt(0.5 * (vu + vl)))


@dataclass(frozen=True, kw_only=True)
class VarianceEstimator(_Estimator):
    """Unconstrained 3-D minimisation of eq. 2 (the patent's starting point).

    Same objective and starting point as :class:`PlaneVarianceEstimator`
    (eqs. 1-2, start from eq. 9) but searched over all of 3-D space with
    Nelder-Mead.  The patent found it inaccurate (para. 0044): for a
    hinge-like joint every point of the axis minimises eq. 2, so the search
    drifts along the axis.

    Parameters
    ----------
    xatol_mm, fatol_mm2, maxiter
        As for :class:`PlaneVarianceEstimator`.
    """

    xatol_mm: float = 1e-3
    fatol_mm2: float = 1e-9
    maxiter: int = 3000

    name = "variance3d"

    def _fit_side(self, points: np.ndarray, axis: np.ndarray) -> tuple[np.ndarray, float]:
        plane = PlaneVarianceEstimator()._plane(points, axis)
        start = foot_of_perpendicular(*plane, _initial_point(points))
        simplex = start + np.vstack([np.zeros(3), np.eye(3)])  # 1 mm steps
        res = minimize(
            _variance_mm2,
            start,
            args=(points,),
            method="Nelder-Mead",
            options={
                "initial_simplex": simplex,
                "xatol": self.xatol_mm,
                "fatol": self.fatol_mm2,
                "maxiter": self.maxiter,
            },
        )
        return res.x, float(res.fun)

    def _solve(self, f: _Frames):
        pu, vu = self._fit_side(*_side_data(f, "upper"))
        pl, vl = self._fit_side(*_side_data(f, "lower"))
        return pu * 1e-3, pl * 1e-3, float(np.sqrt(0.5 * (vu + vl)))


# --------------------------------------------------------------------------
# O'Brien et al. (2000): linear least squares in the parent frame


def _solve_truncated(ata: np.ndarray, atb: np.ndarray, rcond: float) -> np.ndarray:
    """Minimum-norm solution of normal equations, singular values of ``A``
    below ``rcond * max`` discarded."""
    w, v = np.linalg.eigh(ata)
    sv = np.sqrt(np.clip(w, 0.0, None))
    keep = sv > rcond * sv.max()
    return v[:, keep] @ ((v[:, keep].T @ atb) / w[keep])


@dataclass(frozen=True, kw_only=True)
class OBrienEstimator(_Estimator):
    """Linear least squares of O'Brien et al. (2000).

    O'Brien, Bodenheimer, Brostow & Hodgins, "Automatic joint parameter
    estimation from magnetic motion capture data", Graphics Interface 2000,
    pp. 53-60 (the patent's non-patent literature 1).  The centre is a point
    fixed in both segments: in the parent (upper) frame ``c_U = Q(i) c_L +
    d(i)`` for every frame, i.e. ``[I, -Q(i)] [c_U; c_L] = d(i)``, solved for
    the six unknowns in the least-squares sense through the SVD of the
    stacked system.  For a hinge one singular value vanishes (the centre can
    slide along the axis); singular values below ``hinge_rcond`` times the
    largest are dropped, which gives the point of the axis nearest both
    receivers (minimum norm of ``[c_U; c_L]``).

    Parameters
    ----------
    hinge_rcond : float
        Relative singular-value threshold for the hinge case.
    """

    hinge_rcond: float = 0.05

    name = "obrien"

    def __post_init__(self) -> None:
        super().__post_init__()
        if not (np.isfinite(self.hinge_rcond) and 0 <= self.hinge_rcond < 1):
            raise InvalidInputError(f"hinge_rcond must be in [0, 1), got {self.hinge_rcond!r}")

    def _solve(self, f: _Frames):
        n = f.q.shape[0]
        qs = f.q.sum(axis=0)
        ata = np.block([[n * np.eye(3), -qs], [-qs.T, n * np.eye(3)]])
        atb = np.concatenate([f.d.sum(axis=0), -np.einsum("nji,nj->i", f.q, f.d)])
        x = _solve_truncated(ata, atb, self.hinge_rcond)
        cu, cl = x[:3], x[3:]
        resid = cu - np.einsum("nij,j->ni", f.q, cl) - f.d
        return cu, cl, float(np.sqrt((resid**2).sum(axis=1).mean()) * 1e3)
