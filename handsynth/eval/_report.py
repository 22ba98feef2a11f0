"""The camera evaluation's report: tables, JSON and plots."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .._io import json_text, make_folder, write_json
from ..errors import InvalidInputError
from ..models import JOINT_NAMES, HandShape
from ._options import (
    _CONDITION_TEXT,
    CALIBRATION_DILATION_PX,
    CALIBRATION_TEMPERATURE_PX,
    MOVING_DEG,
    PAPER,
    SCHEMA,
    TARGET_CONDITIONS,
    TARGETS,
    EvalOptions,
)
from ._plots import _plot_distance, _plot_histograms, _plot_joint_mae
from ._stats import JointStats, _num, joint_stats

__all__ = ["EvalReport"]


#: The name of the constant answer beside the conditions (:meth:`EvalReport.errors`).
CONSTANT = "constant"
_CONSTANT_TEXT = ("the open hand (every angle 0) answered on every frame: the trivial baseline "
                  "on the same frames")
#: The first lines of :meth:`EvalReport.format`: what the paper's experiment measures.
_PAPER_NOTE = ("The paper's experiment: test poses from the databases' own pose generators,\n"
               "every joint that does not move at exactly the databases' open hand. It flatters\n"
               "the lookups: on hands whose resting fingers are a few degrees off it they read\n"
               "no better than the constant answer (handsynth eval --protocol).")


@dataclass(frozen=True, eq=False)
class EvalReport:
    """Outcome of :func:`evaluate`: per-frame records and per-joint figures.

    Attributes
    ----------
    options : EvalOptions
    hands : tuple of dict
        Per test hand: true ratios, continuous selection ratios, the
        database (shape name) of each condition and the ratio distance
        to it.
    hand_index : ndarray of int64, shape (F,)
        Test hand of each frame.
    pose_set : ndarray of str, shape (F,)
        Pose set each frame's pose came from.
    truth_deg : ndarray of float64, shape (F, 20)
        True joint angles, degrees.
    estimates_deg : dict of str to ndarray of float64, shape (F, 20)
        Estimated angles per condition (NaN rows where no hand was found).
    entry, confidence, low_confidence, no_hand, ratio_distance : dict of str to ndarray (F,)
        Per condition and frame: matched entry, confidence, fall-back flag,
        no-hand flag, and the ratio distance of the rendered hand from the
        database used (0 for ``own_shape``).
    timing_s : dict of str to float
        Seconds spent building databases, rendering and looking up.
    ambiguity : dict of str to dict
        :func:`silhouette_ambiguity` of every database used, by shape name.
    """

    options: EvalOptions
    hands: tuple[dict, ...]
    hand_index: np.ndarray
    pose_set: np.ndarray
    truth_deg: np.ndarray
    estimates_deg: dict
    entry: dict
    confidence: dict
    low_confidence: dict
    no_hand: dict
    ratio_distance: dict
    timing_s: dict
    ambiguity: dict = field(default_factory=dict)

    @property
    def conditions(self) -> tuple[str, ...]:
        """Conditions evaluated, in report order."""
        return tuple(self.estimates_deg)

    def errors(self, condition: str, *, pose_set: str | None = None) -> np.ndarray:
        """Signed errors ``estimate - truth`` (F, 20) in degrees, optionally one pose set's frames.

        `condition` is one of :attr:`conditions`, or ``"constant"``: the open hand (every
        angle 0) answered on every frame, the trivial baseline beside them.
        """
        if condition == CONSTANT:
            e = -self.truth_deg
        elif condition not in self.estimates_deg:
            raise InvalidInputError(
                f"condition must be one of {(*self.conditions, CONSTANT)}, got {condition!r}")
        else:
            e = self.estimates_deg[condition] - self.truth_deg
        return e if pose_set is None else e[self._set_rows(pose_set)]

    def _set_rows(self, pose_set: str) -> np.ndarray:
        if pose_set not in self.options.pose_sets:
            raise InvalidInputError(
                f"pose_set must be one of {self.options.pose_sets}, got {pose_set!r}")
        return self.pose_set == pose_set

    def stats(self, condition: str, *, pose_set: str | None = None,
              moving: bool = False) -> JointStats:
        """:func:`joint_stats` of one condition (all frames, or one pose set's).

        Parameters
        ----------
        condition : str
        pose_set : str, keyword-only, optional
            Only that pose set's frames.
        moving : bool, keyword-only
            Per joint, only the frames where its true angle is away from the
            open hand (``|truth| > MOVING_DEG``).  In the paper's set one
            finger moves at a time, so most frames hold a joint at 0, where
            the lookup is nearly always right; this shows the error where
            the joint actually moves.
        """
        e = self.errors(condition, pose_set=pose_set)
        if moving:
            t = self.truth_deg if pose_set is None else self.truth_deg[self._set_rows(pose_set)]
            e = np.where(np.abs(t) > MOVING_DEG, e, np.nan)
        return joint_stats(e)

    def targets(self, *, pose_set: str | None = None, condition: str = "selected") -> dict:
        """The issue's targets (:data:`TARGETS` of the hand kind) on one condition.

        Parameters
        ----------
        pose_set : str, keyword-only, optional
            Check on one pose set's frames; all frames by default.
        condition : {"selected", "personal", "calibrated"}, keyword-only
            The condition checked (:data:`TARGET_CONDITIONS`); it must also
            beat ``standard``.

        Returns
        -------
        dict
            Per target its value, limit and ``met`` flag; empty when the
            needed conditions were not evaluated.
        """
        if condition not in TARGET_CONDITIONS:
            raise InvalidInputError(
                f"condition must be one of {TARGET_CONDITIONS}, got {condition!r}")
        out = {}
        if condition in self.estimates_deg:
            sel = self.stats(condition, pose_set=pose_set)
            pip, cmc = sel.joint("index_pip_flex"), sel.joint("thumb_cmc_flex")
            mean = pip["mean_deg"]
            checks = (("index_pip_abs_mean_deg", None if mean is None else abs(mean)),
                      ("index_pip_sd_deg", pip["sd_deg"]),
                      ("thumb_cmc_sd_deg", cmc["sd_deg"]))
            limits = TARGETS[self.options.hand]
            for name, value in checks:
                if name not in limits:
                    continue
                limit = limits[name]
                out[name] = {"value": value, "limit": limit,
                             "met": bool(value is not None and value <= limit)}
        if condition in self.estimates_deg and "standard" in self.estimates_deg:
            a = self.stats("standard", pose_set=pose_set).overall_mae_deg
            b = self.stats(condition, pose_set=pose_set).overall_mae_deg
            out[f"{condition}_beats_standard"] = {"standard_mae_deg": _num(a),
                                                  "mae_deg": _num(b), "met": bool(b < a)}
        return out

    def _targets_by_set(self, condition: str) -> dict:
        return {"all": self.targets(condition=condition),
                **{ps: self.targets(pose_set=ps, condition=condition)
                   for ps in self.options.pose_sets}}

    def _condition_dict(self, cond: str) -> dict:
        def block(rows) -> dict:
            s = joint_stats((self.estimates_deg[cond] - self.truth_deg)[rows])
            return {"frames": int(rows.sum()),
                    "no_hand": int(self.no_hand[cond][rows].sum()),
                    "low_confidence": int(self.low_confidence[cond][rows].sum()),
                    "overall_mae_deg": _num(s.overall_mae_deg),
                    "joints": s.as_dict()}

        text = _CONDITION_TEXT[cond].format(dilation=CALIBRATION_DILATION_PX,
                                            temperature=CALIBRATION_TEMPERATURE_PX)
        out = {"description": text,
               "databases": sorted({h["databases"][cond] for h in self.hands}),
               "all": block(np.ones(len(self.truth_deg), bool))}
        for name in self.options.pose_sets:
            out[name] = block(self.pose_set == name)
        out["moving"] = {"note": f"per joint, frames where |truth| > {MOVING_DEG} deg",
                         **{ps or "all": self.stats(cond, pose_set=ps, moving=True).as_dict()
                            for ps in (None, *self.options.pose_sets)}}
        return out

    def _constant_dict(self) -> dict:
        def block(pose_set) -> dict:
            s = self.stats(CONSTANT, pose_set=pose_set)
            return {"overall_mae_deg": _num(s.overall_mae_deg), "joints": s.as_dict()}

        return {"description": _CONSTANT_TEXT, "all": block(None),
                **{ps: block(ps) for ps in self.options.pose_sets},
                "moving": {ps or "all": self.stats(CONSTANT, pose_set=ps, moving=True).as_dict()
                           for ps in (None, *self.options.pose_sets)}}

    def to_dict(self, *, frames: bool = False) -> dict:
        """The report as plain JSON values.

        Parameters
        ----------
        frames : bool, keyword-only
            Also include every frame's truth and estimates (large).

        Returns
        -------
        dict
            ``schema``, ``options``, ``joint_names``, ``hands``,
            ``conditions`` (per condition: ``description``, ``databases``,
            and for ``all`` frames and each pose set: ``frames``,
            ``no_hand``, ``low_confidence``, ``overall_mae_deg`` and
            ``joints`` -> name -> ``mean_deg, sd_deg, mae_deg, n``; and
            ``moving``: the same per-joint figures over the frames where the
            joint moves, for all frames and each pose set), ``constant`` (the same
            per-joint figures of the open hand answered on every frame, the trivial
            baseline: ``description``, ``all``, each pose set and ``moving``),
            ``targets`` (for ``all`` frames and each pose set; ``targets_personal``
            and ``targets_calibrated`` the same on those conditions), ``paper``, ``timing_s``,
            ``ambiguity`` (:func:`silhouette_ambiguity` per database) and optionally ``frames``.
        """
        out = {
            "schema": SCHEMA,
            "options": self.options.as_dict(),
            "joint_names": list(JOINT_NAMES),
            "hands": list(self.hands),
            "conditions": {c: self._condition_dict(c) for c in self.conditions},
            "constant": self._constant_dict(),
            "targets": self._targets_by_set("selected"),
            "targets_personal": self._targets_by_set("personal"),
            "targets_calibrated": self._targets_by_set("calibrated"),
            "paper": {c: {j: {"mean_deg": m, "sd_deg": s} for j, (m, s) in v.items()}
                      for c, v in PAPER.items()},
            "timing_s": {k: round(v, 3) for k, v in self.timing_s.items()},
            "ambiguity": self.ambiguity,
        }
        if frames:
            rows = []
            for f in range(len(self.truth_deg)):
                row = {"hand": int(self.hand_index[f]), "pose_set": str(self.pose_set[f]),
                       "truth_deg": [round(float(v), 4) for v in self.truth_deg[f]]}
                for c in self.conditions:
                    row[c] = {"angles_deg": [_num(v) for v in self.estimates_deg[c][f]],
                              "entry": int(self.entry[c][f]),
                              "confidence": _num(self.confidence[c][f]),
                              "low_confidence": bool(self.low_confidence[c][f]),
                              "no_hand": bool(self.no_hand[c][f])}
                rows.append(row)
            out["frames"] = rows
        return out

    def to_json(self, *, frames: bool = False, indent: int | None = 2) -> str:
        """:meth:`to_dict` as a JSON string (a non-finite number as ``null``)."""
        return json_text(self.to_dict(frames=frames), indent=indent)

    def write_json(self, path, *, frames: bool = False) -> Path:
        """Write :meth:`to_json` to `path` atomically (temporary file, then rename)."""
        return write_json(path, self.to_dict(frames=frames), what="JSON report")

    def write_plots(self, folder, *, prefix: str = "eval_") -> list[Path]:
        """Write the figures as PNG files (matplotlib, Agg canvas).

        * ``<prefix>error_hist.png`` -- histogram of the signed error per
          joint (5 x 4 panels), standard vs selected database;
        * ``<prefix>error_vs_distance.png`` -- per hand and pose set, mean
          absolute error against the ratio distance of the hand from the
          database used, for every database condition (all joints, thumb
          CMC flexion, index PIP);
        * ``<prefix>joint_mae.png`` -- mean absolute error per joint and
          condition, paper and natural poses side by side.

        Parameters
        ----------
        folder : str or os.PathLike
            Created if missing.
        prefix : str, keyword-only

        Returns
        -------
        list of pathlib.Path

        Raises
        ------
        OutputError
            The folder cannot be created or a file cannot be written (each
            file appears complete or not at all).
        """
        folder = make_folder(folder, what="plot folder", writable=True)
        return [_plot_histograms(self, folder / f"{prefix}error_hist.png"),
                _plot_distance(self, folder / f"{prefix}error_vs_distance.png"),
                _plot_joint_mae(self, folder / f"{prefix}joint_mae.png")]

    def format(self) -> str:
        """A plain-text table: per joint mean +- s.d. (MAE) per condition and of the constant
        answer, then the targets."""
        conds = (*self.conditions, CONSTANT)
        width = 24
        lines = [_PAPER_NOTE, f"{'joint':<16}" + "".join(f"{c:>{width}}" for c in conds)]
        stats = {c: self.stats(c) for c in conds}
        for j, name in enumerate(JOINT_NAMES):
            cells = []
            for c in conds:
                s = stats[c]
                cells.append(f"{s.mean_deg[j]:+6.2f} ±{s.sd_deg[j]:6.2f} ({s.mae_deg[j]:5.2f})")
            lines.append(f"{name:<16}" + "".join(f"{x:>{width}}" for x in cells))
        lines.append(f"{'all joints MAE':<16}"
                     + "".join(f"{stats[c].overall_mae_deg:>{width}.2f}" for c in conds))
        for ps in self.options.pose_sets:
            lines.append(f"{ps + ' poses MAE':<16}" + "".join(
                f"{self.stats(c, pose_set=ps).overall_mae_deg:>{width}.2f}" for c in conds))
        lines.append("mean ± s.d. (MAE) of estimate - truth, degrees; "
                     f"{len(self.truth_deg)} frames of {len(self.hands)} hand(s); {CONSTANT}: "
                     "the open hand answered on every frame")
        for ps in self.options.pose_sets:
            moving = {c: self.stats(c, pose_set=ps, moving=True) for c in conds}
            for name in ("index_pip_flex", "thumb_cmc_flex"):
                j = JOINT_NAMES.index(name)
                cells = [f"{m.mean_deg[j]:+6.2f} ±{m.sd_deg[j]:6.2f} ({m.mae_deg[j]:5.2f})"
                         for m in moving.values()]
                label = f"{ps} poses, {name} where it moves (n={moving[conds[0]].n[j]})"
                lines.append(f"{label}:\n{'':<16}" + "".join(f"{x:>{width}}" for x in cells))
        for cond in TARGET_CONDITIONS:
            for subset in (None, *self.options.pose_sets):  # None: all frames
                where = f"{cond}, " + ("all frames" if subset is None else f"{subset} poses")
                for name, t in self.targets(pose_set=subset, condition=cond).items():
                    verdict = "met" if t["met"] else "MISSED"
                    if "limit" in t:
                        lines.append(f"target ({where}) {name} <= {t['limit']}: {t['value']} "
                                     f"({verdict})")
                    else:
                        lines.append(f"target ({where}) {cond} beats standard: MAE "
                                     f"{t['mae_deg']} vs {t['standard_mae_deg']} ({verdict})")
        std = self.ambiguity.get(HandShape().name)
        if std:
            lines.append(
                f"standard database: {std['entries_sharing']} of {std['entries']} entries share "
                f"their 64x64 silhouette with another entry; {std['ambiguous_entries']} with a "
                f"pose differing by > {std['spread_deg']:g} deg (index PIP "
                f"{std['per_joint']['index_pip_flex']}, thumb CMC flexion "
                f"{std['per_joint']['thumb_cmc_flex']})")
        return "\n".join(lines)
