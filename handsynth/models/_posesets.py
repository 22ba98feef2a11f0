"""Pose sets the databases are built from.

``paper``
    The set of seed 001 (SPEC.md section 1, "Paper's experiment"): each of
    index, middle, ring and little flexed and extended alone, their
    abduction-adduction alone, and the thumb alone, the other joints at the
    open hand.  The paper had 20,448 entries per shape; the default size here
    is the same.
``natural``
    Combined poses for users who move more than one finger at a time: fists,
    pinches, pointing and grasps with jitter, and random poses within the
    limits, all with the DIP ~ 2/3 PIP coupling (the relation used by seed 004,
    SPEC.md section 4).

Both are deterministic functions of ``(n, seed)``.  The paper set is sampled
with scrambled Sobol sequences (scipy.stats.qmc), so that any size covers its
space evenly; the natural set with NumPy's random generator (normal jitter
around the named poses, uniform grasp closures).
"""

from __future__ import annotations

import numpy as np

from ..errors import InvalidInputError
from ._joints import FINGERS, JOINT_LIMITS_DEG, JOINT_NAMES
from ._pose import NAMED_POSES

__all__ = ["MAX_POSES", "POSE_SETS", "natural_pose_set", "paper_pose_set", "pose_set"]

#: Entries of one shape's database in the paper's experiment (seed 001 section 3.1,
#: 20448 entries; SPEC.md section 1, "Paper's experiment").
PAPER_SIZE = 20_448
#: DIP flexion follows PIP flexion by this factor in coupled poses (seed 004 eq. 1;
#: SPEC.md section 4, "DIP = (2/3) PIP").
DIP_PIP_RATIO = 2.0 / 3.0
# share of the paper set given to each motion family
_PAPER_SHARES = {"flex": 0.40, "abd": 0.15, "thumb": 0.45}


def _sobol(n: int, dims: int, seed: int) -> np.ndarray:
    from scipy.stats import qmc

    if n == 0:
        return np.empty((0, dims))
    m = int(np.ceil(np.log2(max(n, 2))))
    return qmc.Sobol(d=dims, scramble=True, seed=seed).random_base2(m)[:n]


def _lim(name: str) -> tuple[float, float]:
    lo, hi = JOINT_LIMITS_DEG[JOINT_NAMES.index(name)]
    return float(lo), float(hi)


#: Most poses one pose set holds: 10 million, 1.6 GB of float64 angles.
MAX_POSES = 10_000_000


def _check_n(n, seed) -> tuple[int, int]:
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 1:
        raise InvalidInputError(f"pose count n must be a positive integer, got {n!r}")
    if n > MAX_POSES:
        raise InvalidInputError(f"pose count n must be at most {MAX_POSES:,} (160 bytes a pose "
                                f"in memory: {n:,} would need {n * 160 / 1e9:,.0f} GB), got {n}")
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise InvalidInputError(f"seed must be a non-negative integer, got {seed!r}")
    return int(n), int(seed)


def paper_pose_set(n: int = PAPER_SIZE, *, seed: int = 0) -> np.ndarray:
    """The paper's one-finger-at-a-time pose set.

    Families (shares of `n`): 40 % flexion-extension of one finger (MCP and
    PIP sampled jointly over their ranges, DIP = 2/3 PIP); 15 %
    abduction-adduction of one finger (MCP abduction over its range with MCP
    flexion 0-45 deg); 45 % thumb alone (all four thumb angles over their
    ranges).  Fingers take turns within a family.

    Parameters
    ----------
    n : int
        Number of poses (20,448 in the paper).
    seed : int, keyword-only
        Seed of the Sobol scrambling.

    Returns
    -------
    ndarray, shape (n, 20), float64
        Degrees, canonical order; the first pose is the open hand.
    """
    n, seed = _check_n(n, seed)
    out = np.zeros((n, len(JOINT_NAMES)))
    counts = {k: int(round(v * n)) for k, v in _PAPER_SHARES.items()}
    counts["thumb"] = n - 1 - counts["flex"] - counts["abd"]  # row 0: open hand
    row = 1
    fingers = FINGERS[1:]
    for family, dims in (("flex", 2), ("abd", 2)):
        # each finger gets its own Sobol sequence: taking turns within one
        # sequence would correlate the finger with the point's stratum
        per = np.diff(np.linspace(0, counts[family], 5).round().astype(int))
        for k, f in enumerate(fingers):
            u = _sobol(int(per[k]), dims, seed + 10 * k + (0 if family == "flex" else 5))
            rows = out[row:row + len(u)]
            if family == "flex":
                mcp, pip = _lim(f"{f}_mcp_flex"), _lim(f"{f}_pip_flex")
                rows[:, JOINT_NAMES.index(f"{f}_mcp_flex")] = mcp[0] + u[:, 0] * (mcp[1] - mcp[0])
                p = pip[0] + u[:, 1] * (pip[1] - pip[0])
                rows[:, JOINT_NAMES.index(f"{f}_pip_flex")] = p
                rows[:, JOINT_NAMES.index(f"{f}_dip_flex")] = np.clip(
                    DIP_PIP_RATIO * p, *_lim(f"{f}_dip_flex"))
            else:
                abd = _lim(f"{f}_mcp_abd")
                rows[:, JOINT_NAMES.index(f"{f}_mcp_abd")] = abd[0] + u[:, 0] * (abd[1] - abd[0])
                rows[:, JOINT_NAMES.index(f"{f}_mcp_flex")] = 45.0 * u[:, 1]
            row += len(u)
    u = _sobol(max(counts["thumb"], 0), 4, seed + 100)
    lo, hi = JOINT_LIMITS_DEG[:4, 0], JOINT_LIMITS_DEG[:4, 1]
    out[row:row + len(u), :4] = lo + u * (hi - lo)
    return out


def natural_pose_set(n: int, *, seed: int = 0) -> np.ndarray:
    """Combined multi-finger poses.

    Half the poses are the named poses (fist, pinch, point, grasp, spread,
    open) with Gaussian jitter (s.d. 8 deg); the other half are random
    grasp-like poses: each finger's closure is a shared hand closure plus
    per-finger variation, MCP and PIP follow the closure with noise, DIP =
    2/3 PIP, abduction shrinks as the hand closes, and the thumb is random
    within its limits.  Everything is clipped to the joint limits.

    Parameters
    ----------
    n : int
    seed : int, keyword-only

    Returns
    -------
    ndarray, shape (n, 20), float64
        Degrees, canonical order.
    """
    n, seed = _check_n(n, seed)
    rng = np.random.default_rng(seed)
    lo, hi = JOINT_LIMITS_DEG[:, 0], JOINT_LIMITS_DEG[:, 1]
    names = list(NAMED_POSES)
    n_named = n // 2
    base = np.stack([NAMED_POSES[names[i % len(names)]] for i in range(n_named)]) \
        if n_named else np.empty((0, 20))
    named = base + rng.normal(0.0, 8.0, base.shape)
    n_rand = n - n_named
    closure = rng.uniform(0, 1, (n_rand, 1)) + rng.normal(0, 0.15, (n_rand, 4))
    closure = np.clip(closure, 0, 1)
    rand = np.zeros((n_rand, 20))
    for k, _f in enumerate(FINGERS[1:]):
        j = 4 + 4 * k
        c = closure[:, k]
        rand[:, j] = c * 90 + rng.normal(0, 10, n_rand)              # MCP flex
        rand[:, j + 1] = (1 - c) * rng.uniform(-20, 20, n_rand)      # MCP abd
        rand[:, j + 2] = c * 100 + rng.normal(0, 10, n_rand)         # PIP
    rand[:, :4] = lo[:4] + rng.uniform(0, 1, (n_rand, 4)) * (hi[:4] - lo[:4])
    out = np.vstack([named, rand])
    for k in range(4):  # DIP = 2/3 PIP everywhere
        j = 4 + 4 * k
        out[:, j + 3] = DIP_PIP_RATIO * np.clip(out[:, j + 2], lo[j + 2], hi[j + 2])
    return np.clip(out, lo, hi)


POSE_SETS = {"paper": paper_pose_set, "natural": natural_pose_set}


def pose_set(name: str, n: int | None = None, *, seed: int = 0) -> np.ndarray:
    """Pose set `name` (``"paper"`` or ``"natural"``) of `n` poses (default 20,448).

    Parameters
    ----------
    name : {"paper", "natural"}
        A key of :data:`POSE_SETS`: :func:`paper_pose_set` or
        :func:`natural_pose_set`.
    n : int, optional
        Number of poses, a positive integer; None for ``PAPER_SIZE`` (20,448),
        for either set.
    seed : int, keyword-only
        Non-negative seed, passed to the set's function.

    Returns
    -------
    ndarray, shape (n, 20), float64
        Degrees, canonical order.

    Raises
    ------
    InvalidInputError
        `name` not a key of :data:`POSE_SETS`; `n` or `seed` refused by the
        set's function.
    """
    try:
        fn = POSE_SETS[name]
    except KeyError:
        raise InvalidInputError(
            f"unknown pose set {name!r}; expected one of {', '.join(POSE_SETS)}") from None
    return fn(PAPER_SIZE if n is None else n, seed=seed)
