"""Speed of the live glove (:func:`stream_glove_csv`): one line of five readings at a time.

Usage::

    python scripts/bench_glove_stream.py [--kind dg5] [--models model4,model4+synergy,synergy]

Simulates (before any timing) a calibration recording and a later wearing of the same user
(``handsynth glove simulate``'s defaults: the representative motions, five trials each, and
the range holds), calibrates every estimator on the first, then, on one CPU, streams the
wearing's lines through each estimator of ``--models`` (mixed over the calibrated motions,
the wearing's own range holds mapped), timing every line: the median and 99th percentile
time of a line, and how many lines a second that reads.

The last line is machine-readable: ``<model>_median_ms=<t> <model>_p99_ms=<t> ... lines=<n>``.
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS"):
    os.environ.setdefault(_var, "1")  # one core: before numpy is imported

import argparse
import contextlib
import tempfile
import time
from pathlib import Path

import numpy as np
from click.testing import CliRunner

from handsynth.cli._main import cli
from handsynth.sensors.glove import stream_glove_csv


def _run(*args) -> None:
    res = CliRunner().invoke(cli, [str(a) for a in args])
    if res.exit_code != 0:
        raise SystemExit(res.output)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--kind", default="dg5", choices=("dg5", "5dt"), help="glove design")
    ap.add_argument("--models", default="model4,model4+synergy,synergy",
                    help="estimators, comma-separated")
    args = ap.parse_args()
    with contextlib.suppress(AttributeError, OSError):
        os.sched_setaffinity(0, {min(os.sched_getaffinity(0))})
    with tempfile.TemporaryDirectory() as d:
        cal_csv, wear, cal = Path(d, "cal.csv"), Path(d, "wear.csv"), Path(d, "cal.json")
        _run("glove", "simulate", cal_csv, "--kind", args.kind, "--user", 1)
        _run("glove", "simulate", wear, "--kind", args.kind, "--user", 1, "--donning", 7,
             "--seed", 3, "--no-angles")
        _run("glove", "calibrate", cal_csv, "-o", cal, "--kind", args.kind)
        lines = wear.read_text().splitlines()
        print(f"{args.kind}: {len(lines) - 1} lines of five readings, one core, mixed over the "
              "calibrated motions, the wearing's range holds mapped")
        fields = []
        for model in args.models.split(","):
            times = []
            stream = stream_glove_csv(lines, cal, model=model, range_csv=wear)
            while True:
                t0 = time.perf_counter()
                if next(stream, None) is None:
                    break
                times.append(time.perf_counter() - t0)
            t = 1e3 * np.array(times[1:])  # the first line also reads the calibration
            med, p99 = float(np.median(t)), float(np.percentile(t, 99))
            print(f"  {model:<15} median {med:.3f} ms a line, p99 {p99:.3f} ms: "
                  f"{1e3 / med:,.0f} lines/s")
            fields += [f"{model}_median_ms={med:.4f}", f"{model}_p99_ms={p99:.4f}"]
        print(" ".join(fields + [f"lines={len(lines) - 1}"]))


if __name__ == "__main__":
    main()
