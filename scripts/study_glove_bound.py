"""What five glove readings can tell of the MCP flexions: a ladder of oracles.

On exactly the test samples of ``handsynth glove eval``'s ``rewear/other``
and ``user2/other`` cells (:meth:`handsynth.sensors.glove.EvalSetup.test_data`:
the motions not in the calibration set, worn again by the calibration user
or by a second user, after the open/fist range calibration), each sample's
five joint-3 angles (MCP flexion; thumb CMC flexion) are estimated from its
five readings by oracles that know more than a real user could, beside the
library's estimators and the constant answer.  Errors are mean absolute
errors against the simulator's noise-free truth, over all samples and the
five joints, as in the evaluation.

Every oracle is a posterior mean computed by Monte Carlo: the oracle
simulates, with :func:`handsynth.sensors.glove.simulate_session`, ``--draws``
new trials of each motion of its prior, performed by the test session's own
user (hand, rest posture, grasp style, MCP lead, DIP ratio: the same
generator as the test trials, with new trial variation), and weights every
simulated sample (every third at 60 Hz) by a Gaussian likelihood of the test
sample's features given the simulated sample's.  The answer is the
weighted mean of the simulated MCP angles over the ``--neighbours`` nearest
simulated samples (the weights of the others are negligible or, where the
simulated samples are dense, the answer is their local mean).  The rungs
differ in what the oracle knows:

1. ``strict``: the true bend model of this wearing (the session's own
   :class:`~handsynth.sensors.glove.SensorParams`: gain, offset,
   nonlinearity, hysteresis, noise and slip of this donning on this user)
   and which posture the sample belongs to.  Features: the raw readings;
   the simulated samples' readings are the true model's noise-free ones
   (hysteresis along each simulated trial), the likelihood is Gaussian with
   the sensor's noise s.d. (plus the two roundings to counts).  Its error
   is what sensor noise, hysteresis and the trial variation the readings do
   not show (a PIP-only sensor does not see the MCP's own 4-deg trial
   jitter) leave.
2. ``posture``: which posture, but through the calibrated sensor model,
   which is what calibration gives a user: the range-normalised readings are
   turned into the bend of each sensor's joints by the cubic fitted on the
   calibration session (:meth:`SynergyEstimator.bend`), and the likelihood
   of a simulated sample is Gaussian around its nominal bend (the sensor's
   nominal joint weights, :meth:`SynergyEstimator.weight_matrix`) with the
   calibration fit's residual variance.
3. ``unseen set``: as 2, but the prior is all seven unseen postures, equally
   likely (the oracle knows which postures occur, not which one this is).
4. ``calibrated + unseen``: as 3, with the calibrated motions (three for the
   DG5-like glove, four for the 5DT-like) added to the prior, equally likely.
5. ``calibrated only``: as 4 without the unseen postures: the prior that
   mixing over the calibrated motions assumes, still with the test user's
   own trials and the oracle's posterior mean.  Not a rung of more
   knowledge than 4 but of less: it shows what the calibrated motions alone
   allow on postures outside them.

Where the rungs are approximations, stated plainly:

* The oracles know the test user's grasp style, rest posture and MCP lead
  (the prior is this user's own trials), so the rungs isolate knowledge of
  the postures and of the sensor model, not of the user.
* With a finite number of simulated trials the exact likelihood is too
  narrow for the strict rung (about 0.5 deg of bend against a 4-deg trial
  variation in five dimensions leaves a handful of simulated trials near
  each sample), so each likelihood s.d. is multiplied by a width factor
  (``--strict-width``, default 6; ``--calibrated-width``, default 1.5): a
  kernel estimate of the posterior mean.  Both defaults gave the smallest
  errors over both gloves and both conditions among 1, 2, 3, 4, 6 (strict)
  and 1, 1.5, 2, 3 (calibrated) on seeds 100-101, not the reported seeds.
  Each rung is therefore an estimator that uses only its oracle's
  knowledge, and its error an upper estimate of what that knowledge allows:
  the exact posterior mean would do as well or a little better.  With four
  times the simulated trials (seed 100, DG5-like, ``rewear``) the strict
  rung fell by 0.04 deg and the posture rung changed by 0.02 deg.
* The posterior mean minimises the squared error; the figures are mean
  absolute errors, as everywhere in the glove section.

Below rung 1, to say what its error comes from: the same test angles read
again by the same glove without noise (``strict, no noise``) and without
noise or play hysteresis (``strict, no noise or play``), re-simulated from
the test session's seed (the angles are drawn before the noise, so they are
the same samples' angles), each estimated by rung 1's oracle with rung 1's
kernel, so that only the readings change.

Beside the rungs: every estimator of the calibration with the motion
unknown (``model1`` ... ``model4`` mixed over the calibrated motions,
``pooled_model4``, ``synergy``, ``model4+synergy``) and the constant answer,
on the same samples; ``best real`` is the one with the smallest mean error
over the seeds.

Usage::

    python scripts/study_glove_bound.py --kind both --seeds 5 [--json FILE]

Prints the ladder per glove and condition (``1 -noise``, ``1 -noise-play``:
the two readings below rung 1), then per posture, and as its last
line one JSON object (the ladder's means).  About 3 minutes for
``--kind both --seeds 5`` on the 2-core machine.
"""

from __future__ import annotations

import argparse
import json
import time

import numpy as np
from scipy.spatial import cKDTree

from handsynth._io import write_text
from handsynth.sensors.glove import (
    MODELS,
    OTHER_MOTIONS,
    EvalOptions,
    EvalSetup,
    EvalTestData,
    SynergyEstimator,
    eval_setup,
    finger_joints,
    motions_for,
    simulate_sensors,
    simulate_session,
)

_MCP = [f["j3"] for f in finger_joints()]
CONDITIONS = {"new_session": "rewear", "second_user": "user2"}
RUNGS = ("strict", "posture", "unseen set", "calibrated + unseen", "calibrated only")
FLOOR = ("strict, no noise", "strict, no noise or play")
_SHORT = dict(zip((*RUNGS, *FLOOR), ("1 strict", "2 posture", "3 unseen", "4 cal+unseen",
                                     "5 cal only", "1 -noise", "1 -noise-play")))
ROUND_VAR = 2.0 / 12.0   # two roundings to counts (test and simulated reading), counts^2


def posterior_mean(features: np.ndarray, values: np.ndarray, queries: np.ndarray,
                   sd: np.ndarray, neighbours: int) -> tuple[np.ndarray, float]:
    """Gaussian-likelihood weighted mean of `values` over the nearest simulated samples.

    Parameters
    ----------
    features : ndarray, shape (M, 5)
        Noise-free features of the simulated samples.
    values : ndarray, shape (M, 5)
        Their MCP angles, deg.
    queries : ndarray, shape (N, 5)
        Features of the test samples.
    sd : ndarray, shape (5,)
        Likelihood s.d. of each feature.
    neighbours : int
        Simulated samples weighted per query (the nearest in units of `sd`).

    Returns
    -------
    mean : ndarray, shape (N, 5)
    ess : float
        Median effective number of simulated samples, (sum w)^2 / sum w^2.
    """
    tree = cKDTree(features / sd)
    d, idx = tree.query(queries / sd, k=min(neighbours, len(features)))
    w = np.exp(-0.5 * (d**2 - d[:, :1] ** 2))
    ess = float(np.median(w.sum(axis=1) ** 2 / (w**2).sum(axis=1)))
    return np.einsum("nk,nkj->nj", w, values[idx]) / w.sum(axis=1)[:, None], ess


def simulated_prior(setup: EvalSetup, data: EvalTestData, motions, trials: int,
                    seed: int) -> dict:
    """New trials of each motion by the test session's user, through its glove.

    The trials come from the test session's generator (its user and
    donning) with new trial variation; every third sample is kept.

    Returns
    -------
    dict of str to dict
        Per motion: ``"angles"`` (M, 20) deg, ``"mcp"`` (M, 5) deg,
        ``"readings"`` (M, 5) the true model's noise-free readings (hysteresis
        along each trial), counts, and ``"bends"`` (M, 5) the nominal bend of
        each sensor's joints (the calibrated model's weights), deg.
    """
    syn = setup.estimators["synergy"]
    assert isinstance(syn, SynergyEstimator)
    w = syn.weight_matrix()
    out = {}
    for i, m in enumerate(motions):
        rec = simulate_session(data.user, data.donning, [m], trials=trials, seed=seed + i)
        truth = rec.truth
        assert truth is not None  # simulated sessions carry their truth
        clean = simulate_sensors(truth, data.donning)       # rng None: no noise
        out[m] = {"angles": truth[::3], "mcp": truth[::3][:, _MCP], "readings": clean[::3],
                  "bends": (truth @ w.T)[::3]}
    return out


def _errors(pred: np.ndarray, truth: np.ndarray, motion: np.ndarray, motions) -> dict:
    err = np.abs(pred - truth)
    return {"all": float(err.mean()), **{m: float(err[motion == m].mean()) for m in motions}}


def ladder(setup: EvalSetup, condition: str, args) -> dict:
    """Errors of the rungs, the floor and the real estimators on one cell, per posture."""
    data = setup.test_data(condition, "other")
    rec = data.recording
    assert rec.truth is not None
    truth, motion = rec.truth[:, _MCP], rec.motion
    unseen = list(OTHER_MOTIONS)
    calibrated = list(motions_for(setup.kind))
    seed = 10**6 + 1000 * setup.seed + 100 * list(CONDITIONS).index(condition)
    prior = simulated_prior(setup, data, unseen + calibrated, args.draws, seed)
    syn = setup.estimators["synergy"]
    assert isinstance(syn, SynergyEstimator)
    bend = syn.bend(data.sensors)                              # calibrated sensor model
    sd_raw = args.strict_width * np.sqrt(data.donning.noise_counts**2 + ROUND_VAR)
    sd_bend = args.calibrated_width * np.sqrt(syn.bend_variance)
    k = args.neighbours

    # the same test angles read by the same glove without noise, then also without play
    quiet = data.donning.replace(noise_counts=0.0)
    still = quiet.replace(hysteresis_deg=0.0)
    floor_readings = {}
    for name, don in zip(FLOOR, (quiet, still)):
        again = simulate_session(data.user, don, unseen, trials=setup.test_trials,
                                 seed=data.session_seed)
        assert again.truth is not None and np.array_equal(again.truth, rec.truth)
        floor_readings[name] = again.sensors

    preds = {r: np.empty_like(truth) for r in (*RUNGS, *FLOOR)}
    ess: dict[str, list[float]] = {r: [] for r in (*RUNGS, *FLOOR)}

    def put(rung: str, sel, features, values, queries, sd) -> None:
        preds[rung][sel], e = posterior_mean(features, values, queries, sd, k)
        ess[rung].append(e)

    for m in unseen:
        sel, p = motion == m, prior[m]
        put("strict", sel, p["readings"], p["mcp"], rec.sensors[sel], sd_raw)
        put("posture", sel, p["bends"], p["mcp"], bend[sel], sd_bend)
        put(FLOOR[0], sel, p["readings"], p["mcp"], floor_readings[FLOOR[0]][sel], sd_raw)
        put(FLOOR[1], sel, simulate_sensors(p["angles"], still), p["mcp"],
            floor_readings[FLOOR[1]][sel], sd_raw)
    everywhere = np.ones(len(truth), dtype=bool)
    for rung, motions in (("unseen set", unseen), ("calibrated + unseen", unseen + calibrated),
                          ("calibrated only", calibrated)):
        put(rung, everywhere, np.vstack([prior[m]["bends"] for m in motions]),
            np.vstack([prior[m]["mcp"] for m in motions]), bend, sd_bend)
    for name, est in setup.estimators.items():                # motion unknown
        preds[f"{name}/mixed" if name in MODELS else name] = est.predict(data.sensors)[:, _MCP]
    return {"errors": {r: _errors(p, truth, motion, unseen) for r, p in preds.items()},
            "median_ess": {r: float(np.median(v)) for r, v in ess.items()},
            "samples": int(rec.n_samples)}


def _mean(runs: list[dict]) -> dict:
    return {k: _mean([r[k] for r in runs]) if isinstance(runs[0][k], dict)
            else round(float(np.mean([r[k] for r in runs])), 3) for k in runs[0]}


def study(kind: str, args) -> dict:
    """The ladder of glove `kind` for each condition, mean over the seeds."""
    out = {}
    runs: dict[str, list[dict]] = {c: [] for c in CONDITIONS}
    for seed in range(args.seed, args.seed + args.seeds):
        setup = eval_setup(EvalOptions(kind=kind), seed)
        for cond in CONDITIONS:
            runs[cond].append(ladder(setup, cond, args))
    for cond, rs in runs.items():
        errors = _mean([r["errors"] for r in rs])
        real = [k for k in errors if k not in (*RUNGS, *FLOOR, "constant")]
        best = min(real, key=lambda k: errors[k]["all"])
        out[CONDITIONS[cond]] = {
            "errors": errors, "best_real": best,
            "per_seed": {k: [round(r["errors"][k]["all"], 3) for r in rs]
                         for k in (*RUNGS, *FLOOR, best, "constant")},
            "median_ess": _mean([r["median_ess"] for r in rs]),
            "samples_per_seed": [r["samples"] for r in rs]}
    return out


def _print(kind: str, res: dict) -> None:
    print(f"== {kind}: mean joint-3 (MCP) error, deg, on the eval's '<condition>/other' "
          "samples; oracles know more than a user could")
    order = (FLOOR[1], FLOOR[0], *RUNGS)
    cols = (*(_SHORT[k] for k in order), "best real", "constant")
    print(f"{'condition':<10}" + "".join(f"{c:>14}" for c in cols))
    for cond, r in res.items():
        e = r["errors"]
        vals = [e[k]["all"] for k in order] + [e[r["best_real"]]["all"], e["constant"]["all"]]
        print(f"{cond:<10}" + "".join(f"{v:>14.2f}" for v in vals) + f"   ({r['best_real']})")
    for cond, r in res.items():
        e = r["errors"]
        keys = (*RUNGS, r["best_real"], "constant")
        print(f"-- {kind} {cond}, per posture (best real: {r['best_real']})")
        print(f"{'posture':<24}" + "".join(f"{_SHORT.get(k, k):>14}" for k in keys))
        for m in OTHER_MOTIONS:
            print(f"{m:<24}" + "".join(f"{e[k][m]:>14.2f}" for k in keys))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--kind", choices=("dg5", "5dt", "both"), default="both")
    parser.add_argument("--seeds", type=int, default=5, help="seeds seed .. seed+N-1")
    parser.add_argument("--seed", type=int, default=0, help="first seed (as glove eval)")
    parser.add_argument("--draws", type=int, default=200,
                        help="simulated trials per motion of each oracle's prior")
    parser.add_argument("--neighbours", type=int, default=512,
                        help="simulated samples weighted per test sample")
    parser.add_argument("--strict-width", type=float, default=6.0,
                        help="likelihood s.d. of the strict rung, in sensor noise s.d.")
    parser.add_argument("--calibrated-width", type=float, default=1.5,
                        help="likelihood s.d. of rungs 2-5, in calibration residual s.d.")
    parser.add_argument("--json", help="write every figure (per seed, per posture) here")
    args = parser.parse_args()
    if args.seeds < 1 or args.draws < 1 or args.neighbours < 1:
        parser.error("--seeds, --draws and --neighbours must be positive")

    t0 = time.perf_counter()
    kinds = ("dg5", "5dt") if args.kind == "both" else (args.kind,)
    results = {k: study(k, args) for k in kinds}
    run_s = round(time.perf_counter() - t0, 1)
    for k, res in results.items():
        _print(k, res)
    settings = {"seeds": list(range(args.seed, args.seed + args.seeds)), "draws": args.draws,
                "neighbours": args.neighbours, "strict_width": args.strict_width,
                "calibrated_width": args.calibrated_width, "run_s": run_s}
    if args.json:
        write_text(args.json, json.dumps({"settings": settings, "results": results}, indent=2),
                   what="JSON report")
        print(f"json: {args.json}")
    summary = {k: {cond: {**{rung: r["errors"][rung]["all"] for rung in (*FLOOR, *RUNGS)},
                          "best_real": r["best_real"],
                          "best_real_deg": r["errors"][r["best_real"]]["all"],
                          "constant": r["errors"]["constant"]["all"]}
                   for cond, r in res.items()} for k, res in results.items()}
    print(json.dumps({"settings": settings, "mcp_error_deg": summary}))


if __name__ == "__main__":
    main()
