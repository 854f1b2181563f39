"""Figures of mapping and SLAM results: pose graphs, maps with trajectories and loop closures,
errors against time. Algorithms return data; these functions draw it."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from wheelbase.plot import agg_pyplot, save_and_close

__all__ = ["animate_map", "plot_error", "plot_landmarks", "plot_map", "plot_pose_graph"]


def _edge_lines(ax: Any, poses: np.ndarray, edges: np.ndarray, **style: Any) -> None:
    from matplotlib.collections import LineCollection

    if edges.size:
        ax.add_collection(LineCollection(poses[edges][:, :, :2], **style))


def plot_pose_graph(
    initial: np.ndarray,
    optimised: np.ndarray,
    edges: np.ndarray,
    path: str | Path,
    title: str = "",
) -> Path:
    """The graph before and after optimisation: poses and the non-consecutive edges (loops).

    Parameters
    ----------
    initial : numpy.ndarray, shape (V, 3)
        Initial poses [m, m, rad].
    optimised : numpy.ndarray, shape (V, 3)
        Optimised poses.
    edges : numpy.ndarray, shape (E, 2)
        Vertex rows of each edge.
    path : str or Path
        PNG file to write.
    title : str
        Figure title.

    Returns
    -------
    Path
    """
    plt = agg_pyplot()
    fig, axes = plt.subplots(1, 2, figsize=(12, 6))
    loops = edges[np.abs(edges[:, 1] - edges[:, 0]) != 1]
    for ax, poses, name in ((axes[0], initial, "initial guess"), (axes[1], optimised,
                            "optimised")):  # fmt: skip
        _edge_lines(ax, poses, loops, colors="tab:orange", linewidths=0.3, alpha=0.5)
        ax.plot(*poses[:, :2].T, color="tab:blue", lw=0.6)
        ax.set_aspect("equal")
        ax.autoscale()
        ax.grid(True, alpha=0.3)
        ax.set_xlabel("x [m]")
        ax.set_ylabel("y [m]")
        ax.set_title(f"{title}: {name}" if title else name)
    return save_and_close(fig, path)


def plot_map(
    grid: Any,
    path: str | Path,
    trajectory: np.ndarray | None = None,
    loops: np.ndarray | None = None,
    reference: np.ndarray | None = None,
    title: str = "",
    frontiers: np.ndarray | None = None,
) -> Path:
    """An occupancy map with the trajectory on it and its loop closures.

    Parameters
    ----------
    grid : OccupancyGrid
        The map (unknown cells grey, free white, occupied black).
    path : str or Path
        PNG file to write.
    trajectory : numpy.ndarray or None, shape (T, 3)
        The estimated trajectory.
    loops : numpy.ndarray or None, shape (L, 2)
        Row pairs of ``trajectory`` joined by a loop closure.
    reference : numpy.ndarray or None, shape (T, 3)
        A reference or true trajectory, drawn dashed.
    title : str
        Figure title.
    frontiers : numpy.ndarray or None, shape (G, 2)
        Frontiers visited (x, y) [m], numbered in order (exploration).

    Returns
    -------
    Path
    """
    plt = agg_pyplot()
    image = np.where(grid.occupied, 0.0, 1.0)
    if grid.unknown is not None:
        image = np.where(grid.unknown, 0.75, image)
    fig, ax = plt.subplots(figsize=(8, 8 * grid.height_m / max(grid.width_m, 1e-9) + 0.5))
    ax.imshow(image, cmap="gray", vmin=0, vmax=1, origin="lower", extent=grid.extent,
              interpolation="nearest")  # fmt: skip
    if reference is not None:
        ax.plot(*reference[:, :2].T, color="k", lw=0.8, ls="--", label="reference")
    if trajectory is not None:
        ax.plot(*trajectory[:, :2].T, color="tab:blue", lw=0.9, label="estimate")
        if loops is not None and len(loops):
            _edge_lines(ax, trajectory, np.asarray(loops), colors="tab:red", linewidths=0.6,
                        label=f"loop closures ({len(loops)})")  # fmt: skip
    if frontiers is not None and len(frontiers):
        points = np.asarray(frontiers, float).reshape(-1, 2)
        ax.plot(
            *points.T, "o", color="tab:orange", ms=5, label=f"frontiers visited ({len(points)})"
        )
        for k, (x, y) in enumerate(points):
            ax.annotate(str(k + 1), (x, y), fontsize=6, xytext=(3, 3), textcoords="offset points")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_title(title)
    if trajectory is not None or reference is not None:
        ax.legend(loc="best", fontsize=8)
    return save_and_close(fig, path)


def plot_error(
    t: np.ndarray, errors: dict[str, np.ndarray], path: str | Path, title: str = "",
    ylabel: str = "position error [m]", xlabel: str = "time [s]",
) -> Path:  # fmt: skip
    """Errors against time (or what ``t`` counts), one line per entry.

    Parameters
    ----------
    t : numpy.ndarray, shape (T,)
        Times [s].
    errors : dict of str to numpy.ndarray
        Label → errors of shape ``(T,)``.
    path : str or Path
        PNG file to write.
    title : str
        Figure title.
    ylabel : str
        Label of the y axis (with its unit).
    xlabel : str
        Label of the x axis (``scan`` for a log whose stamps are not times).

    Returns
    -------
    Path
    """
    plt = agg_pyplot()
    fig, ax = plt.subplots(figsize=(9, 4))
    for label, values in errors.items():
        ax.plot(t, values, lw=0.9, label=label)
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.grid(True, alpha=0.3)
    ax.set_title(title)
    ax.legend(loc="best", fontsize=8)
    return save_and_close(fig, path)


def _image(grid: Any) -> np.ndarray:
    image = np.where(grid.occupied, 0.0, 1.0)
    if grid.unknown is not None:
        image = np.where(grid.unknown, 0.75, image)
    return image


def animate_map(frames: list[tuple[Any, np.ndarray]], path: str | Path, title: str = "",
                fps: int = 5) -> Path:  # fmt: skip
    """A GIF of a map growing: one frame per ``(grid, trajectory so far)``.

    The frames' grids may differ in extent; all are drawn in the last one's.

    Parameters
    ----------
    frames : list of tuple
        ``(OccupancyGrid, poses (T, 3))`` in order.
    path : str or Path
        GIF file to write.
    title : str
        Figure title.
    fps : int
        Frames per second.

    Returns
    -------
    Path
    """
    plt = agg_pyplot()
    from matplotlib.animation import FuncAnimation, PillowWriter

    last = frames[-1][0]
    x0, x1, y0, y1 = last.extent
    fig, ax = plt.subplots(figsize=(6, 6 * (y1 - y0) / max(x1 - x0, 1e-9) + 0.4))
    shown = ax.imshow(_image(frames[0][0]), cmap="gray", vmin=0, vmax=1, origin="lower",
                      extent=frames[0][0].extent, interpolation="nearest")  # fmt: skip
    (line,) = ax.plot([], [], color="tab:blue", lw=0.8)
    ax.set_xlim(x0, x1)
    ax.set_ylim(y0, y1)
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")

    def draw(k: int) -> tuple:
        grid, poses = frames[k]
        shown.set_data(_image(grid))
        shown.set_extent(grid.extent)
        line.set_data(poses[:, 0], poses[:, 1])
        ax.set_title(f"{title} ({k + 1}/{len(frames)})")
        return shown, line

    anim = FuncAnimation(fig, draw, frames=len(frames), blit=False)
    path = Path(path)
    anim.save(path, writer=PillowWriter(fps=fps))
    plt.close(fig)
    return path


def plot_landmarks(result: Any, path: str | Path, title: str = "") -> Path:
    """A landmark SLAM result: estimated landmarks with 3σ ellipses beside the surveyed ones,
    the estimated and the true trajectory.

    Parameters
    ----------
    result : LandmarkSlamResult
        The run.
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
    ax.plot(*result.truth[:, :2].T, color="k", lw=1.0, label="ground truth (Vicon)")
    ax.plot(*result.estimate[:, :2].T, color="tab:blue", lw=0.8, label=result.method)
    ax.plot(*result.true_landmarks.T, "*", color="tab:green", ms=12, label="surveyed landmarks")
    ax.plot(*result.landmarks.T, "+", color="tab:red", ms=10, mew=2, label="estimated")
    angle = np.linspace(0, 2 * np.pi, 60)
    circle = np.stack([np.cos(angle), np.sin(angle)])
    for xy, cov in zip(result.landmarks, result.landmark_cov, strict=True):
        if np.all(np.isfinite(cov)):
            vals, vecs = np.linalg.eigh(cov)
            ellipse = vecs @ (3.0 * np.sqrt(np.maximum(vals, 0.0))[:, None] * circle)
            ax.plot(xy[0] + ellipse[0], xy[1] + ellipse[1], color="tab:red", lw=0.6)
    ax.set_aspect("equal")
    ax.grid(True, alpha=0.3)
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_title(title)
    ax.legend(loc="best", fontsize=8)
    return save_and_close(fig, path)
