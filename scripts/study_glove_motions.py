"""The five-sensor glove on motions of another generator: the IMU simulator's.

Measured for docs/glove.md ("Motions of another generator").

Usage::

    python scripts/study_glove_motions.py [--seeds 5]

The glove evaluation's motions not calibrated are postures written for it
(``OTHER_MOTIONS``).  Here the joint angles come from the IMU simulator instead, written
for another system: its free motion (30 s, every joint swinging with its own frequency and
phase) and its minimum-jerk reaches into five grasps with holds, resampled at the glove's
60 Hz.  For each glove kind and seed of ``handsynth glove eval`` (:func:`eval_setup`: the
calibration user, session and estimators), the angles are read by the glove as worn again
by the calibration user (``rewear``) and by the second user (``user2``), each with its range
calibration (:class:`RangeNormalizer`), with the donning's noise.  Per estimator: the mean
absolute MCP (joint 3) error against the angles, beside the constant (the mean calibration
posture).  About 1 min.  Last line: ``<kind>_<condition>_<motion>_best=<name>:<deg>
..._constant=<deg>``.
"""

from __future__ import annotations

import argparse
import warnings

import numpy as np

from handsynth.models import JOINT_NAMES
from handsynth.sensors.glove import (
    EvalOptions,
    RangeNormalizer,
    eval_setup,
    range_readings,
    simulate_range_holds,
    simulate_sensors,
)
from handsynth.sensors.imu import MODEL_JOINTS, free_motion, grasp_motion

#: Joint 3 of each digit (seed 004): the thumb's CMC flexion and the fingers' MCP flexions.
_JOINT3 = [JOINT_NAMES.index(n) for n in ("thumb_cmc_flex", "index_mcp_flex", "middle_mcp_flex",
                                          "ring_mcp_flex", "little_mcp_flex")]
_RATE_HZ = 60.0


def _motions(seed: int) -> dict[str, np.ndarray]:
    cols = [MODEL_JOINTS.index(n) for n in JOINT_NAMES]
    out = {}
    for name, m in (("free", free_motion(30.0, seed=11 + seed)),
                    ("grasps", grasp_motion(seed=12 + seed))):
        t = np.asarray(m.t)
        q = np.asarray(m.q)[:, cols]
        t_new = np.arange(t[0], t[-1], 1.0 / _RATE_HZ)
        out[name] = np.column_stack([np.interp(t_new, t, q[:, j]) for j in range(q.shape[1])])
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=5, help="seeds 0 .. N-1 of glove eval")
    args = ap.parse_args()
    table: dict = {}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # readings off the calibration's range, on purpose
        for kind in ("dg5", "5dt"):
            for seed in range(args.seeds):
                setup = eval_setup(EvalOptions(kind=kind), seed)
                rng = np.random.default_rng(seed + 500)
                for cond, user_key in (("rewear", "calibration"), ("user2", "second")):
                    don = setup.donnings["new_session" if cond == "rewear" else "second_user"]
                    user = setup.users[user_key]
                    held = range_readings(simulate_range_holds(user, don, seed=seed + 600))
                    norm = RangeNormalizer(source_open=held[0], source_fist=held[1],
                                           target_open=setup.range_reference[0],
                                           target_fist=setup.range_reference[1])
                    for motion, angles in _motions(seed).items():
                        sensors = norm.apply(simulate_sensors(angles, don, rng=rng))
                        truth = angles[:, _JOINT3]
                        for name, est in setup.estimators.items():
                            err = np.abs(est.predict(sensors)[:, _JOINT3] - truth).mean()
                            table.setdefault((kind, cond, motion), {}).setdefault(
                                name, []).append(err)
    last = []
    for (kind, cond, motion), per in table.items():
        mean = {name: float(np.mean(v)) for name, v in per.items()}
        best = min((n for n in mean if n != "constant"), key=mean.get)
        print(f"{kind:3s} {cond:6s} {motion:6s} " + ", ".join(
            f"{n} {v:.2f}" for n, v in sorted(mean.items(), key=lambda kv: kv[1])), flush=True)
        last.append(f"{kind}_{cond}_{motion}_best={best}:{mean[best]:.2f} "
                    f"{kind}_{cond}_{motion}_constant={mean['constant']:.2f}")
    print(" ".join(last))


if __name__ == "__main__":
    main()
