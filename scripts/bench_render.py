"""Benchmark of the batch silhouette renderer: masks per second per core.

Each worker process pins Mesa's llvmpipe to one thread (``LP_NUM_THREADS=1``)
and renders a batch of 128x128 masks of the paper pose set; all cores run one
worker at the same time, and the figure is the total rate divided by the
number of workers.  The last line is machine-readable:
``render_fps_per_core=<number>``.

Usage: python scripts/bench_render.py [--size 128] [--count 3000] [--workers N]
"""

from __future__ import annotations

import argparse
import os
import platform
import time
from concurrent.futures import ProcessPoolExecutor

from handsynth._cores import usable_cores


def _worker(args: tuple[int, int]) -> tuple[int, float]:
    size, count = args
    os.environ["LP_NUM_THREADS"] = "1"
    from handsynth.models import paper_pose_set
    from handsynth.render import SilhouetteRenderer

    poses = paper_pose_set(count, seed=1)
    r = SilhouetteRenderer(width_px=size, height_px=size)
    r.masks(poses[:50])  # warm up the GL pipeline
    t = time.perf_counter()
    r.masks(poses)
    return count, time.perf_counter() - t


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--size", type=int, default=128)
    ap.add_argument("--count", type=int, default=3000)
    ap.add_argument("--workers", type=int, default=usable_cores(),
                    help="worker processes [default: the cores this process may use]")
    a = ap.parse_args()
    os.environ.setdefault("MUJOCO_GL", "egl")
    with ProcessPoolExecutor(a.workers) as ex:
        single = next(iter(ex.map(_worker, [(a.size, a.count)])))
        t0 = time.perf_counter()
        res = list(ex.map(_worker, [(a.size, a.count)] * a.workers))
        wall = time.perf_counter() - t0
    one = single[0] / single[1]
    per_worker = [n / t for n, t in res]
    per_core = sum(per_worker) / a.workers
    print(f"machine: {platform.processor() or platform.machine()}, "
          f"{usable_cores()} cores (of the machine's {os.cpu_count()}), "
          f"MUJOCO_GL={os.environ['MUJOCO_GL']}")
    print(f"{a.size}x{a.size} masks, {a.count} poses per worker")
    print(f"one worker alone: {one:.0f} masks/s")
    print(f"{a.workers} workers together: {sum(per_worker):.0f} masks/s "
          f"({[round(x) for x in per_worker]}; wall incl. start-up {wall:.1f} s)")
    print(f"render_fps_per_core={per_core:.0f}")


if __name__ == "__main__":
    main()
