"""Plots of an IMU evaluation: orientation error over time, side-view stick figure."""

from __future__ import annotations

from pathlib import Path

import numpy as np

__all__ = ["plot_orientation_error", "plot_stick_figure"]


def _figure():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def plot_orientation_error(t, errors: dict, path, *, title: str = "") -> Path:
    """Mean orientation error over the segments against time, one line per filter.

    Parameters
    ----------
    t : ndarray, shape (N,), s
    errors : dict
        filter -> (N,) error in degrees.
    path : path-like
        PNG to write.
    """
    plt = _figure()
    fig, ax = plt.subplots(figsize=(7, 3.5))
    for name, e in errors.items():
        ax.plot(t, e, label=name, lw=1)
    ax.set_xlabel("time [s]")
    ax.set_ylabel("orientation error, mean of segments [deg]")
    ax.set_yscale("log")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7, ncol=2)
    ax.set_title(title, fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return Path(path)


def plot_stick_figure(chains: dict, path, *, title: str = "") -> Path:
    """Side view (world y-z plane) of the chains from the elbow, truth and estimates.

    Parameters
    ----------
    chains : dict
        label -> dict finger -> (L + 1, 3) points from the elbow (metres).
    path : path-like
    """
    plt = _figure()
    fig, ax = plt.subplots(figsize=(6, 4))
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
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return Path(path)
