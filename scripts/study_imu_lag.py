"""One sensor's stream lagging the others (a wireless logger's latency): what it costs, and told.

Measured for docs/imu.md ("Sensor streams out of step").

Usage::

    python scripts/study_imu_lag.py [--seed 1] [--lags-ms 20,50,100] [--seeds 1,2,3,4,5,6]

*Cost*: the held-out configuration's draw ``--seed`` (its devices, mounting errors and
motions), its calibration as ``handsynth imu eval`` makes it, and its 15-s free motion with
the elbow fixed, read by Filter 4 as recorded and with the readings of one sensor (a
proximal and a middle phalanx, a hand sensor) delayed by each of ``--lags-ms``: the
joint-angle RMSE (mean over the 20 joints, and the worst joint), the worst segment's
orientation RMSE, and whether :func:`~handsynth.sensors.imu.late_sensors` (which
``ImuCalibration.track`` runs) names the sensor.

*Told*: the tuning configuration and the held-out draws ``--seeds``, each a 15-s free motion
with the elbow fixed and one with it moving and the grasp reaches, with the draw's own
calibration: warned of as recorded (false alarms), and with each sensor of a finger's hinge
(:data:`~handsynth.sensors.imu.HINGES`, :data:`~handsynth.sensors.imu.CARRIED`), of the
forearm plate and of the hand (:data:`~handsynth.sensors.imu.RIGID`) in turn 10, 20 and
50 ms late, named.  About 1 min.
Last line: ``as_recorded_joints_deg=<x> worst_joint_deg=<x> false_alarms=<n> recordings=<n>
named_10ms=<n> named_20ms=<n> named_50ms=<n> late=<n>``.
"""

from __future__ import annotations

import argparse
import dataclasses
import warnings

import numpy as np

from handsynth.sensors.imu import (
    CARRIED,
    HELDOUT,
    HINGES,
    RIGID,
    TUNING,
    ImuHand,
    delayed,
    grasp_motion,
    late_sensors,
    simulate_imu,
)
from handsynth.sensors.imu._eval import _calibrate, _device_seed, _trial, free_trials

_SENSORS = ("index_proximal", "index_middle", "hand_radial")


def _errors(rec, calib) -> tuple[float, str, float, float]:
    """Filter 4's joint-angle RMSE (mean over the 20 joints, the worst joint and its RMSE) and
    the worst segment's orientation RMSE, deg."""
    t = _trial(rec, ("filter4",), calib)
    joints = t["joint_rmse_deg"]["filter4"]
    name = max(joints, key=joints.get)
    return (float(np.mean(list(joints.values()))), name, joints[name],
            max(t["orientation_rmse_deg"]["filter4"].values()))


def _named(rec, calib, name: str) -> bool:
    said = late_sensors(rec, calib.frames, static_n=int(rec.rate_hz))
    return said is not None and f"{name} " in said


def _cost(seed: int, lags_ms) -> tuple[float, float]:
    config = dataclasses.replace(HELDOUT, seed=seed)
    placement = config.placement()
    _, calib, sensor_cal = _calibrate(config, placement)
    hand = ImuHand(config.shape, placement=placement)
    rec = sensor_cal.apply(next(free_trials(config, hand, durations=(15.0,),
                                            elbows=("fixed",)))[2])
    base = _errors(rec, calib)
    print(f"as recorded: joints {base[0]:.2f} deg (worst {base[1]}, {base[2]:.2f}), worst "
          f"segment {base[3]:.2f} deg", flush=True)
    worst = 0.0
    for name in _SENSORS:
        for ms in lags_ms:
            lag = max(1, round(ms * 1e-3 * rec.rate_hz))
            late = delayed(rec, name, lag)
            r = _errors(late, calib)
            worst = max(worst, r[2])
            print(f"{name} {lag / rec.rate_hz * 1e3:.0f} ms late: joints {r[0]:.2f} deg (worst "
                  f"{r[1]}, {r[2]:.2f}), worst segment {r[3]:.2f} deg; "
                  f"{'named' if _named(late, calib, name) else 'not named'}", flush=True)
    return base[0], worst


def _told(seeds) -> dict:
    n = dict.fromkeys(("false_alarms", "recordings", "named_10ms", "named_20ms", "named_50ms",
                       "late"), 0)
    missed: dict[str, int] = {}  # sensor -> recordings where it was not named 20 ms late
    for config in (TUNING, *(dataclasses.replace(HELDOUT, seed=s) for s in seeds)):
        placement = config.placement()
        _, calib, sensor_cal = _calibrate(config, placement)
        hand = ImuHand(config.shape, placement=placement)
        recs = [t[2] for t in free_trials(config, hand, durations=(15.0,))]
        # the draw's own physical sensors, as its calibration's (before, the grasps were
        # simulated with other sensors than those the calibration corrects)
        recs.append(simulate_imu(grasp_motion(seed=config.seed), hand=hand, noise=config.noise,
                                 skin=config.skin, seed=config.seed + 3,
                                 device_seed=_device_seed(config)))
        for rec in map(sensor_cal.apply, recs):
            said = late_sensors(rec, calib.frames, static_n=int(rec.rate_hz))
            n["false_alarms"] += said is not None
            n["recordings"] += 1
            for name in dict.fromkeys(s for pair in HINGES + CARRIED + RIGID for s in pair):
                n["late"] += 1
                for ms in (10, 20, 50):
                    lag = round(ms * 1e-3 * rec.rate_hz)
                    told = _named(delayed(rec, name, lag), calib, name)
                    n[f"named_{ms}ms"] += told
                    if ms == 20 and not told:
                        missed[name] = missed.get(name, 0) + 1
        print(f"{config.label} {config.seed}: " + ", ".join(f"{k} {v}" for k, v in n.items()),
              flush=True)
    print("not named 20 ms late: " + (", ".join(f"{k} {v}" for k, v in sorted(missed.items()))
                                     or "none"), flush=True)
    return n


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seed", type=int, default=1, help="the held-out draw the cost is read on")
    ap.add_argument("--lags-ms", default="20,50,100", help="lags, ms, comma-separated")
    ap.add_argument("--seeds", default="1,2,3,4,5,6", help="held-out draws the warning is tried on")
    args = ap.parse_args()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the configuration's magnet and still-start notes
        base, worst = _cost(args.seed, [float(x) for x in args.lags_ms.split(",")])
        n = _told(int(s) for s in args.seeds.split(","))
    print(f"as_recorded_joints_deg={base:.2f} worst_joint_deg={worst:.2f} "
          + " ".join(f"{k}={v}" for k, v in n.items()))


if __name__ == "__main__":
    main()
