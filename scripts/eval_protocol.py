"""Score camera estimators with the protocol that cannot flatter (handsynth.eval._protocol).

Test hands: model hands of random geometry beyond the four ratios (the
development hands: every constant was chosen on them) and the glTF hands of
handsynth.testhands (held out). Frames: each hand's relaxed rest posture
with the paper's motions ("paper") and natural grasps ("natural"), from a
generator no estimator is built from. Every figure has the constant
open-hand answer beside it.

Methods:
  standard    the paper's lookup in the standard hand's 20,448-entry database
  selected    the database chosen by formulas (1)-(4) (hands with measurements only)
  calibrated  PoseLookup.from_open_frame on the hand's rest frame
  fingers         LearnedEstimator, per-digit kNN on each digit's cells, calibrated to the rest frame
  mlp             LearnedEstimator, perceptron, calibrated
  knn             LearnedEstimator, kNN on the whole frame, calibrated
  fingers_norest  fingers without the rest frame
  ensemble        the mean of fingers and mlp

Example:
  python scripts/eval_protocol.py --cache ~/handsynth_cache --model-hands 4 \
      --frames 200 --json protocol.json

The last line printed is machine-readable: one JSON object of the headline
figures (flexion MAE, constant, skill per hand kind, method and pose set).
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path

os.environ.setdefault("MUJOCO_GL", "egl")

import numpy as np

from handsynth.db import BuildOptions, LearningSetOptions, build_databases
from handsynth.estimate import EnsembleEstimator, LearnedOptions, PoseLookup, learned_estimator
from handsynth.eval import ProtocolOptions, mesh_test_hands, model_test_hands, run_protocol
from handsynth.models import HandShape
from handsynth.render import CameraMount

_ALL = ("standard", "selected", "calibrated", "fingers", "mlp", "knn", "fingers_norest", "ensemble")

#: The learnt methods' options (chosen on model hands: docs in the README section
#: "Camera estimator for unseen hands").
LEARNED = {
    "fingers": LearnedOptions(kind="fingers", k=128),
    "mlp": LearnedOptions(kind="mlp", target="angles"),
    "knn": LearnedOptions(kind="knn", target="angles", k=8),
    "fingers_norest": LearnedOptions(kind="fingers", k=128, use_rest=False),
}


def _methods(names, cache: Path, data: LearningSetOptions, mount: CameraMount, say):
    out = {}
    dbs = cache / "dbs"
    if {"standard", "selected"} & set(names):
        build_databases(dbs, [HandShape()], mount, options=BuildOptions(), workers=1)
        standard = PoseLookup.open(dbs, shape=HandShape())
    if "standard" in names:
        out["standard"] = lambda rest, hand: standard
    if "selected" in names:
        def selected(rest, hand):
            if hand.measurements is None:
                return None
            from handsynth.estimate import select_shape

            shape = select_shape(hand.measurements).shape
            build_databases(dbs, [shape], mount, options=BuildOptions(), workers=1)
            return PoseLookup.open(dbs, shape=shape)
        out["selected"] = selected
    if "calibrated" in names:
        out["calibrated"] = lambda rest, hand: PoseLookup.from_open_frame(dbs, rest, mount=mount,
                                                                          workers=1)
    built = {}
    for name, opts in LEARNED.items():
        if name not in names and not (name in ("fingers", "mlp") and "ensemble" in names):
            continue
        t0 = time.perf_counter()
        built[name] = learned_estimator(cache, opts, data=data, mount=mount, progress=say)
        say(f"{name}: ready in {time.perf_counter() - t0:.1f} s")
    for name, est in built.items():
        if name not in names:
            continue
        if est.options.use_rest:
            out[name] = lambda rest, hand, est=est: est.calibrated(rest)
        else:
            out[name] = lambda rest, hand, est=est: est
    if "ensemble" in names:
        ens = EnsembleEstimator([built["fingers"], built["mlp"]])
        out["ensemble"] = lambda rest, hand: ens.calibrated(rest)
    return out


def headline(result: dict) -> dict:
    """Flexion MAE, constant and skill per hand kind (mean over hands), method and pose set."""
    rows: dict = {}
    for hand in result["hands"].values():
        for ps in result["options"]["pose_sets"]:
            for m, s in hand.get(ps, {}).items():
                key = f"{hand['kind']}/{ps}/{m}"
                rows.setdefault(key, []).append((
                    s["method"]["groups_mae_deg"]["finger_flexion"],
                    s["constant"]["groups_mae_deg"]["finger_flexion"],
                    s["method"]["joints"]["index_pip_flex"]["moving_mae_deg"]))
    out = {}
    for key, vals in rows.items():
        a = np.array([[np.nan if x is None else x for x in v] for v in vals], float)
        out[key] = {"flexion_mae": round(float(np.nanmean(a[:, 0])), 2),
                    "constant": round(float(np.nanmean(a[:, 1])), 2),
                    "skill": round(float(1 - np.nanmean(a[:, 0]) / np.nanmean(a[:, 1])), 3),
                    "index_pip_moving_mae": round(float(np.nanmean(a[:, 2])), 2)}
    return out


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--cache", required=True, type=Path, help="folder for databases and learnt estimators")
    p.add_argument("--methods", default="standard,selected,calibrated,fingers,mlp,ensemble")
    p.add_argument("--model-hands", type=int, default=4)
    p.add_argument("--model-seed", type=int, default=1, help="seed of the model hands (0: the "
                   "development hands the options were chosen on)")
    p.add_argument("--model-spread", type=float, default=1.5,
                   help="HandVariation spread of the model hands (learning: 1.0)")
    p.add_argument("--mesh", default="godot_xr_tools,mrtk", help="glTF hands ('' for none)")
    p.add_argument("--frames", type=int, default=200)
    p.add_argument("--pose-sets", default="paper,natural")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--hands", type=int, default=2000, help="learning set: hands")
    p.add_argument("--poses-per-hand", type=int, default=100, help="learning set: frames per hand")
    p.add_argument("--json", type=Path)
    a = p.parse_args(argv)
    names = [m for m in a.methods.split(",") if m]
    bad = [m for m in names if m not in _ALL]
    if bad:
        p.error(f"unknown methods {bad}; choose from {', '.join(_ALL)}")
    mount = CameraMount.paper()

    def say(line):
        print(line, flush=True)

    data = LearningSetOptions(hands=a.hands, poses_per_hand=a.poses_per_hand)
    methods = _methods(names, a.cache, data, mount, say)
    hands = model_test_hands(a.model_hands, seed=a.model_seed, mount=mount, spread=a.model_spread)
    if a.mesh:
        hands += mesh_test_hands([m for m in a.mesh.split(",") if m], mount=mount)
    opts = ProtocolOptions(frames=a.frames, pose_sets=tuple(a.pose_sets.split(",")), seed=a.seed)
    t0 = time.perf_counter()
    result = run_protocol(methods, hands, opts, progress=say)
    result["learning_set"] = {"hands": a.hands, "poses_per_hand": a.poses_per_hand}
    result["seconds"] = round(time.perf_counter() - t0, 1)
    result["headline"] = headline(result)
    if a.json:
        a.json.parent.mkdir(parents=True, exist_ok=True)
        a.json.write_text(json.dumps(result, indent=1))
    for k, v in result["headline"].items():
        say(f"{k:40s} flexion MAE {v['flexion_mae']:6.2f} (constant {v['constant']:6.2f}, "
            f"skill {v['skill']:+.3f}); index PIP moving MAE {v['index_pip_moving_mae']}")
    print(json.dumps(result["headline"]))
    return 0


if __name__ == "__main__":
    sys.exit(main())
