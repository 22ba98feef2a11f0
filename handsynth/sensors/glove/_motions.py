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
in the calibration set come from the hand model's own named poses
(:data:`handsynth.models.NAMED_POSES`) and from 50/50 blends of two
representative grasps.
"""

from __future__ import annotations

import numpy as np

from ...errors import InvalidInputError
from ...models import JOINT_LIMITS_DEG, NAMED_POSES

__all__ = [
    "MOTIONS",
    "OTHER_MOTIONS",
    "REPRESENTATIVE_MOTIONS",
    "grasp_posture",
    "motions_for",
]


def _pose(thumb, index, middle, ring, little) -> np.ndarray:
    """(cmc_flex, cmc_abd, mcp, ip) and (mcp, abd, pip) per finger; DIP = 2/3 PIP."""
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


#: Motions outside every calibration set: the hand model's named poses and
#: blends of two representative grasps (deg, canonical order).
OTHER_MOTIONS: dict[str, np.ndarray] = {
    "fist": NAMED_POSES["fist"],
    "point": NAMED_POSES["point"],
    "pinch": NAMED_POSES["pinch"],
    "grasp": NAMED_POSES["grasp"],
    "standard+tripod": _blend("standard", "tripod"),
    "lateral_contact+tripod": _blend("lateral_contact", "tripod"),
}

#: Every motion the simulator knows.
MOTIONS: dict[str, np.ndarray] = {**REPRESENTATIVE_MOTIONS, **OTHER_MOTIONS}


def motions_for(kind: str) -> tuple[str, ...]:
    """Representative motions of glove `kind` (seed 004 section 3.1).

    ``"dg5"`` (PIP-only sensors): Standard, Lateral Contact, Tripod;
    ``"5dt"`` (MCP + PIP sensors): the four of section 2.1.
    """
    if kind == "dg5":
        return ("standard", "lateral_contact", "tripod")
    if kind == "5dt":
        return tuple(REPRESENTATIVE_MOTIONS)
    raise InvalidInputError(f"glove kind must be one of dg5, 5dt, got {kind!r}")


def grasp_posture(name: str) -> np.ndarray:
    """Copy of the grasp posture of motion `name` (deg, canonical order).

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
