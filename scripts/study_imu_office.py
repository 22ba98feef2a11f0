"""The single-IMU filters in a synthetic office: BROAD's real motions, a field that varies in space.

BROAD's nine absent trials include its two office recordings and its mixed
one, where the field changes from place to place.  This study makes such
recordings from the undisturbed trials present on disk: real motions and real
sensor readings, to which it adds the field of four magnetic dipoles fixed in
the room (steel furniture), placed by a seeded generator 0.3-0.9 m from the
trial's mean position and at least 0.2 m from every optical position, each
scaled so that its largest field along the path is `--peak` uT (a range,
drawn per dipole).  The added field at each sample is the dipoles' field at
the optical position, turned into the sensor's frame by the optical
orientation (both forward-filled over missing samples).  The error is
BROAD's (total RMSE over the movement phases against the optical reference,
whose earth frame is the undisturbed field's).  A field that is off where the
sensor starts turns every filter's north, so the figures are large for every
filter; the comparison between filters is the point.

Usage::

    python scripts/study_imu_office.py BROAD_DIR [--seeds 0,1,2] [--peak 2,10]
        [--filters gated,vqf]

Prints a line per recording and the mean per filter; the last line is
machine-readable JSON.  BROAD itself is not part of the project (CC-BY-4.0,
github.com/dlaidig/broad); give the folder that holds ``data_mat``.
"""

from __future__ import annotations

import argparse
import dataclasses
import json

import numpy as np
from scipy.io import loadmat

from handsynth.sensors.imu import StaticStart
from handsynth.sensors.imu._broad import (
    _Q_NWU_FROM_ENU,
    broad_errors,
    find_broad_trials,
    read_broad_trial,
)
from handsynth.sensors.imu._eval import make_filter
from handsynth.sensors.imu._quat import qconj, qmul, qrotinv


def _forward_fill(a: np.ndarray) -> np.ndarray:
    """Rows with NaN replaced by the last finite row (the first finite one at the start)."""
    ok = np.all(np.isfinite(a), axis=1)
    if not ok.any():
        raise ValueError("no finite optical sample")
    idx = np.where(ok, np.arange(len(a)), 0)
    np.maximum.accumulate(idx, out=idx)
    idx[: int(np.argmax(ok))] = int(np.argmax(ok))
    return a[idx]


def dipole_field_ut(pos_m: np.ndarray, rng: np.random.Generator, *, count: int = 4,
                    peak_ut: tuple[float, float] = (2.0, 10.0)) -> np.ndarray:
    """The field (N, 3), uT, of `count` dipoles fixed in the room at the positions `pos_m`
    (each scaled to its drawn peak, so the constant mu_0 / 4 pi does not appear)."""
    centre = pos_m.mean(axis=0)
    total = np.zeros_like(pos_m)
    placed = 0
    while placed < count:
        d = rng.normal(size=3)
        p = centre + d / np.linalg.norm(d) * rng.uniform(0.3, 0.9)
        r = pos_m - p
        dist = np.linalg.norm(r, axis=1, keepdims=True)
        if dist.min() < 0.2:
            continue
        m = rng.normal(size=3)
        m /= np.linalg.norm(m)
        rh = r / dist
        b = (3.0 * (rh @ m)[:, None] * rh - m) / dist ** 3
        total += b * (rng.uniform(*peak_ut) / np.linalg.norm(b, axis=1).max())
        placed += 1
    return total


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("broad_dir")
    ap.add_argument("--seeds", default="0,1,2")
    ap.add_argument("--peak", default="2,10", help="range of each dipole's peak field, uT")
    ap.add_argument("--filters", default="gated,vqf")
    args = ap.parse_args()
    seeds = [int(s) for s in args.seeds.split(",")]
    lo, hi = (float(x) for x in args.peak.split(","))
    filters = args.filters.split(",")
    rows: dict = {}
    for path in find_broad_trials(args.broad_dir):
        if "_undisturbed_" not in path.stem or path.suffix != ".mat":
            continue
        rec, opt, movement = read_broad_trial(path)
        pos = _forward_fill(np.asarray(loadmat(path)["opt_pos"], float))
        q_opt = _forward_fill(opt)
        q_opt /= np.linalg.norm(q_opt, axis=1, keepdims=True)
        first = int(np.argmax(movement))
        static = StaticStart(static_s=max(2.0 / rec.rate_hz, min(2.0, first / rec.rate_hz)),
                             align_start_s=None, align_end_s=None)
        for seed in seeds:
            rng = np.random.default_rng(1000 * seed + int(path.stem[:2]))
            field_w = dipole_field_ut(pos, rng, peak_ut=(lo, hi))
            mag = rec.mag + qrotinv(q_opt, field_w)[None]
            office = dataclasses.replace(rec, mag=mag)
            row: dict = {}
            for name in filters:
                est = make_filter(name)
                if hasattr(est, "static"):
                    est = dataclasses.replace(est, static=static)
                q = est.run(office)[0]
                row[name] = broad_errors(qmul(qconj(_Q_NWU_FROM_ENU), q), opt, movement)
            row["added_mean_ut"] = float(np.linalg.norm(field_w, axis=1).mean())
            rows[f"{path.stem}/{seed}"] = row
            print(f"{path.stem[:36]:36s} seed {seed}  added {row['added_mean_ut']:5.1f} uT  "
                  + "  ".join(f"{n} {row[n]['total_rmse_deg']:6.2f}" for n in filters),
                  flush=True)
    if not rows:
        raise SystemExit(f"{args.broad_dir}: no undisturbed BROAD trial in .mat form")
    mean = {n: float(np.mean([r[n]["total_rmse_deg"] for r in rows.values()])) for n in filters}
    better = {n: int(sum(r[n]["total_rmse_deg"] < min(r[m]["total_rmse_deg"] for m in filters
                                                        if m != n) for r in rows.values()))
              for n in filters}
    for n in filters:
        print(f"{n}: mean total RMSE {mean[n]:.2f} deg, best on {better[n]} of {len(rows)}")
    print(json.dumps({"mean_total_rmse_deg": mean, "best_count": better, "recordings": rows,
                      "seeds": seeds, "peak_ut": [lo, hi]}))


if __name__ == "__main__":
    main()
