"""Grasp motions from the open hand: the representative ones and others.

Seed 004 section 2.1 (its Fig. 3) takes four representative grasps, each a
motion from the open hand to the grasp posture: Standard, Lateral Contact,
Tripod and Parallel Extension.  Section 3.1 drops Parallel Extension for a
glove with sensors over the PIP joints only, because that motion is mostly
MCP flexion and hardly moves such a sensor (its Fig. 5).

The postures below are this project's reading of those grasp names (the
seed gives pictures, not angles): a power grasp round a ~4 cm cylinder, a
key pinch with the thumb pad on the side of the curled index, a three-jaw
chuck of thumb, index and middle, and a flat-hand plate grasp.  Motions not
in the calibration set (:data:`OTHER_MOTIONS`) are postures written here
from their everyday descriptions, independently of every pose generator an
estimator learns from (the synergy prior is learnt from
:func:`handsynth.models.natural_pose_set`, which jitters the hand model's
named poses, so those are not used as unseen motions), and 50/50 blends of
two representative grasps.  The named poses stay available for simulation
(:data:`NAMED_MOTIONS`).
"""

from __future__ import annotations

import numpy as np

from ...errors import InvalidInputError
from ...models import JOINT_LIMITS_DEG, NAMED_POSES

__all__ = [
    "MOTIONS",
    "NAMED_MOTIONS",
    "OTHER_MOTIONS",
    "REPRESENTATIVE_MOTIONS",
    "grasp_posture",
    "motions_for",
]


def _pose(thumb, index, middle, ring, little) -> np.ndarray:
    """(cmc_flex, cmc_abd, mcp, ip) and (mcp, abd, pip) per finger; DIP = 2/3 PIP (seed 004 eq. 1)."""
    out = list(thumb)
    for mcp, abd, pip in (index, middle, ring, little):
        out += [mcp, abd, pip, 2.0 / 3.0 * pip]
    arr = np.array(out, dtype=np.float64)
    arr.setflags(write=False)
    return arr


#: Grasp postures (deg, canonical order) of the four representative motions.
REPRESENTATIVE_MOTIONS: dict[str, np.ndarray] = {
    "standard": _pose((30, 45, 30, 25), (55, 5, 65), (60, 0, 75), (65, -5, 80), (70, -10, 80)),
    "lateral_contact": _pose((10, 10, 20, 35), (55, 0, 90), (70, 0, 95), (75, -3, 95),
                             (80, -6, 90)),
    "tripod": _pose((35, 45, 15, 20), (45, 0, 50), (45, -3, 45), (30, -5, 35), (25, -10, 30)),
    "parallel_extension": _pose((20, 50, 10, 5), (55, 0, 10), (55, 0, 8), (50, -3, 8),
                                (50, -6, 10)),
}


def _blend(a: str, b: str) -> np.ndarray:
    arr = 0.5 * (REPRESENTATIVE_MOTIONS[a] + REPRESENTATIVE_MOTIONS[b])
    arr.setflags(write=False)
    return arr


#: Motions outside every calibration set and every learnt prior: hook grip,
#: V sign, OK sign, large-cylinder wrap, thumb-to-little opposition (written
#: from their descriptions, not fitted to anything) and blends of two
#: representative grasps (deg, canonical order).
OTHER_MOTIONS: dict[str, np.ndarray] = {
    "hook": _pose((5, 20, 5, 5), (5, 2, 85), (5, 0, 85), (5, -2, 85), (5, -4, 85)),
    "v_sign": _pose((35, 30, 35, 30), (0, 12, 0), (0, -8, 0), (75, -3, 95), (80, -6, 95)),
    "ok_sign": _pose((30, 45, 20, 25), (40, 0, 60), (10, -2, 10), (10, -5, 10), (10, -10, 10)),
    "large_cylinder": _pose((20, 55, 10, 10), (30, 3, 40), (30, 0, 40), (30, -3, 40),
                            (35, -6, 40)),
    "opposition": _pose((45, 50, 30, 20), (10, 0, 10), (15, 0, 15), (30, -3, 30), (50, 0, 50)),
    "standard+tripod": _blend("standard", "tripod"),
    "lateral_contact+tripod": _blend("lateral_contact", "tripod"),
}

#: The hand model's named poses as motions (simulation only: they are in the
#: synergy prior's source).
NAMED_MOTIONS: dict[str, np.ndarray] = {
    name: NAMED_POSES[name] for name in ("fist", "point", "pinch", "grasp")}

#: Every motion the simulator knows.
MOTIONS: dict[str, np.ndarray] = {**REPRESENTATIVE_MOTIONS, **OTHER_MOTIONS, **NAMED_MOTIONS}


def motions_for(kind: str) -> tuple[str, ...]:
    """Representative motions of glove `kind` (seed 004 section 3.1).

    ``"dg5"`` (PIP-only sensors): Standard, Lateral Contact, Tripod;
    ``"5dt"`` (MCP + PIP sensors): the four of section 2.1.

    Parameters
    ----------
    kind : {"dg5", "5dt"}
        Glove design.

    Returns
    -------
    tuple of str
        Keys of :data:`REPRESENTATIVE_MOTIONS`.

    Raises
    ------
    InvalidInputError
        `kind` neither ``"dg5"`` nor ``"5dt"``.
    """
    if kind == "dg5":
        return ("standard", "lateral_contact", "tripod")
    if kind == "5dt":
        return tuple(REPRESENTATIVE_MOTIONS)
    raise InvalidInputError(f"glove kind must be one of dg5, 5dt, got {kind!r}")


def grasp_posture(name: str) -> np.ndarray:
    """Copy of the grasp posture of motion `name` (deg, canonical order).

    Parameters
    ----------
    name : str
        A key of :data:`MOTIONS`.

    Returns
    -------
    ndarray, shape (20,), float64, deg
        The posture clipped to :data:`handsynth.models.JOINT_LIMITS_DEG`; a
        writable copy.

    Raises
    ------
    InvalidInputError
        If `name` is not one of :data:`MOTIONS`.
    """
    try:
        out = MOTIONS[name].copy()
    except KeyError:
        raise InvalidInputError(
            f"unknown motion {name!r}; expected one of {', '.join(MOTIONS)}") from None
    return np.clip(out, JOINT_LIMITS_DEG[:, 0], JOINT_LIMITS_DEG[:, 1])
