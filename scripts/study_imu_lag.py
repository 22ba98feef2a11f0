"""One sensor's stream lagging the others (a wireless logger's latency): what it costs.

Measured for docs/imu.md ("Misses and limits").

Usage::

    python scripts/study_imu_lag.py [--seed 1] [--lags-ms 20,50,100]

The held-out configuration's draw ``--seed`` (its devices, mounting errors and motions),
its calibration as ``handsynth imu eval`` makes it, and its 15-s free motion with the elbow
fixed, read by Filter 4 as recorded and with the readings of one sensor (a proximal and a
middle phalanx, a hand sensor) delayed by each of ``--lags-ms``.
Per case: the joint-angle RMSE (mean over the 20 joints, and the worst joint) and the worst
segment's orientation RMSE.  Nothing in the library tells such a lag (the readings stay
plausible); the figures say how closely the loggers must agree.  About 1 min.  Last line:
``as_recorded_joints_deg=<x> worst_mean_joints_deg=<x> worst_joint_deg=<x>
worst_segment_deg=<x> lags_ms=<list>``.
"""

from __future__ import annotations

import argparse
import dataclasses
import warnings

import numpy as np

from handsynth.sensors.imu import HELDOUT, ImuHand
from handsynth.sensors.imu._eval import _calibrate, _trial, free_trials

_SENSORS = ("index_proximal", "index_middle", "hand_radial")


def _lagged(rec, k: int, lag: int):
    """`rec` with sensor `k`'s readings `lag` samples late; its first `lag` samples are those
    that follow them in the still start (not repeats, which read as samples lost)."""
    out = {}
    for name in ("acc", "gyr", "mag"):
        a = getattr(rec, name).copy()
        a[k, lag:] = getattr(rec, name)[k, :-lag]
        a[k, :lag] = getattr(rec, name)[k, lag:2 * lag]
        out[name] = a
    return dataclasses.replace(rec, **out)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seed", type=int, default=1, help="the held-out configuration's draw")
    ap.add_argument("--lags-ms", default="20,50,100", help="lags, ms, comma-separated")
    args = ap.parse_args()
    lags_ms = [float(x) for x in args.lags_ms.split(",")]
    config = dataclasses.replace(HELDOUT, seed=args.seed)
    placement = config.placement()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the configuration's magnet and still-start notes
        _, calib, sensor_cal = _calibrate(config, placement)
        hand = ImuHand(config.shape, placement=placement)
        rec = sensor_cal.apply(next(free_trials(config, hand, durations=(15.0,),
                                                elbows=("fixed",)))[2])
        base = _errors(rec, calib)
        print(f"as recorded: joints {base[0]:.2f} deg (worst {base[1]}, {base[2]:.2f}), "
              f"worst segment {base[3]:.2f} deg", flush=True)
        worst = np.zeros(3)
        for name in _SENSORS:
            for ms in lags_ms:
                lag = max(1, round(ms * 1e-3 * rec.rate_hz))
                r = _errors(_lagged(rec, rec.sensors.index(name), lag), calib)
                worst = np.maximum(worst, [r[0], r[2], r[3]])
                print(f"{name} {lag / rec.rate_hz * 1e3:.0f} ms late: joints {r[0]:.2f} deg "
                      f"(worst {r[1]}, {r[2]:.2f}), worst segment {r[3]:.2f} deg", flush=True)
    print(f"as_recorded_joints_deg={base[0]:.2f} worst_mean_joints_deg={worst[0]:.2f} "
          f"worst_joint_deg={worst[1]:.2f} worst_segment_deg={worst[2]:.2f} "
          f"lags_ms={','.join(f'{x:g}' for x in lags_ms)}")


def _errors(rec, calib) -> tuple[float, str, float, float]:
    """Filter 4's joint-angle RMSE (mean over the 20 joints, the worst joint and its RMSE) and
    the worst segment's orientation RMSE, deg."""
    t = _trial(rec, ("filter4",), calib)
    joints = t["joint_rmse_deg"]["filter4"]
    name = max(joints, key=joints.get)
    return (float(np.mean(list(joints.values()))), name, joints[name],
            max(t["orientation_rmse_deg"]["filter4"].values()))


if __name__ == "__main__":
    main()
