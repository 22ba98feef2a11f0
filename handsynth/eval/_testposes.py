"""Test poses for the camera evaluation, from a generator no estimator is built from.

Every pose set an estimator of handsynth is built or trained from
(:func:`~handsynth.models.paper_pose_set`, :func:`~handsynth.models.natural_pose_set`,
:func:`~handsynth.db.learning_poses`) starts from its own rest or samples
joints independently.  The test poses here are drawn differently on purpose,
so that an estimator that has learnt a generator's habits gains nothing:

* a **rest posture** per test hand (:func:`relaxed_rest_posture`): one
  relaxation level shared by the fingers, flexion increasing toward the
  little finger (the cascade of a relaxed hand), DIP following PIP by half,
  the fingers fanned by one spread level, the thumb at a varied rest; every
  joint jittered (normal, s.d. 2-3 deg); or a near-open one
  (:func:`open_rest_posture`: every finger joint flexed 3-5 deg);
* **paper** frames (:func:`paper_protocol_poses`): that rest posture with one
  digit moving: one finger flexing at its MCP only, at its PIP and DIP only,
  or at all three; one finger abducting; or the thumb moving;
* **natural** frames (:func:`natural_test_poses`): grasp types with random
  amplitudes (power grasp, precision and lateral pinch, tripod, hook,
  pointing, counting with some fingers out, spread hand), the fingers not
  taking part left at the rest posture.
"""

from __future__ import annotations

import numpy as np

from ..errors import InvalidInputError
from ..models import JOINT_LIMITS_DEG

__all__ = ["REST_POSTURES", "natural_test_poses", "open_rest_posture", "paper_protocol_poses",
           "relaxed_rest_posture"]

_LO, _HI = JOINT_LIMITS_DEG[:, 0], JOINT_LIMITS_DEG[:, 1]
_SPREAD_DEG = np.array([6.0, 0.0, -5.0, -11.0])  # index, middle, ring, little at full spread


def _fj(k: int) -> int:
    return 4 + 4 * k


def relaxed_rest_posture(rng: np.random.Generator) -> np.ndarray:
    """A relaxed rest posture (degrees, shape (20,)): module docstring.

    Relaxation ``r ~ U(0, 1)``: finger ``k`` (0 index .. 3 little) has MCP
    flexion ``2 + 10 r + 1.5 k``, PIP ``3 + 15 r + 2 k``, DIP half the PIP;
    spread ``s ~ U(0, 1)`` fans the fingers by ``s`` times (index +6, middle 0,
    ring -5, little -11 deg); thumb CMC flexion ~ N(5, 8), palmar abduction
    ~ U(5, 35), MCP ~ N(8, 6), IP ~ N(8, 8).  Every finger joint is jittered
    by N(0, 2) (abduction) or N(0, 3) (flexion).

    Parameters
    ----------
    rng : numpy.random.Generator
        Draws ``r`` and ``s`` first, then the thumb's four angles, then each
        finger's (index to little) MCP, abduction, PIP and DIP jitter.

    Returns
    -------
    ndarray, shape (20,), float64
        Degrees, canonical order, clipped to
        :data:`~handsynth.models.JOINT_LIMITS_DEG`.
    """
    r, s = rng.uniform(0, 1, 2)
    a = np.zeros(20)
    a[0], a[1] = rng.normal(5, 8), rng.uniform(5, 35)
    a[2], a[3] = rng.normal(8, 6), rng.normal(8, 8)
    for k in range(4):
        j = _fj(k)
        a[j] = 2 + 10 * r + 1.5 * k + rng.normal(0, 3)
        a[j + 1] = s * _SPREAD_DEG[k] + rng.normal(0, 2)
        a[j + 2] = 3 + 15 * r + 2 * k + rng.normal(0, 3)
        a[j + 3] = 0.5 * a[j + 2] + rng.normal(0, 3)
    return np.clip(a, _LO, _HI)


def open_rest_posture(rng: np.random.Generator) -> np.ndarray:
    """A near-open rest posture (degrees, shape (20,)): the hand held open, not flat.

    The thumb as in :func:`relaxed_rest_posture` (whose draws come first);
    every finger flexion (MCP, PIP, DIP) ``U(3, 5) + N(0, 1)``, as the issue
    describes a natural rest ("non-moving finger joints flexed 3-5 deg,
    fingers fanned"); the fingers fanned by a new spread level ``s ~ U(0,
    1)`` with ``N(0, 2)`` jitter.

    Parameters
    ----------
    rng : numpy.random.Generator
        Draws all of :func:`relaxed_rest_posture`'s numbers first, then ``s``,
        then each finger's (index to little) MCP, abduction, PIP and DIP.

    Returns
    -------
    ndarray, shape (20,), float64
        Degrees, canonical order, clipped to
        :data:`~handsynth.models.JOINT_LIMITS_DEG`.
    """
    a = relaxed_rest_posture(rng)
    s = rng.uniform(0, 1)
    for k in range(4):
        j = _fj(k)
        a[j] = rng.uniform(3, 5) + rng.normal(0, 1.0)
        a[j + 1] = s * _SPREAD_DEG[k] + rng.normal(0, 2)
        a[j + 2] = rng.uniform(3, 5) + rng.normal(0, 1.0)
        a[j + 3] = rng.uniform(3, 5) + rng.normal(0, 1.0)
    return np.clip(a, _LO, _HI)


#: The rest postures :func:`~handsynth.eval.run_protocol` can draw.
REST_POSTURES = {"relaxed": relaxed_rest_posture, "open": open_rest_posture}


def _check(n) -> int:
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 1:
        raise InvalidInputError(f"frame count must be a positive integer, got {n!r}")
    return int(n)


def paper_protocol_poses(rest: np.ndarray, n: int, rng: np.random.Generator
                         ) -> tuple[np.ndarray, np.ndarray]:
    """The paper's motions, one digit at a time, from a rest posture.

    Motions (equally likely): a finger flexes at the MCP only, at the PIP and
    DIP only, or at all three (MCP and PIP uniform over their ranges, DIP
    ``q`` times the PIP with ``q ~ U(0.5, 0.9)``); a finger abducts (uniform
    over its range); the thumb moves (its four angles uniform over their
    ranges).  The moving finger is drawn uniformly.

    Parameters
    ----------
    rest : ndarray, shape (20,)
        Degrees.
    n : int
    rng : numpy.random.Generator

    Returns
    -------
    poses : ndarray, shape (n, 20), float64
        Degrees.
    motion : ndarray, shape (n,), int
        0-3 flexion of index-little, 4-7 abduction of index-little, 8 thumb.
    """
    n = _check(n)
    out = np.tile(np.asarray(rest, float), (n, 1))
    motion = np.empty(n, int)
    for i in range(n):
        family = rng.integers(3)
        a = out[i]
        if family == 2:
            motion[i] = 8
            a[:4] = rng.uniform(_LO[:4], _HI[:4])
            continue
        k = int(rng.integers(4))
        j = _fj(k)
        if family == 1:
            motion[i] = 4 + k
            a[j + 1] = rng.uniform(_LO[j + 1], _HI[j + 1])
            continue
        motion[i] = k
        which = rng.integers(3)  # 0: MCP, 1: PIP+DIP, 2: all
        if which != 1:
            a[j] = rng.uniform(_LO[j], _HI[j])
        if which != 0:
            a[j + 2] = rng.uniform(0.0, _HI[j + 2])
            a[j + 3] = rng.uniform(0.5, 0.9) * a[j + 2]
    return np.clip(out, _LO, _HI), motion


def _curl(a: np.ndarray, k: int, c: float, rng: np.random.Generator, *, rest: np.ndarray) -> None:
    """Finger `k` closed to level `c` (0 rest .. 1 fist) with anatomical jitter."""
    j = _fj(k)
    a[j] = (1 - c) * rest[j] + c * 85 + rng.normal(0, 6)
    a[j + 2] = (1 - c) * rest[j + 2] + c * 100 + rng.normal(0, 6)
    a[j + 3] = (1 - c) * rest[j + 3] + c * 60 + rng.normal(0, 6)
    a[j + 1] = (1 - c) * rest[j + 1] + rng.normal(0, 2)


_GRASPS = ("power", "precision", "lateral", "tripod", "hook", "point", "count", "spread")


def natural_test_poses(rest: np.ndarray, n: int, rng: np.random.Generator
                       ) -> tuple[np.ndarray, np.ndarray]:
    """Natural multi-finger poses from a rest posture (module docstring).

    Parameters
    ----------
    rest : ndarray, shape (20,)
    n : int
    rng : numpy.random.Generator

    Returns
    -------
    poses : ndarray, shape (n, 20), float64
        Degrees.
    grasp : ndarray, shape (n,), int
        Index into ``("power", "precision", "lateral", "tripod", "hook",
        "point", "count", "spread")``.
    """
    n = _check(n)
    rest = np.asarray(rest, float)
    out = np.tile(rest, (n, 1))
    kind = rng.integers(len(_GRASPS), size=n)
    for i in range(n):
        a, g = out[i], _GRASPS[kind[i]]
        if g == "power":
            level = rng.uniform(0.3, 1.0)
            for k in range(4):
                _curl(a, k, min(1.0, level + 0.05 * k), rng, rest=rest)
            a[:4] = [rng.uniform(0, 40), rng.uniform(20, 60), rng.uniform(10, 50), rng.uniform(0, 50)]
        elif g in ("precision", "tripod"):
            fingers = (0,) if g == "precision" else (0, 1)
            for k in fingers:
                j = _fj(k)
                a[j] = rng.uniform(20, 60)
                a[j + 2] = rng.uniform(20, 70)
                a[j + 3] = rng.uniform(0.3, 0.9) * a[j + 2]
            others = rng.uniform(0, 0.8)
            for k in range(len(fingers), 4):
                _curl(a, k, others, rng, rest=rest)
            a[:4] = [rng.uniform(0, 40), rng.uniform(30, 65), rng.uniform(0, 40), rng.uniform(0, 40)]
        elif g == "lateral":
            level = rng.uniform(0.5, 1.0)
            for k in range(4):
                _curl(a, k, level, rng, rest=rest)
            a[:4] = [rng.uniform(10, 45), rng.uniform(0, 25), rng.uniform(0, 30), rng.uniform(0, 30)]
        elif g == "hook":
            for k in range(4):
                j = _fj(k)
                a[j] = rng.uniform(-10, 25)
                a[j + 2] = rng.uniform(50, 100)
                a[j + 3] = rng.uniform(30, 70)
        elif g == "point":
            level = rng.uniform(0.6, 1.0)
            for k in (1, 2, 3):
                _curl(a, k, level, rng, rest=rest)
            a[:4] = [rng.uniform(10, 40), rng.uniform(10, 40), rng.uniform(10, 40), rng.uniform(0, 40)]
        elif g == "count":
            out_fingers = rng.random(4) < 0.5
            level = rng.uniform(0.6, 1.0)
            for k in range(4):
                if not out_fingers[k]:
                    _curl(a, k, level, rng, rest=rest)
            if rng.random() < 0.5:
                a[:4] = [rng.uniform(10, 45), rng.uniform(10, 45), rng.uniform(10, 50), rng.uniform(0, 50)]
        else:  # spread
            s = rng.uniform(1.0, 1.6)
            for k in range(4):
                j = _fj(k)
                a[j + 1] = s * _SPREAD_DEG[k] + rng.normal(0, 3)
                a[j] = rng.uniform(-10, 10)
                a[j + 2] = rng.uniform(-5, 10)
                a[j + 3] = rng.uniform(-5, 10)
            a[1] = rng.uniform(20, 60)
    return np.clip(out, _LO, _HI), kind
