"""Gyro and magnetometer axes in another convention: told, and never said of the right ones.

Measured for docs/imu.md ("Axes in another convention").

Usage::

    python scripts/study_imu_axes.py [--seeds 1,2,3,4,5,6] [--broad DIR]

Simulated recordings (the tuning configuration and the held-out configuration's draws
``--seeds``: each its own devices, mounting errors and motions; a 15-s free motion with the
elbow fixed and one with it moving, and the calibration recording with its static poses)
are checked by :func:`~handsynth.sensors.imu.check_recording` as recorded and with the gyros'
axes changed as a logger might (every gyro's y axis with the other sign, x and y exchanged,
the AK8963's order (y, x, -z), every axis with the other sign, and one sensor's y axis with
the other sign, a different sensor in each recording), and with the magnetometers' axes
changed (the AK8963's order (y, x, -z), x and y exchanged).  With ``--broad DIR`` the BROAD
trials present there (one real IMU each) as recorded, with the gyro's y axis reversed and
with the magnetometer in the AK8963's order.  Per recording: the ratio of the axes as read
to the best other signed permutation (the gyro's pooled over the sensors, the
magnetometer's the largest per sensor as recorded and the smallest changed), and whether
the warning is given.  About 1.5 min (BROAD 1 min more).  Last line: ``false_alarms=<n>
recordings=<n> gyro_caught=<n> gyro_changed=<n> one_sensor_caught=<n> one_sensor=<n>
mag_caught=<n> mag_changed=<n>``.
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
from handsynth.sensors.imu._axes import REVERSED, gyro_axes_errors, mag_axes_errors
from handsynth.sensors.imu._eval import _device_seed, free_trials

_CHANGES = {"-y": lambda g: g * np.array([1.0, -1.0, 1.0]), "y, x, z": lambda g: g[..., [1, 0, 2]],
            "y, x, -z": lambda g: g[..., [1, 0, 2]] * np.array([1.0, 1.0, -1.0]),
            "-x, -y, -z": lambda g: -g}
_MAG_CHANGES = ("y, x, -z", "y, x, z")
_GYRO, _MAG = "gravity's direction", "turns with its gyro"


def _ratios(rec) -> tuple[float, float]:
    """The gyro's ratio pooled over the sensors and the largest per sensor."""
    sq, n, _ = gyro_axes_errors(rec.acc, rec.gyr, rec.rate_hz, static_n=int(rec.rate_hz))
    keep = n > 0
    rms = np.sqrt(sq[keep] / n[keep, None])
    pooled = np.sqrt(sq[keep].sum(axis=0) / n[keep].sum())
    return float(pooled[0] / pooled[1:].min()), float((rms[:, 0] / rms[:, 1:].min(axis=1)).max())


def _mag_ratios(rec) -> np.ndarray:
    """The magnetometer's ratio per judged sensor (the reverse of every axis left out)."""
    sq, n, _ = mag_axes_errors(rec.gyr, rec.mag, rec.rate_hz, static_n=int(rec.rate_hz))
    keep = n > 0
    rms = np.sqrt(sq[keep] / n[keep, None])
    others = [j for j in range(rms.shape[1]) if j not in (0, REVERSED)]
    return rms[:, 0] / rms[:, others].min(axis=1)


def _warns(rec, mark: str) -> bool:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return any(mark in w for w in check_recording(rec))


def _moved_mag(rec, name: str):
    m = rec.mag[..., [1, 0, 2]]
    return dataclasses.replace(rec, mag=m * np.array([1.0, 1.0, -1.0]) if name == "y, x, -z" else m)


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
    n = dict.fromkeys(("false_alarms", "recordings", "gyro_caught", "gyro_changed",
                       "one_sensor_caught", "one_sensor", "mag_caught", "mag_changed"), 0)
    sims = list(_recordings(int(s) for s in args.seeds.split(",")))
    for i, (label, rec) in enumerate(sims):
        pooled, worst = _ratios(rec)
        alarm = _warns(rec, _GYRO) or _warns(rec, _MAG)
        n["false_alarms"] += alarm
        n["recordings"] += 1
        row = [f"{label:28s} as read: gyro pooled {pooled:5.2f} worst sensor {worst:5.2f}, "
               f"magnetometer worst {_mag_ratios(rec).max():5.2f}{' WARNED' if alarm else ''}"]
        for name, change in _CHANGES.items():
            moved = dataclasses.replace(rec, gyr=change(rec.gyr))
            pooled, _ = _ratios(moved)
            hit = _warns(moved, _GYRO)
            n["gyro_caught"] += hit
            n["gyro_changed"] += 1
            row.append(f"gyro {name}: {pooled:5.2f}{'' if hit else ' missed'}")
        k = i % len(rec.sensors)
        gyr = rec.gyr.copy()
        gyr[k, :, 1] *= -1
        hit = _warns(dataclasses.replace(rec, gyr=gyr), _GYRO)
        n["one_sensor_caught"] += hit
        n["one_sensor"] += 1
        row.append(f"{rec.sensors[k]} -y {'told' if hit else 'missed'}")
        for name in _MAG_CHANGES:
            moved = _moved_mag(rec, name)
            hit = _warns(moved, _MAG)
            n["mag_caught"] += hit
            n["mag_changed"] += 1
            row.append(f"magnetometer {name}: {_mag_ratios(moved).min():5.2f}"
                       f"{'' if hit else ' missed'}")
        print("; ".join(row), flush=True)
    if args.broad is not None:
        for path in find_broad_trials(args.broad):
            rec = read_broad_trial(path)[0]
            pooled, _ = _ratios(rec)
            mag_ratio = float(_mag_ratios(rec).max())
            alarm = _warns(rec, _GYRO) or _warns(rec, _MAG)
            n["false_alarms"] += alarm
            n["recordings"] += 1
            moved = dataclasses.replace(rec, gyr=_CHANGES["-y"](rec.gyr))
            p_moved, _ = _ratios(moved)
            hit = _warns(moved, _GYRO)
            n["gyro_caught"] += hit
            n["gyro_changed"] += 1
            moved = _moved_mag(rec, "y, x, -z")
            m_moved = float(_mag_ratios(moved).min())
            m_hit = _warns(moved, _MAG)
            n["mag_caught"] += m_hit
            n["mag_changed"] += 1
            print(f"BROAD {path.stem[:36]:36s} as read: gyro {pooled:5.2f}, magnetometer "
                  f"{mag_ratio:5.2f}{' WARNED' if alarm else ''}; gyro -y {p_moved:5.2f}"
                  f"{'' if hit else ' missed'}; magnetometer y, x, -z {m_moved:5.2f}"
                  f"{'' if m_hit else ' missed'}", flush=True)
    print(" ".join(f"{k}={v}" for k, v in n.items()))


if __name__ == "__main__":
    main()
