"""Keypoints of the learnt camera estimator on the glTF hands (docs/camera_estimator.md, "Keypoints").

Usage::

    python scripts/study_keypoints.py --cache DIR [--kind ensemble|perceptrons]
                                      [--frames 150] [--seeds 0 1] [--json FILE]

The learnt estimators read joint angles; :class:`handsynth.estimate.KeypointEstimator`
poses the handsynth hand of a given shape by them and reports its 21
keypoints.  Here each shipped glTF hand (:data:`handsynth.testhands.TEST_HANDS`:
none of them is a handsynth hand, and their rigs put the joints where their
authors did) is posed from a relaxed rest posture
(:func:`handsynth.eval.relaxed_rest_posture`) in paper-protocol and natural
frames (:func:`handsynth.eval.paper_protocol_poses`,
:func:`handsynth.eval.natural_test_poses`), the estimator is calibrated to its
rest frame, and the keypoints are compared with the glTF hand's own
(:meth:`handsynth.testhands.MeshHandRenderer.keypoints`), in the hand frame,
millimetres.  Rows per hand, pose set and hand shape (the standard hand, or
the hand's own shape from its measurements by formulas (1)-(4) without the
grid, as ``--measurements`` gives it):

* ``estimated``: the estimator's angles;
* ``true angles``: the true angles on the handsynth hand of that shape (what the
  shape alone costs: the floor of any angle estimator);
* ``open hand``: the constant answer, all angles 0;
* ``rest``: the true rest posture (the answer of an estimator that saw
  nothing move).

Figures: mean distance of the five fingertips and of all 21 keypoints, and
the fingertips' error on frames where the digit's own flexion (sum of its
joints') truly changed by more than 30 deg from rest.  Last line:
``tips_estimated_own=<mm> tips_open_own=<mm> tips_truth_own=<mm>``.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np

TIPS = [4, 8, 12, 16, 20]
# the joints of each digit's flexion, thumb first (canonical order)
DIGIT_FLEX = [[0, 2, 3], [4, 6, 7], [8, 10, 11], [12, 14, 15], [16, 18, 19]]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cache", type=Path, required=True,
                    help="folder of the learnt estimator (learnt there first if missing)")
    ap.add_argument("--kind", default="ensemble", choices=["ensemble", "perceptrons"])
    ap.add_argument("--frames", type=int, default=150, help="frames per hand, pose set and seed")
    ap.add_argument("--seeds", type=int, nargs="+", default=[0, 1])
    ap.add_argument("--json", type=Path, default=None)
    args = ap.parse_args()

    from handsynth.estimate import (
        LEARNED_ENSEMBLES,
        KeypointEstimator,
        SelectionOptions,
        learned_ensemble,
        select_shape,
    )
    from handsynth.eval import natural_test_poses, paper_protocol_poses, relaxed_rest_posture
    from handsynth.models import HandShape
    from handsynth.testhands import TEST_HANDS, MeshHandRenderer, shipped_hand_path

    t0 = time.perf_counter()
    ens = learned_ensemble(args.cache, members=LEARNED_ENSEMBLES[args.kind])
    results: dict = {}
    pooled: dict = {}
    for name in sorted(TEST_HANDS):
        hand = MeshHandRenderer(path=shipped_hand_path(name))
        own = select_shape(hand.measurements(), options=SelectionOptions(normalize="none")).ratios
        shapes = {"standard": HandShape(), "own": HandShape.from_name(own.name)}
        print(f"{name}: {hand.hand_length_mm:.0f} mm; own shape {shapes['own'].name}", flush=True)
        for seed in args.seeds:
            rng = np.random.default_rng(np.random.SeedSequence([seed, 0x6B9, *name.encode()]))
            rest = relaxed_rest_posture(rng)
            cal = ens.calibrated(hand.mask(rest))
            for pose_set, draw in (("paper", paper_protocol_poses), ("natural", natural_test_poses)):
                poses, _ = draw(rest, args.frames, rng)
                est = np.array([cal.estimate(hand.mask(p)).angles for p in poses])
                kp_true = np.array([hand.keypoints(p) for p in poses])
                flex = np.array([[p[j].sum() for j in DIGIT_FLEX] for p in poses])
                rest_flex = np.array([rest[j].sum() for j in DIGIT_FLEX])
                moving = np.abs(flex - rest_flex) > 30.0  # (n, 5), per fingertip
                for key in shapes:
                    wrapped = KeypointEstimator(cal, shape=shapes[key])
                    answers = {"estimated": est, "true angles": poses,
                               "open hand": np.zeros_like(poses), "rest": np.tile(rest, (len(poses), 1))}
                    for label, angles in answers.items():
                        kp = np.array([wrapped.keypoints(a) for a in angles], dtype=np.float64)
                        d = np.linalg.norm(kp - kp_true, axis=2) * 1e3
                        row = {"tips_mm": float(d[:, TIPS].mean()), "all_mm": float(d.mean()),
                               "tips_moving_mm": float(d[:, TIPS][moving].mean()),
                               "tips_moving_n": int(moving.sum())}
                        results.setdefault(name, {}).setdefault(f"seed{seed}", {}) \
                            .setdefault(pose_set, {}).setdefault(key, {})[label] = row
                        pooled.setdefault((pose_set, key, label), []).append(
                            (d[:, TIPS], d, d[:, TIPS][moving]))
                r = results[name][f"seed{seed}"][pose_set]
                print(f"  seed {seed} {pose_set:7s} " + "  ".join(
                    f"{key}: est {r[key]['estimated']['tips_mm']:.1f} / truth "
                    f"{r[key]['true angles']['tips_mm']:.1f} / open {r[key]['open hand']['tips_mm']:.1f}"
                    f" / rest {r[key]['rest']['tips_mm']:.1f} (moving tips: est "
                    f"{r[key]['estimated']['tips_moving_mm']:.1f}, open "
                    f"{r[key]['open hand']['tips_moving_mm']:.1f})" for key in shapes), flush=True)
    summary = {}
    print("\npooled over hands and seeds (mm): fingertips / all 21 / fingertips of moving digits")
    for (pose_set, key, label), parts in sorted(pooled.items()):
        tips = np.concatenate([p[0].ravel() for p in parts])
        every = np.concatenate([p[1].ravel() for p in parts])
        mov = np.concatenate([p[2].ravel() for p in parts])
        summary[f"{pose_set}/{key}/{label}"] = {"tips_mm": float(tips.mean()),
                                                "all_mm": float(every.mean()),
                                                "tips_moving_mm": float(mov.mean()),
                                                "tips_moving_n": int(mov.size)}
        print(f"  {pose_set:7s} {key:8s} {label:11s} {tips.mean():6.1f} {every.mean():6.1f} "
              f"{mov.mean():6.1f} (n={mov.size})")
    if args.json is not None:
        args.json.write_text(json.dumps({"per_hand": results, "pooled": summary,
                                         "kind": args.kind, "frames": args.frames,
                                         "seeds": args.seeds}, indent=1))
    print(f"took {time.perf_counter() - t0:.0f} s")
    nat = "natural/own/"
    print(f"tips_estimated_own={summary[nat + 'estimated']['tips_mm']:.2f} "
          f"tips_open_own={summary[nat + 'open hand']['tips_mm']:.2f} "
          f"tips_truth_own={summary[nat + 'true angles']['tips_mm']:.2f}")


if __name__ == "__main__":
    main()
