"""IMU sensors exchanged since the calibration: told, and never said of the right ones (docs/imu.md).

Usage::

    python scripts/study_imu_swaps.py [--seeds 1,2,3,4,5,6] [--exchanges 8]

Recordings as the sensors were calibrated, and the same recordings with two sensors'
readings exchanged (:func:`handsynth.sensors.imu.swapped_sensors`): the tuning
configuration, and the held-out configuration's draws of
``scripts/study_imu_draws.py`` (other seeds: devices, mounting errors, motions; three
hand sizes), a 15-s free motion with the elbow fixed and one with it moving each; for
the held-out seed 1 also the grasp reaches of ``scripts/study_imu_motions.py`` (elbow
fixed and moving) and a 10-s still hold.  Per recording: the smallest share of any pair
as labelled (a warning below :data:`~handsynth.sensors.imu.SWAP_RATIO`), whether it
warns, and of ``--exchanges`` random pairs of sensors exchanged how many it warns of and
how many it names first.  The calibration is ``handsynth imu eval``'s.  About 4 min.
Last line: ``false_alarms=<n> recordings=<n> caught=<n> named_first=<n> exchanged=<n>``.
"""

from __future__ import annotations

import argparse
import dataclasses

import numpy as np
from study_imu_draws import SHAPES  # the same three hand sizes

from handsynth.models import HandShape
from handsynth.sensors.imu import (
    GRASP_POSES,
    HELDOUT,
    TUNING,
    ImuHand,
    grasp_motion,
    simulate_imu,
    static_motion,
    swap_ratios,
    swapped_sensors,
)
from handsynth.sensors.imu._eval import _calibrate, _device_seed, free_trials


def _exchanged(rec, a: str, b: str):
    i, j = rec.index(a), rec.index(b)
    order = list(range(len(rec.sensors)))
    order[i], order[j] = j, i
    return dataclasses.replace(rec, acc=rec.acc[order], gyr=rec.gyr[order], mag=rec.mag[order])


def grasp_reaches(config, hand):
    """(label, recording) of the grasp reaches of ``scripts/study_imu_motions.py`` with the
    elbow fixed and moving, uncorrected."""
    grasps = tuple(g for g in GRASP_POSES if g != "open")
    for k, elbow in enumerate(("fixed", "moving")):
        seed = config.seed * 100 + 50 + k
        yield f"grasp reaches, elbow {elbow}", simulate_imu(
            grasp_motion(grasps, elbow=elbow, seed=seed), hand=hand, noise=config.noise,
            skin=config.skin, seed=seed + 7, device_seed=_device_seed(config))


def recordings(seeds: str):
    """(config, calibration, label, recording corrected by the draw's sensor calibration) of
    the tuning configuration and the held-out draws of `seeds` (comma-separated), as the
    module docstring says."""
    configs = [TUNING] + [dataclasses.replace(HELDOUT, seed=int(s), shape=shape)
                          for s in seeds.split(",") for shape in SHAPES]
    for config in configs:
        placement = config.placement()
        _, calib, sensor_cal = _calibrate(config, placement)
        hand = ImuHand(config.shape, placement=placement)
        recs = [(f"15 s, elbow {elbow}", rec)
                for _, elbow, rec in free_trials(config, hand, durations=(15.0,))]
        if config.seed == 1 and config.shape == HandShape():
            recs += list(grasp_reaches(config, hand))
            recs.append(("10 s still", simulate_imu(
                static_motion(10.0), hand=hand, noise=config.noise, skin=config.skin, seed=77,
                device_seed=_device_seed(config))))
        for label, rec in recs:
            yield config, calib, label, sensor_cal.apply(rec)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", default="1,2,3,4,5,6", help="held-out seeds, comma-separated")
    ap.add_argument("--exchanges", type=int, default=8, help="random pairs per recording")
    args = ap.parse_args()
    alarms = count = caught = named = exchanged = 0
    for config, calib, label, rec in recordings(args.seeds):
        shares = swap_ratios(rec, calib.model)
        low = min(shares, key=lambda p: shares[p][0])
        warned = swapped_sensors(rec, calib.model) is not None
        alarms += warned
        count += 1
        rng = np.random.default_rng([config.seed, count])
        sensors = sorted({s for pair in shares for s in pair}, key=rec.index)
        got = first = 0
        for _ in range(args.exchanges):
            a, b = (str(s) for s in rng.choice(sensors, 2, replace=False))
            said = swapped_sensors(_exchanged(rec, a, b), calib.model)
            got += said is not None
            head = "" if said is None else said.split("(")[0]
            first += f"{a} and {b}" in head or f"{b} and {a}" in head
        caught, named, exchanged = caught + got, named + first, exchanged + args.exchanges
        print(f"{config.label} seed {config.seed} {config.shape.name} {label}: smallest share "
              f"as labelled {shares[low][0]:.2f} ({low[0]}, {low[1]}; {shares[low][1]:.3f} "
              f"m/s^2){' WARNED' if warned else ''}; exchanged {got} of {args.exchanges} "
              f"told, {first} named first", flush=True)
    print(f"false_alarms={alarms} recordings={count} caught={caught} named_first={named} "
          f"exchanged={exchanged}")

if __name__ == "__main__":
    main()
