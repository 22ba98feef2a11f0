"""IMU readings held by the logger: what they cost, what bridging them gives back (docs/imu.md).

Usage::

    python scripts/study_imu_held.py [--seeds 1,2] [--sensors 3] [--broad DIR]

One sensor's readings held (the reading before repeated in its place, as a logger does
for samples lost on a wireless link) for 0.1, 0.2, 0.3, 0.5, 1 and 2 s from a random time in
a 15-s free motion: the tuning configuration and the held-out configuration's draws of
``--seeds`` (other devices, mounting errors and motions; ``scripts/study_imu_draws.py``),
elbow fixed and moving, ``--sensors`` random sensors per hold, Filter 4 with the
calibration of ``handsynth imu eval``.  Per configuration and hold: the joint-angle RMSE
and the worst segment's orientation RMSE of the recording as it was, read with the held
readings (the check turned off for this), with them bridged from the other sensors
(:func:`handsynth.sensors.imu.bridge_lost`, beyond its limit for the 2-s holds), the same
without Filter 4 loosening the held sensor's attitude over the filled samples (``filled``
dropped: as before it did) and bridged by straight lines alone (``predict=False``).
Then how many held stretches
:func:`~handsynth.sensors.imu.lost_stretches` finds in the recordings as made (none is
right), and with ``--broad DIR`` in BROAD's real trials.  About 15 min for two seeds.
Last line: ``false_alarms=<n> recordings=<n> broad_trials=<n> broad_flagged=<n>``.
"""

from __future__ import annotations

import argparse
import contextlib
import dataclasses

import numpy as np

from handsynth.sensors.imu import (
    HELDOUT,
    TUNING,
    ImuHand,
    _lost,
    bridge_lost,
    evaluate_trial,
    find_broad_trials,
    lost_stretches,
    read_broad_trial,
)
from handsynth.sensors.imu._eval import _calibrate, free_trials

_HOLDS_S = (0.1, 0.2, 0.3, 0.5, 1.0, 2.0)


@contextlib.contextmanager
def _unchecked():
    """Read held readings as a filter did before they were refused."""
    keep = _lost.lost_stretches
    _lost.lost_stretches = lambda rec, **kw: []
    try:
        yield
    finally:
        _lost.lost_stretches = keep


def _scores(rec, calib) -> tuple[float, float]:
    s = evaluate_trial(rec, calib)["filter4"]
    return s["joint_angle_mean_rmse_deg"], s["orientation_worst_segment_deg"]


def _held_copy(rec, k: int, start: int, n: int):
    arrays = {name: getattr(rec, name).copy() for name in ("acc", "gyr", "mag")}
    for a in arrays.values():
        a[k, start:start + n] = a[k, start - 1]
    return dataclasses.replace(rec, **arrays)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", default="1,2", help="held-out seeds, comma-separated")
    ap.add_argument("--sensors", type=int, default=3, help="random sensors held per hold")
    ap.add_argument("--broad", default=None, help="folder of BROAD's trials (hdf5 or mat)")
    args = ap.parse_args()
    configs = [TUNING] + [dataclasses.replace(HELDOUT, seed=int(s)) for s in args.seeds.split(",")]
    alarms = recordings = 0
    for config in configs:
        placement = config.placement()
        _, calib, sensor_cal = _calibrate(config, placement)
        hand = ImuHand(config.shape, placement=placement)
        rows: dict = {}
        for _, elbow, rec in free_trials(config, hand, durations=(15.0,)):
            rec = sensor_cal.apply(rec)
            recordings += 1
            alarms += len(lost_stretches(rec))
            clean = _scores(rec, calib)
            rng = np.random.default_rng([config.seed, recordings])
            for hold in _HOLDS_S:
                for k in rng.choice(len(rec.sensors), args.sensors, replace=False):
                    start = int(rng.uniform(4.0, 13.0) * rec.rate_hz)
                    held = _held_copy(rec, int(k), start, round(hold * rec.rate_hz))
                    with _unchecked():
                        as_read = _scores(held, calib)
                    filled = bridge_lost(held, max_s=3.0)[0]
                    bridged = _scores(filled, calib)
                    tight = _scores(dataclasses.replace(filled, filled=None), calib)
                    lines = _scores(bridge_lost(held, max_s=3.0, predict=False)[0], calib)
                    rows.setdefault(hold, []).append((*clean, *as_read, *bridged, *lines, *tight))
                    print(f"{config.label} seed {config.seed} elbow {elbow} {rec.sensors[k]:17s} "
                          f"held {hold:.1f} s at {start / rec.rate_hz:5.2f} s: joints / worst "
                          f"segment {clean[0]:.2f} / {clean[1]:.2f} deg as recorded, "
                          f"{as_read[0]:.2f} / {as_read[1]:.2f} held, {bridged[0]:.2f} / "
                          f"{bridged[1]:.2f} bridged, {tight[0]:.2f} / {tight[1]:.2f} bridged "
                          f"not loosened, {lines[0]:.2f} / {lines[1]:.2f} by lines", flush=True)
        for hold, r in rows.items():
            a = np.array(r)
            print(f"{config.label} seed {config.seed}, held {hold:.1f} s ({len(a)}): joints "
                  f"{a[:, 0].mean():.2f} as recorded, {a[:, 2].mean():.2f} held, "
                  f"{a[:, 4].mean():.2f} bridged, {a[:, 8].mean():.2f} not loosened, "
                  f"{a[:, 6].mean():.2f} by lines; worst segment "
                  f"{a[:, 1].mean():.2f}, held {a[:, 3].mean():.2f} (up to {a[:, 3].max():.1f}), "
                  f"bridged {a[:, 5].mean():.2f} (up to {a[:, 5].max():.1f}), not loosened "
                  f"{a[:, 9].mean():.2f} (up to {a[:, 9].max():.1f}), by lines "
                  f"{a[:, 7].mean():.2f} (up to {a[:, 7].max():.1f})", flush=True)
    trials = flagged = 0
    if args.broad:
        for path in find_broad_trials(args.broad):
            rec = read_broad_trial(path)[0]
            found = lost_stretches(rec)
            longest = max((h.duration_s for h in found), default=0.0)
            trials, flagged = trials + 1, flagged + bool(found)
            print(f"BROAD {path.name}: {len(found)} held stretches (longest {longest:.3f} s)")
    print(f"false_alarms={alarms} recordings={recordings} broad_trials={trials} "
          f"broad_flagged={flagged}")


if __name__ == "__main__":
    main()
