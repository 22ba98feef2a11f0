"""Filter 4 with the sensors sampled at 50 to 1,000 Hz (docs/imu.md quotes it).

Usage::

    python scripts/study_imu_rates.py [--rates 50,100,200,400,1000] [--seeds 1,2,3]

The held-out configuration (:data:`handsynth.sensors.imu.HELDOUT`) with other seeds,
the calibration recording and one 15-s trial with the elbow fixed both sampled at
each rate, calibrated and corrected as ``handsynth imu eval`` does at 100 Hz (the
eval's own rate).  Per rate and seed: the sensor-to-joint vectors' median error,
the link vectors' median error, and Filter 4's orientation RMSE (mean, worst
segment), joint-angle RMSE and fingertip RMSE from the elbow.  About 3 min per
seed on one core.  Last line: ``rate_hz=<r>:tips_mm_mean=<m> ...``.
"""

from __future__ import annotations

import argparse
import dataclasses
import warnings

import numpy as np

from handsynth.sensors.imu import (
    HELDOUT,
    ImuHand,
    calibrate,
    calibrate_vectors,
    calibration_motion,
    evaluate_trial,
    free_motion,
    simulate_imu,
    truth_chain_model,
)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rates", default="50,100,200,400,1000", help="sampling rates, Hz")
    ap.add_argument("--seeds", default="1,2,3", help="seeds of the draws, comma-separated")
    args = ap.parse_args()
    tips: dict[float, list[float]] = {}
    for rate in (float(r) for r in args.rates.split(",")):
        for seed in (int(s) for s in args.seeds.split(",")):
            config = dataclasses.replace(HELDOUT, seed=seed)
            placement = config.placement()
            quiet = dataclasses.replace(config.noise, disturbances=())
            device = seed * 7 + 3
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")  # the disturbance and still-start warnings
                cal = simulate_imu(calibration_motion(acc_poses=True, rate_hz=rate),
                                   hand=ImuHand(config.shape, placement=placement, tip_sensors=True),
                                   noise=quiet, skin=config.skin, seed=seed + 7, device_seed=device)
                calib = calibrate(cal)
                corrected = calib.sensor_calibration.apply(cal)
                true = cal.truth.joint_vectors
                vec = [np.linalg.norm(v.vector - true[k]) * 1e3
                       for k, v in calibrate_vectors(corrected).items() if k in true]
                truth_links = truth_chain_model(cal).links
                links = [np.linalg.norm(v - truth_links[k]) * 1e3 for k, v in calib.model.links.items()]
                rec = simulate_imu(free_motion(15.0, seed=seed * 100, elbow="fixed", rate_hz=rate),
                                   hand=ImuHand(config.shape, placement=placement),
                                   noise=config.noise, skin=config.skin, seed=seed * 100 + 50,
                                   device_seed=device)
                s = evaluate_trial(calib.sensor_calibration.apply(rec), calib, filters=("filter4",))
            f4 = s["filter4"]
            tips.setdefault(rate, []).append(f4["fingertip_mean_rmse_mm"])
            print(f"{rate:6.0f} Hz seed {seed}: vectors {np.median(vec):.2f} mm, links "
                  f"{np.median(links):.2f} mm; orientation {f4['orientation_mean_deg']:.2f} deg "
                  f"(worst segment {f4['orientation_worst_segment_deg']:.2f}), joints "
                  f"{f4['joint_angle_mean_rmse_deg']:.2f} deg, tips {f4['fingertip_mean_rmse_mm']:.2f} mm",
                  flush=True)
    print(" ".join(f"rate_hz={r:g}:tips_mm_mean={np.mean(v):.2f}" for r, v in tips.items()))


if __name__ == "__main__":
    main()
