"""The hand's motion in ``imu track --bvh-out``: the hand's attitude and the BVH's fingertips.

Measured for docs/imu.md ("The hand's motion as a BVH file"). Needs the test extras (the
independent `bvh` reader: `pip install -e ".[test]"`).

Usage::

    python scripts/study_imu_bvh.py [--seeds 1,2,3,4,5,6]

For each held-out draw (its devices, mounting errors, skin motion and calibration as
``handsynth imu eval`` makes them) its 15-s free motion with the elbow fixed is read by
Filter 4 (``ImuCalibration.track``).  Against the simulated hand: the hand's attitude
(:func:`~handsynth.sensors.imu.hand_attitude`) beside the hand frame's true attitude (the
rigid fit of the model hand's palm points onto the simulation's), the wrist from the elbow
(eq. 3.12's chain), and the fingertips of the BVH file (the draw's hand shape, read back by
the ``bvh`` package and posed by forward kinematics) from the elbow, every 25th sample.
Beside each, the constant answer: the first sample's attitude, and the first frame's
fingertips, held.  About 1 min.  Last line: ``attitude_rmse_deg=<lo>-<hi> wrist_mm=<lo>-<hi>
tips_mm=<lo>-<hi> held_attitude_deg=<lo>-<hi> held_tips_mm=<lo>-<hi> draws=<n>``.
"""

from __future__ import annotations

import argparse
import dataclasses
import warnings

import bvh
import numpy as np
from scipy.spatial.transform import Rotation

from handsynth.models import BVH_BONE_STARTS, BVH_BONES, KEYPOINT_SITES, HandModel, HandShape, bvh_text
from handsynth.sensors.imu import (
    HELDOUT,
    POINTS,
    ImuHand,
    bone_lengths_mm,
    hand_attitude,
    truth_hand_attitude,
)
from handsynth.sensors.imu._eval import _calibrate, free_trials


def _bvh_tips(mocap: bvh.Bvh, frame: int) -> dict[str, np.ndarray]:
    """Each finger's End Site, mm, by forward kinematics from the root's place."""
    place = {}
    turn = {}
    tips = {}
    for name in mocap.get_joints_names():
        zyx = mocap.frame_joint_channels(frame, name, ["Zrotation", "Yrotation", "Xrotation"])
        own = Rotation.from_euler("ZYX", zyx, degrees=True)
        parent = mocap.joint_parent(name)
        if parent is None:
            place[name] = np.array(mocap.frame_joint_channels(
                frame, name, ["Xposition", "Yposition", "Zposition"]))
            turn[name] = own
        else:
            offset = np.array(mocap.joint_offset(name), float)
            place[name] = place[parent.name] + turn[parent.name].apply(offset)
            turn[name] = turn[parent.name] * own
        for child in mocap.get_joint(name).children:
            if child.value[:2] == ["End", "Site"]:
                end = np.array([float(v) for v in child["OFFSET"]])
                tips[name.split("_")[0]] = place[name] + turn[name].apply(end)
    return tips


def _shape(seed: int, random_shape: bool) -> HandShape:
    """The held-out configuration's hand, or one drawn for `seed` (ratios 0.9-1.1)."""
    if not random_shape:
        return HELDOUT.shape
    rng = np.random.default_rng(seed + 4000)
    return HandShape(*(float(v) for v in rng.uniform(0.9, 1.1, 4)))


def _tip_errors(angles, q, wrist, kp, elbow, rate_hz, **skeleton) -> tuple[float, float]:
    """RMS distance of the BVH file's fingertips from the simulated ones, and of the first
    frame's held, mm (every 25th sample)."""
    mocap = bvh.Bvh(bvh_text(angles, rate_hz=rate_hz, units="mm", root_quat=q,
                             root_position_mm=1e3 * wrist, **skeleton))
    tip_err, held_tips = [], []
    first = _bvh_tips(mocap, 0)
    for frame in range(0, len(angles), 25):
        for finger, tip in _bvh_tips(mocap, frame).items():
            true = 1e3 * (kp[frame, POINTS.index(f"{finger}_tip")] - elbow[frame])
            tip_err.append(np.linalg.norm(tip - true))
            held_tips.append(np.linalg.norm(first[finger] - true))  # the first frame held
    return float(np.sqrt(np.mean(np.square(tip_err)))), float(np.sqrt(np.mean(np.square(held_tips))))


def _bones_mm(points, names) -> dict[str, float]:
    """Each BVH bone's length, mm, between two of `points` ((P, 3) m, named by `names`)."""
    where = dict(zip(names, points))
    return {bone: float(np.linalg.norm(where[bone] - where[start]) * 1e3)
            for bone, start in BVH_BONE_STARTS.items()}


def _draw(seed: int, random_shape: bool) -> dict[str, float]:
    config = dataclasses.replace(HELDOUT, seed=seed, shape=_shape(seed, random_shape))
    placement = config.placement()
    _, calib, _ = _calibrate(config, placement)
    hand = ImuHand(config.shape, placement=placement)
    rec = next(free_trials(config, hand, durations=(15.0,), elbows=("fixed",)))[2]
    res = calib.track(rec)
    q = hand_attitude(res["quat"], calib.sensors, calib.frames)
    est = Rotation.from_quat(q[:, [1, 2, 3, 0]])
    true_att = Rotation.from_matrix(truth_hand_attitude(rec, hand))
    err = np.degrees((est.inv() * true_att).magnitude())
    held_att = np.degrees((est[0].inv() * true_att).magnitude())  # the first attitude held
    wrist = res["chains"]["index_joints"][:, 0]
    kp = rec.truth.keypoints
    elbow = kp[:, POINTS.index("elbow")]
    wrist_err = np.linalg.norm(wrist - (kp[:, POINTS.index("wrist")] - elbow), axis=1) * 1e3
    args = (res["angles"], q, wrist, kp, elbow, rec.rate_hz)
    lengths = bone_lengths_mm(res["chains"])
    true_bones = _bones_mm(kp[0], POINTS)
    standard = HandModel(HandShape(), forearm=False)
    standard_bones = _bones_mm(standard.keypoints(), KEYPOINT_SITES)  # the open hand
    tips_measured, held_tips = _tip_errors(*args, bone_lengths_mm=lengths)
    return {"attitude": float(np.sqrt(np.mean(err ** 2))), "worst": float(err.max()),
            "held_attitude": float(np.sqrt(np.mean(held_att ** 2))),
            "wrist": float(np.sqrt(np.mean(wrist_err ** 2))),
            "tips": tips_measured, "held_tips": held_tips,
            "tips_standard": _tip_errors(*args)[0],
            "tips_true_shape": _tip_errors(*args, shape=config.shape)[0],
            "bones": float(np.mean([abs(lengths[b] - true_bones[b]) for b in BVH_BONES])),
            "bones_standard": float(np.mean([abs(standard_bones[b] - true_bones[b])
                                             for b in BVH_BONES]))}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", default="1,2,3,4,5,6", help="held-out draws, comma-separated")
    ap.add_argument("--random-shapes", action="store_true",
                    help="each draw's hand of its own random shape (ratios 0.9-1.1) instead of "
                         "the held-out configuration's")
    args = ap.parse_args()
    rows = []
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the configuration's magnet and still-start notes
        for seed in (int(s) for s in args.seeds.split(",")):
            r = _draw(seed, args.random_shapes)
            rows.append(r)
            print(f"held-out draw {seed} ({_shape(seed, args.random_shapes).name}): hand attitude "
                  f"{r['attitude']:.2f} deg RMSE (at most {r['worst']:.1f}; the first held "
                  f"{r['held_attitude']:.1f}), wrist {r['wrist']:.1f} mm, BVH fingertips from the "
                  f"elbow {r['tips']:.1f} mm RMS with the bones measured (standard hand "
                  f"{r['tips_standard']:.1f}, the hand's true shape {r['tips_true_shape']:.1f}; "
                  f"the first frame held {r['held_tips']:.0f}); bones measured within "
                  f"{r['bones']:.1f} mm mean (the standard hand's {r['bones_standard']:.1f})",
                  flush=True)

    def span(key: str, digits: int = 1) -> str:
        v = [r[key] for r in rows]
        return f"{min(v):.{digits}f}-{max(v):.{digits}f}"

    print(f"attitude_rmse_deg={span('attitude', 2)} wrist_mm={span('wrist')} tips_mm={span('tips')} "
          f"tips_standard_mm={span('tips_standard')} tips_true_shape_mm={span('tips_true_shape')} "
          f"held_attitude_deg={span('held_attitude')} held_tips_mm={span('held_tips', 0)} "
          f"bones_mm={span('bones')} bones_standard_mm={span('bones_standard')} "
          f"draws={len(rows)}")


if __name__ == "__main__":
    main()
