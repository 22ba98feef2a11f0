"""IMU sensors misplaced since the calibration, read as put back (``imu track --undo-misplaced``).

Usage::

    python scripts/study_imu_undo.py [--seeds 19,20,21,22,23,24] [--faults 2]
                                     [--motion free|elbow-moving|grasps]

Per draw of the held-out configuration (``--seeds``, each in the three hand sizes of
``scripts/study_imu_draws.py``; a 15-s free motion with the elbow fixed, or with
``--motion elbow-moving`` moving, or with ``--motion grasps`` the grasp reaches of
``scripts/study_imu_motions.py`` with the elbow fixed; the calibration
``handsynth imu eval`` makes, the recordings corrected by its sensor calibration), the
recording as calibrated and ``--faults`` recordings of each misplacement, made in the
simulator where it can be (not by turning the readings, which is what the undoing does):

- two sensors exchanged (a random pair of those ``track`` judges; their corrected
  readings exchanged, as sensors put back on each other's segments read once each
  sensor's own calibration is applied);
- a sensor turned on its segment by one of :data:`~handsynth.sensors.imu.TURNS` (the
  simulated sensor turned so where it sits, its own mounting error kept);
- a phalanx's sensor slipped 10-40 deg either way round the finger (the simulated sensor
  turned about the phalanx's long axis and carried round it, as a strap slips).

Each is tracked (Filter 4, ``ImuCalibration.track``) as it is and with
``undo_misplaced=True``.  Per recording: the joint-angle RMSE against the truth over the
motion (mean over the 20 joints, and the worst joint) as it is, put back, and for the
recording as calibrated; what was put back.  The constant answer (every joint at the
calibration's zero, the open hand) beside them.  About 7 min for six seeds on one core.
Seeds 7-18 chose how the put back is made (docs/imu.md, "Reading misplaced sensors as put
back"); the default seeds chose nothing.

The faults are drawn per run (by the count of draws so far), so one run of six seeds draws
other faults than two runs of three; docs/imu.md's free-motion figures are two runs,
``--seeds 19,20,21`` and ``--seeds 22,23,24``, its grasp reaches' one run of the six.

Last line: ``recordings=<n> undone_as_calibrated=<n> faults=<n> put_back=<n>
put_back_right=<n> mean_as_calibrated=<deg> mean_faulty=<deg> mean_undone=<deg>
worst_faulty=<deg> worst_undone=<deg> constant=<deg>`` (means of the per-recording mean
joint RMSE; worst: the largest worst-joint RMSE of any faulty recording).
"""

from __future__ import annotations

import argparse
import dataclasses
import warnings

import numpy as np
from scipy.spatial.transform import Rotation
from study_imu_draws import SHAPES  # the same three hand sizes
from study_imu_swaps import grasp_reaches

from handsynth.sensors.imu import HELDOUT, TURNS, ImuHand, turn_ratios
from handsynth.sensors.imu._eval import _calibrate, free_trials


def _rmse(angles: np.ndarray, rec) -> np.ndarray:
    """Per-joint RMSE (deg) of `angles` against `rec`'s truth over the motion (after the
    common rotation)."""
    truth = rec.truth
    start = next((b for s, _, b in truth.segments if s == "align"), 0)
    err = angles[start:] - truth.angles[start:, 9:]
    return np.sqrt(np.nanmean(err * err, axis=0))


def _track(calib, rec, undo: bool):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")   # the faults' warnings: counted from "undone"
        out = calib.track(rec, sensor_calibration=False, undo_misplaced=undo)
    return _rmse(out["angles"], rec), out["undone"]


def _recording(config, hand, motion: str):
    """The draw's recording of `motion` (as the module docstring says), uncorrected."""
    if motion == "grasps":
        return next(rec for label, rec in grasp_reaches(config, hand) if label.endswith("fixed"))
    elbow = "moving" if motion == "elbow-moving" else "fixed"
    return next(rec for _, _, rec in free_trials(config, hand, durations=(15.0,), elbows=(elbow,)))


def _moved(config, placement, sensor: str, turn: np.ndarray, motion: str, *,
           about_long_axis: bool):
    """The draw's recording of `motion` with `sensor` turned by `turn` on
    its segment: in place (`turn` in the sensor's frame) or, `about_long_axis`, turned and
    carried round the phalanx's long axis (`turn` in its body's frame, about the body's y
    axis through its origin, the joint's centre)."""
    site = ImuHand(config.shape, placement=placement).model.site(f"imu_{sensor}")
    pos, quat = np.array(site.pos), np.array(site.quat)
    mount = Rotation.from_quat(np.r_[quat[1:], quat[0]])
    tilts, offsets = dict(placement.tilts_deg), dict(placement.offsets_mm)
    if about_long_axis:
        spin = Rotation.from_matrix(turn)
        new = spin * mount
        offsets[sensor] = tuple(np.asarray(offsets.get(sensor, (0, 0, 0)), float)
                                + 1e3 * (spin.apply(pos) - pos))
    else:
        new = mount * Rotation.from_matrix(turn)
    tilts[sensor] = tuple(np.degrees(new.as_rotvec()))
    moved = dataclasses.replace(placement, tilts_deg=tilts, offsets_mm=offsets)
    return _recording(config, ImuHand(config.shape, placement=moved), motion)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", default="19,20,21,22,23,24", help="held-out seeds, comma-separated")
    ap.add_argument("--faults", type=int, default=2, help="recordings of each misplacement a draw")
    ap.add_argument("--motion", choices=("free", "elbow-moving", "grasps"), default="free",
                    help="the recording's motion (module docstring)")
    args = ap.parse_args()
    names = list(TURNS)
    rows: list = []      # (kind, mean as it is, worst as it is, mean undone, worst undone, right)
    calibrated: list = []
    constants: list = []
    undone_clean = count = 0
    for seed in (int(s) for s in args.seeds.split(",")):
        for shape in SHAPES:
            config = dataclasses.replace(HELDOUT, seed=seed, shape=shape)
            placement = config.placement()
            _, calib, sensor_cal = _calibrate(config, placement)
            hand = ImuHand(config.shape, placement=placement)
            rec = sensor_cal.apply(_recording(config, hand, args.motion))
            clean, undone = _track(calib, rec, True)
            count += 1
            undone_clean += bool(undone)
            calibrated.append(float(np.nanmean(clean)))
            constants.append(float(np.nanmean(_rmse(np.zeros((rec.n, 20)), rec))))
            print(f"seed {seed} {shape.name}: as calibrated {np.nanmean(clean):.2f} deg mean, "
                  f"worst joint {np.nanmax(clean):.2f}"
                  f"{'; PUT BACK: ' + undone.describe() if undone else ''}", flush=True)
            rng = np.random.default_rng([seed, count, 11])
            judged = sorted(turn_ratios(rec, calib.model), key=rec.index)
            phalanges = [s for s in judged if s.split("_")[-1] in ("proximal", "middle", "distal")]
            for _ in range(args.faults):
                a, b = (str(s) for s in rng.choice(judged, 2, replace=False))
                i, j = rec.index(a), rec.index(b)
                order = list(range(len(rec.sensors)))
                order[i], order[j] = j, i
                faulty = dataclasses.replace(rec, acc=rec.acc[order], gyr=rec.gyr[order],
                                             mag=rec.mag[order])
                rows.append(_run(calib, "exchanged", faulty, f"{a} and {b} exchanged",
                                 lambda u, a=a, b=b: [set(p) for p in u.exchanged] == [{a, b}]
                                 and not u.turned))
                sensor, name = str(rng.choice(judged)), names[int(rng.integers(len(names)))]
                faulty = sensor_cal.apply(_moved(config, placement, sensor, TURNS[name],
                                                 args.motion, about_long_axis=False))
                rows.append(_run(calib, "turned", faulty, f"{sensor} {name}",
                                 lambda u, s=sensor, n=name: [(t[0], t[1]) for t in u.turned]
                                 == [(s, n)] and not u.exchanged))
                sensor = str(rng.choice(phalanges))
                deg = float(rng.uniform(10.0, 40.0) * rng.choice((-1, 1)))
                spin = Rotation.from_rotvec(np.radians(deg) * np.array([0.0, 1.0, 0.0]))
                faulty = sensor_cal.apply(_moved(config, placement, sensor, spin.as_matrix(),
                                                 args.motion, about_long_axis=True))
                rows.append(_run(calib, "slipped", faulty, f"{sensor} slipped {deg:+.0f} deg",
                                 lambda u, s=sensor: [t[0] for t in u.turned] == [s]
                                 and not u.exchanged))
    kinds = ("exchanged", "turned", "slipped")
    for kind in kinds:
        got = [r for r in rows if r[0] == kind]
        print(f"{kind}: {sum(r[5] for r in got)} of {len(got)} put back as made; joint RMSE "
              f"mean {np.mean([r[1] for r in got]):.2f} -> {np.mean([r[3] for r in got]):.2f} "
              f"deg, worst joint up to {max(r[2] for r in got):.2f} -> "
              f"{max(r[4] for r in got):.2f} deg")
    print(f"as calibrated {np.mean(calibrated):.2f} deg mean joint RMSE (draws "
          f"{min(calibrated):.2f}-{max(calibrated):.2f}); constant (open hand) "
          f"{np.mean(constants):.2f}")
    print(f"recordings={count} undone_as_calibrated={undone_clean} faults={len(rows)} "
          f"put_back={sum(r[6] for r in rows)} put_back_right={sum(r[5] for r in rows)} "
          f"mean_as_calibrated={np.mean(calibrated):.2f} "
          f"mean_faulty={np.mean([r[1] for r in rows]):.2f} "
          f"mean_undone={np.mean([r[3] for r in rows]):.2f} "
          f"worst_faulty={max(r[2] for r in rows):.2f} worst_undone={max(r[4] for r in rows):.2f} "
          f"constant={np.mean(constants):.2f}")


def _run(calib, kind: str, faulty, made: str, right) -> tuple:
    """Track `faulty` as it is and put back; print and return the row."""
    as_is, _ = _track(calib, faulty, False)
    back, undone = _track(calib, faulty, True)
    ok = bool(right(undone))
    print(f"  {made}: {np.nanmean(as_is):.2f} deg mean, worst joint {np.nanmax(as_is):.2f}; "
          f"put back {np.nanmean(back):.2f} / {np.nanmax(back):.2f}"
          f" ({undone.describe() or 'nothing put back'}{'' if ok else '; NOT AS MADE'})",
          flush=True)
    return (kind, float(np.nanmean(as_is)), float(np.nanmax(as_is)), float(np.nanmean(back)),
            float(np.nanmax(back)), ok, bool(undone))


if __name__ == "__main__":
    main()
