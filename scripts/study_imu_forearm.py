"""Where the fingertip-from-elbow error beyond the from-wrist error comes from.

For the eval's configuration (the calibration and the four free-motion
trials of ``handsynth imu eval``, same seeds) and each filter, with and
without the forearm plate fusion (:func:`fuse_plate`), prints

- the orientation RMSE of the three forearm sensors, deg;
- the error of the elbow-to-wrist vector that each forearm sensor's chain
  uses (its attitude times its link vector), RMSE and the length of its mean
  over the trial (the part that stays constant), mm;
- the fingertip RMSE from the elbow and from the wrist (mean of 5 fingers), mm.

It also splits each forearm link vector's calibration error (eq. 3.6: the
hand sensor's elbow and wrist vectors, turned by the relative static-start
attitude of the forearm and hand sensors) into the part from the hand
sensor's two vectors and the part from the relative attitude.  The last
line is machine-readable.

Usage::

    python scripts/study_imu_forearm.py [--config tuning|heldout] [--filters raw,filter4]
"""

from __future__ import annotations

import argparse
import json

import numpy as np

from handsynth.sensors.imu import HELDOUT, PLATE_SENSORS, TUNING, ImuHand, free_motion, simulate_imu
from handsynth.sensors.imu._attitude import initial_attitude
from handsynth.sensors.imu._eval import _calibrate, _device_seed, make_filter
from handsynth.sensors.imu._kinematics import fingertip_positions
from handsynth.sensors.imu._layout import CHAINS, POINTS
from handsynth.sensors.imu._quat import angle_deg, quat_to_mat
from handsynth.sensors.imu._vectors import _calibration_static, calibrate_vectors, truth_chain_model

LINK = ("elbow", "wrist")


def _rms(x) -> float:
    return float(np.sqrt(np.mean(np.square(x))))


def _link_split(cal, calib) -> dict:
    """Forearm link vector errors, mm: total, from the hand sensor's vectors, from the attitudes."""
    vec = calibrate_vectors(cal)
    jv = cal.truth.joint_vectors
    d_est = vec[("hand_radial", "elbow")].vector - vec[("hand_radial", "wrist")].vector
    d_true = jv[("hand_radial", "elbow")] - jv[("hand_radial", "wrist")]
    st = _calibration_static(cal)
    r_est = quat_to_mat(initial_attitude(cal, st))
    r_true = quat_to_mat(cal.truth.quat[:, int(st.static_s * cal.rate_hz) // 2])
    truth = truth_chain_model(cal).links
    hr = cal.index("hand_radial")
    out = {}
    for s in PLATE_SENSORS:
        k = cal.index(s)
        rel_e, rel_t = r_est[k].T @ r_est[hr], r_true[k].T @ r_true[hr]
        out[s] = {"total": float(np.linalg.norm(calib.model.links[(s, *LINK)] - truth[(s, *LINK)]) * 1e3),
                  "hand_vectors": float(np.linalg.norm(rel_t @ (d_est - d_true)) * 1e3),
                  "relative_attitude": float(np.linalg.norm((rel_e - rel_t) @ d_true) * 1e3)}
    return out


def _trial_rows(rec, calib, filters) -> dict:
    truth = rec.truth
    a = next((b for s, _, b in truth.segments if s == "align"), 0)
    sl = slice(a, None)
    kp = truth.keypoints
    w_true = (kp[:, POINTS.index("wrist")] - kp[:, POINTS.index("elbow")])[sl]
    rows = {}
    for name in filters:
        q_own = make_filter(name, calib.model).run(rec)
        for fused in (False, True):
            q = calib.fuse(q_own, rec.sensors, plate_fusion=fused)
            row: dict = {"ori": [], "wrist": [], "wrist_const": []}
            for s in PLATE_SENSORS:
                k = rec.index(s)
                row["ori"].append(_rms(angle_deg(q[k, sl], truth.quat[k, sl])))
                e = quat_to_mat(q[k, sl]) @ calib.model.links[(s, *LINK)] - w_true
                row["wrist"].append(_rms(np.linalg.norm(e, axis=-1)) * 1e3)
                row["wrist_const"].append(float(np.linalg.norm(e.mean(axis=0)) * 1e3))
            tips = fingertip_positions(q, rec.sensors, calib.model)
            fe, fw = [], []
            for f in CHAINS:
                true = (kp[:, POINTS.index(f"{f}_tip")] - kp[:, POINTS.index("elbow")])[sl]
                est = tips[f][sl]
                fe.append(_rms(np.linalg.norm(est - true, axis=-1)) * 1e3)
                west = tips[f"{f}_joints"][sl, 0]
                fw.append(_rms(np.linalg.norm((est - west) - (true - w_true), axis=-1)) * 1e3)
            row["tips_elbow"], row["tips_wrist"] = float(np.mean(fe)), float(np.mean(fw))
            rows[(name, fused)] = row
    return rows


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--config", choices=("tuning", "heldout"), default="tuning")
    ap.add_argument("--filters", default="raw,filter4,gated,vqf")
    args = ap.parse_args()
    config = TUNING if args.config == "tuning" else HELDOUT
    filters = args.filters.split(",")
    placement = config.placement()
    cal, calib, sensor_cal = _calibrate(config, placement)
    split = _link_split(cal, calib)
    for s, v in split.items():
        print(f"{s}: link vector error {v['total']:5.2f} mm (hand sensor's vectors "
              f"{v['hand_vectors']:5.2f}, relative static attitude {v['relative_attitude']:5.2f})")
    hand = ImuHand(config.shape, placement=placement)
    acc: dict = {}
    for k, dur in enumerate((15.0, 30.0)):
        for m, elbow in enumerate(("fixed", "moving")):
            seed = config.seed * 100 + 10 * k + m
            rec = simulate_imu(free_motion(dur, seed=seed, elbow=elbow), hand=hand,
                               noise=config.noise, skin=config.skin, seed=seed + 50,
                               device_seed=_device_seed(config))
            for key, row in _trial_rows(sensor_cal.apply(rec), calib, filters).items():
                acc.setdefault(key, []).append(row)
    summary = {}
    print(f"{config.label}, mean of 4 trials: forearm_1/2/3 orientation (deg), elbow-to-wrist "
          "vector RMSE (constant part) mm, tips from the elbow / from the wrist mm")
    for (name, fused), rows in acc.items():
        mean = {k: np.mean([r[k] for r in rows], axis=0).tolist() for k in rows[0]}
        summary[f"{name}{'+plate' if fused else ''}"] = mean
        print(f"{name:8s} {'plate fused' if fused else 'own':11s} "
              f"ori {' '.join(f'{x:.2f}' for x in mean['ori'])}  "
              f"wrist {' '.join(f'{x:.1f}({c:.1f})' for x, c in zip(mean['wrist'], mean['wrist_const']))}  "
              f"tips {mean['tips_elbow']:.2f} / {mean['tips_wrist']:.2f}")
    print(json.dumps({"config": config.label, "link_split_mm": split, "summary": summary}))


if __name__ == "__main__":
    main()
