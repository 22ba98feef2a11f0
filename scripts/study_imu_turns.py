"""IMU sensors turned on their segments since the calibration: told, and never said of the right ones.

Usage::

    python scripts/study_imu_turns.py [--seeds 1,2,3,4,5,6] [--turns 8] [--exchanges 4]

The recordings of ``scripts/study_imu_swaps.py`` (the tuning configuration and the
held-out configuration's draws of ``--seeds`` in three hand sizes, 15-s free motions with
the elbow fixed and moving; for the held-out seed 1 also grasp reaches and a 10-s still
hold), each as the sensors were calibrated and with one sensor's readings turned by one of
:data:`~handsynth.sensors.imu.TURNS` (``--turns`` random sensor-turn pairs a recording; the
sensors :func:`~handsynth.sensors.imu.turn_ratios` judges).  Per recording: the smallest
share of any sensor and turn as labelled (a warning below
:data:`~handsynth.sensors.imu.SWAP_RATIO`), whether :func:`turned_sensors` warns, how many
turned sensors it tells, and how many it names first with the turn that was made; and,
of ``--exchanges`` random pairs of sensors exchanged, how many
:func:`~handsynth.sensors.imu.misplaced_sensors` (what ``track`` runs) also says a sensor
is turned (a sensor of the pair is not named as turned).  Also per turn, how many were
told, and, for the turns not told, what the joint angles read (``track``) against the
recording as calibrated (not for the still hold, which ``track`` refuses: it has no
common rotation), and whether ``track``'s check of the angles
(:func:`~handsynth.sensors.imu.angles_beyond_range`) tells them.  About 10 min.

Also ``--rolls`` random phalanx sensors a recording turned 5-40 deg either way about the
phalanx's long axis (a strap slipped round the finger): how many were told, by band of
angle, and how well the angle was read.

Last line: ``false_alarms=<n> recordings=<n> told=<n> named_first=<n> turned=<n>
turn_said_of_exchanges=<n> exchanges=<n> untold_by_angles=<n> rolled=<n> rolled_told=<n>``
(rolled: in the recordings that move).
"""

from __future__ import annotations

import argparse
import dataclasses
import warnings

import numpy as np
from study_imu_swaps import _exchanged, recordings

from handsynth.sensors.imu import (
    SWAP_RATIO,
    TURNS,
    misplaced_sensors,
    turn_ratios,
    turned_sensors,
)


def _turned(rec, sensor: str, turn: str):
    """`rec` with `sensor` turned by ``TURNS[turn]`` on its segment: it reads R^T v."""
    out = dataclasses.replace(rec, acc=rec.acc.copy(), gyr=rec.gyr.copy(), mag=rec.mag.copy())
    k = rec.index(sensor)
    for c in (out.acc, out.gyr, out.mag):
        c[k] = c[k] @ TURNS[turn]
    return out


def _track(calib, rec) -> tuple[np.ndarray, bool]:
    """Joint angles ``track`` reads, and whether its angles' check warned."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        angles = calib.track(rec, sensor_calibration=False)["angles"]
    return angles, any("beyond the hand's range" in str(w.message) for w in caught)


def _rolled(rec, calib, sensor: str, deg: float):
    """`rec` with `sensor` turned `deg` about its phalanx's long axis (the link frame's y)."""
    from scipy.spatial.transform import Rotation

    turn = Rotation.from_rotvec(np.radians(deg) * np.asarray(calib.frames[sensor])[1]).as_matrix()
    out = dataclasses.replace(rec, acc=rec.acc.copy(), gyr=rec.gyr.copy(), mag=rec.mag.copy())
    for c in (out.acc, out.gyr, out.mag):
        c[rec.index(sensor)] = c[rec.index(sensor)] @ turn
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", default="1,2,3,4,5,6", help="held-out seeds, comma-separated")
    ap.add_argument("--turns", type=int, default=8, help="random sensor-turn pairs a recording")
    ap.add_argument("--exchanges", type=int, default=4, help="random pairs a recording")
    ap.add_argument("--rolls", type=int, default=4,
                    help="random phalanx sensors a recording turned 5-40 deg about the phalanx")
    args = ap.parse_args()
    names = list(TURNS)
    alarms = count = told = first = turned = confused = exchanges = 0
    per_turn = {name: [0, 0] for name in names}
    rolls: list = []   # (|deg|, told, error of the angle read, in the still hold)
    untold: list[float] = []
    by_angles = 0
    for config, calib, label, rec in recordings(args.seeds):
        shares = turn_ratios(rec, calib.model)
        low = min((share, s, t) for s, d in shares.items() for t, (share, _) in d.items())
        warned = turned_sensors(rec, calib.model, calib.frames) is not None
        alarms += warned
        count += 1
        rng = np.random.default_rng([config.seed, count, 3])
        sensors = sorted(shares, key=rec.index)
        got = right = 0
        missed = []
        whole = None
        for _ in range(args.turns):
            sensor, name = str(rng.choice(sensors)), names[int(rng.integers(len(names)))]
            faulty = _turned(rec, sensor, name)
            said = turned_sensors(faulty, calib.model, calib.frames)
            per_turn[name][1] += 1
            if said is not None:
                got += 1
                per_turn[name][0] += 1
                right += said.split(": ", 1)[1].startswith(f"{sensor} {name} (")
                continue
            # not told: what track reads, and whether its angles' check tells it
            if "still" in label:             # no common rotation: track refuses it
                missed.append(f"{sensor} {name}")
                continue
            if whole is None:
                whole = _track(calib, rec)[0]
            angles, beyond = _track(calib, faulty)
            err = np.sqrt(np.nanmean((angles - whole) ** 2, axis=0))
            untold.append(float(np.nanmax(err)))
            by_angles += beyond
            missed.append(f"{sensor} {name} (worst joint {np.nanmax(err):.1f} deg off"
                          f"{', told by the angles' if beyond else ''})")
        rolled_told = 0
        hinge_sensors = [s for s in sensors if s in calib.frames and s.split("_")[-1] in
                         ("proximal", "middle", "distal")]
        for _ in range(args.rolls):
            sensor = str(rng.choice(hinge_sensors))
            deg = float(rng.uniform(5.0, 40.0) * rng.choice((-1, 1)))
            said = turned_sensors(_rolled(rec, calib, sensor, deg), calib.model, calib.frames)
            got_deg = None
            if said is not None and f": {sensor} " in said and "long axis" in said:
                number = said.split(f": {sensor} ", 1)[1].split(" deg", 1)[0]
                way = -1.0 if "(clockwise" in said.split(f": {sensor} ", 1)[1][:80] else 1.0
                got_deg = way * float(number)
            rolls.append((abs(deg), got_deg is not None and "still" not in label,
                          None if got_deg is None else got_deg - deg, "still" in label))
            rolled_told += got_deg is not None
        said_turn = 0
        for _ in range(args.exchanges):
            a, b = (str(s) for s in rng.choice(sensors, 2, replace=False))
            said_turn += any(m.startswith("sensors read as turned")
                             for m in misplaced_sensors(_exchanged(rec, a, b), calib.model,
                                                        calib.frames))
        told, first, turned = told + got, first + right, turned + args.turns
        confused, exchanges = confused + said_turn, exchanges + args.exchanges
        print(f"{config.label} seed {config.seed} {config.shape.name} {label}: smallest share "
              f"as labelled {low[0]:.2f} ({low[1]} {low[2]}){' WARNED' if warned else ''}; "
              f"turned {got} of {args.turns} told, {right} named first with the turn"
              f"{'; not told: ' + ', '.join(missed) if missed else ''}; exchanges said turned "
              f"{said_turn} of {args.exchanges}; rolled {rolled_told} of {args.rolls} told",
              flush=True)
    for name, (got, made) in per_turn.items():
        print(f"  {name}: {got} of {made} told")
    print(f"(a sensor reads as turned below {SWAP_RATIO} of its joints' residual)")
    moving = [r for r in rolls if not r[3]]
    for low, high in ((5, 10), (10, 20), (20, 40)):
        band = [r for r in moving if low <= r[0] < high]
        errs = [abs(r[2]) for r in band if r[2] is not None]
        print(f"  turned {low}-{high} deg about the phalanx: {sum(r[1] for r in band)} of "
              f"{len(band)} told, the angle read to {max(errs, default=float('nan')):.1f} deg "
              "at worst")
    if untold:
        print(f"turns not told: {len(untold)}, {by_angles} of them told by track's angles' check; "
              f"the worst joint off by {np.median(untold):.1f} deg median (up to "
              f"{max(untold):.1f}) against the recording as calibrated")
    print(f"false_alarms={alarms} recordings={count} told={told} named_first={first} "
          f"turned={turned} turn_said_of_exchanges={confused} exchanges={exchanges} "
          f"untold_by_angles={by_angles} rolled={len(moving)} "
          f"rolled_told={sum(r[1] for r in moving)}")


if __name__ == "__main__":
    main()
