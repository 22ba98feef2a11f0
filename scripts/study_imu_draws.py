"""Filter 4 on other draws of the held-out IMU configuration (docs/imu.md quotes it).

Usage::

    python scripts/study_imu_draws.py [--seeds 1,2,3,4,5,6]

The held-out configuration (:data:`handsynth.sensors.imu.HELDOUT`: its noise
figures, sensor misalignment, skin motion and magnetic disturbance) with other
seeds (each its own devices, mounting errors and motions) and three hand sizes
(the standard hand, one 10 % smaller, one 10 % larger), one 15-s trial with the
elbow fixed each, the calibration as ``handsynth imu eval`` makes it.  Per draw
Filter 4's orientation RMSE (mean, worst segment, distal phalanges), joint-angle
RMSE and fingertip RMSE from the elbow; then the range over the draws.  About
3 min.  Last line: ``tips_mm_min=<> tips_mm_max=<> tips_over_10mm=<count> draws=<n>``.
"""

from __future__ import annotations

import argparse
import dataclasses
import warnings

import numpy as np

from handsynth.models import HandShape
from handsynth.sensors.imu import HELDOUT, evaluate

_KEYS = {"orientation_mean_deg": "orientation mean", "orientation_worst_segment_deg": "worst segment",
         "orientation_distal_mean_deg": "distal", "joint_angle_mean_rmse_deg": "joints",
         "fingertip_mean_rmse_mm": "tips (mm)"}
#: The three hand sizes of the IMU studies of other draws (also study_imu_swaps, study_imu_ulnar).
SHAPES = (HandShape(), HandShape(length=0.9, width=0.92, palm=0.9, thumb=0.95),
           HandShape(length=1.1, width=1.08, palm=1.1, thumb=1.05))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", default="1,2,3,4,5,6", help="seeds of the draws, comma-separated")
    args = ap.parse_args()
    rows = []
    for seed in (int(s) for s in args.seeds.split(",")):
        for shape in SHAPES:
            config = dataclasses.replace(HELDOUT, seed=seed, shape=shape)
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")  # the disturbance and still-start warnings
                summary = evaluate(config, durations=(15.0,), elbows=("fixed",),
                                   filters=("filter4",), grasps=False)["summary"]["filter4"]
            rows.append([summary[k] for k in _KEYS])
            print(f"seed {seed} {shape.name}: " + ", ".join(
                f"{name} {v:.2f}" for name, v in zip(_KEYS.values(), rows[-1])), flush=True)
    a = np.array(rows)
    for j, name in enumerate(_KEYS.values()):
        print(f"{name:18s} {a[:, j].min():6.2f} - {a[:, j].max():6.2f} (mean {a[:, j].mean():.2f})")
    tips = a[:, -1]
    print(f"tips_mm_min={tips.min():.2f} tips_mm_max={tips.max():.2f} "
          f"tips_over_10mm={int((tips > 10).sum())} draws={len(a)}")


if __name__ == "__main__":
    main()
