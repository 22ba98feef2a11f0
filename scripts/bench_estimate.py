"""End-to-end speed of PoseLookup on one core: 720x480 BGR frame in -> 20 angles out.

Usage::

    python scripts/bench_estimate.py [--db FOLDER] [--entries 20448] [--frames 2000]
                                     [--calibrated]
    python scripts/bench_estimate.py --learned FOLDER [--kind ensemble|perceptrons|fingers|mlp]
                                     [--scene natural|paper|photo] [--frames 2000]
                                     [--hands 4000] [--poses-per-hand 100]

The database of the standard hand is read from ``FOLDER/<HandShape().name>.h5``
or, without ``--db``, rendered into a temporary folder (about 30 s for
20,448 entries).  Frames show an off-grid hand (not the database's shape),
rendered by MuJoCo as bright skin on a dark background and reused
cyclically, in two sets timed separately: poses from the database's own
distribution (paper set, other seed: the main figure) and natural poses
(grasps, several fingers at once), which a one-finger-at-a-time database
matches poorly, so the search often has to fall back to scoring every
entry (the worst case).  The process is pinned to one CPU and OpenCV to
one thread.  The last line is machine-readable (paper-set frames):
``estimate_fps_median=<number> latency_p99_ms=<number>``.

``--learned FOLDER`` times the estimator learnt from randomised model hands
instead (docs/camera_estimator.md; read from ``FOLDER`` or
learnt there first: minutes), ``--kind ensemble`` (default:
:data:`handsynth.estimate.LEARNED_ENSEMBLE`, the weighted mean of the
per-digit estimator and three perceptrons), ``perceptrons``
(:data:`handsynth.estimate.LEARNED_PERCEPTRONS`: those three alone),
``fingers`` or ``mlp``, on frames of
the glTF hands of :mod:`handsynth.testhands` (Godot XR Tools and MRTK, not
the model it learnt from) in natural poses, painted as skin on a dark
background (BGR uint8); ``--scene paper`` times paper-protocol poses instead,
``--scene photo`` natural poses over photographs
(:func:`handsynth.eval.background_photos`: frames unlike any learnt, which
the searches might find slower; the rest frame over one too, so the default
``segment="auto"`` tells the hand by the skin's colour, and the parts show
:func:`handsynth.render.skin_mask` instead of Otsu's threshold).  It is calibrated to each hand's rest frame
once, not timed.  It also prints the median cost of its parts: the lens correction of
``--intrinsics`` (a wide-angle camera's calibration; not in the frame's time above), binarizing (Otsu),
the coverage grid (wrist cut, cell averages, made once for every member) and
each member's estimate from the grid, and how long the estimator took to be
ready (read from ``FOLDER``, including its search indices; or learnt there
first).  Its last line: ``learned_fps_median=<number> latency_p99_ms=<number>
ready_s=<number>``.

``--calibrated`` times :meth:`PoseLookup.calibrated` instead (calibrated
with the off-grid hand's open-hand frame: entries are bounded, then scored
by their pixel difference outside the ignore mask, and the weighted mean of
those near the best is reported).
"""

from __future__ import annotations

import argparse
import os
import tempfile
import time
from pathlib import Path

# one core: the process is pinned to one CPU, where a second BLAS thread would only wait on
# the first (with the other core busy it tripled a frame's time); set before numpy loads
for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import numpy as np


def _build(folder: Path, n: int) -> None:
    from handsynth.db import database_meta, render_entries, write_database
    from handsynth.models import HandShape, paper_pose_set
    from handsynth.render import CameraMount

    shape, mount = HandShape(), CameraMount()
    rows = render_entries(paper_pose_set(n, seed=0), shape, mount, render_size=(720, 480))
    write_database(folder / f"{shape.name}.h5", angles=rows["angles"], hlac=rows["hlac"],
                   sil_bits=rows["sil_bits"], ridge_bits=rows["ridge_bits"],
                   ridge_area=rows["ridge_area"], keypoints=rows["keypoints"],
                   meta=database_meta(shape, mount, side="right", pose_set="paper", count=n,
                                      seed=0, render_size=(720, 480)))


#: ``--scene``: what the frames of ``--learned`` show.
_SCENES = {"natural": "natural poses, dark background",
           "paper": "paper-protocol poses (one digit moving from rest), dark background",
           "photo": "natural poses over photographs (skimage.data; the rest frame too, so the "
                    "hand is told by its colour)"}


def _median_ms(fn, items, repeat: int) -> float:
    times = []
    for i in range(repeat):
        x = items[i % len(items)]
        t0 = time.perf_counter()
        fn(x)
        times.append(time.perf_counter() - t0)
    return float(np.median(times) * 1e3)


def _bench_learned(args) -> None:
    """``--learned``: the learnt estimator on frames of the glTF hands."""
    import cv2

    cv2.setNumThreads(1)
    if hasattr(os, "sched_setaffinity"):
        os.sched_setaffinity(0, {sorted(os.sched_getaffinity(0))[0]})

    from handsynth.db import LearningSetOptions
    from handsynth.estimate import LEARNED_ENSEMBLES, learned_ensemble, learned_estimator
    from handsynth.eval import (
        background_photos,
        natural_test_poses,
        paper_protocol_poses,
        relaxed_rest_posture,
    )
    from handsynth.render import CameraIntrinsics, CameraMount, LensCorrection, binarize, coverage
    from handsynth.testhands import TEST_HANDS, MeshHandRenderer, shipped_hand_path

    mount = CameraMount.paper()
    from handsynth.eval import LEARNED_METHODS as LEARNED

    share = {} if args.open_rest_share is None else {"open_rest_share": args.open_rest_share}
    data = LearningSetOptions(hands=args.hands, poses_per_hand=args.poses_per_hand, **share)
    t_ready = time.perf_counter()
    if args.kind in LEARNED_ENSEMBLES:
        members = LEARNED_ENSEMBLES[args.kind]
        est = learned_ensemble(args.learned, members=members, data=data, mount=mount,
                               progress=print)
        names = [f"{m.options.kind} (seed {m.options.seed}, weight {w:.2f}"
                 + (f", {', '.join(f'{k} {v}' for k, v in member[2])})" if member[2] else ")")
                 for m, w, member in zip(est.members, est.weights, members)]
    else:
        est = learned_estimator(args.learned, LEARNED[args.kind], data=data, mount=mount,
                                progress=print)
        names = [args.kind]
    ready_s = time.perf_counter() - t_ready
    rng = np.random.default_rng(0)
    skin, dark = np.array([120, 150, 210], np.uint8), np.array([25, 20, 15], np.uint8)
    photos = background_photos() if args.scene == "photo" else []

    def bgr(mask, i=None):
        f = np.empty(mask.shape + (3,), np.uint8)
        f[...] = dark if i is None else photos[i % len(photos)]
        f[mask] = skin
        return f

    per_hand = []
    for name in sorted(TEST_HANDS):
        with MeshHandRenderer(mount, path=shipped_hand_path(name)) as r:
            rest = relaxed_rest_posture(rng)
            if args.scene == "paper":
                poses = paper_protocol_poses(rest, 50, rng)[0]
            else:
                poses, _ = natural_test_poses(rest, 50, rng)
            frames = [bgr(m, i if photos else None) for i, m in enumerate(r.masks(poses))]
            per_hand.append((est.calibrated(bgr(r.mask(rest), len(photos) - 1 if photos else None)),
                             frames))
    print(f"frames: {sum(len(f) for _, f in per_hand)} BGR 720x480 of {len(per_hand)} mesh hands "
          f"({', '.join(sorted(TEST_HANDS))}), {_SCENES[args.scene]}")

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
    members_cal = cal.members if args.kind in LEARNED_ENSEMBLES else [cal]
    if getattr(members_cal[0], "segment", "brightness") == "colour":
        from handsynth.render import skin_mask

        skin = members_cal[0].skin
        masks = [skin_mask(f, skin) for f in frames]
        told = {"skin_mask (colour) of the BGR frame": _median_ms(lambda f: skin_mask(f, skin),
                                                                   frames, n)}
    else:
        told = {"binarize (Otsu) of the BGR frame": _median_ms(binarize, frames, n)}
    # a wide-angle board camera's calibration (about 100 deg, barrel distortion): the cost of
    # --intrinsics, paid before every other part
    wide = CameraIntrinsics(720, 480, 302.0, 301.0, 367.0, 233.0,
                            distortion=(-0.30, 0.09, 0.001, -0.0008, -0.012))
    lens, half = LensCorrection(wide, mount), LensCorrection(wide, mount, scale=0.5)
    parts = {
        "lens correction (remap of the BGR frame to 720x480)": _median_ms(lens, frames, n),
        "lens correction to 360x240 (--intrinsics with --learned)": _median_ms(half, frames, n),
        **told,
        "coverage grid (wrist cut, cell means)": _median_ms(lambda m: coverage(m, mount), masks, n),
    }
    grids = [members_cal[0].grid(m) for m in masks]
    for name, m in zip(names, members_cal):
        parts[f"{name}: estimate from the grid"] = _median_ms(m.estimate_grid, grids, n)
    print(f"{args.kind}: median {med * 1e3:.3f} ms ({1 / med:.0f} fps), p99 {p99 * 1e3:.3f} ms, "
          f"one core, {args.frames} frames")
    for k, v in parts.items():
        print(f"  {k:55s} {v:.3f} ms")
    print(f"ready in {ready_s:.1f} s (read from {args.learned}, or learnt there first)")
    print(f"learned_fps_median={1.0 / med:.1f} latency_p99_ms={p99 * 1e3:.3f} "
          f"ready_s={ready_s:.1f}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--db", type=Path, help="folder of <shape>.h5 databases")
    ap.add_argument("--entries", type=int, default=20448, help="entries when rendering a database")
    ap.add_argument("--frames", type=int, default=2000, help="timed frames")
    ap.add_argument("--calibrated", action="store_true",
                    help="time a lookup calibrated with the hand's open-hand frame")
    ap.add_argument("--learned", type=Path, metavar="FOLDER",
                    help="time the learnt estimator (read from FOLDER or learnt there first)")
    ap.add_argument("--kind", default="ensemble",
                    choices=["ensemble", "perceptrons", "fingers", "mlp"],
                    help="--learned: which learnt estimator")
    ap.add_argument("--hands", type=int, default=4000, help="--learned: learning set hands")
    ap.add_argument("--poses-per-hand", type=int, default=100,
                    help="--learned: learning set frames per hand")
    ap.add_argument("--scene", default="natural", choices=list(_SCENES),
                    help="--learned: the frames timed (natural poses on a dark background, "
                         "paper-protocol poses, or natural poses over photographs)")
    ap.add_argument("--open-rest-share", type=float, default=None,
                    help="--learned: share of learning hands resting near open "
                         "[default: the library's]")
    args = ap.parse_args()
    if args.db is not None and not args.db.is_dir():
        ap.error(f"--db {str(args.db)!r} is not a folder (leave it out to render a database)")
    if args.learned is not None:
        _bench_learned(args)
        return

    import cv2

    if hasattr(os, "sched_setaffinity"):
        os.sched_setaffinity(0, {min(os.sched_getaffinity(0))})
    cv2.setNumThreads(1)

    from handsynth import HandShape, PoseLookup
    from handsynth.models import natural_pose_set, paper_pose_set
    from handsynth.render import SilhouetteRenderer

    tmp = None
    folder = args.db
    if folder is None:
        tmp = tempfile.TemporaryDirectory()
        folder = Path(tmp.name)
        t0 = time.perf_counter()
        _build(folder, args.entries)
        print(f"rendered a {args.entries}-entry database in {time.perf_counter() - t0:.1f} s")
    lookup = PoseLookup.open(folder, shape=HandShape())
    print(f"database: {len(lookup)} entries, {lookup.database.nbytes / 1e6:.1f} MB")

    renderer = SilhouetteRenderer(HandShape(length=1.03, width=1.06, palm=0.98, thumb=1.04),
                                  lookup.mount, width_px=720, height_px=480)
    rng = np.random.default_rng(0)

    def bgr(mask):
        img = np.where(mask[..., None], np.uint8([120, 160, 210]), np.uint8([15, 20, 25]))
        return np.ascontiguousarray(img + rng.integers(0, 12, img.shape, dtype=np.uint8))

    if args.calibrated:
        lookup = lookup.calibrated(bgr(renderer.mask(np.zeros(20))))
        print(f"calibrated: {int(lookup.calibration.ignore.sum())} of 4096 pixels ignored")
    results = {}
    for name, poses in (("natural", natural_pose_set(64, seed=11)),
                        ("paper", paper_pose_set(64, seed=11))):
        frames = [bgr(renderer.mask(pose)) for pose in poses]
        for f in frames[:8]:  # warm-up (compilation)
            lookup.estimate(f)
        lat = np.empty(args.frames)
        cpu = np.empty(args.frames)
        low = 0
        for k in range(args.frames):
            f = frames[k % len(frames)]
            t0, c0 = time.perf_counter(), time.process_time()
            est = lookup.estimate(f)
            lat[k], cpu[k] = time.perf_counter() - t0, time.process_time() - c0
            low += est.low_confidence
        pre = []
        for f in frames:  # stage split, separately so it does not disturb the timing above
            t0 = time.perf_counter()
            lookup.silhouette(f)
            pre.append(time.perf_counter() - t0)
        med, p99 = float(np.median(lat)), float(np.percentile(lat, 99))
        results[name] = (med, p99)
        print(f"{name} poses: {args.frames} frames of 720x480 BGR; median latency "
              f"{med * 1e3:.3f} ms ({1 / med:.0f} fps; preprocessing "
              f"{np.median(pre) * 1e3:.3f} ms), p99 {p99 * 1e3:.3f} ms, "
              f"{low / args.frames:.0%} low-confidence (fallback) frames; CPU time per frame "
              f"median {np.median(cpu) * 1e3:.3f} ms ({1 / np.median(cpu):.0f} fps on an idle "
              f"core); load average {os.getloadavg()[0]:.1f}")
    med, p99 = results["paper"]
    print(f"estimate_fps_median={1.0 / med:.1f} latency_p99_ms={p99 * 1e3:.3f}")
    if tmp is not None:
        tmp.cleanup()


if __name__ == "__main__":
    main()
