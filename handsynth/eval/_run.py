"""Running the camera evaluation: render the test hands, look them up, tally (:func:`evaluate`)."""

from __future__ import annotations

import time
from collections import OrderedDict
from collections.abc import Callable
from dataclasses import replace

import numpy as np

from ..errors import InvalidInputError
from ..estimate import PoseLookup, select_shape_from_frame
from ..models import JOINT_NAMES, HandShape
from ..models import pose_set as make_pose_set
from ._hands import (
    _mesh_measurements,
    _mesh_renderer_factory,
    _plan_hands,
    _pose_seed,
    _TestHand,
)
from ._options import CALIBRATION_DILATION_PX, CALIBRATION_TEMPERATURE_PX, EvalOptions
from ._report import EvalReport
from ._stats import silhouette_ambiguity

__all__ = ["evaluate"]


class _Lookups:
    """Opened databases by shape, the few most recent kept in memory."""

    def __init__(self, paths: dict, *, ties: str, keep: int = 4) -> None:
        self.paths, self.keep, self.ties = paths, keep, ties
        self._open: OrderedDict[str, PoseLookup] = OrderedDict()
        self.ambiguity: dict[str, dict] = {}

    def __getitem__(self, shape: HandShape) -> PoseLookup:
        from ..db import open_database

        name = shape.name
        if name in self._open:
            self._open.move_to_end(name)
            return self._open[name]
        db = open_database(self.paths[name])
        if name not in self.ambiguity:
            self.ambiguity[name] = silhouette_ambiguity(db)
        lookup = PoseLookup(db, temporal=False, ties=self.ties)
        self._open[name] = lookup
        while len(self._open) > self.keep:
            self._open.popitem(last=False)
        return lookup


def _calibration_frames(hands: list[_TestHand], options: EvalOptions, mesh) -> dict:
    """Render each hand open and flat; choose its ``calibrated`` database from that frame."""
    zero = np.zeros((1, len(JOINT_NAMES)))
    frames = {}
    for hand in hands:
        if mesh is not None:
            frame = mesh.masks(zero)[0]
        else:
            with _model_renderer(hand.model_ratios(), options) as r:
                frame = r.masks(zero)[0]
        sel = select_shape_from_frame(frame, mount=options.camera(), side=options.side)
        hand.databases["calibrated"] = sel.shape
        hand.selection["open_frame"] = sel.shape
        frames[hand.index] = frame
    return frames


def _model_renderer(shape: HandShape, options: EvalOptions):
    from ..render import SilhouetteRenderer

    w, h = options.frame_size
    return SilhouetteRenderer(shape, options.camera(), side=options.side, width_px=w, height_px=h)


def evaluate(options: EvalOptions, *,
             progress: Callable[[str], None] | None = None) -> EvalReport:
    """Run the accuracy experiment: standard vs selected database on known poses.

    For each test hand: choose its databases (module docstring), build the
    missing ones in ``options.db_folder``, render ``frames_per_hand`` poses
    of each pose set at ``options.frame_size`` and look every frame up in
    the database of each condition (:class:`PoseLookup`, no temporal seed:
    frames are independent).

    Parameters
    ----------
    options : EvalOptions
    progress : callable, keyword-only, optional
        Called with one line of text at each step.

    Returns
    -------
    EvalReport

    Raises
    ------
    InvalidInputError
        `options` is not an :class:`EvalOptions`.
    DatabaseError
        A database could not be built or read.
    """
    from ..db import BuildOptions, build_databases, database_path

    if not isinstance(options, EvalOptions):
        raise InvalidInputError(f"options must be EvalOptions, got {type(options).__name__}")
    say = progress or (lambda _line: None)
    mount = options.camera()
    timing = {"build": 0.0, "render": 0.0, "lookup": 0.0}

    mesh = None
    mesh_meas = None
    if options.hand == "mesh":
        w, h = options.frame_size
        mesh = _mesh_renderer_factory()(mount, side=options.side, width_px=w, height_px=h)
        mesh_meas = _mesh_measurements(mesh)
    hands = _plan_hands(options, mesh_meas)
    open_frames = _calibration_frames(hands, options, mesh) if "calibrated" in options.conditions \
        else {}

    needed: dict[str, HandShape] = {}
    for hand in hands:
        for shape in hand.databases.values():
            needed.setdefault(shape.name, shape)
    build = BuildOptions(pose_set=options.db_pose_set, count=options.count, seed=options.db_seed,
                         side=options.side)
    if options.render_size is not None:
        build = replace(build, render_size=options.render_size)
    say(f"databases: {len(needed)} shape(s) of {options.count} entries in {options.db_folder}")
    t = time.perf_counter()
    summary = build_databases(options.db_folder, list(needed.values()), mount,
                              options=build, workers=options.workers)
    timing["build"] = time.perf_counter() - t
    say(f"databases: {len(summary.built)} built, {len(summary.skipped)} verified and kept "
        f"({timing['build']:.1f} s)")
    lookups = _Lookups({n: database_path(options.db_folder, s, side=options.side)
                        for n, s in needed.items()},
                       ties=options.ties)

    conds = options.conditions
    rec: dict[str, dict[str, list[np.ndarray]]] = {
        k: {c: [] for c in conds} for k in ("est", "entry", "conf", "low", "none", "dist")}
    hand_index, set_names, truth = [], [], []
    for hand in hands:
        poses = [make_pose_set(name, options.frames_per_hand,
                               seed=_pose_seed(options.seed, hand.index, k))
                 for k, name in enumerate(options.pose_sets)]
        angles = np.vstack(poses)
        n = len(angles)
        t = time.perf_counter()
        if mesh is not None:
            frames = mesh.masks(angles)
        else:
            with _model_renderer(hand.model_ratios(), options) as r:
                frames = r.masks(angles)
        cond_frames = dict.fromkeys(conds, frames)  # own_shape: rendered from its own database
        if "own_shape" in conds:
            with _model_renderer(hand.databases["own_shape"], options) as r:
                cond_frames["own_shape"] = r.masks(angles)
        timing["render"] += time.perf_counter() - t
        t = time.perf_counter()
        for cond in conds:
            lookup = lookups[hand.databases[cond]]
            if cond == "calibrated":
                lookup = lookup.calibrated(open_frames[hand.index],
                                           dilation_px=CALIBRATION_DILATION_PX,
                                           temperature_px=CALIBRATION_TEMPERATURE_PX)
            src = cond_frames[cond]
            ests = [lookup.estimate(src[i]) for i in range(n)]
            rec["est"][cond].append(np.stack([e.angles for e in ests]))
            rec["entry"][cond].append(np.array([e.entry for e in ests], np.int64))
            rec["conf"][cond].append(np.array([e.confidence for e in ests]))
            rec["low"][cond].append(np.array([e.low_confidence for e in ests], bool))
            rec["none"][cond].append(np.array([e.no_hand for e in ests], bool))
            rec["dist"][cond].append(np.full(n, hand.distance(cond)))
        timing["lookup"] += time.perf_counter() - t
        hand_index.append(np.full(n, hand.index, np.int64))
        set_names.append(np.repeat(np.array(options.pose_sets), options.frames_per_hand))
        truth.append(angles)
        desc = hand.model_ratios().name if hand.kind == "model" else hand.kind
        say(f"hand {hand.index + 1}/{len(hands)} ({desc}): {n} frames, databases "
            + ", ".join(f"{c}={s.name}" for c, s in hand.databases.items()))
    if mesh is not None and hasattr(mesh, "close"):
        mesh.close()

    def cat(key):
        return {c: np.concatenate(rec[key][c]) for c in conds}

    return EvalReport(
        options=options, hands=tuple(h.as_dict() for h in hands),
        hand_index=np.concatenate(hand_index), pose_set=np.concatenate(set_names),
        truth_deg=np.vstack(truth), estimates_deg=cat("est"), entry=cat("entry"),
        confidence=cat("conf"), low_confidence=cat("low"), no_hand=cat("none"),
        ratio_distance=cat("dist"), timing_s=timing, ambiguity=dict(lookups.ambiguity))
