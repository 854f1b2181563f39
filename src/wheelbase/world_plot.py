"""Drawing a run among obstacles: the world's truth and what the robot made of it.

:func:`draw_world` draws the static obstacles that are not on the map (dark red, hatched);
:func:`world_overlay` gives the animation, frame by frame, the agents (brown discs with their
velocity over the next second), the robot's confirmed tracks (cyan discs and velocities), the
cells its lidar marked in its costmap (small black squares) and the plan it follows now (orange:
the latest replan). Algorithms return data; this module only draws it.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from wheelbase.sim import Log

__all__ = ["draw_plans", "draw_world", "world_overlay"]

_CIRCLE = np.stack(
    [np.cos(np.linspace(0, 2 * np.pi, 17)), np.sin(np.linspace(0, 2 * np.pi, 17))], -1
)
_MAX_MARKS = 800


def draw_world(ax: Any, world: Any) -> None:
    """The static obstacles of a :class:`wheelbase.world.World` that the map does not show.

    Parameters
    ----------
    ax : matplotlib.axes.Axes
        Where to draw.
    world : World or None
        The world (None: nothing).
    """
    if world is None:
        return
    from matplotlib.patches import Circle, Polygon

    style = {"facecolor": "none", "edgecolor": "darkred", "hatch": "////", "lw": 1.0}
    for k, ring in enumerate(world.obstacles.polygons):
        label = "not on the map" if k == 0 else None
        ax.add_patch(Polygon(np.asarray(ring), closed=True, label=label, **style))
    for k, (x, y, r) in enumerate(world.obstacles.discs):
        label = "not on the map" if k == 0 and not len(world.obstacles.polygons) else None
        ax.add_patch(Circle((x, y), r, label=label, **style))


def draw_plans(ax: Any, log: Log, robot: int = 0) -> None:
    """Every plan a navigator made during the run (faint orange), robot ``robot``.

    Parameters
    ----------
    ax : matplotlib.axes.Axes
        Where to draw.
    log : Log
        The run.
    robot : int
        Which robot.
    """
    if not log.summaries or robot >= len(log.summaries):
        return
    plans = log.summaries[robot].get("plans", [])
    for k, (_, poses) in enumerate(plans):
        ax.plot(poses[:, 0], poses[:, 1], "-", color="tab:orange", lw=0.6, alpha=0.35,
                label="replanned" if k == 0 else None)  # fmt: skip


def world_overlay(log: Log, world: Any = None, *, robot: int = 0):
    """What the animation draws of the world and of the robot's perception at row ``k``.

    Parameters
    ----------
    log : Log
        The run (``agents``, ``perceived`` and the navigator's plans in ``summaries``).
    world : World, optional
        The world (the agents' radii); without it agents are drawn 0.3 m wide.
    robot : int
        Whose perception and plans.

    Returns
    -------
    callable
        ``overlay(k)`` → mapping of colours to polylines (for :func:`wheelbase.plot.animate`).
    """
    radii = None if world is None else np.asarray(world.agent_radius, dtype=np.float64)
    plans = log.summaries[robot].get("plans", []) if robot < len(log.summaries) else []
    plan_times = np.array([t for t, _ in plans])
    seen_rows = np.array(sorted(row for (r, row) in log.perceived if r == robot))

    def discs(centres: np.ndarray, velocity: np.ndarray, radius: np.ndarray) -> list:
        lines = [c + r * _CIRCLE for c, r in zip(centres, radius, strict=True)]
        lines += [np.array([c, c + v]) for c, v in zip(centres, velocity, strict=True)]
        return lines

    def overlay(k: int) -> dict[str, list[np.ndarray]]:
        drawn: dict[str, list[np.ndarray]] = {}
        if log.agents is not None and len(log.agents):
            worlds = log.agents[min(robot, log.agents.shape[0] - 1)]
            agents = np.asarray(worlds[min(k, worlds.shape[0] - 1)], dtype=np.float64)
            radius = radii if radii is not None else np.full(len(agents), 0.3)
            drawn["tab:brown"] = discs(agents[:, :2], agents[:, 2:4], radius)
        if seen_rows.size:
            past = seen_rows[seen_rows <= k]
            if past.size:
                seen = log.perceived[(robot, int(past[-1]))]
                tracks = np.asarray(seen["tracks"], dtype=np.float64)
                if len(tracks):
                    drawn["tab:cyan"] = discs(tracks[:, :2], tracks[:, 2:4], tracks[:, 4])
                marks = np.asarray(seen["marks"], dtype=np.float64)[:_MAX_MARKS]
                if len(marks):
                    half = 0.05
                    square = np.array([[-half, -half], [half, -half], [half, half],
                                       [-half, half], [-half, -half]])  # fmt: skip
                    drawn["black"] = [m + square for m in marks]
        if plan_times.size:
            latest = np.flatnonzero(plan_times <= log.t[k] + 1e-9)
            if latest.size:
                drawn["tab:orange"] = [np.asarray(plans[int(latest[-1])][1])[:, :2]]
        return drawn

    return overlay
