"""6-axis sensors (no magnetometer) beside the same sensors read with theirs.

Many IMU gloves and lab set-ups have no magnetometer, or leave it off near
steel.  Without a compass each sensor's heading comes from the common
rotation alone (``initial_attitude``: eqs. 4.18-4.19 with w_g in the
compass's place) and then drifts with its gyro.  This study reads the same
simulated recordings twice: as recorded (9-axis) and with every
magnetometer column dropped (6-axis: calibrated from the calibration
recording without its magnetometers too).

Conditions, held-out configuration (other noise figures, sensor misalignment,
skin motion, a magnet near the hand), and the tuning configuration for
reference:

1. the eval's free-motion trials (15 and 30 s, elbow fixed and moving);
2. 120-s free motions (elbow fixed and moving) with the gyro bias constant,
   and drifting by 0.15 deg/s per minute (s.d. per axis, a sensor warming on
   the skin: ``AxisNoise.bias_drift_rate``).

Filters: raw integration, Filter 4, ``filter4b``, gated, vqf (offline, 6D
without the magnetometer) and vqf online; the constant answer beside them.
The orientation errors of 6-axis runs are taken after one turn about the
vertical per recording (the hand's heading in the world is unobservable
without a compass; the turn is fixed at the first sample, so that drift
stays in the errors); joint angles and fingertips from the wrist need no
turn.

Prints, per condition and filter, orientation RMSE mean (worst segment),
joint-angle RMSE and fingertip RMSE from the wrist, 9-axis then 6-axis;
the last line is machine-readable JSON.  About 10 min on one core.

Usage::

    python scripts/study_imu_six_axis.py [--quick]
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import warnings

import numpy as np

import handsynth.sensors.imu._eval as ev
from handsynth.sensors.imu import HELDOUT, TUNING, ImuHand, free_motion, simulate_imu

FILTERS = ("constant", "raw", "filter4", "filter4b", "gated", "vqf", "vqf_online")
DRIFT_DPS_PER_MIN = 0.15


def _long(config, hand, drift):
    noise = config.noise
    rate = np.radians(drift) / 60.0
    noise = dataclasses.replace(noise, gyro=dataclasses.replace(noise.gyro, bias_drift_rate=rate))
    for k, elbow in enumerate(("fixed", "moving")):
        seed = config.seed * 100 + 91 + k
        yield simulate_imu(free_motion(120.0, elbow=elbow, seed=seed), hand=hand, noise=noise,
                           skin=config.skin, seed=seed + 7, device_seed=ev._device_seed(config))


def _conditions(config, quick: bool):
    placement = config.placement()
    hand = ImuHand(config.shape, placement=placement)
    durations = (15.0,) if quick else (15.0, 30.0)
    yield "eval trials", [r for _d, _e, r in ev.free_trials(config, hand, durations=durations)]
    drifts = (DRIFT_DPS_PER_MIN,) if quick else (0.0, DRIFT_DPS_PER_MIN)
    for drift in drifts:
        yield f"120 s, bias drift {drift:g} deg/s/min", list(_long(config, hand, drift))


def _line(label, axes, name, s) -> str:
    return (f"{label:36s} {axes} {name:10s} orientation {s['orientation_mean_deg']:6.2f} "
            f"({s['orientation_worst_segment_deg']:6.2f})  joints {s['joint_angle_mean_rmse_deg']:6.2f}"
            f"  tips from the wrist {s['fingertip_from_wrist_mean_rmse_mm']:6.2f} mm")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--quick", action="store_true",
                        help="held-out only, 15-s trials and the drifting 120 s (about 4 min)")
    args = parser.parse_args()
    warnings.simplefilter("ignore")  # the held-out magnet is warned about on purpose
    out: dict = {}
    for config in (HELDOUT,) if args.quick else (HELDOUT, TUNING):
        placement = config.placement()
        _, calib9, scal9 = ev._calibrate(config, placement)
        _, calib6, scal6 = ev._calibrate(config, placement, six_axis=True)
        for label, recs in _conditions(config, args.quick):
            key = f"{config.label}, {label}"
            nine = ev._summary([ev._trial(scal9.apply(r), FILTERS, calib9) for r in recs], FILTERS)
            six = ev._summary([ev._trial(scal6.apply(dataclasses.replace(r, mag=None)), FILTERS,
                                         calib6) for r in recs], FILTERS)
            out[key] = {"9-axis": nine, "6-axis": six}
            for name in FILTERS:
                print(_line(key, "9-axis", name, nine[name]), flush=True)
                print(_line(key, "6-axis", name, six[name]), flush=True)
    print(json.dumps(out))


if __name__ == "__main__":
    main()
