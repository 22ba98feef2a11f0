"""Speed of the IMU orientation filters: 20 sensors at 100 Hz on one core.

Usage::

    python scripts/bench_imu.py [--duration 60] [--rate 100] [--repeat 3]

Simulates (before any timing) a calibration and a free motion of
``--duration`` s of the 20-IMU system with datasheet noise, builds the link
model from the calibration, then, pinned to one CPU (numpy/BLAS and numba
on one thread), times each filter on the whole recording (best of
``--repeat``, after one warm-up run that also compiles the numba code) and
reports how many times faster than real time it runs, and the time of the
forearm plate fusion that follows every filter (:func:`fuse_plate`).  The
target of issue 18 is >= 10x for 20 sensors at 100 Hz.

The last line is machine-readable: ``filter4_x_realtime=<n> filter4b_x_realtime=<n> raw_x_realtime=<n>
filter1_x_realtime=<n> gated_x_realtime=<n> vqf_x_realtime=<n> plate_fusion_s=<s>
sensors=20 rate_hz=<n>``.
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS"):
    os.environ.setdefault(_var, "1")  # one core: before numpy is imported

import argparse
import contextlib
import time

from handsynth.sensors.imu import (
    FILTER4B,
    ChainEKF,
    Filter1,
    GatedFilter,
    ImuHand,
    RawIntegration,
    VQFEstimator,
    calibration_motion,
    chain_model,
    free_motion,
    fuse_plate,
    plate_rotations,
    simulate_imu,
)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--duration", type=float, default=60.0, help="recording length, s")
    ap.add_argument("--rate", type=float, default=100.0, help="sampling rate, Hz")
    ap.add_argument("--repeat", type=int, default=3, help="timed runs per filter (best kept)")
    args = ap.parse_args()
    with contextlib.suppress(AttributeError, OSError):
        os.sched_setaffinity(0, {min(os.sched_getaffinity(0))})
    cal = simulate_imu(calibration_motion(), hand=ImuHand(tip_sensors=True), seed=1)
    model = chain_model(cal)
    rec = simulate_imu(free_motion(args.duration, rate_hz=args.rate, seed=2), seed=3)
    print(f"{len(rec.sensors)} sensors, {rec.n} samples at {rec.rate_hz:g} Hz "
          f"({rec.duration_s:.0f} s), one core")
    results = {}
    q = None
    for est in (RawIntegration(), Filter1(), GatedFilter(), ChainEKF(model),
                ChainEKF(model, options=FILTER4B, name="filter4b"), VQFEstimator()):
        est.run(rec.slice(0, int(3 * rec.rate_hz)))  # warm-up (numba compilation): 3 s
        # of data, past the 2-s static start at any rate (300 samples were 0.3 s at 1,000 Hz)
        best = float("inf")
        for _ in range(args.repeat):
            t0 = time.perf_counter()
            q = est.run(rec)
            best = min(best, time.perf_counter() - t0)
        results[est.name] = rec.duration_s / best
        print(f"  {est.name:<8} {best:7.3f} s for {rec.duration_s:.0f} s of data: "
              f"{results[est.name]:7.1f}x real time")
    plate = plate_rotations(cal)
    fuse_s = float("inf")
    for _ in range(args.repeat):
        t0 = time.perf_counter()
        fuse_plate(q, rec.sensors, plate)
        fuse_s = min(fuse_s, time.perf_counter() - t0)
    print(f"  forearm plate fusion {fuse_s:7.3f} s for {rec.duration_s:.0f} s of data (after "
          "any filter)")
    print(f"filter4_x_realtime={results['filter4']:.1f} "
          f"filter4b_x_realtime={results['filter4b']:.1f} raw_x_realtime={results['raw']:.1f} "
          f"filter1_x_realtime={results['filter1']:.1f} gated_x_realtime={results['gated']:.1f} "
          f"vqf_x_realtime={results['vqf']:.1f} "
          f"plate_fusion_s={fuse_s:.4f} sensors={len(rec.sensors)} rate_hz={rec.rate_hz:g}")


if __name__ == "__main__":
    main()
