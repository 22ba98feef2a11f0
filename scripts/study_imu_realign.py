"""IMU streams late against each other, read realigned (``imu track --realign-late``).

Usage::

    python scripts/study_imu_realign.py [--seeds 19,20,21,22,23,24] [--faults 3]

Per draw of the held-out configuration (``--seeds``, each in the three hand sizes of
``scripts/study_imu_draws.py``; the calibration ``handsynth imu eval`` makes, at 100 Hz):
its 15-s free motion with the elbow fixed simulated at 1,000 Hz and read at 100 Hz the way
a sensor that averages its own samples is (each reading the mean of the ten 1-ms samples
up to its tick), and ``--faults`` times with one sensor's readings taken late by a random
lag of 12-120 ms (its ticks that much earlier than the others': any fraction of the 10-ms
period, not a shift by whole samples, which is what :func:`~handsynth.sensors.imu.delayed`
makes and close to what the realignment does).  The sensors are those the streams' check
judges (the phalanges, the thumb's metacarpal, the forearm plate, the hand's two).

Each recording is tracked (Filter 4, ``ImuCalibration.track``, the sensor calibration
applied first as ``eval`` does) as it is and with ``realign_late=True``: the joint-angle
RMSE against the truth over the motion (mean over the 20 joints, and the worst joint), the
sensor and lag read, and whether it was the sensor made late (to 3 ms).  The constant
answer (every joint at the calibration's zero) beside them.  About 6 min on one core.

The faults are drawn per run (by the count of draws so far), so one run of six seeds draws
other faults than two runs of three; docs/imu.md's figures are two runs, ``--seeds
19,20,21`` and ``--seeds 22,23,24``.

Last line: ``recordings=<n> realigned_as_recorded=<n> faults=<n> realigned=<n>
realigned_right=<n> hand_pair=<n> mean_as_recorded=<deg> mean_late=<deg>
mean_realigned=<deg> worst_late=<deg> worst_realigned=<deg> constant=<deg>`` (hand_pair:
faults of the hand's two sensors, which the check cannot assign to one of them).
"""

from __future__ import annotations

import argparse
import dataclasses
import warnings

import numpy as np
from study_imu_draws import SHAPES  # the same three hand sizes

from handsynth.sensors.imu import (
    CARRIED,
    HELDOUT,
    HINGES,
    RIGID,
    ImuHand,
    ImuRecording,
    free_motion,
    simulate_imu,
)
from handsynth.sensors.imu._eval import _calibrate, _device_seed

_FINE = 10          # 1,000 Hz samples per 100 Hz reading


def _sum_upto(samples: np.ndarray, cum: np.ndarray, x: np.ndarray) -> np.ndarray:
    """Sum of `samples` (N, 3) up to the fractional index `x` (linear within a sample); `cum`
    their cumulative sum with a zero row first."""
    x = np.clip(x + 1.0, 0.0, len(samples))
    i = np.minimum(np.floor(x).astype(int), len(samples) - 1)
    return cum[i] + (x - i)[:, None] * samples[i]


def _read(fine, late: dict[str, float]) -> ImuRecording:
    """100-Hz readings of the 1,000-Hz recording `fine`: each the mean of the ten samples up
    to its tick, a sensor of `late` (name -> ms) ticking that much earlier (its first ticks,
    before the recording began, read within the still start as in a mirror: readings held
    bit for bit read as samples lost)."""
    n = fine.n // _FINE
    ticks = np.arange(n) * _FINE + _FINE - 1.0
    out = {}
    for name in ("acc", "gyr", "mag"):
        a = getattr(fine, name)
        b = np.empty((a.shape[0], n, 3))
        for k, s in enumerate(fine.sensors):
            end = ticks - late.get(s, 0.0)                 # ms, fractional
            end = np.where(end < _FINE - 1, 2.0 * (_FINE - 1) - end, end)
            cum = np.vstack([np.zeros((1, 3)), np.cumsum(a[k], axis=0)])
            b[k] = (_sum_upto(a[k], cum, end) - _sum_upto(a[k], cum, end - _FINE)) / _FINE
        out[name] = b
    return ImuRecording(fine.rate_hz / _FINE, fine.sensors, out["acc"], out["gyr"], out["mag"])


def _rmse(angles: np.ndarray, truth: np.ndarray, start: int) -> np.ndarray:
    err = angles[start:] - truth[start:]
    return np.sqrt(np.nanmean(err * err, axis=0))


def _track(draw, rec, realign: bool) -> tuple[np.ndarray, dict]:
    """Per-joint RMSE of Filter 4's angles of `rec` (its draw's sensor calibration applied) and
    what was realigned."""
    calib, sensor_cal, truth, start = draw
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        out = calib.track(sensor_cal.apply(rec), sensor_calibration=False, realign_late=realign)
    return _rmse(out["angles"], truth, start), out["realigned"]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", default="19,20,21,22,23,24", help="held-out seeds, comma-separated")
    ap.add_argument("--faults", type=int, default=3, help="late recordings a draw")
    args = ap.parse_args()
    judged = sorted({s for pair in HINGES + CARRIED + RIGID for s in pair})
    rows: list = []     # (sensor, lag, mean late, worst late, mean realigned, worst, right, any)
    calibrated, constants = [], []
    realigned_clean = count = 0
    for seed in (int(s) for s in args.seeds.split(",")):
        for shape in SHAPES:
            config = dataclasses.replace(HELDOUT, seed=seed, shape=shape)
            placement = config.placement()
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                _, calib, sensor_cal = _calibrate(config, placement)
                fine = simulate_imu(
                    free_motion(15.0, seed=config.seed * 100, elbow="fixed",
                                rate_hz=100.0 * _FINE),
                    hand=ImuHand(config.shape, placement=placement), noise=config.noise,
                    skin=config.skin, seed=config.seed * 100 + 50,
                    device_seed=_device_seed(config))
            truth = fine.truth.angles[_FINE - 1::_FINE, 9:]
            start = next(b for s, _, b in fine.truth.segments if s == "align") // _FINE
            draw = (calib, sensor_cal, truth, start)
            clean, found = _track(draw, _read(fine, {}), True)
            count += 1
            realigned_clean += bool(found)
            calibrated.append(float(np.nanmean(clean)))
            constants.append(float(np.nanmean(_rmse(np.zeros_like(truth), truth, start))))
            print(f"seed {seed} {shape.name}: as recorded {np.nanmean(clean):.2f} deg mean, worst "
                  f"joint {np.nanmax(clean):.2f}{'; REALIGNED: ' + str(found) if found else ''}",
                  flush=True)
            rng = np.random.default_rng([seed, count, 17])
            for _ in range(args.faults):
                sensor = str(rng.choice(judged))
                lag = float(rng.uniform(12.0, 120.0))
                rec = _read(fine, {sensor: lag})
                as_is, _ = _track(draw, rec, False)
                back, found = _track(draw, rec, True)
                right = set(found) == {sensor} and abs(found[sensor] * 1e3 - lag) <= 3.0
                rows.append((sensor, lag, float(np.nanmean(as_is)), float(np.nanmax(as_is)),
                             float(np.nanmean(back)), float(np.nanmax(back)), right, bool(found)))
                read = ", ".join(f"{s} {v * 1e3:.1f} ms" for s, v in found.items()) or "nothing"
                print(f"  {sensor} {lag:.1f} ms late: {np.nanmean(as_is):.2f} deg mean, worst "
                      f"joint {np.nanmax(as_is):.2f}; realigned {np.nanmean(back):.2f} / "
                      f"{np.nanmax(back):.2f} ({read}{'' if right else '; NOT AS MADE'})",
                      flush=True)
    hand = [r for r in rows if r[0].startswith("hand_")]
    rest = [r for r in rows if not r[0].startswith("hand_")]
    for label, group in (("phalanges, metacarpal, forearm", rest), ("hand's two sensors", hand)):
        if group:
            print(f"{label}: {sum(r[6] for r in group)} of {len(group)} realigned as made; joint "
                  f"RMSE mean {np.mean([r[2] for r in group]):.2f} -> "
                  f"{np.mean([r[4] for r in group]):.2f} deg, worst joint up to "
                  f"{max(r[3] for r in group):.2f} -> {max(r[5] for r in group):.2f} deg")
    print(f"as recorded {np.mean(calibrated):.2f} deg mean joint RMSE (draws "
          f"{min(calibrated):.2f}-{max(calibrated):.2f}); constant (open hand) "
          f"{np.mean(constants):.2f}")
    print(f"recordings={count} realigned_as_recorded={realigned_clean} faults={len(rows)} "
          f"realigned={sum(r[7] for r in rows)} realigned_right={sum(r[6] for r in rows)} "
          f"hand_pair={len(hand)} mean_as_recorded={np.mean(calibrated):.2f} "
          f"mean_late={np.mean([r[2] for r in rows]):.2f} "
          f"mean_realigned={np.mean([r[4] for r in rows]):.2f} "
          f"worst_late={max(r[3] for r in rows):.2f} worst_realigned={max(r[5] for r in rows):.2f} "
          f"constant={np.mean(constants):.2f}")


if __name__ == "__main__":
    main()
