"""Figures of the ground: the terrain under a path, and slip and traction against time.

:func:`draw_terrain` colours a :class:`~wheelbase.terrain.TerrainMap`'s surfaces (one colour
each, a legend of their names) and marks the slopes with uphill arrows; :func:`figure_traction`
plots what the wheels did (:class:`~wheelbase.sim.TerrainPlant`'s signals in a
:class:`~wheelbase.sim.Log`): the slip ratio of each drive wheel, the ground's traction force
beside the normal load, and the surface under each wheel.
"""

from __future__ import annotations

from typing import Any

import numpy as np

__all__ = ["SURFACE_COLOURS", "draw_terrain", "figure_traction", "has_traction"]

SURFACE_COLOURS: dict[str, str] = {
    "dry_concrete": "#d9d9d9",
    "wet_concrete": "#6baed6",
    "ice": "#b9f0f5",
    "grass": "#a1d99b",
    "dry_sand": "#fdd49e",
    "sandy_loam": "#d6b98c",
    "clay": "#b07a55",
    "floor": "#f0f0f0",
}
"""Colour of each named surface; others take the next of matplotlib's tab10."""


def _colour(name: str, index: int) -> str:
    import matplotlib

    return SURFACE_COLOURS.get(name, matplotlib.colormaps["tab10"](index % 10))


def draw_terrain(ax: Any, terrain: Any, *, alpha: float = 0.5) -> None:
    """Colour the surfaces of ``terrain`` on ``ax`` and arrow its slopes uphill.

    Parameters
    ----------
    ax : matplotlib.axes.Axes
        Where to draw.
    terrain : TerrainMap or None
        The ground (None: nothing drawn).
    alpha : float
        Opacity of the colours.
    """
    if terrain is None:
        return
    from matplotlib.colors import ListedColormap
    from matplotlib.patches import Patch

    names = terrain.names
    colours = [_colour(name, k) for k, name in enumerate(names)]
    rows, cols = terrain.cells.shape
    x0, y0 = terrain.origin
    res = terrain.resolution
    if rows * cols > 1:
        extent = (x0, x0 + cols * res, y0, y0 + rows * res)
        ax.imshow(
            terrain.cells, origin="lower", extent=extent, cmap=ListedColormap(colours),
            vmin=-0.5, vmax=len(names) - 0.5, alpha=alpha, interpolation="nearest", zorder=1,
        )  # fmt: skip
        slope = terrain.slope
        if np.any(slope != 0):
            step = max(1, int(max(rows, cols) / 25))
            yy, xx = np.mgrid[0:rows:step, 0:cols:step]
            s = slope[::step, ::step]
            tilted = np.hypot(s[..., 0], s[..., 1]) > 0
            ax.quiver(
                x0 + (xx[tilted] + 0.5) * res, y0 + (yy[tilted] + 0.5) * res,
                s[..., 0][tilted], s[..., 1][tilted], color="0.35", alpha=0.7, width=0.002,
                zorder=2,
            )  # fmt: skip
    else:
        ax.set_facecolor(colours[0])
    handles = [Patch(color=c, alpha=alpha, label=n) for n, c in zip(names, colours, strict=True)]
    ax.add_artist(ax.legend(handles=handles, loc="upper right", fontsize=7, title="ground"))


def has_traction(log: Any) -> bool:
    """Whether ``log`` holds a terrain plant's signals (slip, traction, loads)."""
    return "slip_left" in getattr(log, "extras", {})


def figure_traction(log: Any, terrain: Any = None, *, robot: int = 0):
    """Slip, traction and loads, and the surface under each wheel, against time.

    Parameters
    ----------
    log : Log
        A run on a :class:`~wheelbase.sim.TerrainPlant` (its ``extras``).
    terrain : TerrainMap, optional
        The ground (names of the surfaces).
    robot : int
        Which robot.
    """
    import matplotlib.pyplot as plt

    extras = log.extras
    n = int(log.length[robot])
    t = log.t[:n]
    fig, axes = plt.subplots(3, 1, figsize=(8, 7.5), sharex=True)
    for side, colour in (("left", "tab:blue"), ("right", "tab:orange")):
        axes[0].plot(t, extras[f"slip_{side}"][robot, :n], color=colour, label=side)
        axes[1].plot(t, extras[f"traction_{side}"][robot, :n], color=colour, label=f"F_x {side}")
        axes[1].plot(t, extras[f"load_{side}"][robot, :n], "--", color=colour, lw=0.8,
                     label=f"N {side}")  # fmt: skip
    axes[0].set_ylabel("slip ratio κ")
    axes[0].legend(fontsize=8)
    axes[1].set_ylabel("ground force [N]")
    axes[1].legend(fontsize=7, ncol=2)
    names = terrain.names if terrain is not None else None
    for k, side in enumerate(("left", "right")):
        codes = extras[f"surface_{side}"][robot, :n].astype(int)
        for code in np.unique(codes):
            label = names[code] if names is not None and code < len(names) else str(code)
            mask = codes == code
            axes[2].fill_between(
                t,
                k,
                k + 0.8,
                where=mask,
                step="post",
                color=_colour(label, int(code)),
                label=label if k == 0 else None,
            )
    sinkage = np.maximum(extras["sinkage_left"][robot, :n], extras["sinkage_right"][robot, :n])
    if np.any(sinkage > 0):
        twin = axes[2].twinx()
        twin.plot(t, 100 * sinkage, color="k", lw=0.8)
        twin.set_ylabel("sinkage [cm]")
    axes[2].set_yticks([0.4, 1.4], ["left", "right"])
    axes[2].set_ylabel("surface")
    axes[2].legend(fontsize=7, loc="upper left", ncol=4)
    axes[-1].set_xlabel("t [s]")
    for ax in axes:
        ax.grid(True, alpha=0.3)
    axes[0].set_title(f"wheels on the ground ({log.statuses[robot]})")
    fig.tight_layout()
    return fig
