"""Approximate (IVF) against exact search on a large database: speed on one core and accuracy.

Usage::

    python scripts/bench_ann.py [--entries 1000000] [--db-dir ~/.cache/handsynth/bench]
                                [--frames 300] [--nprobe 16] [--sweep 4,8,16,32,64]
                                [--max-scored 2048|none]

1. Builds (once; reused while it verifies) a database of ``--entries``
   natural-set poses of the standard hand into ``<db-dir>/natural-<entries>/``
   with :func:`handsynth.db.build_database` (``--build-workers`` processes;
   about 1.5 ms per entry per core, so 10^6 entries take ~15 min on 2 cores),
   then loads or trains the approximate index next to it
   (``<database>.ann.npz``).
2. Renders ``--frames`` 720x480 BGR frames of an off-grid hand in natural
   poses (not the database's shape or poses) before any timing.
3. Pinned to one CPU (numpy/BLAS, OpenCV and faiss on one thread), times per
   frame the lookup only: :func:`handsynth.render.preprocess`,
   :func:`handsynth.db.extract_features` and the search -- the exact
   two-stage search and the approximate one -- and reports median and p99.
4. Compares the answers with the truth: mean absolute joint-angle error
   (MAE, degrees, all 20 joints) of the exact and of the approximate answers
   and the extra MAE of the approximate one.  ``--sweep`` repeats the
   search-only timing and accuracy for other ``nprobe``.

The last line is machine-readable:
``ann_fps_median=<n> exact_fps_median=<n> extra_mae_deg=<n> entries=<n>``.
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS"):
    os.environ.setdefault(_var, "1")  # one core: before numpy is imported
os.environ.setdefault("MUJOCO_GL", "egl")

import argparse
import resource
import time
from pathlib import Path

import numpy as np

QUERY_SHAPE = {"length": 1.03, "width": 1.06, "palm": 0.98, "thumb": 1.04}


def _build_database(folder: Path, n: int, workers: int) -> Path:
    from handsynth.db import build_database
    from handsynth.models import HandShape

    t0 = time.perf_counter()
    last = [0.0]

    def progress(p) -> None:
        now = time.perf_counter()
        if p.entries_total and (p.finished or now - last[0] > 60):
            last[0] = now
            print(f"  build: {p.entries_done}/{p.entries_total} entries, "
                  f"{now - t0:.0f} s", flush=True)

    path = build_database(folder, HandShape(), workers=workers, pose_set="natural", count=n,
                          seed=0, progress=progress)
    print(f"database {path} ready in {time.perf_counter() - t0:.1f} s", flush=True)
    return path


def _frames(mount, count: int) -> tuple[list[np.ndarray], np.ndarray]:
    from handsynth.models import HandShape, natural_pose_set
    from handsynth.render import SilhouetteRenderer

    renderer = SilhouetteRenderer(HandShape(**QUERY_SHAPE), mount, width_px=720, height_px=480)
    rng = np.random.default_rng(0)
    poses = natural_pose_set(count, seed=11)
    frames = []
    for pose in poses:
        mask = renderer.mask(pose)
        img = np.where(mask[..., None], np.uint8([120, 160, 210]), np.uint8([15, 20, 25]))
        frames.append(np.ascontiguousarray(img + rng.integers(0, 12, img.shape, dtype=np.uint8)))
    return frames, np.asarray(poses, np.float64)


def _time_lookup(frames, mount, find, repeat: int):
    """Latencies (s) of preprocess + features + `find`, and the answers of the first pass."""
    from handsynth.db import extract_features
    from handsynth.render import preprocess

    for f in frames[:4]:  # warm-up (compilation)
        find(extract_features(preprocess(f, mount)))
    lat, answers, low = [], [], 0
    for rep in range(repeat):
        for f in frames:
            t0 = time.perf_counter()
            sil = preprocess(f, mount)
            r = find(extract_features(sil)) if sil.any() else None
            lat.append(time.perf_counter() - t0)
            if rep == 0:
                answers.append(-1 if r is None else r.index)
                low += r is not None and r.low_confidence
    return np.asarray(lat), np.asarray(answers), low


def _mae(angles, answers, truth) -> float:
    ok = answers >= 0
    return float(np.abs(angles[answers[ok]] - truth[ok]).mean())


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--entries", type=int, default=1_000_000, help="database entries")
    ap.add_argument("--db-dir", type=Path, default=Path("~/.cache/handsynth/bench"),
                    help="folder of the cached benchmark databases")
    ap.add_argument("--build-workers", type=int, default=2, help="processes building the database")
    ap.add_argument("--frames", type=int, default=300, help="query frames (rendered once)")
    ap.add_argument("--repeat", type=int, default=3, help="timed passes over the frames (approx.)")
    ap.add_argument("--exact-frames", type=int, default=None,
                    help="frames timed with the exact search (all by default)")
    ap.add_argument("--nlist", type=int, default=None, help="cells (default sqrt(N), power of 2)")
    ap.add_argument("--nprobe", type=int, default=16, help="cells probed per query")
    ap.add_argument("--dims", type=int, default=64, help="PCA dimensions")
    ap.add_argument("--max-scored", default="2048",
                    help="exact scorings per frame at most ('none': no limit)")
    ap.add_argument("--sweep", default="4,8,16,32,64", help="nprobe values for the search-only sweep")
    args = ap.parse_args()

    folder = args.db_dir.expanduser() / f"natural-{args.entries}"
    db_path = _build_database(folder, args.entries, args.build_workers)

    import cv2
    import faiss

    from handsynth.db import extract_features, open_database
    from handsynth.estimate._ann import ApproximateIndex, ApproximateOptions, ann_path
    from handsynth.estimate._search import SearchTables, search
    from handsynth.render import CameraMount, preprocess

    cv2.setNumThreads(1)
    faiss.omp_set_num_threads(1)
    if hasattr(os, "sched_setaffinity"):
        os.sched_setaffinity(0, {min(os.sched_getaffinity(0))})

    t0 = time.perf_counter()
    db = open_database(db_path)
    tables = SearchTables.from_arrays(hlac=db.hlac, sil_bits=db.sil_bits,
                                      ridge_bits=db.ridge_bits, ridge_area=db.ridge_area)
    print(f"opened {len(db)} entries in {time.perf_counter() - t0:.1f} s: database "
          f"{db.nbytes / 1e6:.0f} MB",
          flush=True)
    cap = None if args.max_scored.lower() == "none" else int(args.max_scored)
    options = ApproximateOptions(nlist=args.nlist, nprobe=args.nprobe, dims=args.dims,
                                 max_scored=cap)
    had = ann_path(db_path).is_file()
    t0 = time.perf_counter()
    index = ApproximateIndex.open(db, tables, options=options, seed=0)
    sizes = np.diff(index.offsets)
    print(f"approximate index ({'loaded or rebuilt' if had else 'built'}) in "
          f"{time.perf_counter() - t0:.1f} s: nlist {index.nlist}, dims {index.options.dims}, "
          f"cell sizes {sizes.min()}-{sizes.max()} (median {np.median(sizes):.0f}), "
          f"{index.nbytes / 1e6:.0f} MB, file {ann_path(db_path).stat().st_size / 1e6:.0f} MB",
          flush=True)

    mount = CameraMount(**db.meta["mount"])
    t0 = time.perf_counter()
    frames, truth = _frames(mount, args.frames)
    print(f"rendered {len(frames)} query frames (720x480 BGR) in {time.perf_counter() - t0:.1f} s",
          flush=True)
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")

    n_exact = args.exact_frames or len(frames)
    t0 = time.perf_counter()
    n_rows = tables.prepare().rows.size
    print(f"exact search index: {n_rows} distinct rows, built in {time.perf_counter() - t0:.1f} s",
          flush=True)
    lat_a, ans_a, low_a = _time_lookup(frames, mount, index.search, args.repeat)
    lat_e, ans_e, low_e = _time_lookup(frames[:n_exact], mount, lambda f: search(f, tables), 1)
    t_pre = []
    for f in frames:
        t1 = time.perf_counter()
        extract_features(preprocess(f, mount))
        t_pre.append(time.perf_counter() - t1)
    angles = np.asarray(db.angles, np.float64)
    truth_e = truth[:n_exact]
    mae_e = _mae(angles, ans_e, truth_e)
    mae_a_sub = _mae(angles, ans_a[:n_exact], truth_e)
    mae_a = _mae(angles, ans_a, truth)
    same = float(np.mean(ans_a[:n_exact] == ans_e))
    ok = (ans_e >= 0) & (ans_a[:n_exact] >= 0)
    between = float(np.abs(angles[ans_a[:n_exact][ok]] - angles[ans_e[ok]]).mean())
    extra = mae_a_sub - mae_e

    # search only, over nprobe values (features computed once)
    feats = [extract_features(s) for s in (preprocess(f, mount) for f in frames[:n_exact])]
    t_ex, exact_res = [], []
    for f in feats:
        t1 = time.perf_counter()
        exact_res.append(search(f, tables))
        t_ex.append(time.perf_counter() - t1)
    print(f"search only (same frames), one core: exact median {np.median(t_ex) * 1e3:.3f} ms, "
          f"p99 {np.percentile(t_ex, 99) * 1e3:.3f} ms")
    for nprobe in sorted({int(v) for v in args.sweep.split(",") if v} | {args.nprobe}):
        index.search(feats[0], nprobe=nprobe)
        t = []
        res = []
        for f in feats:
            t1 = time.perf_counter()
            res.append(index.search(f, nprobe=nprobe))
            t.append(time.perf_counter() - t1)
        idx = np.asarray([r.index for r in res])
        worse = np.mean([a.error > b.error for a, b in zip(res, exact_res, strict=True)])
        print(f"  nprobe {nprobe:4d}: median {np.median(t) * 1e3:.3f} ms, p99 "
              f"{np.percentile(t, 99) * 1e3:.3f} ms, same answer {np.mean(idx == ans_e):.3f}, "
              f"larger E {worse:.3f}, MAE {_mae(angles, idx, truth_e):.3f} deg "
              f"(exact {mae_e:.3f})")

    med_a, med_e = float(np.median(lat_a)), float(np.median(lat_e))
    rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1e3
    print(f"end to end (preprocess + features + search), one core, load average {load:.2f} "
          f"before timing, {os.getloadavg()[0]:.2f} after; preprocess + features alone: "
          f"median {np.median(t_pre) * 1e3:.3f} ms:")
    print(f"  exact:       median {med_e * 1e3:.3f} ms ({1 / med_e:.1f} fps), p99 "
          f"{np.percentile(lat_e, 99) * 1e3:.3f} ms, {n_exact} frames, {low_e} low-confidence")
    print(f"  approximate: median {med_a * 1e3:.3f} ms ({1 / med_a:.1f} fps), p99 "
          f"{np.percentile(lat_a, 99) * 1e3:.3f} ms ({1 / np.percentile(lat_a, 99):.1f} fps), "
          f"{len(lat_a)} lookups, nprobe {args.nprobe}, max_scored {cap}, {low_a} "
          f"low-confidence")
    print(f"MAE vs truth: exact {mae_e:.3f} deg, approximate {mae_a_sub:.3f} deg "
          f"(all {len(frames)} frames: {mae_a:.3f}); extra {extra:+.3f} deg; same answer "
          f"{same:.3f}; exact vs approximate answers differ by {between:.3f} deg on average")
    print(f"memory: peak RSS {rss:.0f} MB; index {index.nbytes / 1e6:.0f} MB")
    print(f"ann_fps_median={1 / med_a:.1f} exact_fps_median={1 / med_e:.1f} "
          f"extra_mae_deg={extra:.3f} entries={len(db)}")


if __name__ == "__main__":
    main()
