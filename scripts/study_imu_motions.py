"""The IMU filters on other motion families: reaches into grasps, or the camera's test poses.

``handsynth imu eval`` scores free sinusoidal finger, wrist and elbow motion,
the family the EKF's options were chosen on.  This scores the same
calibration (the eval's, for the configuration given) on minimum-jerk reaches
into the five Cutkosky grasps of :data:`handsynth.sensors.imu.GRASP_POSES`
(power sphere, medium wrap, lateral pinch, precision tripod, tip pinch;
``--family grasps``), or into eight poses of the camera evaluation's natural test-pose
generator (``--family natural``: :func:`handsynth.eval.natural_test_poses` from a relaxed
rest, seed 21 and 22; written for another system, several fingers at their own closures),
each held 2 s and released, with the elbow fixed and moving (24 and 36.5 s each),
and prints per filter the orientation RMSE per segment (mean and worst
segment-trial), the joint-angle RMSE (mean over the 20 DOFs) and the
fingertip RMSE from the elbow and from the wrist (mean of 5 fingers), mean of
the two trials.  The forearm plate is fused as in the eval.  The last line
is machine-readable JSON.

Usage::

    python scripts/study_imu_motions.py [--config heldout|tuning] [--family grasps|natural]
        [--filters constant,raw,filter4,gated,vqf,madgwick]
"""

from __future__ import annotations

import argparse
import json

import numpy as np

from handsynth.sensors.imu import (
    GRASP_POSES,
    HELDOUT,
    TUNING,
    ImuHand,
    grasp_motion,
    pose_motion,
    simulate_imu,
)
from handsynth.sensors.imu._eval import _calibrate, _device_seed, _summary, _trial


def _motion(family: str, elbow: str, seed: int, k: int):
    if family == "grasps":
        grasps = tuple(g for g in GRASP_POSES if g != "open")
        return grasp_motion(grasps, elbow=elbow, seed=seed)
    from handsynth.eval import natural_test_poses, relaxed_rest_posture

    rng = np.random.default_rng(21 + k)
    poses, _ = natural_test_poses(relaxed_rest_posture(rng), 8, rng)
    return pose_motion(poses, elbow=elbow, seed=seed, label="natural")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--config", choices=("tuning", "heldout"), default="heldout")
    ap.add_argument("--family", choices=("grasps", "natural"), default="grasps")
    ap.add_argument("--filters", default="constant,raw,filter4,gated,vqf,madgwick")
    args = ap.parse_args()
    config = TUNING if args.config == "tuning" else HELDOUT
    filters = tuple(args.filters.split(","))
    placement = config.placement()
    _, calib, sensor_cal = _calibrate(config, placement)
    hand = ImuHand(config.shape, placement=placement)
    trials = []
    for k, elbow in enumerate(("fixed", "moving")):
        seed = config.seed * 100 + 50 + k
        rec = simulate_imu(_motion(args.family, elbow, seed, k), hand=hand,
                           noise=config.noise, skin=config.skin, seed=seed + 7,
                           device_seed=_device_seed(config))
        trials.append(_trial(sensor_cal.apply(rec), filters, calib))
        print(f"{elbow} elbow: {rec.duration_s:.0f} s", flush=True)
    summary = _summary(trials, filters)
    print(f"{config.label}, {args.family} reaches, mean of 2 trials: orientation mean (worst) deg, "
          "joint angles deg, tips from the elbow / wrist mm")
    for name, s in summary.items():
        print(f"{name:9s} {s['orientation_mean_deg']:6.2f} ({s['orientation_worst_segment_deg']:5.1f})"
              f"  joints {s['joint_angle_mean_rmse_deg']:5.2f}  tips "
              f"{s['fingertip_mean_rmse_mm']:6.1f} / {s['fingertip_from_wrist_mean_rmse_mm']:5.1f}")
    print(json.dumps({"config": config.label, "family": args.family,
                      "summary": {k: {n: round(float(v), 3) for n, v in s.items()}
                                  for k, s in summary.items()}}))


if __name__ == "__main__":
    main()
