"""Plots of the camera evaluation."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from .._io import atomic_open
from ..models import JOINT_NAMES

if TYPE_CHECKING:
    from ._report import EvalReport

__all__: list[str] = []


# matplotlib is imported here only, lazily, and drawn on the Agg canvas
# directly, so the caller's pyplot backend is never touched.

_COLOURS = {"standard": "tab:blue", "selected": "tab:red", "selected_none": "tab:green",
            "personal": "tab:purple", "calibrated": "tab:orange", "own_shape": "tab:grey"}


def _figure(figsize):
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=figsize, dpi=100)
    FigureCanvasAgg(fig)
    return fig


def _save(fig, path: Path) -> Path:
    with atomic_open(path, "wb", what="plot") as f:
        fig.savefig(f, format="png")
    return Path(path)


def _plot_histograms(report: EvalReport, path: Path) -> Path:
    conds: list[str] = [c for c in ("standard", "selected") if c in report.conditions] or \
        list(report.conditions[:1])
    errs = {c: report.errors(c) for c in conds}
    fig = _figure((13, 14))
    axes = fig.subplots(5, 4)
    for j, name in enumerate(JOINT_NAMES):
        ax = axes[j // 4, j % 4]
        values = [e[:, j][~np.isnan(e[:, j])] for e in errs.values()]
        both = np.concatenate(values) if values else np.zeros(1)
        lim = max(5.0, float(np.percentile(np.abs(both), 99)) if both.size else 5.0)
        bins = np.linspace(-lim, lim, 41)
        title = [name]
        for c, v in zip(conds, values):
            ax.hist(np.clip(v, -lim, lim), bins=bins, histtype="step", lw=1.4,
                    color=_COLOURS[c], label=c)
            if v.size:
                sd = v.std(ddof=1) if v.size > 1 else float("nan")
                title.append(f"{c[:3]} {v.mean():+.1f}±{sd:.1f}")
        ax.set_title("\n".join(title), fontsize=8)
        ax.tick_params(labelsize=7)
        ax.axvline(0, color="k", lw=0.5)
    axes[0, 0].legend(fontsize=7)
    for ax in axes[-1]:
        ax.set_xlabel("estimate - truth (deg)", fontsize=8)
    fig.suptitle(f"signed joint-angle error, {len(report.truth_deg)} frames, "
                 f"{len(report.hands)} hand(s) (values beyond the range pile up at its ends)")
    fig.tight_layout(rect=(0, 0, 1, 0.98))
    return _save(fig, path)


def _plot_distance(report: EvalReport, path: Path) -> Path:
    conds = [c for c in report.conditions if c != "own_shape"]
    sets = report.options.pose_sets
    panels = (("all joints", None), ("thumb CMC flexion", JOINT_NAMES.index("thumb_cmc_flex")),
              ("index PIP", JOINT_NAMES.index("index_pip_flex")))
    fig = _figure((14, 3.9 * len(sets)))
    axes = np.asarray(fig.subplots(len(sets), len(panels))).reshape(len(sets), len(panels))
    for row, ps in enumerate(sets):
        in_set = report.pose_set == ps
        for h in range(len(report.hands)):
            rows = in_set & (report.hand_index == h)
            if not rows.any():
                continue
            pts = {}
            for c in conds:
                e = np.abs(report.errors(c)[rows])
                ys = [np.nanmean(e) if j is None else np.nanmean(e[:, j]) for _, j in panels]
                pts[c] = (report.ratio_distance[c][rows][0], ys)
            for k, ax in enumerate(axes[row]):
                if "standard" in pts and "selected" in pts:
                    ax.plot([pts["standard"][0], pts["selected"][0]],
                            [pts["standard"][1][k], pts["selected"][1][k]],
                            color="0.8", lw=0.8, zorder=1)
                for c, (d, ys) in pts.items():
                    ax.scatter(d, ys[k], color=_COLOURS[c], s=22, zorder=2,
                               label=c if h == 0 else None)
        for ax, (what, _) in zip(axes[row], panels):
            ax.set_title(f"{ps} poses, {what}", fontsize=9)
            ax.set_ylabel("mean absolute error (deg)", fontsize=8)
            ax.grid(alpha=0.3)
            ax.tick_params(labelsize=7)
    for ax in axes[-1]:
        ax.set_xlabel("ratio distance of the hand from the database's shape (grid steps)",
                      fontsize=8)
    axes[0, 0].legend(fontsize=7)
    fig.suptitle("error vs ratio distance, one point per hand and database "
                 "(grey lines join a hand's standard and selected databases)", fontsize=10)
    fig.tight_layout(rect=(0, 0, 1, 0.97))
    return _save(fig, path)


def _plot_joint_mae(report: EvalReport, path: Path) -> Path:
    sets = report.options.pose_sets
    fig = _figure((13, 3.6 * len(sets)))
    axes = np.atleast_1d(fig.subplots(len(sets), 1))
    conds = report.conditions
    x = np.arange(len(JOINT_NAMES))
    w = 0.8 / len(conds)
    for ax, ps in zip(axes, sets):
        for k, c in enumerate(conds):
            s = report.stats(c, pose_set=ps)
            ax.bar(x + (k - (len(conds) - 1) / 2) * w, s.mae_deg, width=w, color=_COLOURS[c],
                   label=f"{c} (all {s.overall_mae_deg:.1f})")
        ax.set_xticks(x, JOINT_NAMES, rotation=60, ha="right", fontsize=7)
        ax.set_ylabel("MAE (deg)")
        ax.set_title(f"{ps} poses", fontsize=9)
        ax.grid(axis="y", alpha=0.3)
        ax.legend(fontsize=7, ncols=len(conds))
    fig.tight_layout()
    return _save(fig, path)
