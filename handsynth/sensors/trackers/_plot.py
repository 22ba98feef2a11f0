"""Figure of the axis-angle histogram (the patent's Fig. 11).

Matplotlib is imported here only, lazily, and drawn with the Agg canvas
directly, so the caller's pyplot backend is never touched.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from ..._io import atomic_open
from ._axis_filter import AxisFilterResult

__all__ = ["plot_axis_histogram"]


def plot_axis_histogram(result: AxisFilterResult, path: str | os.PathLike, *, title: str = "",
                        inputs=()) -> Path:
    """Save the lateral-component histogram with the chosen bin highlighted.

    Parameters
    ----------
    result : AxisFilterResult
        From :meth:`AxisAngleFilter.apply` or ``JointCentreResult.axis_filter``.
    path : path-like
        PNG file to write.
    title : str
        Figure title.
    inputs : iterable of path-like, keyword-only
        Files the caller read; `path` must be none of them.

    Returns
    -------
    pathlib.Path
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(7, 3.6), dpi=100)
    FigureCanvasAgg(fig)
    ax_all, ax_zoom = fig.subplots(1, 2)
    widths = np.diff(result.edges)
    colours = np.where(np.arange(result.counts.size) == result.chosen_bin, "tab:red", "tab:blue")
    for ax in (ax_all, ax_zoom):
        ax.bar(result.edges[:-1], result.counts, width=widths, align="edge", color=colours)
        ax.set_xlabel("lateral component of the joint axis")
    ax_all.set_ylabel("frames")
    used = np.flatnonzero(result.counts)
    lo = result.edges[used[0]] if used.size else result.edges[0]
    ax_zoom.set_xlim(max(lo, result.edges[-1] - 0.1), result.edges[-1])
    a, b = result.chosen_range
    ax_zoom.set_title(f"chosen bin {a:.2f}-{b:.2f}: {result.frames.size} frames", fontsize=9)
    if title:
        fig.suptitle(title)
    fig.tight_layout()
    with atomic_open(path, "wb", what="plot", inputs=inputs) as f:
        fig.savefig(f, format="png")
    return Path(path)
