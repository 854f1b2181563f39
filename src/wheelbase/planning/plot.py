"""Matplotlib figures of maps and planned paths (no plotting inside the algorithms).

Above the paths and maps it draws: they never import it (``plot_path(path, grid=...)``).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike

from wheelbase.geometry import transform_points

if TYPE_CHECKING:
    from wheelbase.planning.footprint import Footprint
    from wheelbase.planning.occupancy import OccupancyGrid
    from wheelbase.planning.path import PlannedPath
    from wheelbase.planning.world import PolygonWorld

__all__ = ["draw_obstacles", "plot_grid", "plot_path"]


def draw_obstacles(ax: Any, world: PolygonWorld, color: Any = "black") -> None:
    """Draw a polygon world's polygons (holes left open) and discs, exactly, as filled shapes.

    Parameters
    ----------
    ax : matplotlib.axes.Axes
        Axes to draw on.
    world : PolygonWorld
        The world (its grid, if any, is not drawn here).
    color : color
        Fill colour.
    """
    from matplotlib.patches import Circle, PathPatch
    from matplotlib.path import Path as MplPath

    def oriented(ring: np.ndarray, ccw: bool) -> np.ndarray:
        area2 = np.sum(ring[:, 0] * np.roll(ring[:, 1], -1) - np.roll(ring[:, 0], -1) * ring[:, 1])
        return ring if (area2 > 0) == ccw else ring[::-1]

    for exterior, holes in world.polygons:
        # exterior counter-clockwise, holes clockwise: the non-zero fill rule leaves holes open
        rings = [oriented(exterior, True), *(oriented(h, False) for h in holes)]
        vertices = np.concatenate([np.vstack([r, r[:1]]) for r in rings])
        codes = np.concatenate(
            [[MplPath.MOVETO, *[MplPath.LINETO] * (len(r) - 1), MplPath.CLOSEPOLY] for r in rings]
        )
        ax.add_patch(PathPatch(MplPath(vertices, codes), facecolor=color, edgecolor=color, lw=0.5))
    for x, y, r in world.discs:
        ax.add_patch(Circle((x, y), r, facecolor=color, edgecolor=color, lw=0.5))


def plot_grid(grid: OccupancyGrid | PolygonWorld, ax: Any = None) -> Any:
    """Draw a map in world coordinates [m]: an occupancy grid (occupied black, unknown grey),
    or a polygon world's exact polygons and discs (over its grid, if it has one).

    Parameters
    ----------
    grid : OccupancyGrid or PolygonWorld
        The map.
    ax : matplotlib.axes.Axes or None
        Axes to draw on; a new figure when ``None``.

    Returns
    -------
    matplotlib.axes.Axes
    """
    import matplotlib.pyplot as plt

    from wheelbase.planning.world import PolygonWorld

    if ax is None:
        _, ax = plt.subplots(figsize=(8, 8 * grid.height_m / max(grid.width_m, 1e-9) + 0.5))
    cells = grid.grid if isinstance(grid, PolygonWorld) else grid
    if cells is not None:
        image = np.where(cells.occupied, 0.0, 1.0)
        if cells.unknown is not None:
            image = np.where(cells.unknown, 0.75, image)
        ax.imshow(image, origin="lower", extent=cells.extent, cmap="gray", vmin=0, vmax=1)
    if isinstance(grid, PolygonWorld):
        draw_obstacles(ax, grid)
        x0, x1, y0, y1 = grid.extent
        ax.set_xlim(x0, x1)
        ax.set_ylim(y0, y1)
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_aspect("equal")
    return ax


def plot_path(
    path: PlannedPath,
    ax: Any = None,
    *,
    grid: OccupancyGrid | PolygonWorld | None = None,
    footprint: Footprint | None = None,
    footprint_every: float = 2.0,
    start: ArrayLike | None = None,
    goal: ArrayLike | None = None,
) -> Any:
    """Draw a path (forward blue, reverse red), footprints along it and start/goal arrows.

    Parameters
    ----------
    path : PlannedPath
        The planned path.
    ax : matplotlib.axes.Axes or None
        Axes to draw on; a new figure when ``None``.
    grid : OccupancyGrid, PolygonWorld or None
        Map drawn underneath (polygons exactly).
    footprint : Footprint or None
        Outline drawn every ``footprint_every`` metres and at the start and goal.
    footprint_every : float
        Spacing [m] of the drawn footprints.
    start : array_like or None
        Start pose for the green arrow (default: the first pose of the path).
    goal : array_like or None
        Goal pose for the red arrow (default: the last pose).

    Returns
    -------
    matplotlib.axes.Axes
    """
    import matplotlib.pyplot as plt

    if ax is None:
        if grid is not None:
            ax = plot_grid(grid)
        else:
            _, ax = plt.subplots(figsize=(8, 6))
            ax.set_aspect("equal")
    elif grid is not None:
        plot_grid(grid, ax)
    poses = path.poses
    if len(poses):
        if footprint is not None:
            marks = np.searchsorted(
                path.arc_length, np.arange(0.0, path.length + 1e-9, footprint_every)
            )
            marks = np.unique(np.concatenate([marks, path.cusp_indices, [len(poses) - 1]]))
            for i in marks:
                outline = transform_points(poses[i], footprint.polygon)
                ax.fill(*outline.T, facecolor="none", edgecolor="0.4", linewidth=0.6)
        for sign, color, label in ((1, "tab:blue", "forward"), (-1, "tab:red", "reverse")):
            xy = np.where((path.directions == sign)[:, None], poses[:, :2], np.nan)
            if np.isfinite(xy).any():
                ax.plot(xy[:, 0], xy[:, 1], color=color, linewidth=1.8, label=label)
        cusps = path.cusp_indices
        if len(cusps):
            ax.plot(poses[cusps, 0], poses[cusps, 1], "ko", markersize=4, label="cusp")
    for pose, color, label in (
        (start if start is not None else (poses[0] if len(poses) else None), "tab:green", "start"),
        (goal if goal is not None else (poses[-1] if len(poses) else None), "tab:red", "goal"),
    ):
        if pose is None:
            continue
        x, y, th = np.asarray(pose, dtype=float)
        scale = 0.05 * max(np.ptp(ax.get_xlim()), np.ptp(ax.get_ylim()), 1.0)
        ax.annotate(
            "",
            xy=(x + scale * np.cos(th), y + scale * np.sin(th)),
            xytext=(x, y),
            arrowprops={"arrowstyle": "-|>", "color": color, "linewidth": 2},
        )
        ax.plot([x], [y], "o", color=color, markersize=5, label=label)
    ax.legend(loc="best", fontsize="small")
    return ax
