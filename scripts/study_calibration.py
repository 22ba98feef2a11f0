"""Studies of the calibrated lookup on the mesh hand: the temperature, and an imperfect open hand.

:meth:`handsynth.PoseLookup.calibrated` reports the mean of the entries whose
masked pixel difference ``X`` is within ``10 T`` of the best, weighted
``exp(-(X - X_min) / T)`` (``T = 0``: the tied entries only).  Both studies
look up the realistic mesh hand's paper-pose frames of several seeds (400
per seed, 720x480, the paper's device; the frames ``handsynth eval --hand
mesh --seed S`` renders) and print the MAE over all joints, the index PIP
error mean +- s.d. and the thumb CMC flexion s.d.  The database and the
ignore mask come from :meth:`PoseLookup.from_open_frame` (the grid shape
whose open hand fits the open-hand frame best, built in ``--db`` when
missing), as in the eval's ``calibrated`` condition.

``temperature``
    Each ``T`` of ``--temperatures`` on the mesh's exact open hand.
    ``T = 1`` (the library's default) was chosen on seeds 2-5; the recorded
    evaluations use seeds 0 and 1.  With ``--own`` it also looks up frames
    of two grid shapes in their own databases (no mismatch: what the
    weighting costs when the model is exact).
``open-pose``
    The default ``T`` with a calibration frame of a hand that is not quite
    open and flat: every joint off by a normal error of s.d. ``--sigmas``
    degrees (three draws each, clipped to the joint limits), as a user's
    "open, flat hand" will be.

Usage::

    MUJOCO_GL=egl python scripts/study_calibration.py --db dbs temperature [--own]
        [--seeds 0 1 2 3 4 5] [--temperatures 0 0.5 1 1.5 2] [--json FILE]
    MUJOCO_GL=egl python scripts/study_calibration.py --db dbs open-pose [--seeds 0 1]
        [--sigmas 3 6] [--json FILE]

About 1-2 minutes each on 2 cores once the databases exist.
"""

from __future__ import annotations

import argparse
import json

import numpy as np

from handsynth import JOINT_NAMES, CameraMount, HandShape, PoseLookup
from handsynth._io import write_text
from handsynth.eval._hands import _pose_seed
from handsynth.models import JOINT_LIMITS_DEG, pose_set
from handsynth.render import SilhouetteRenderer
from handsynth.testhands import MeshHandRenderer

_IP = JOINT_NAMES.index("index_pip_flex")
_CMC = JOINT_NAMES.index("thumb_cmc_flex")
_FRAMES = 400
_OWN_SHAPES = ("L1.000_W1.000_P1.000_T1.000", "L0.950_W1.100_P0.950_T1.000")


def figures(lookup: PoseLookup, frames: np.ndarray, truth: np.ndarray) -> dict:
    """MAE, index PIP mean and s.d., thumb CMC s.d. of `lookup` on `frames`, degrees."""
    est = np.stack([lookup.estimate(f).angles for f in frames])
    e = est - truth
    return {"mae_deg": round(float(np.abs(e).mean()), 3),
            "index_pip_mean_deg": round(float(e[:, _IP].mean()), 3),
            "index_pip_sd_deg": round(float(e[:, _IP].std()), 3),
            "thumb_cmc_sd_deg": round(float(e[:, _CMC].std()), 3)}


def _line(label: str, t: float, f: dict) -> str:
    return (f"{label:>10} T={t:<4g} MAE {f['mae_deg']:5.2f}  index PIP "
            f"{f['index_pip_mean_deg']:+5.2f} +- {f['index_pip_sd_deg']:5.2f}  "
            f"thumb CMC s.d. {f['thumb_cmc_sd_deg']:5.2f}")


def _temperature(args, mount, mesh, open_frame, data) -> dict:
    out = {"mesh": {}, "own_shape": {}}
    base = PoseLookup.from_open_frame(args.db, open_frame, mount=mount)
    print(f"mesh: database {base.database.path.name}, "
          f"{int(base.calibration.ignore.sum())} of 4096 pixels ignored")
    lookups = {t: base.calibrated(open_frame, temperature_px=t) for t in args.temperatures}
    for seed, (truth, frames) in data.items():
        for t, lookup in lookups.items():
            f = figures(lookup, frames, truth)
            out["mesh"].setdefault(str(seed), {})[f"{t:g}"] = f
            print(_line(f"seed {seed}", t, f), flush=True)
    for t in args.temperatures:
        runs = [out["mesh"][str(s)][f"{t:g}"]["index_pip_sd_deg"] for s in data]
        print(f"T={t:<4g} index PIP s.d. over seeds: mean {np.mean(runs):.2f}, "
              f"max {np.max(runs):.2f}")
    if args.own:
        zero = np.zeros((1, len(JOINT_NAMES)))
        for name in _OWN_SHAPES:
            shape = HandShape.from_name(name)
            truth = pose_set("paper", _FRAMES, seed=_pose_seed(7, 0, 0))
            with SilhouetteRenderer(shape, mount, width_px=720, height_px=480) as r:
                own_open, frames = r.masks(zero)[0], r.masks(truth)
            own = PoseLookup.from_open_frame(args.db, own_open, mount=mount, shapes=[shape])
            for t in args.temperatures:
                f = figures(own.calibrated(own_open, temperature_px=t), frames, truth)
                out["own_shape"].setdefault(name, {})[f"{t:g}"] = f
                print(_line("own", t, f) + f"  ({name})", flush=True)
    return out


def _open_pose(args, mount, mesh, open_frame, data) -> dict:
    out = {"draws": []}
    rng = np.random.default_rng(0)
    for sigma in (0.0, *args.sigmas):
        for draw in range(3 if sigma else 1):
            pose = np.clip(rng.normal(0.0, sigma, len(JOINT_NAMES)), JOINT_LIMITS_DEG[:, 0],
                           JOINT_LIMITS_DEG[:, 1])
            lookup = PoseLookup.from_open_frame(args.db, mesh.masks(pose[None])[0], mount=mount)
            row = {"sigma_deg": sigma, "draw": draw, "database": lookup.database.path.stem,
                   "ignored_px": int(lookup.calibration.ignore.sum()), "seeds": {}}
            for seed, (truth, frames) in data.items():
                f = figures(lookup, frames, truth)
                row["seeds"][str(seed)] = f
                print(_line(f"seed {seed}", lookup.calibration.temperature_px, f)
                      + f"  open pose s.d. {sigma:g} deg, draw {draw}: {row['database']}, "
                      f"{row['ignored_px']} px ignored", flush=True)
            out["draws"].append(row)
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--db", required=True, help="database folder (built when missing)")
    parser.add_argument("--json", help="write the figures to this file")
    sub = parser.add_subparsers(dest="study", required=True)
    temp = sub.add_parser("temperature", help="each T on the exact open hand")
    temp.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2, 3, 4, 5])
    temp.add_argument("--temperatures", type=float, nargs="+", default=[0, 0.5, 1, 1.5, 2])
    temp.add_argument("--own", action="store_true",
                      help="also look up grid shapes' frames in their own databases")
    pose = sub.add_parser("open-pose", help="calibration frames of a not quite open hand")
    pose.add_argument("--seeds", type=int, nargs="+", default=[0, 1])
    pose.add_argument("--sigmas", type=float, nargs="+", default=[3.0, 6.0])
    args = parser.parse_args()

    mount = CameraMount.paper()
    mesh = MeshHandRenderer(mount, width_px=720, height_px=480)
    open_frame = mesh.masks(np.zeros((1, len(JOINT_NAMES))))[0]
    data = {}
    for seed in args.seeds:
        truth = pose_set("paper", _FRAMES, seed=_pose_seed(seed, 0, 0))
        data[seed] = (truth, mesh.masks(truth))
    study = _temperature if args.study == "temperature" else _open_pose
    out = {"study": args.study, "frames_per_seed": _FRAMES,
           **study(args, mount, mesh, open_frame, data)}
    mesh.close()
    if args.json:
        write_text(args.json, json.dumps(out, indent=2), what="JSON report")
        print(f"json: {args.json}")


if __name__ == "__main__":
    main()
