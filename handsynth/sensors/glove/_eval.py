"""The seed's tables on simulated data, and the conditions they leave out.

Seed 004 reports, per finger and per representative motion, the mean error
of joint 3 (the MCP; thumb: CMC flexion) of each model (Tables 2-5) and the
R^2 of model 4 (Table 6), with the motion known.  :func:`evaluate` builds the
same tables for every estimator in four conditions:

``loto``
    Leave one trial out: the calibration user and donning, each trial of
    every motion estimated by estimators calibrated on the other trials
    (the seed's setting).
``new_session``
    The calibration user later, glove taken off and put on again (new
    offsets, gains and slip), after a range calibration (open hand, fist;
    :class:`RangeNormalizer`): "calibrate once, then wear".
``second_user``
    Another user (other hand length, rest posture, grasp style, DIP/PIP
    ratio and sensor slip) wearing the same glove after a range
    calibration, estimated with the first user's calibration.
``second_user_raw``
    The same without the range calibration.

``new_session`` and ``second_user`` also hold motions outside the
calibration set (:data:`OTHER_MOTIONS`): with those the motion is unknown,
so only mixing (eqs. 4-6), the pooled model, the synergy baseline and the
constant apply.  Every cell carries the constant answer's error on the same
samples and the s.d. of the true angle there.  Errors are against the
simulator's noise-free truth; calibration used the noisy reference glove.
"""

from __future__ import annotations

import dataclasses
import warnings
from dataclasses import dataclass, field

import numpy as np

from ..._checks import check_options
from ...errors import InvalidInputError
from ...models import FINGERS
from ._calibrate import CalibrationOptions, calibrate, range_readings
from ._estimators import RangeNormalizer, RegressionEstimator
from ._models import MODELS, GloveWarning, finger_joints
from ._motions import OTHER_MOTIONS, motions_for
from ._recording import GloveRecording
from ._sensors import SensorParams
from ._simulate import (
    GLOVE_TUNING,
    GloveConfig,
    GloveUser,
    don_glove,
    make_user,
    simulate_range_holds,
    simulate_session,
)

__all__ = [
    "CONDITIONS",
    "LATER_CONDITIONS",
    "MOTION_SETS",
    "EvalOptions",
    "EvalSetup",
    "EvalTestData",
    "eval_setup",
    "evaluate",
]

CONDITIONS = ("loto", "new_session", "second_user", "second_user_raw")
_J = finger_joints()
_MCP = [f["j3"] for f in _J]
_PIP = [f["j2"] for f in _J]
_DIP = [f["j1"] for f in _J]
_ABD = [f["abd"] for f in _J]
#: The estimators' warning about readings off the calibration's range (:func:`check_reading_range`).
_OFF_RANGE = r".* readings lie off the calibration's range"


@dataclass(frozen=True)
class EvalOptions:
    """Options of :func:`evaluate`.

    Parameters
    ----------
    kind : {"dg5", "5dt"}
    trials : int
        Calibration trials per motion (>= 3 for leave-one-trial-out).
    test_trials : int
        Trials per motion in the later sessions.
    seed : int
        Base seed; users, donnings and sessions derive theirs from it.
    seeds : int
        Independent repetitions (seeds ``seed`` .. ``seed + seeds - 1``: new
        users, gloves and sessions each time); the tables hold their means.
    calibration : CalibrationOptions
    config : GloveConfig
        The spreads the gloves and donnings are drawn from (:data:`GLOVE_TUNING`, on
        which the estimators' options were chosen; :data:`GLOVE_HELDOUT` sets others).

    Raises
    ------
    InvalidInputError
        An unknown kind, a count out of its range, or a `calibration` that is
        no :class:`CalibrationOptions`, a `config` no :class:`GloveConfig` (named in
        the message).
    """

    kind: str = "dg5"
    trials: int = 5
    test_trials: int = 3
    seed: int = 0
    seeds: int = 1
    calibration: CalibrationOptions = field(default_factory=CalibrationOptions)
    config: GloveConfig = GLOVE_TUNING

    def __post_init__(self) -> None:
        motions_for(self.kind)  # validates the kind
        for name, flag, lo, hi in (("trials", "--trials", 3, 100), ("seeds", "--seeds", 1, 100),
                                   ("test_trials", "--test-trials", 1, 100),
                                   ("seed", "--seed", 0, 2**31 - 1)):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, int) or not lo <= v <= hi:
                raise InvalidInputError(f"EvalOptions.{name} ({flag}) must be an integer in "
                                        f"[{lo}, {hi}], got {v!r}")
        if not isinstance(self.calibration, CalibrationOptions):
            raise InvalidInputError(f"EvalOptions.calibration must be CalibrationOptions, got "
                                    f"{type(self.calibration).__name__} {self.calibration!r:.40}")
        if not isinstance(self.config, GloveConfig):
            raise InvalidInputError(f"EvalOptions.config must be a GloveConfig (GLOVE_TUNING, "
                                    f"GLOVE_HELDOUT), got {type(self.config).__name__} "
                                    f"{self.config!r:.40}")




def _variants(estimators: dict, representative: bool) -> dict:
    """Prediction functions name -> f(sensors, motion) for a motion set."""
    out = {}
    for name, est in estimators.items():
        if isinstance(est, RegressionEstimator) and name in MODELS:
            if representative:
                out[f"{name}/known"] = (est, True)
            out[f"{name}/mixed"] = (est, False)
        else:
            out[name] = (est, False)
    return out


def _predict(est, known: bool, rec: GloveRecording, sensors: np.ndarray) -> np.ndarray:
    # The conditions put readings off the calibration's range on purpose (another
    # user without the range calibration, motions not calibrated); the tables show
    # what that costs, so the estimators' warning about it would only repeat them.
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message=_OFF_RANGE, category=GloveWarning)
        if not known:
            return est.predict(sensors)
        out = np.empty((rec.n_samples, 20))
        for m in dict.fromkeys(rec.motion.tolist()):
            sel = rec.motion == m
            out[sel] = est.predict(sensors[sel], motion=m)
        return out


def _cell(pred, base, truth) -> dict:
    err = np.abs(pred - truth)
    sst = float(((truth - truth.mean()) ** 2).sum())
    r2 = 1.0 - float(((pred - truth) ** 2).sum()) / sst if sst > 0 else float("nan")
    return {"mcp_error_deg": round(float(err.mean()), 3), "r2": round(r2, 4),
            "baseline_mcp_error_deg": round(float(np.abs(base - truth).mean()), 3),
            "truth_sd_deg": round(float(truth.std()), 3)}


def _table(preds: dict, rec: GloveRecording) -> dict:
    """Per variant: per motion per finger cells, the seed's "Ave." row, a summary."""
    truth = rec.truth
    assert truth is not None  # simulated sessions carry their truth
    base = preds["constant"]
    motions = list(dict.fromkeys(rec.motion.tolist()))
    tables, summary = {}, {}
    for name, pred in preds.items():
        rows = {}
        for m in motions:
            sel = rec.motion == m
            rows[m] = {f: _cell(pred[sel, j], base[sel, j], truth[sel, j])
                       for f, j in zip(FINGERS, _MCP)}
        rows["Ave."] = {f: {k: round(float(np.mean([rows[m][f][k] for m in motions])), 3)
                            for k in ("mcp_error_deg", "baseline_mcp_error_deg", "r2",
                                      "truth_sd_deg")} for f in FINGERS}
        tables[name] = rows

        def mean_err(cols, p=pred):
            return round(float(np.abs(p[:, cols] - truth[:, cols]).mean()), 3)

        summary[name] = {
            "mcp_error_deg": mean_err(_MCP), "baseline_mcp_error_deg": mean_err(_MCP, base),
            "pip_error_deg": mean_err(_PIP), "dip_error_deg": mean_err(_DIP),
            "abduction_error_deg": mean_err(_ABD),
            "all_joints_error_deg": mean_err(list(range(20))),
            "baseline_all_joints_error_deg": mean_err(list(range(20)), base),
        }
    return {"motions": motions, "tables": tables, "summary": summary}


def _evaluate_on(estimators: dict, rec: GloveRecording, sensors: np.ndarray,
                 representative: bool) -> dict:
    preds = {name: _predict(est, known, rec, sensors)
             for name, (est, known) in _variants(estimators, representative).items()}
    return _table(preds, rec)


def _mixing_accuracy(est: RegressionEstimator, rec: GloveRecording, sensors) -> dict:
    """Mean weight r_p of the true motion, per motion (eq. 6)."""
    if est.mixer is None:
        return {}
    r = est.weights(sensors)
    out = {}
    for p, m in enumerate(est.mixer.motions):
        sel = rec.motion == m
        if sel.any():
            out[m] = round(float(np.nanmean(r[sel, p])), 3)
    return out


def _mean_tree(trees: list):
    """Element-wise mean of equally shaped nested dicts; other leaves from the first."""
    first = trees[0]
    if isinstance(first, dict):
        return {k: _mean_tree([t[k] for t in trees]) for k in first}
    if isinstance(first, (int, float)) and not isinstance(first, bool):
        return round(float(np.mean(trees)), 3)
    return first


def evaluate(options: EvalOptions | None = None) -> dict:
    """Run the four conditions and return the tables (JSON-serialisable).

    Parameters
    ----------
    options : EvalOptions, optional
        Glove kind, trial counts, seeds and calibration; ``EvalOptions()`` for
        None.

    Returns
    -------
    dict
        ``config``, ``users``, ``fit_r2`` (R^2 of the joint-3 regression of
        each model on the full calibration, the seed's Table 6) and
        ``conditions``: for each of :data:`CONDITIONS` a dict of motion sets
        (``"representative"``, ``"other"``) holding ``motions``, ``tables``
        (variant -> motion -> finger -> cell, plus the "Ave." row) and
        ``summary`` (variant -> mean errors over all samples, with the
        constant answer's beside them).  With ``seeds > 1`` every number is
        the mean over the seeds, and each summary entry adds
        ``mcp_error_deg_per_seed``.

    Raises
    ------
    InvalidInputError
        `options` neither None nor an :class:`EvalOptions`.
    """
    o = check_options(options, EvalOptions)
    runs = [_evaluate_one(o, s) for s in range(o.seed, o.seed + o.seeds)]
    out = _mean_tree(runs)
    out["config"] = dict(runs[0]["config"])  # what was asked, not a mean of it (seed 2.0)
    for cond, sets in out["conditions"].items():
        for set_name, res in sets.items():
            for variant, summ in res["summary"].items():
                summ["mcp_error_deg_per_seed"] = [
                    r["conditions"][cond][set_name]["summary"][variant]["mcp_error_deg"]
                    for r in runs]
    out["config"]["seeds"] = list(range(o.seed, o.seed + o.seeds))
    out["users"] = [r["users"] for r in runs]
    return out


#: The conditions after the calibration session (a later wearing or wearer).
LATER_CONDITIONS = ("new_session", "second_user", "second_user_raw")
#: The motion sets of a later condition.
MOTION_SETS = ("representative", "other")


@dataclass(frozen=True, eq=False)
class EvalTestData:
    """The test samples of one cell of :func:`evaluate`, with what made them.

    Attributes
    ----------
    condition : str
        One of :data:`LATER_CONDITIONS`.
    motion_set : str
        ``"representative"`` (the calibrated motions) or ``"other"``
        (:data:`OTHER_MOTIONS`).
    user : GloveUser
        The wearer of this session.
    donning : SensorParams
        The glove as worn in this session (the simulator's true sensor model).
    recording : GloveRecording
        The session: raw readings, motion labels and the noise-free ``truth``.
    sensors : ndarray, shape (N, 5), counts
        The readings the estimators are given: the raw ones mapped onto the
        calibration's by the range calibration, or the raw ones for
        ``"second_user_raw"``.
    normalizer : RangeNormalizer or None
        The range calibration of this session (None for ``"second_user_raw"``).
    session_seed : int
        The `seed` of :func:`simulate_session` that made ``recording`` (with
        ``user``, ``donning``, the motions of the set and the setup's
        ``test_trials``).
    """

    condition: str
    motion_set: str
    user: GloveUser
    donning: SensorParams
    recording: GloveRecording
    sensors: np.ndarray
    normalizer: RangeNormalizer | None
    session_seed: int


@dataclass(frozen=True, eq=False)
class EvalSetup:
    """What one seed of :func:`evaluate` simulates and calibrates.

    Made by :func:`eval_setup`; :meth:`test_data` gives the samples of each
    later cell, so that other studies can use exactly the evaluation's data.

    Attributes
    ----------
    kind : str
    seed : int
    test_trials : int
        Trials per motion of each later session.
    users : dict of str to GloveUser
        ``"calibration"`` (the calibration user) and ``"second"``.
    donnings : dict of str to SensorParams
        The glove as worn in the calibration session (``"calibration"``)
        and in each of :data:`LATER_CONDITIONS`.
    calibration : GloveRecording
        The calibration session (trials of the representative motions).
    range_reference : tuple of ndarray
        Median readings (open hand, fist) of the calibration session's range
        holds, each shape (5,).
    estimators : dict of str to GloveEstimator
        Everything :func:`calibrate` fits on ``calibration``.
    """

    kind: str
    seed: int
    test_trials: int
    users: dict
    donnings: dict
    calibration: GloveRecording
    range_reference: tuple
    estimators: dict

    def test_data(self, condition: str, motion_set: str) -> EvalTestData:
        """The samples of cell (`condition`, `motion_set`) of :func:`evaluate`.

        Raises
        ------
        InvalidInputError
            Unknown condition or motion set.
        """
        if condition not in LATER_CONDITIONS:
            raise InvalidInputError(f"condition must be one of {', '.join(LATER_CONDITIONS)}, "
                                    f"got {condition!r}")
        if motion_set not in MOTION_SETS:
            raise InvalidInputError(f"motion set must be one of {', '.join(MOTION_SETS)}, "
                                    f"got {motion_set!r}")
        user = self.users["calibration" if condition == "new_session" else "second"]
        don = self.donnings[condition]
        s_seed = self.seed + (20 if condition == "new_session" else 30)
        motions = motions_for(self.kind) if motion_set == "representative" else OTHER_MOTIONS
        session_seed = s_seed + (0 if motion_set == "representative" else 1)
        rec = simulate_session(user, don, list(motions), trials=self.test_trials,
                               seed=session_seed)
        norm = None
        if condition != "second_user_raw":
            src = range_readings(simulate_range_holds(user, don, seed=s_seed + 2))
            assert src is not None  # _range_holds labels both holds
            norm = RangeNormalizer(source_open=src[0], source_fist=src[1],
                                   target_open=self.range_reference[0],
                                   target_fist=self.range_reference[1])
        sensors = norm.apply(rec.sensors) if norm is not None else rec.sensors
        return EvalTestData(condition=condition, motion_set=motion_set, user=user, donning=don,
                            recording=rec, sensors=sensors, normalizer=norm,
                            session_seed=session_seed)


def eval_setup(options: EvalOptions | None = None, seed: int | None = None) -> EvalSetup:
    """Users, donnings, calibration session and estimators of one seed of :func:`evaluate`.

    Parameters
    ----------
    options : EvalOptions
        Kind, trials, test trials and calibration options.
    seed : int
        The seed (default ``options.seed``).

    Returns
    -------
    EvalSetup
    """
    o = check_options(options, EvalOptions)
    seed = o.seed if seed is None else int(seed)
    user_a = make_user(seed, name="calibration user", hand_length=1.04, config=o.config)
    user_b = make_user(seed + 1000, name="second user", hand_length=0.94, config=o.config)
    don_a1 = don_glove(user_a, o.kind, seed=seed + 1, glove_seed=seed, config=o.config)
    don_a2 = don_glove(user_a, o.kind, seed=seed + 2, glove_seed=seed, config=o.config)
    don_b = don_glove(user_b, o.kind, seed=seed + 3, glove_seed=seed, config=o.config)
    cal = simulate_session(user_a, don_a1, motions_for(o.kind), trials=o.trials, seed=seed + 10)
    ref = range_readings(simulate_range_holds(user_a, don_a1, seed=seed + 11))
    assert ref is not None  # _range_holds labels both holds
    return EvalSetup(kind=o.kind, seed=seed, test_trials=o.test_trials,
                     users={"calibration": user_a, "second": user_b},
                     donnings={"calibration": don_a1, "new_session": don_a2,
                               "second_user": don_b, "second_user_raw": don_b},
                     calibration=cal, range_reference=ref,
                     estimators=calibrate(cal, options=o.calibration))


def _evaluate_one(o: EvalOptions, seed: int) -> dict:
    kind = o.kind
    rep = motions_for(kind)
    setup = eval_setup(o, seed)
    cal, estimators = setup.calibration, setup.estimators

    conditions = {}
    # leave one trial out (the seed's setting)
    preds: dict[str, list[np.ndarray]] = {}
    parts = []
    for k in range(o.trials):
        test = cal.select(cal.trial == k)
        est_k = calibrate(cal.select(cal.trial != k), options=o.calibration,
                          where=f"calibration without trial {k}")
        for name, (est, known) in _variants(est_k, True).items():
            preds.setdefault(name, []).append(_predict(est, known, test, test.sensors))
        parts.append(test)
    loto = GloveRecording.concatenate(parts)
    conditions["loto"] = {"representative": _table(
        {n: np.vstack(p) for n, p in preds.items()}, loto)}

    for cond in LATER_CONDITIONS:
        conditions[cond] = {}
        for set_name in MOTION_SETS:
            data = setup.test_data(cond, set_name)
            rec, sensors = data.recording, data.sensors
            res = _evaluate_on(estimators, rec, sensors, set_name == "representative")
            m4 = estimators.get("model4")
            if set_name == "representative" and isinstance(m4, RegressionEstimator):
                res["mixing_weight_of_true_motion"] = _mixing_accuracy(m4, rec, sensors)
            conditions[cond][set_name] = res

    fit_r2 = {}
    for name in o.calibration.models:
        est = estimators[name]
        assert isinstance(est, RegressionEstimator)
        fit_r2[name] = {m: {f: round(est.models[m].fits[j].r2, 4) for f, j in zip(FINGERS, _MCP)}
                        for m in est.motions}
    return {
        "config": {"kind": kind, "simulator": dataclasses.asdict(o.config),
                   "trials": o.trials, "test_trials": o.test_trials,
                   "seed": seed, "rate_hz": 60.0, "models": list(o.calibration.models),
                   "t_threshold": o.calibration.t_threshold,
                   "n_points": o.calibration.n_points,
                   "synergy_k": o.calibration.synergy_k,
                   "representative_motions": list(rep),
                   "other_motions": list(OTHER_MOTIONS),
                   "joint3": dict(zip(FINGERS, ("thumb_cmc_flex", "index_mcp_flex",
                                                "middle_mcp_flex", "ring_mcp_flex",
                                                "little_mcp_flex"))),
                   "errors": "mean absolute error against the simulated truth, deg"},
        "users": {u.name: {"hand_length": round(u.hand_length, 3),
                           "dip_ratio": [round(float(x), 3) for x in u.dip_ratio]}
                  for u in setup.users.values()},
        "fit_r2": fit_r2,
        "conditions": conditions,
    }
