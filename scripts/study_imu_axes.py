"""Gyro axes in another convention than the accelerometer's: told, never said of the right ones.

Measured for docs/imu.md ("Gyro axes in another convention").

Usage::

    python scripts/study_imu_axes.py [--seeds 1,2,3,4,5,6] [--broad DIR]

Simulated recordings (the tuning configuration and the held-out configuration's draws
``--seeds``: each its own devices, mounting errors and motions; a 15-s free motion with the
elbow fixed and one with it moving, and the calibration recording with its static poses)
are checked by :func:`~handsynth.sensors.imu.check_recording` as recorded and with the gyros'
axes changed as a logger might: every gyro's y axis with the other sign, x and y exchanged,
the AK8963's order (y, x, -z), every axis with the other sign, and one sensor's y axis with
the other sign (a different sensor in each recording). With ``--broad DIR`` the BROAD trials
present there (one real IMU each) as recorded and with the y axis of the gyro reversed. Per
recording: the ratio of the axes as read to the best other signed permutation (pooled over
the sensors, and the largest per sensor), and whether the gyro-axes warning is given.
About 1 min (BROAD 30 s more).  Last line:
``false_alarms=<n> recordings=<n> caught=<n> changed=<n> one_sensor_caught=<n>
one_sensor=<n>``.
"""

from __future__ import annotations

import argparse
import dataclasses
import warnings
from pathlib import Path

import numpy as np

from handsynth.sensors.imu import (
    HELDOUT,
    TUNING,
    ImuHand,
    calibration_motion,
    check_recording,
    find_broad_trials,
    read_broad_trial,
    simulate_imu,
)
from handsynth.sensors.imu._axes import gyro_axes_errors
from handsynth.sensors.imu._eval import _device_seed, free_trials

_CHANGES = {"-y": lambda g: g * np.array([1.0, -1.0, 1.0]), "y, x, z": lambda g: g[..., [1, 0, 2]],
            "y, x, -z": lambda g: g[..., [1, 0, 2]] * np.array([1.0, 1.0, -1.0]),
            "-x, -y, -z": lambda g: -g}
_MARK = "gravity's direction"


def _ratios(rec) -> tuple[float, float]:
    sq, n = gyro_axes_errors(rec.acc, rec.gyr, rec.rate_hz, static_n=int(rec.rate_hz))
    keep = n > 0
    rms = np.sqrt(sq[keep] / n[keep, None])
    pooled = np.sqrt(sq[keep].sum(axis=0) / n[keep].sum())
    return float(pooled[0] / pooled[1:].min()), float((rms[:, 0] / rms[:, 1:].min(axis=1)).max())


def _warns(rec) -> bool:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return any(_MARK in w for w in check_recording(rec))


def _recordings(seeds):
    for config in (TUNING, *(dataclasses.replace(HELDOUT, seed=s) for s in seeds)):
        hand = ImuHand(config.shape, placement=config.placement())
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # the disturbance and still-start warnings
            for _, elbow, rec in free_trials(config, hand, durations=(15.0,)):
                yield f"{config.label} {config.seed} {elbow}", rec
            quiet = dataclasses.replace(config.noise, disturbances=())
            yield f"{config.label} {config.seed} calibration", simulate_imu(
                calibration_motion(acc_poses=True), hand=hand, noise=quiet, skin=config.skin,
                seed=config.seed + 7, device_seed=_device_seed(config))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", default="1,2,3,4,5,6", help="held-out draws, comma-separated")
    ap.add_argument("--broad", type=Path, help="a folder of BROAD trials (.hdf5 or .mat)")
    args = ap.parse_args()
    false_alarms = recordings = caught = changed = one_caught = ones = 0
    sims = list(_recordings(int(s) for s in args.seeds.split(",")))
    for i, (label, rec) in enumerate(sims):
        pooled, worst = _ratios(rec)
        alarm = _warns(rec)
        false_alarms += alarm
        recordings += 1
        row = [f"{label:28s} as read: pooled {pooled:5.2f} worst sensor {worst:5.2f}"
               f"{' WARNED' if alarm else ''}"]
        for name, change in _CHANGES.items():
            moved = dataclasses.replace(rec, gyr=change(rec.gyr))
            pooled, _ = _ratios(moved)
            hit = _warns(moved)
            caught += hit
            changed += 1
            row.append(f"{name}: {pooled:5.2f}{'' if hit else ' missed'}")
        k = i % len(rec.sensors)
        gyr = rec.gyr.copy()
        gyr[k, :, 1] *= -1
        one = dataclasses.replace(rec, gyr=gyr)
        hit = _warns(one)
        one_caught += hit
        ones += 1
        row.append(f"{rec.sensors[k]} -y {'told' if hit else 'missed'}")
        print("; ".join(row), flush=True)
    if args.broad is not None:
        for path in find_broad_trials(args.broad):
            rec = read_broad_trial(path)[0]
            pooled, _ = _ratios(rec)
            alarm = _warns(rec)
            false_alarms += alarm
            recordings += 1
            moved = dataclasses.replace(rec, gyr=_CHANGES["-y"](rec.gyr))
            p_moved, _ = _ratios(moved)
            hit = _warns(moved)
            caught += hit
            changed += 1
            print(f"BROAD {path.stem[:36]:36s} as read {pooled:5.2f}{' WARNED' if alarm else ''}; "
                  f"-y {p_moved:5.2f}{'' if hit else ' missed'}", flush=True)
    print(f"false_alarms={false_alarms} recordings={recordings} caught={caught} changed={changed} "
          f"one_sensor_caught={one_caught} one_sensor={ones}")


if __name__ == "__main__":
    main()
