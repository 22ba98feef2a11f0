"""Speed of LearnedEstimator on one core: 720x480 BGR frame of a realistic hand in -> 20 angles out.

Usage::

    python scripts/bench_learned.py --cache FOLDER [--kind mlp|knn] [--frames 2000]
                                    [--hands 400] [--poses-per-hand 100]

The estimator is read from ``FOLDER`` (or learnt there first: minutes).
Frames are the glTF hands of :mod:`handsynth.testhands` (Godot XR Tools and
MRTK, not the model the estimator learnt from) in natural poses, rendered by
MuJoCo as masks and painted as skin on a dark background (BGR uint8), reused
cyclically.  The estimator is calibrated to each hand's rest frame once, not
timed.  The process is pinned to one CPU, BLAS and OpenCV to one thread.

Printed: median and p99 latency of ``estimate`` (``--kind ensemble``, the
default: the mean of the per-digit kNN and the perceptron, as
scripts/eval_protocol.py builds them), and the median cost of its parts on
the same frames: binarizing (Otsu) the BGR frame, the coverage grid (wrist
cut, cell averages), and each member's estimate from the mask (its own
coverage grid, principal-component codes and regressor).  The last line is machine-readable:
``learned_fps_median=<number> latency_p99_ms=<number>``.
"""

from __future__ import annotations

import os

for _v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_v] = "1"
os.environ.setdefault("MUJOCO_GL", "egl")

import argparse
import sys
import time
from pathlib import Path

import numpy as np


def _median_ms(fn, items, repeat: int) -> float:
    times = []
    for i in range(repeat):
        x = items[i % len(items)]
        t0 = time.perf_counter()
        fn(x)
        times.append(time.perf_counter() - t0)
    return float(np.median(times) * 1e3)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cache", type=Path, required=True, help="folder of the learnt estimator")
    ap.add_argument("--kind", default="ensemble", choices=["ensemble", "fingers", "mlp"],
                    help="the estimator of scripts/eval_protocol.py of that name")
    ap.add_argument("--frames", type=int, default=2000, help="timed frames")
    ap.add_argument("--hands", type=int, default=2000, help="learning set: hands")
    ap.add_argument("--poses-per-hand", type=int, default=100, help="learning set: frames per hand")
    args = ap.parse_args()

    import cv2

    cv2.setNumThreads(1)
    if hasattr(os, "sched_setaffinity"):
        os.sched_setaffinity(0, {sorted(os.sched_getaffinity(0))[0]})

    from handsynth.db import LearningSetOptions
    from handsynth.estimate import EnsembleEstimator, learned_estimator
    from handsynth.eval import natural_test_poses, relaxed_rest_posture
    from handsynth.render import CameraMount, binarize, coverage
    from handsynth.testhands import TEST_HANDS, MeshHandRenderer, shipped_hand_path

    mount = CameraMount.paper()
    sys.path.insert(0, str(Path(__file__).parent))
    from eval_protocol import LEARNED

    data = LearningSetOptions(hands=args.hands, poses_per_hand=args.poses_per_hand)
    members = {k: learned_estimator(args.cache, LEARNED[k], data=data, mount=mount, progress=print)
               for k in (("fingers", "mlp") if args.kind == "ensemble" else (args.kind,))}
    est = EnsembleEstimator(list(members.values())) if args.kind == "ensemble" \
        else members[args.kind]
    rng = np.random.default_rng(0)
    skin, dark = np.array([120, 150, 210], np.uint8), np.array([25, 20, 15], np.uint8)

    def bgr(mask):
        f = np.empty(mask.shape + (3,), np.uint8)
        f[...] = dark
        f[mask] = skin
        return f

    per_hand = []
    for name in sorted(TEST_HANDS):
        with MeshHandRenderer(mount, path=shipped_hand_path(name)) as r:
            rest = relaxed_rest_posture(rng)
            poses, _ = natural_test_poses(rest, 50, rng)
            per_hand.append((est.calibrated(bgr(r.mask(rest))), [bgr(m) for m in r.masks(poses)]))
    print(f"frames: {sum(len(f) for _, f in per_hand)} BGR 720x480 of {len(per_hand)} mesh hands "
          f"({', '.join(sorted(TEST_HANDS))}), natural poses")

    for cal, frames in per_hand:  # warm up
        for f in frames[:20]:
            cal.estimate(f)
    lat = []
    for i in range(args.frames):
        cal, frames = per_hand[i % len(per_hand)]
        f = frames[(i // len(per_hand)) % len(frames)]
        t0 = time.perf_counter()
        cal.estimate(f)
        lat.append(time.perf_counter() - t0)
    lat = np.array(lat)
    med, p99 = float(np.median(lat)), float(np.percentile(lat, 99))

    cal, frames = per_hand[0]
    masks = [binarize(f) for f in frames]
    n = min(args.frames, 500)
    parts = {
        "binarize (Otsu) of the BGR frame": _median_ms(binarize, frames, n),
        "coverage grid (wrist cut, cell means)": _median_ms(lambda m: coverage(m, mount), masks, n),
    }
    members_cal = cal.members if args.kind == "ensemble" else [cal]
    for name, m in zip(members, members_cal):
        parts[f"{name}: estimate from the mask"] = _median_ms(m.estimate, masks, n)
    print(f"{args.kind}: median {med * 1e3:.3f} ms ({1 / med:.0f} fps), p99 {p99 * 1e3:.3f} ms, "
          f"one core, {args.frames} frames")
    for k, v in parts.items():
        print(f"  {k:45s} {v:.3f} ms")
    print(f"learned_fps_median={1.0 / med:.1f} latency_p99_ms={p99 * 1e3:.3f}")


if __name__ == "__main__":
    main()
