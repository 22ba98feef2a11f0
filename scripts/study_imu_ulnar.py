"""The ring and little fingers' links across the hand's hinge, closed on the wrist or not.

Measured for docs/imu.md ("The hand's ulnar side").

Usage::

    python scripts/study_imu_ulnar.py [--seeds 1,2,3,4,5,6]

For each held-out draw (:data:`handsynth.sensors.imu.HELDOUT` with that seed: its devices,
mounting errors, skin motion and noise; the standard hand, one 10 % smaller and one 10 %
larger, as ``study_imu_draws.py``) a calibration recording is simulated twice, as the
thesis' protocol makes it (``calibration_motion()``: no static poses, so no sensor
calibration) and with the static poses (``acc_poses=True``, the sensors corrected, as
``handsynth imu eval``).  Its link model is made twice from the same vectors: with the
links across the ulnar hinge closed on the ring and little proximal phalanges' view of the
wrist (the default, ``calibrate_vectors``) and without (those two vectors left out: eq.
3.6 as the thesis has it).  A 15-s free motion with the elbow fixed is tracked by Filter 4
with each, and each finger's fingertip RMSE from the elbow is printed; beside them the
first frame's fingertips held; a calibration refused is said and counted.  About 3 min.
Last line: ``ulnar_closed_mm=<lo>-<hi> ulnar_open_mm=<lo>-<hi> radial_mm=<lo>-<hi>
static_poses_closed_mm=<lo>-<hi> static_poses_open_mm=<lo>-<hi> held_mm=<lo>-<hi> draws=<n>
refused=<n> static_poses_refused=<n>`` (ulnar: the ring and little
fingers' mean, radial: the thumb, index and middle fingers' mean, without static poses
unless named).
"""

from __future__ import annotations

import argparse
import dataclasses
import warnings

import numpy as np
from study_imu_draws import SHAPES  # the same three hand sizes

from handsynth.errors import EstimationError
from handsynth.models import HandShape
from handsynth.sensors.imu import (
    HELDOUT,
    POINTS,
    ImuHand,
    calibrate,
    calibrate_vectors,
    chain_model,
    fingertip_positions,
)
from handsynth.sensors.imu._eval import _calibration_recording, free_trials
from handsynth.sensors.imu._vectors import CLOSING_VECTORS

_FINGERS = ("thumb", "index", "middle", "ring", "little")


def _tips_mm(quats, sensors, model, kp) -> np.ndarray:
    """Each finger's fingertip RMSE from the elbow, mm, (5,)."""
    tips = fingertip_positions(quats, sensors, model)
    elbow = kp[:, POINTS.index("elbow")]
    return np.array([np.sqrt(np.mean(np.sum(
        (tips[f] - (kp[:, POINTS.index(f"{f}_tip")] - elbow)) ** 2, axis=1))) * 1e3
        for f in _FINGERS])


def _draw(seed: int, shape: HandShape, static_poses: bool) -> dict[str, np.ndarray] | None:
    config = dataclasses.replace(HELDOUT, seed=seed, shape=shape)
    placement = config.placement()
    rec_cal = _calibration_recording(config, placement, acc_poses=static_poses)
    try:
        cal = calibrate(rec_cal)
    except EstimationError as exc:  # counted, and said
        print(f"seed {seed} {shape.name}: calibration refused: {exc}", flush=True)
        return None
    used = rec_cal if cal.sensor_calibration is None else cal.sensor_calibration.apply(rec_cal)
    vectors = calibrate_vectors(used)
    rec = next(free_trials(config, ImuHand(shape, placement=placement), durations=(15.0,),
                           elbows=("fixed",)))[2]
    kp = rec.truth.keypoints
    out = {}
    for name, vec in (("closed", vectors),
                      ("open", {k: v for k, v in vectors.items() if k not in CLOSING_VECTORS})):
        model = chain_model(used, vec)
        this = dataclasses.replace(cal, model=model)  # the attitudes and tips read only the model
        res = this.track(rec)
        out[name] = _tips_mm(res["quat"], this.sensors, model, kp)
        if name == "closed":
            first = np.repeat(res["quat"][:, :1], rec.n, axis=1)  # the first frame held
            out["held"] = _tips_mm(first, this.sensors, model, kp)
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", default="1,2,3,4,5,6", help="held-out draws, comma-separated")
    args = ap.parse_args()
    rows: dict[str, list] = {}
    refused: dict[str, int] = {}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the configuration's magnet and still-start notes
        for seed in (int(s) for s in args.seeds.split(",")):
            for shape in SHAPES:
                for static_poses in (False, True):
                    r = _draw(seed, shape, static_poses)
                    tag = "static_poses_" if static_poses else ""
                    if r is None:
                        refused[tag] = refused.get(tag, 0) + 1
                        continue
                    for k, v in r.items():
                        rows.setdefault(tag + k, []).append(v)
                    protocol = "static poses" if static_poses else "thesis protocol"
                    print(f"seed {seed} {shape.name} {protocol}: "
                          + "; ".join(f"{k} " + " ".join(f"{x:.1f}" for x in v)
                                      for k, v in r.items())
                          + "  (thumb index middle ring little, mm)", flush=True)

    def span(key: str, fingers: slice) -> str:
        v = np.array(rows[key])[:, fingers].mean(axis=1)
        return f"{v.min():.1f}-{v.max():.1f}"

    ulnar, radial = slice(3, 5), slice(0, 3)
    print(f"ulnar_closed_mm={span('closed', ulnar)} ulnar_open_mm={span('open', ulnar)} "
          f"radial_mm={span('closed', radial)} "
          f"static_poses_closed_mm={span('static_poses_closed', ulnar)} "
          f"static_poses_open_mm={span('static_poses_open', ulnar)} "
          f"held_mm={span('held', slice(0, 5))} draws={len(rows['closed'])} "
          f"refused={refused.get('', 0)} static_poses_refused={refused.get('static_poses_', 0)}")


if __name__ == "__main__":
    main()
