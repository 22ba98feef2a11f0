"""Does the thesis' Kalman denoising (seed 003 eqs. 4.9-4.17) help Filter 4?

For the tuning and the held-out simulator configurations: the gyros' Allan
coefficients from a 120-s static recording, then two 30-s free motions (elbow
fixed and moving) tracked by Filter 4 with the raw gyros and with gyros
denoised at several ``q_signal``.  Prints the orientation RMSE (mean over the
20 segments and the worst segment) and the joint-angle RMSE, mean of the two
trials.  The last line is machine-readable:
``denoise_gain_deg=<held-out orientation mean, raw minus best denoised>``.

Usage::

    python scripts/study_imu_denoise.py
"""

from __future__ import annotations

import argparse
import dataclasses

import numpy as np

from handsynth.sensors.imu import HELDOUT, TUNING, simulate_imu
from handsynth.sensors.imu._allan import KalmanDenoiser, allan_deviation, noise_coefficients
from handsynth.sensors.imu._eval import _calibrate, _trial
from handsynth.sensors.imu._model import ImuHand
from handsynth.sensors.imu._motion import free_motion, static_motion

Q_SIGNALS = (None, 50.0, 5.0, 0.5)


def main() -> None:
    argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                            formatter_class=argparse.RawDescriptionHelpFormatter).parse_args()
    gain = float("nan")
    for name, config in (("tuning", TUNING), ("held-out", HELDOUT)):
        placement = config.placement()
        _, calib, _ = _calibrate(config, placement)
        hand = ImuHand(config.shape, placement=placement)
        still = simulate_imu(static_motion(120.0), hand=hand,
                             noise=dataclasses.replace(config.noise, disturbances=()), seed=3)
        taus, adev = allan_deviation(still.gyr[5, :, 0], still.rate_hz)
        c = noise_coefficients(taus, adev)
        print(f"{name}: gyro Q {c.random_walk:.3g} rad/s/sqrt(Hz), K {c.rate_random_walk:.3g}")
        means = {}
        for qs in Q_SIGNALS:
            res = []
            for k, elbow in enumerate(("fixed", "moving")):
                seed = config.seed * 100 + 10 + k
                rec = simulate_imu(free_motion(30.0, seed=seed, elbow=elbow), hand=hand,
                                   noise=config.noise, skin=config.skin, seed=seed + 50)
                if qs is not None:
                    d = KalmanDenoiser(random_walk=c.random_walk,
                                       rate_random_walk=c.rate_random_walk, q_signal=qs,
                                       rate_hz=rec.rate_hz)
                    rec = dataclasses.replace(rec, gyr=np.stack([d.apply(g) for g in rec.gyr]))
                t = _trial(rec, ("filter4",), calib)
                o = np.array(list(t["orientation_rmse_deg"]["filter4"].values()))
                res.append((o.mean(), o.max(), np.mean(list(t["joint_rmse_deg"]["filter4"].values()))))
            r = np.mean(res, axis=0)
            means[qs] = r[0]
            label = "raw gyros" if qs is None else f"denoised, q_signal {qs:g}"
            print(f"  {label:28s} orientation mean {r[0]:.2f} deg, worst {r[1]:.2f}, "
                  f"joint angles {r[2]:.2f}")
        gain = means[None] - min(v for k, v in means.items() if k is not None)
    print(f"denoise_gain_deg={gain:.3f}")


if __name__ == "__main__":
    main()
