"""The camera estimators the protocol compares, by name, and its headline figures.

:func:`run_protocol` takes estimators as factories ``(rest_frame, hand) ->
estimator``; :func:`protocol_methods` makes them for the names users give
(``handsynth eval --protocol --conditions ...``), building the databases and
learning the estimators they need into one folder, and
:func:`protocol_headline` reduces a protocol's result to the figures the
docs/camera_estimator.md reports (finger flexion MAE beside the constant, skill, index PIP
where it moves).
"""

from __future__ import annotations

import time
from dataclasses import asdict
from pathlib import Path

import numpy as np

from .._checks import check_options
from ..db import BuildOptions, LearningSetOptions, build_databases
from ..errors import InvalidInputError
from ..estimate import (
    LEARNED_ENSEMBLES,
    LearnedOptions,
    PoseLookup,
    learned_ensemble,
    learned_estimator,
    select_shape,
)
from ..models import HandShape
from ..render import CameraMount, as_mount

__all__ = ["LEARNED_METHODS", "PROTOCOL_METHODS", "describe_methods", "format_headline",
           "protocol_headline", "protocol_methods"]

#: The learnt estimators by name (options chosen on model hands: docs/camera_estimator.md, "Camera
#: estimator for unseen hands").
LEARNED_METHODS: dict[str, LearnedOptions] = {
    "fingers": LearnedOptions(kind="fingers"),
    "fingers_mean": LearnedOptions(kind="fingers", local="mean"),
    "mlp": LearnedOptions(kind="mlp"),
    "knn": LearnedOptions(kind="knn", k=8),
    "fingers_norest": LearnedOptions(kind="fingers", use_rest=False),
}

#: Every name :func:`protocol_methods` knows: the paper's lookups, the
#: calibrated lookup, the learnt estimators and ``ensemble``
#: (:data:`~handsynth.estimate.LEARNED_ENSEMBLE`: the weighted mean of ``fingers`` and three
#: perceptrons, one of them learnt from relaxed rests) and ``perceptrons``
#: (:data:`~handsynth.estimate.LEARNED_PERCEPTRONS`: those perceptrons alone).
PROTOCOL_METHODS: tuple[str, ...] = ("standard", "selected", "calibrated", *LEARNED_METHODS,
                                     *LEARNED_ENSEMBLES)


def protocol_methods(names, folder, *, data: LearningSetOptions | None = None,
                     mount: CameraMount | None = None, progress=None, workers: int = 1) -> dict:
    """Estimator factories for :func:`~handsynth.eval.run_protocol`.

    Parameters
    ----------
    names : sequence of str
        From :data:`PROTOCOL_METHODS`: ``standard`` (the paper's lookup in
        the standard hand's 20,448-entry database), ``selected`` (the
        database chosen by formulas (1)-(4) from the hand's measurements;
        hands without measurements are skipped), ``calibrated``
        (:meth:`PoseLookup.from_open_frame` on the hand's rest frame), the
        learnt estimators of :data:`LEARNED_METHODS` (calibrated to the rest
        frame when they read one), ``ensemble`` and ``perceptrons``.
    folder : str or os.PathLike
        Where databases (``folder/dbs``) and learnt estimators are built
        when missing and read when present.
    data : LearningSetOptions, keyword-only, optional
        The learning set of the learnt estimators.
    mount : CameraMount, keyword-only, optional
        The device (the paper's by default).
    progress : callable, keyword-only, optional
        Called with a line of text at each stage.
    workers : int, keyword-only
        Processes rendering a learning set the folder lacks (default 1).

    Returns
    -------
    dict
        Name to a factory ``(rest_frame, hand) -> estimator or None``.

    Raises
    ------
    InvalidInputError
        An unknown or repeated name, or none.
    """
    names = list(names)
    bad = [n for n in names if n not in PROTOCOL_METHODS]
    if bad or not names or len(set(names)) != len(names):
        raise InvalidInputError(f"methods must be distinct names from "
                                f"{', '.join(PROTOCOL_METHODS)}, got {', '.join(names) or 'none'}")
    mount = as_mount(mount)
    say = progress or (lambda _line: None)
    folder = Path(folder)
    dbs = folder / "dbs"
    out: dict = {}
    if {"standard", "selected"} & set(names):
        build_databases(dbs, [HandShape()], mount, options=BuildOptions(), workers=1)
        standard = PoseLookup.open(dbs, shape=HandShape())
    if "standard" in names:
        out["standard"] = lambda rest, hand: standard
    if "selected" in names:
        def selected(rest, hand):
            if hand.measurements is None:
                return None
            shape = select_shape(hand.measurements).shape
            build_databases(dbs, [shape], mount, options=BuildOptions(), workers=1)
            return PoseLookup.open(dbs, shape=shape)
        out["selected"] = selected
    if "calibrated" in names:
        out["calibrated"] = lambda rest, hand: PoseLookup.from_open_frame(dbs, rest, mount=mount,
                                                                          workers=1)
    needed = set(names)
    built = {}
    for name, opts in LEARNED_METHODS.items():
        if name in needed:
            t0 = time.perf_counter()
            built[name] = learned_estimator(folder, opts, data=data, mount=mount, progress=say,
                                            workers=workers)
            say(f"{name}: ready in {time.perf_counter() - t0:.1f} s")
    for name, est in built.items():
        if name in names:
            out[name] = ((lambda rest, hand, est=est: est.calibrated(rest))
                         if est.options.use_rest else (lambda rest, hand, est=est: est))
    for name, members in LEARNED_ENSEMBLES.items():
        if name in names:
            ens = learned_ensemble(folder, members=members, data=data, mount=mount,
                                   progress=say, learnt=built.values(), workers=workers)
            out[name] = lambda rest, hand, ens=ens: ens.calibrated(rest)
    return {n: out[n] for n in names}


def describe_methods(names, *, data: LearningSetOptions | None = None) -> dict:
    """What each method of :func:`protocol_methods` is, as JSON-ready values.

    So that a protocol's report says which estimators its figures belong to:
    the learnt estimators' options (those of every ensemble member, with its
    weight) and their learning set; the lookups by what they read.

    Parameters
    ----------
    names : sequence of str
        From :data:`PROTOCOL_METHODS`.
    data : LearningSetOptions, keyword-only, optional
        The learnt estimators' learning set (the default set when omitted).

    Returns
    -------
    dict
        Name to a description: ``{"lookup": ...}`` for the database
        lookups, ``{"learnt": options}`` for a learnt estimator and
        ``{"ensemble": [{"learnt": options, "weight": w,
        "learning_set_changes": {...}}, ...]}`` (what a member's learning
        set changes from the others'); the key
        ``"learning_set"`` holds the learning set's options when a learnt
        method is among `names`.

    Raises
    ------
    InvalidInputError
        A name not in :data:`PROTOCOL_METHODS`.
    """
    lookups = {"standard": "the paper's lookup, standard hand's 20,448-entry database",
               "selected": "the paper's lookup, database chosen by formulas (1)-(4)",
               "calibrated": "PoseLookup.from_open_frame on the hand's rest frame"}
    out: dict = {}
    for name in names:
        if name in lookups:
            out[name] = {"lookup": lookups[name]}
        elif name in LEARNED_METHODS:
            out[name] = {"learnt": asdict(LEARNED_METHODS[name])}
        elif name in LEARNED_ENSEMBLES:
            out[name] = {"ensemble": [{"learnt": asdict(o), "weight": w,
                                       "learning_set_changes": dict(changes)}
                                      for o, w, changes in LEARNED_ENSEMBLES[name]]}
        else:
            raise InvalidInputError(f"methods must be names from {', '.join(PROTOCOL_METHODS)}, "
                                    f"got {name!r}")
    if any("lookup" not in v for v in out.values()):
        out["learning_set"] = asdict(check_options(data, LearningSetOptions, name="data"))
    return out


def _finite(value) -> float:
    """`value` as a float, NaN for None, a non-number or a non-finite number."""
    if value is None or isinstance(value, bool):
        return float("nan")
    try:
        v = float(value)
    except (TypeError, ValueError):
        return float("nan")
    return v if np.isfinite(v) else float("nan")


def protocol_headline(result: dict) -> dict:
    """Headline figures of a :func:`~handsynth.eval.run_protocol` result.

    Parameters
    ----------
    result : dict
        A :func:`~handsynth.eval.run_protocol` result.  Read: its
        ``options["pose_sets"]`` and, of every hand, its ``kind`` and per
        pose set and method the ``method`` and ``constant`` figures'
        ``groups_mae_deg["finger_flexion"]`` and the method's
        ``joints["index_pip_flex"]["moving_mae_deg"]``.  A figure may be
        None or NaN (a method that found the hand in no frame, an index PIP
        that never moves): it is left out, never averaged in.

    Returns
    -------
    dict
        ``"<hand kind>/<pose set>/<method>"`` to the finger flexion MAE, the
        constant's, the skill and the index PIP MAE on frames where it truly
        moves (means over the hands of that kind; degrees).  Each value is a
        dict: ``flexion_mae`` and ``constant`` (2 decimals), ``skill``
        (``1 - flexion_mae / constant`` of the unrounded means, 3 decimals),
        ``index_pip_moving_mae`` (2 decimals, over the hands that have
        the figure), ``hands`` (how many hands the flexion figures are the
        mean of: those with both the method's and the constant's figure) and
        ``note``: None, or why a figure is None or leaves hands out.  A
        figure no hand has is None, never NaN: ``flexion_mae``,
        ``constant`` and ``skill`` when no hand has both flexion figures,
        ``skill`` also when the constant's MAE is 0 (the fingers never
        moved from the open hand), ``index_pip_moving_mae`` when the index
        PIP moved in no hand's frames.

    Raises
    ------
    InvalidInputError
        `result` is not shaped as :func:`~handsynth.eval.run_protocol`
        returns it (a key missing), naming what is missing.
    """
    rows: dict = {}
    try:
        for name, hand in result["hands"].items():
            for ps in result["options"]["pose_sets"]:
                for m, s in hand.get(ps, {}).items():
                    rows.setdefault(f"{hand['kind']}/{ps}/{m}", []).append((
                        name,
                        _finite(s["method"]["groups_mae_deg"]["finger_flexion"]),
                        _finite(s["constant"]["groups_mae_deg"]["finger_flexion"]),
                        _finite(s["method"]["joints"]["index_pip_flex"]["moving_mae_deg"])))
    except (KeyError, TypeError, AttributeError) as exc:
        raise InvalidInputError(f"result is not a run_protocol result: {type(exc).__name__} "
                                f"{exc}") from None
    out = {}
    for key, vals in rows.items():
        names = [v[0] for v in vals]
        a = np.array([v[1:] for v in vals], float).reshape(-1, 3)
        both = np.isfinite(a[:, 0]) & np.isfinite(a[:, 1])
        pip = a[:, 2][np.isfinite(a[:, 2])]
        notes = []
        if not both.all():
            left = [n for n, ok in zip(names, both, strict=True) if not ok]
            why = "no frame with a reading: the method found no hand, or there were no frames"
            notes.append(f"no flexion figure ({', '.join(left)}: {why})" if not both.any() else
                         f"{len(left)} of {len(names)} hands left out ({', '.join(left)}: {why})")
        flexion = float(np.mean(a[both, 0])) if both.any() else None
        constant = float(np.mean(a[both, 1])) if both.any() else None
        skill = None
        if flexion is not None and constant is not None:
            if constant > 0:
                skill = round(1.0 - flexion / constant, 3)
            else:
                notes.append("no skill: the constant's flexion MAE is 0 (the fingers never "
                             "moved from the open hand)")
        if not len(pip):
            notes.append("no index PIP figure: no frame where it moved and the hand was found")
        out[key] = {"flexion_mae": None if flexion is None else round(flexion, 2),
                    "constant": None if constant is None else round(constant, 2),
                    "skill": skill,
                    "index_pip_moving_mae": round(float(pip.mean()), 2) if len(pip) else None,
                    "hands": int(both.sum()),
                    "note": "; ".join(notes) or None}
    return out


def _fmt(value, spec: str) -> str:
    return "-" if value is None else format(value, spec)


def format_headline(headline: dict) -> str:
    """The headline of :func:`protocol_headline` as lines of text, one per condition.

    Parameters
    ----------
    headline : dict
        As :func:`protocol_headline` returns it: a condition's key to its
        ``flexion_mae``, ``constant``, ``skill`` and ``index_pip_moving_mae``
        (None is printed as ``-``) and its ``note`` (printed in brackets at
        the end of the line when there is one).

    Returns
    -------
    str
        One line per key, in the dict's order, joined by newlines (none at
        the end); MAEs in degrees.  Empty for an empty `headline`.
    """
    lines = []
    for key, v in headline.items():
        pip = v.get("index_pip_moving_mae")
        line = (f"{key:32s} flexion MAE {_fmt(v.get('flexion_mae'), '6.2f'):>6s} (constant "
                f"{_fmt(v.get('constant'), '6.2f'):>6s}, skill {_fmt(v.get('skill'), '+.3f')}); "
                f"index PIP where it moves: MAE {_fmt(pip, '.1f')}")
        if v.get("note"):
            line += f" [{v['note']}]"
        lines.append(line)
    return "\n".join(lines)
