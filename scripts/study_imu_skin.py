"""Sensor-to-joint and link vectors with skin motion: eqs. 3.1-3.10 against the static-pose fit.

The eval's tuning configuration has no skin motion, so the choice is made on
development configurations built from it (the standard hand, datasheet
noise, exact mounting) with skin motion of other sizes than the held-out
one's (2 mm and 4 deg per 90 deg): 3 mm / 2 deg and 1 mm / 6 deg, and none.
For each, the calibration recording is simulated, the accelerometer/gyro
calibration applied, and the vectors estimated by eqs. 3.1-3.10 alone and
with ``static_pose=True`` (extrapolated to the static pose's angle); prints
the median / max error of the 37 vectors and the median link-vector error,
mm.  ``--heldout`` adds the held-out
configuration (a check, never a choice).  The last line is machine-readable.

Usage::

    python scripts/study_imu_skin.py [--heldout]
"""

from __future__ import annotations

import argparse
import dataclasses

import numpy as np

from handsynth.sensors.imu import HELDOUT, TUNING, SkinMotion
from handsynth.sensors.imu._eval import _calibrate
from handsynth.sensors.imu._vectors import calibrate_vectors, chain_model, truth_chain_model


def _errors(cal, static_pose: bool) -> tuple[float, float, float]:
    truth = cal.truth.joint_vectors
    vec = calibrate_vectors(cal, static_pose=static_pose)
    err = [np.linalg.norm(v.vector - truth[k]) * 1e3 for k, v in vec.items()
           if not k[0].endswith("_tip")]
    model = chain_model(cal, vec)
    tl = truth_chain_model(cal).links
    lerr = [np.linalg.norm(v - tl[k]) * 1e3 for k, v in model.links.items()]
    return float(np.median(err)), float(np.max(err)), float(np.median(lerr))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--heldout", action="store_true", help="also check on the held-out config")
    args = ap.parse_args()
    configs = [("tuning (no skin)", TUNING),
               ("tuning + skin 3 mm / 2 deg", dataclasses.replace(
                   TUNING, label="dev-a", skin=SkinMotion(3.0, 2.0), seed=5)),
               ("tuning + skin 1 mm / 6 deg", dataclasses.replace(
                   TUNING, label="dev-b", skin=SkinMotion(1.0, 6.0), seed=6))]
    if args.heldout:
        configs.append(("held-out", HELDOUT))
    last = {}
    for name, config in configs:
        cal, _, _ = _calibrate(config, config.placement())
        for static_pose in (False, True):
            med, mx, link = _errors(cal, static_pose)
            label = "static pose" if static_pose else "eqs. 3.1-3.10"
            print(f"{name:30s} {label:14s} vectors median {med:5.2f} max {mx:5.1f} mm, "
                  f"links median {link:5.2f} mm")
            last[(name, static_pose)] = med
    name = configs[-1][0]
    print(f"vector_median_mm_eq310={last[(name, False)]:.3f} "
          f"vector_median_mm_static_pose={last[(name, True)]:.3f} config={name!r}")


if __name__ == "__main__":
    main()
