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

from handsynth.models import bvh_text
from handsynth.sensors.imu import (
    HELDOUT,
    POINTS,
    ImuHand,
    fingertip_positions,
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


def _draw(seed: int) -> tuple[float, float, float, float]:
    config = dataclasses.replace(HELDOUT, seed=seed)
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
    wrist = fingertip_positions(res["quat"], calib.sensors, calib.model)["index_joints"][:, 0]
    kp = rec.truth.keypoints
    elbow = kp[:, POINTS.index("elbow")]
    wrist_err = np.linalg.norm(wrist - (kp[:, POINTS.index("wrist")] - elbow), axis=1) * 1e3
    mocap = bvh.Bvh(bvh_text(res["angles"], rate_hz=rec.rate_hz, shape=config.shape,
                             units="mm", root_quat=q, root_position_mm=1e3 * wrist))
    tip_err, held_tips = [], []
    first = _bvh_tips(mocap, 0)
    for frame in range(0, rec.n, 25):
        for finger, tip in _bvh_tips(mocap, frame).items():
            true = 1e3 * (kp[frame, POINTS.index(f"{finger}_tip")] - elbow[frame])
            tip_err.append(np.linalg.norm(tip - true))
            held_tips.append(np.linalg.norm(first[finger] - true))  # the first frame held
    rms = [float(np.sqrt(np.mean(np.square(e))))
           for e in (err, wrist_err, tip_err, held_att, held_tips)]
    return rms[0], float(err.max()), rms[1], rms[2], rms[3], rms[4]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", default="1,2,3,4,5,6", help="held-out draws, comma-separated")
    args = ap.parse_args()
    rows = []
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the configuration's magnet and still-start notes
        for seed in (int(s) for s in args.seeds.split(",")):
            rows.append(_draw(seed))
            att, worst, wrist, tips, held_att, held_tips = rows[-1]
            print(f"held-out draw {seed}: hand attitude {att:.2f} deg RMSE (at most {worst:.1f}; "
                  f"the first held {held_att:.1f}), wrist {wrist:.1f} mm, BVH fingertips from "
                  f"the elbow {tips:.1f} mm RMS (the first frame held {held_tips:.0f})",
                  flush=True)
    r = np.array(rows)
    print(f"attitude_rmse_deg={r[:, 0].min():.2f}-{r[:, 0].max():.2f} "
          f"wrist_mm={r[:, 2].min():.1f}-{r[:, 2].max():.1f} "
          f"tips_mm={r[:, 3].min():.1f}-{r[:, 3].max():.1f} "
          f"held_attitude_deg={r[:, 4].min():.1f}-{r[:, 4].max():.1f} "
          f"held_tips_mm={r[:, 5].min():.0f}-{r[:, 5].max():.0f} draws={len(r)}")


if __name__ == "__main__":
    main()
