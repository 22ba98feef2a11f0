"""Plots of an IMU evaluation: orientation error over time, side-view stick figure.

Matplotlib is imported here only, lazily, and drawn with the Agg canvas
directly (never through pyplot), so the caller's backend and figures are
never touched; the PNG is written atomically by :func:`handsynth._io.atomic_open`.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..._io import atomic_open

__all__ = ["plot_orientation_error", "plot_stick_figure"]


def _figure(figsize):
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=figsize)  # dpi from rcParams, as pyplot's figures
    FigureCanvasAgg(fig)
    return fig


def _save(fig, path, inputs) -> Path:
    with atomic_open(path, "wb", what="plot", inputs=inputs) as f:
        fig.savefig(f, format="png", dpi=110)
    return Path(path)


def plot_orientation_error(t, errors: dict, path, *, title: str = "", inputs=()) -> Path:
    """Mean orientation error over the segments against time, one line per filter.

    Parameters
    ----------
    t : ndarray, shape (N,), s
    errors : dict
        filter -> (N,) error in degrees.
    path : path-like
        PNG to write (atomically).
    title : str, keyword-only
    inputs : iterable of path-like, keyword-only
        Files the caller read; `path` must be none of them.

    Returns
    -------
    pathlib.Path

    Raises
    ------
    OutputError
        `path` cannot be written (its folder is missing, it is a folder...),
        naming it; nothing is left under `path` then.
    """
    fig = _figure((7, 3.5))
    ax = fig.subplots()
    for name, e in errors.items():
        ax.plot(t, e, label=name, lw=1)
    ax.set_xlabel("time [s]")
    ax.set_ylabel("orientation error, mean of segments [deg]")
    ax.set_yscale("log")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7, ncol=2)
    ax.set_title(title, fontsize=9)
    fig.tight_layout()
    return _save(fig, path, inputs)


def plot_stick_figure(chains: dict, path, *, title: str = "", inputs=()) -> Path:
    """Side view (world y-z plane) of the chains from the elbow, truth and estimates.

    Parameters
    ----------
    chains : dict
        label -> dict finger -> (L + 1, 3) points from the elbow (metres).
    path : path-like
        PNG to write (atomically).
    title, inputs : keyword-only
        As in :func:`plot_orientation_error`.

    Returns
    -------
    pathlib.Path

    Raises
    ------
    OutputError
        As in :func:`plot_orientation_error`.
    """
    fig = _figure((6, 4))
    ax = fig.subplots()
    styles = ["-k", "--r", ":b", "-.g"]
    for (label, fingers), style in zip(chains.items(), styles):
        for k, pts in enumerate(fingers.values()):
            p = np.asarray(pts) * 1e3
            ax.plot(p[:, 1], p[:, 2], style, lw=1.2, marker="o", ms=2,
                    label=label if k == 0 else None)
    ax.set_xlabel("y [mm] (forearm axis)")
    ax.set_ylabel("z [mm] (up)")
    ax.set_aspect("equal")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    ax.set_title(title, fontsize=9)
    fig.tight_layout()
    return _save(fig, path, inputs)
