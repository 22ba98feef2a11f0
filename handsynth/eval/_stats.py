"""Error statistics of the camera evaluation, and the hand shapes it tests."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .._checks import check_instance, check_number
from ..errors import InvalidInputError
from ..models import GRID_LEVELS, JOINT_NAMES, HandShape

__all__ = ["JointStats", "joint_stats", "ratio_distance", "silhouette_ambiguity"]


@dataclass(frozen=True, eq=False)
class JointStats:
    """Per-joint statistics of signed errors.

    Attributes
    ----------
    mean_deg : ndarray of float64, shape (20,)
        Mean signed error (estimate - truth), degrees.
    sd_deg : ndarray of float64, shape (20,)
        Sample standard deviation (``ddof=1``) of the signed error, degrees;
        NaN with fewer than 2 frames.
    mae_deg : ndarray of float64, shape (20,)
        Mean absolute error, degrees.
    n : ndarray of int64, shape (20,)
        Frames counted per joint (NaN errors are left out).
    """

    mean_deg: np.ndarray
    sd_deg: np.ndarray
    mae_deg: np.ndarray
    n: np.ndarray

    @property
    def overall_mae_deg(self) -> float:
        """Mean of the 20 joints' MAE, degrees (NaN if any joint has no frame)."""
        return float(np.mean(self.mae_deg))

    def joint(self, name: str) -> dict:
        """The figures of one joint by canonical name."""
        if name not in JOINT_NAMES:
            raise InvalidInputError(f"unknown joint {name!r}; expected one of JOINT_NAMES")
        j = JOINT_NAMES.index(name)
        return {"mean_deg": _num(self.mean_deg[j]), "sd_deg": _num(self.sd_deg[j]),
                "mae_deg": _num(self.mae_deg[j]), "n": int(self.n[j])}

    def as_dict(self) -> dict:
        """``{joint name: {"mean_deg", "sd_deg", "mae_deg", "n"}}`` in canonical order."""
        return {name: self.joint(name) for name in JOINT_NAMES}


def _num(v) -> float | None:
    v = float(v)
    return None if not math.isfinite(v) else round(v, 4)


def joint_stats(errors_deg) -> JointStats:
    """Mean, s.d. and mean absolute value of signed errors, per joint.

    Parameters
    ----------
    errors_deg : array_like, shape (N, 20)
        Signed errors in degrees (estimate - truth); NaN entries (frames
        without an estimate) are left out of their joint's figures.

    Returns
    -------
    JointStats
        Sample s.d. with ``ddof=1``.

    Raises
    ------
    InvalidInputError
        Not an (N, 20) array of numbers, no rows (N = 0: no statistic is
        defined), or infinite values.
    """
    try:
        e = np.asarray(errors_deg, dtype=np.float64)
    except (TypeError, ValueError):
        raise InvalidInputError(f"errors_deg must be an (N, 20) array of degrees, got "
                                f"{type(errors_deg).__name__}") from None
    if e.ndim != 2 or e.shape[1] != len(JOINT_NAMES):
        raise InvalidInputError(f"errors_deg must have shape (N, 20), got {e.shape}")
    if len(e) == 0:
        raise InvalidInputError(f"errors_deg must have at least one row (frame), got shape {e.shape}")
    if np.isinf(e).any():
        raise InvalidInputError("errors_deg must be finite or NaN, got an infinite value")
    ok = ~np.isnan(e)
    n = ok.sum(axis=0)
    z = np.where(ok, e, 0.0)
    with np.errstate(invalid="ignore", divide="ignore"):
        mean = np.where(n > 0, z.sum(axis=0) / n, np.nan)
        mae = np.where(n > 0, np.abs(z).sum(axis=0) / n, np.nan)
        sq = np.where(ok, (e - mean) ** 2, 0.0).sum(axis=0)
        sd = np.where(n > 1, np.sqrt(sq / np.maximum(n - 1, 1)), np.nan)
    return JointStats(mean_deg=mean, sd_deg=sd, mae_deg=mae, n=n.astype(np.int64))


def ratio_distance(shape: HandShape, grid: HandShape) -> float:
    """Distance of `shape`'s ratios from `grid`'s, in grid steps.

    ``sqrt(sum_k ((r_k - g_k) / s_k)^2)`` over length, width, palm and thumb,
    with ``s_k`` half the span of ratio ``k``'s levels in
    :data:`~handsynth.models.GRID_LEVELS` (one grid step).

    Parameters
    ----------
    shape, grid : HandShape

    Returns
    -------
    float
        Unitless; 0 when the ratios are equal.

    Raises
    ------
    InvalidInputError
        `shape` or `grid` is not a :class:`HandShape`.
    """
    check_instance(shape, HandShape, name="shape")
    check_instance(grid, HandShape, name="grid")
    total = 0.0
    for name, levels in GRID_LEVELS.items():
        step = 0.5 * (levels[-1] - levels[0])
        total += ((getattr(shape, name) - getattr(grid, name)) / step) ** 2
    return math.sqrt(total)


def silhouette_ambiguity(database, *, spread_deg: float = 20.0) -> dict:
    """How far a database's silhouettes can tell its poses apart.

    Entries are grouped by identical 64x64 silhouettes (the packed bits);
    within a group the search has nothing to choose by but the HLAC of the
    same contour (identical too), so any of the group's poses may come back.

    Parameters
    ----------
    database : handsynth.db.Database
    spread_deg : float, keyword-only
        A joint is *ambiguous* in an entry when the entry's group spans more
        than this (max - min of the joint's angle), degrees.

    Returns
    -------
    dict
        ``entries``, ``distinct_silhouettes``, ``entries_sharing`` (entries
        whose silhouette another entry has too), ``ambiguous_entries``
        (entries with at least one ambiguous joint), ``spread_deg`` and
        ``per_joint``: canonical joint name -> number of entries in which it
        is ambiguous.

    Raises
    ------
    InvalidInputError
        `spread_deg` not a finite number > 0 (at 0 or below every entry would
        read as ambiguous), or `database` without (N, words) silhouettes, N >= 1.
    """
    check_number(spread_deg, "spread_deg", above=0)
    bits = np.ascontiguousarray(np.asarray(database.sil_bits, dtype=np.uint64))
    if bits.ndim != 2 or len(bits) == 0:
        raise InvalidInputError(f"database.sil_bits must be (N, words) with N >= 1, "
                                f"got shape {bits.shape}")
    rows = bits.view(np.dtype((np.void, bits.dtype.itemsize * bits.shape[1]))).ravel()
    _, inverse, counts = np.unique(rows, return_inverse=True, return_counts=True)
    inverse = inverse.ravel()
    angles = np.asarray(database.angles, dtype=np.float64)
    hi = np.full((len(counts), angles.shape[1]), -np.inf)
    lo = np.full((len(counts), angles.shape[1]), np.inf)
    np.maximum.at(hi, inverse, angles)
    np.minimum.at(lo, inverse, angles)
    ambiguous = (hi - lo)[inverse] > spread_deg
    return {"entries": len(angles), "distinct_silhouettes": len(counts),
            "entries_sharing": int((counts[inverse] > 1).sum()),
            "ambiguous_entries": int(ambiguous.any(axis=1).sum()),
            "spread_deg": float(spread_deg),
            "per_joint": {n: int(ambiguous[:, j].sum()) for j, n in enumerate(JOINT_NAMES)}}
