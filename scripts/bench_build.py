"""Benchmark of the database build: entries per second per core, full-grid time, quality, size.

1. Builds one complete 20,448-entry paper database (standard shape) with
   :func:`handsynth.db.build_databases` on all cores (process pool): masks
   (:class:`~handsynth.render.SilhouetteRasterizer`) + preprocessing +
   features + HDF5 write, wall time including the start of the workers.  Entries per second
   per core = entries / (wall x workers); the full-grid projection is
   81 x 20,448 entries at that rate on all cores.
2. Prints the file size on disk and the bytes the opened database holds in
   memory (target <= 60 MB each).
3. Silhouette quality: the IoU of the 64x64 silhouettes of the database
   (the build's masks, preprocessed) and of high-quality renders by
   MuJoCo's own renderer (1440x960 with 4x multisampling, and the device's
   720x480) over a few hundred paper and natural poses (target >= 0.99).

Besides wall time the script sums the CPU time of this process and its
workers (``getrusage``), which a machine shared with other jobs does not
inflate; on an idle machine the two agree when the workers scale.  The
last line is machine-readable, from CPU time, with the wall-time projection
appended: ``build_entries_per_s_per_core=<number> full_grid_minutes=<number>
wall_full_grid_minutes=<number>``.

Usage: python scripts/bench_build.py [--render-size 720x480] [--workers N] [--iou-poses 300]
"""

from __future__ import annotations

import argparse
import os
import platform
import resource
import tempfile
import time

import numpy as np

from handsynth._cores import usable_cores

GRID_SHAPES = 81
PAPER_COUNT = 20_448


def _silhouettes(poses, size, *, reference: bool = False, samples: int = 0):
    from handsynth.render import SilhouetteRasterizer, SilhouetteRenderer, preprocess

    maker = (SilhouetteRenderer(width_px=size[0], height_px=size[1], samples=samples)
             if reference else SilhouetteRasterizer(width_px=size[0], height_px=size[1]))
    with maker as r:
        return np.stack([preprocess(m, r.mount) for m in r.masks(poses)])


def _iou(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    inter = (a & b).sum(axis=(1, 2))
    union = (a | b).sum(axis=(1, 2))
    return np.where(union > 0, inter / np.maximum(union, 1), 1.0)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--render-size", default=None, help="WIDTHxHEIGHT (build default if unset)")
    ap.add_argument("--workers", type=int, default=usable_cores(),
                    help="worker processes [default: the cores this process may use]")
    ap.add_argument("--iou-poses", type=int, default=300)
    a = ap.parse_args()
    os.environ.setdefault("MUJOCO_GL", "egl")
    from handsynth.db import DEFAULT_RENDER_SIZE, build_databases, open_database
    from handsynth.models import HandShape, natural_pose_set, paper_pose_set

    size = tuple(int(v) for v in a.render_size.split("x")) if a.render_size \
        else DEFAULT_RENDER_SIZE
    print(f"machine: {platform.processor() or platform.machine()}, "
          f"{usable_cores()} cores (of the machine's {os.cpu_count()}), "
          f"MUJOCO_GL={os.environ['MUJOCO_GL']}, {a.workers} worker(s), "
          f"render size {size[0]}x{size[1]}")

    def cpu_s() -> float:
        own, kids = resource.getrusage(resource.RUSAGE_SELF), \
            resource.getrusage(resource.RUSAGE_CHILDREN)
        return own.ru_utime + own.ru_stime + kids.ru_utime + kids.ru_stime

    load_before = os.getloadavg()[0]
    with tempfile.TemporaryDirectory() as tmp:
        t, c = time.perf_counter(), cpu_s()
        summary = build_databases(tmp, [HandShape()], workers=a.workers, count=PAPER_COUNT,
                                  render_size=size)
        wall, cpu = time.perf_counter() - t, cpu_s() - c
        path = summary.paths[0]
        disk_mb = path.stat().st_size / 1e6
        db = open_database(path)
        mem_mb = db.nbytes / 1e6
    wall_per_core = PAPER_COUNT / (wall * a.workers)
    wall_grid_min = GRID_SHAPES * PAPER_COUNT / (wall_per_core * a.workers) / 60
    per_core = PAPER_COUNT / cpu
    grid_min = GRID_SHAPES * PAPER_COUNT / (per_core * a.workers) / 60
    print(f"one {PAPER_COUNT}-entry database on {a.workers} worker(s): {wall:.1f} s wall, "
          f"{cpu:.1f} s CPU (render + preprocessing + features + write, worker start-up "
          f"included); load average before: {load_before:.1f}")
    print(f"  CPU: {per_core:.0f} entries/s per core = {1e3 / per_core:.3f} ms per entry; "
          f"full grid ({GRID_SHAPES} shapes x {PAPER_COUNT} poses) on {a.workers} idle "
          f"core(s): {grid_min:.1f} min (target <= 15)")
    print(f"  wall: {wall_per_core:.0f} entries/s per core; full grid {wall_grid_min:.1f} min "
          f"on this machine as loaded now")
    print(f"  size: {disk_mb:.1f} MB on disk, {mem_mb:.1f} MB in memory (target <= 60 each)")

    n = a.iou_poses
    poses = np.vstack([paper_pose_set(PAPER_COUNT, seed=0)[:: PAPER_COUNT // n][: n],
                       natural_pose_set(n // 2, seed=1)])
    ours = _silhouettes(poses, size)
    for ref_size, samples in (((1440, 960), 4), ((720, 480), 0)):
        iou = _iou(ours, _silhouettes(poses, ref_size, reference=True, samples=samples))
        print(f"  silhouette IoU, database ({size[0]}x{size[1]} raster) vs MuJoCo render "
              f"{ref_size[0]}x{ref_size[1]}{f' {samples}x MSAA' if samples else ''} over "
              f"{len(poses)} paper+natural poses: mean {iou.mean():.4f}, 5th percentile "
              f"{np.percentile(iou, 5):.4f}, min {iou.min():.4f} (target mean >= 0.99)")
    print(f"build_entries_per_s_per_core={per_core:.0f} full_grid_minutes={grid_min:.1f} "
          f"wall_full_grid_minutes={wall_grid_min:.1f}")


if __name__ == "__main__":
    main()
