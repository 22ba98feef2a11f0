"""Speed of live IMU tracking (:class:`ImuStream`): 20 sensors, one push at a time, one core.

Usage::

    python scripts/bench_imu_stream.py [--duration 30] [--rate 100] [--packets 1,2,5,10,50]

Simulates (before any timing) a calibration and a free motion of ``--duration`` s of the
20-IMU system with datasheet noise and calibrates on it; then, pinned to one CPU
(numpy/BLAS and numba on one thread), feeds the motion to an :class:`ImuStream` in packets
of each size of ``--packets`` samples, timing every push after the warm-up (the static
start; numba compiled by a first stream).  Each push runs Filter 4 over its samples and
returns their fused attitudes, joint angles and fingertips; the push that completes a
stretch of 20 s also checks it as ``track`` checks a recording (the stream's default).
Reported per packet size: the median and 99th percentile time of a push, what one sample
costs, how many times faster than real time that is, and the latency of a sample's answer
at the median (the wait for the packet's last sample and the next one, which the gyro's
derivative reads, plus the push); then the slowest push (the one that checked a
stretch) and the real-time factor over all pushes, checks included.

The last line is machine-readable: ``push<k>_median_ms=<t> push<k>_p99_ms=<t>
x_realtime_<k>=<n> push<k>_max_ms=<t> x_realtime_all_<k>=<n> ... sensors=20 rate_hz=<n>``
for every packet size k.
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS"):
    os.environ.setdefault(_var, "1")  # one core: before numpy is imported

import argparse
import contextlib
import time
import warnings

import numpy as np

from handsynth.sensors.imu import (
    ImuHand,
    ImuStream,
    calibrate,
    calibration_motion,
    free_motion,
    simulate_imu,
)


def _times(cal, rec, packet: int) -> np.ndarray:
    """Seconds of every push after the warm-up."""
    stream = ImuStream(cal, rate_hz=rec.rate_hz)
    out = []
    for i in range(0, rec.n, packet):
        sl = slice(i, i + packet)
        t0 = time.perf_counter()
        stream.push(rec.acc[:, sl], rec.gyr[:, sl], rec.mag[:, sl])
        dt = time.perf_counter() - t0
        if stream.tracking and i >= stream.warmup_n:
            out.append(dt)
    stream.close()
    return np.array(out)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--duration", type=float, default=30.0, help="recording length, s")
    ap.add_argument("--rate", type=float, default=100.0, help="sampling rate, Hz")
    ap.add_argument("--packets", default="1,2,5,10,50", help="samples per push, comma-separated")
    args = ap.parse_args()
    packets = [int(k) for k in args.packets.split(",")]
    with contextlib.suppress(AttributeError, OSError):
        os.sched_setaffinity(0, {min(os.sched_getaffinity(0))})
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the simulation's notes
        cal = calibrate(simulate_imu(calibration_motion(rate_hz=args.rate),
                                     hand=ImuHand(tip_sensors=True), seed=1),
                        sensor_calibration=False)
        rec = simulate_imu(free_motion(args.duration, rate_hz=args.rate, seed=2),
                           seed=3).subset(cal.sensors)
    print(f"{len(rec.sensors)} sensors, {rec.n} samples at {rec.rate_hz:g} Hz "
          f"({rec.duration_s:.0f} s), one core; Filter 4, forearm plate fused, joint angles and "
          "fingertips")
    _times(cal, rec.slice(0, int(5 * rec.rate_hz)), 7)  # compiles the filter's loop
    period_ms = 1e3 / rec.rate_hz
    fields = []
    for k in packets:
        t = 1e3 * _times(cal, rec, k)
        med, p99 = float(np.median(t)), float(np.percentile(t, 99))
        x = k * period_ms / med
        latency = k * period_ms + med  # a packet's last sample waits for the next packet
        print(f"  {k:3d} sample(s) a push: median {med:6.2f} ms, p99 {p99:6.2f} ms; "
              f"{med / k:5.2f} ms a sample, {x:6.1f}x real time; a sample answered "
              f"{latency:5.1f} ms after it was read (at most)")
        whole = len(t) * k * period_ms / t.sum()
        print(f"      slowest push {t.max():6.1f} ms (a stretch checked); {whole:6.1f}x real "
              "time over all pushes")
        fields += [f"push{k}_median_ms={med:.3f}", f"push{k}_p99_ms={p99:.3f}",
                   f"x_realtime_{k}={x:.1f}", f"push{k}_max_ms={t.max():.1f}",
                   f"x_realtime_all_{k}={whole:.1f}"]
    print(" ".join(fields + [f"sensors={len(rec.sensors)}", f"rate_hz={rec.rate_hz:g}"]))


if __name__ == "__main__":
    main()
