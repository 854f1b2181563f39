"""Figures of a localisation run (:class:`~wheelbase.localization.mrclam.LocalizationResult`)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from wheelbase.plot import agg_pyplot, save_and_close

__all__ = ["plot_error", "plot_paths"]


def plot_paths(result: Any, path: str | Path, title: str = "") -> Path:
    """The true path, the estimate and dead reckoning on the landmark map.

    Parameters
    ----------
    result : LocalizationResult
        A run of :func:`wheelbase.localization.mrclam.localize`.
    path : str or Path
        PNG file to write.
    title : str
        Figure title.

    Returns
    -------
    Path
    """
    plt = agg_pyplot()
    fig, ax = plt.subplots(figsize=(7.5, 7.5))
    ax.plot(*result.truth[:, :2].T, color="k", lw=1.2, label="ground truth (Vicon)")
    ax.plot(*result.estimate[:, :2].T, color="tab:blue", lw=0.9, label=result.filter.upper())
    ax.plot(*result.dead_reckoning[:, :2].T, color="tab:red", lw=0.8, ls="--",
            label="dead reckoning")  # fmt: skip
    ax.plot(*result.landmarks.T, "*", color="tab:green", ms=12, label="landmarks")
    ax.plot(*result.truth[0, :2], "ko", ms=6)
    ax.set_aspect("equal")
    ax.grid(True, alpha=0.3)
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_title(title)
    ax.legend(loc="best", fontsize=8)
    return save_and_close(fig, path)


def plot_error(result: Any, path: str | Path, title: str = "") -> Path:
    """Position error against time with the filter's 3σ bound 3·√(σ_x² + σ_y²).

    Parameters
    ----------
    result : LocalizationResult
        A run of :func:`wheelbase.localization.mrclam.localize`.
    path : str or Path
        PNG file to write.
    title : str
        Figure title.

    Returns
    -------
    Path
    """
    plt = agg_pyplot()
    error = np.hypot(*(result.estimate[:, :2] - result.truth[:, :2]).T)
    bound = 3.0 * np.sqrt(np.maximum(result.cov[:, 0, 0] + result.cov[:, 1, 1], 0.0))
    fig, ax = plt.subplots(figsize=(10, 4))
    ax.plot(result.t, error, color="tab:blue", lw=0.9, label="position error")
    ax.plot(result.t, bound, color="tab:orange", lw=0.8, label="3σ bound")
    ax.set_xlabel("time [s]")
    ax.set_ylabel("error [m]")
    ax.set_ylim(0.0, max(1.2 * float(np.percentile(error, 99.5)), 0.1))
    ax.grid(True, alpha=0.3)
    ax.set_title(title)
    ax.legend(loc="upper right", fontsize=8)
    return save_and_close(fig, path)
