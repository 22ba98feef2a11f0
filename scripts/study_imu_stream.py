"""Live tracking (:class:`ImuStream`) against the whole recording's, with readings lost.

Usage::

    python scripts/study_imu_stream.py [--seeds 1,2] [--sensors 3]

On the held-out configuration's draws of ``--seeds`` (calibrated as ``handsynth imu eval``
calibrates them; 15-s free motions, elbow fixed and moving), one sensor's readings are lost
for 0.1, 0.2, 0.3, 0.5 and 1 s from a random time, ``--sensors`` random sensors per length.  Joint
angles, RMSE from the end of the common rotation, mean over the 20 joints and the worst
joint, are compared for: the recording as made (the stream's answers equal the whole
recording's, a test shows); the stream given the lost readings as not finite (it holds each
sensor's last reading and loosens its attitude, causally); the whole recording with the
lost readings bridged from the other sensors (:func:`bridge_lost`, which reads both sides
of the gap: what ``imu track --bridge-lost`` does afterwards).  About 5 min for two seeds.

The last line is machine-readable: ``hold<ms>_stream_deg=<x> hold<ms>_bridged_deg=<x>
... recorded_deg=<x>`` (the worst joint's RMSE, mean over the losses).
"""

from __future__ import annotations

import argparse
import dataclasses
import warnings

import numpy as np

from handsynth.sensors.imu import HELDOUT, ImuHand, ImuStream, bridge_lost
from handsynth.sensors.imu._eval import _calibrate, free_trials

_HOLDS_S = (0.1, 0.2, 0.3, 0.5, 1.0)


def _errors(angles: np.ndarray, rec) -> tuple[float, float]:
    """Joint-angle RMSE (mean over joints, worst joint) from the common rotation's end."""
    start = next(b for s, _, b in rec.truth.segments if s == "align")
    rmse = np.sqrt(np.nanmean((angles[start:] - rec.truth.angles[start:, 9:]) ** 2, axis=0))
    return float(np.nanmean(rmse)), float(np.nanmax(rmse))


def _streamed(calib, rec, packet: int = 5) -> np.ndarray:
    stream = ImuStream(calib, rate_hz=rec.rate_hz, sensor_calibration=False, max_hold_s=2.0)
    sub = rec.subset(calib.sensors)
    parts = [stream.push(sub.acc[:, i:i + packet], sub.gyr[:, i:i + packet],
                         sub.mag[:, i:i + packet]) for i in range(0, sub.n, packet)]
    parts.append(stream.close())
    return np.concatenate([p.angles_deg for p in parts])


def heldout_draw(seed: int):
    """The held-out configuration's draw `seed`: (config, calibration, sensor calibration,
    hand), calibrated as ``handsynth imu eval`` calibrates it."""
    config = dataclasses.replace(HELDOUT, seed=seed)
    placement = config.placement()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the configuration's magnet, on purpose
        _, calib, sensor_cal = _calibrate(config, placement)
    return config, calib, sensor_cal, ImuHand(config.shape, placement=placement)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", default="1,2", help="held-out seeds, comma-separated")
    ap.add_argument("--sensors", type=int, default=3, help="random sensors lost per length")
    args = ap.parse_args()
    rows: dict = {h: [] for h in _HOLDS_S}
    recorded = []
    for seed in (int(s) for s in args.seeds.split(",")):
        config, calib, sensor_cal, hand = heldout_draw(seed)
        for n, (_, elbow, rec) in enumerate(free_trials(config, hand, durations=(15.0,))):
            rec = sensor_cal.apply(rec)
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                whole = calib.track(rec, sensor_calibration=False)["angles"]
                clean = _errors(_streamed(calib, rec), rec)
            recorded.append(clean)
            print(f"seed {seed} elbow {elbow}: as recorded {clean[0]:.2f} / {clean[1]:.2f} deg "
                  f"(joints mean / worst; the whole recording's {_errors(whole, rec)[0]:.2f} / "
                  f"{_errors(whole, rec)[1]:.2f})", flush=True)
            rng = np.random.default_rng([seed, n])
            for hold in _HOLDS_S:
                for k in rng.choice(len(rec.sensors), args.sensors, replace=False):
                    k = int(k)
                    start = int(rng.uniform(4.5, 13.0) * rec.rate_hz)
                    stop = start + round(hold * rec.rate_hz)
                    lost = {c: getattr(rec, c).copy() for c in ("acc", "gyr", "mag")}
                    held = {c: a.copy() for c, a in lost.items()}
                    for c in lost:
                        lost[c][k, start:stop] = np.nan
                        held[c][k, start:stop] = held[c][k, start - 1]
                    with warnings.catch_warnings():
                        warnings.simplefilter("ignore")
                        live = _errors(_streamed(calib, dataclasses.replace(rec, **lost)), rec)
                        filled = bridge_lost(dataclasses.replace(rec, **held), max_s=2.0)[0]
                        bridged = _errors(calib.track(filled, sensor_calibration=False)["angles"],
                                          rec)
                    rows[hold].append((*clean, *live, *bridged))
                    print(f"  {rec.sensors[k]:17s} lost {hold:.1f} s at {start / rec.rate_hz:5.2f} s: "
                          f"stream {live[0]:.2f} / {live[1]:.2f}, bridged {bridged[0]:.2f} / "
                          f"{bridged[1]:.2f}", flush=True)
    fields = []
    rec_mean = np.mean(recorded, axis=0)
    print(f"as recorded ({len(recorded)} recordings): joints {rec_mean[0]:.2f} deg mean, worst "
          f"joint {rec_mean[1]:.2f}")
    for hold, r in rows.items():
        a = np.array(r)
        print(f"lost {hold:.1f} s ({len(a)}): joints mean {a[:, 2].mean():.2f} deg streamed "
              f"(predicted), {a[:, 4].mean():.2f} bridged, {a[:, 0].mean():.2f} as recorded; worst "
              f"joint {a[:, 3].mean():.2f} streamed (up to {a[:, 3].max():.2f}), "
              f"{a[:, 5].mean():.2f} bridged (up to {a[:, 5].max():.2f}), {a[:, 1].mean():.2f} "
              "as recorded")
        ms = round(hold * 1e3)
        fields += [f"hold{ms}_stream_deg={a[:, 3].mean():.3f}",
                   f"hold{ms}_bridged_deg={a[:, 5].mean():.3f}"]
    print(" ".join(fields + [f"recorded_deg={rec_mean[1]:.3f}"]))


if __name__ == "__main__":
    main()
