"""Metrics and figures of a closed-loop run (what ``wheelbase run`` writes into its report).

Algorithms return data; this module turns a :class:`~wheelbase.sim.Log` of one robot (and the
map and plan it ran on) into figures and an animation; the numbers come from
:meth:`wheelbase.sim.Log.metrics`. Nothing here changes a result.
"""

from __future__ import annotations

import numpy as np

from wheelbase.geometry import transform_points, wrap_angle
from wheelbase.sim import Log

__all__ = [
    "MCAP_FILE",
    "REPORT_FILES",
    "TRACTION_FILE",
    "animate_run",
    "figure_commands",
    "figure_errors",
    "figure_map",
    "sensing_overlay",
    "status_at",
    "write_report",
]


def _draw_map(ax, grid) -> None:
    if grid is None:
        return
    from wheelbase.planning.world import PolygonWorld

    world = grid if isinstance(grid, PolygonWorld) else None
    cells = world.grid if world is not None else grid
    if cells is not None:
        x0, y0 = cells.origin
        rows, cols = cells.occupied.shape
        extent = (x0, x0 + cols * cells.resolution, y0, y0 + rows * cells.resolution)
        ax.imshow(
            cells.occupied, origin="lower", extent=extent, cmap="Greys", vmin=0, vmax=1.6,
            interpolation="nearest",
        )  # fmt: skip
    if world is not None:  # the exact polygons and discs, in the grey of occupied cells
        import matplotlib

        from wheelbase.planning.plot import draw_obstacles

        draw_obstacles(ax, world, color=matplotlib.colormaps["Greys"](1.0 / 1.6))


def _outline(pose: np.ndarray, polygon: np.ndarray) -> np.ndarray:
    closed = np.vstack([polygon, polygon[:1]])
    return transform_points(pose, closed)


def figure_map(
    grid, plan_poses, log: Log, polygon=None, *, title: str = "", terrain=None, world=None
):
    """Map with the plan, the driven path, the odometry estimate and footprints (and the
    terrain's surfaces and slopes under them).

    Parameters
    ----------
    grid : OccupancyGrid or None
        The map (None: blank background).
    plan_poses : numpy.ndarray, shape (N, 3) or None
        The planned path.
    log : Log
        The recorded run.
    polygon : numpy.ndarray, shape (M, 2), optional
        Footprint outline in the body frame, drawn at the start, the end and along the way.
    title : str
        Figure title.
    terrain : TerrainMap, optional
        The ground, coloured by surface (:func:`wheelbase.terrain_plot.draw_terrain`).
    world : World, optional
        The obstacles the map does not show (:func:`wheelbase.world_plot.draw_world`); the
        navigator's replans are drawn too.
    """
    import matplotlib.pyplot as plt

    from wheelbase.world_plot import draw_plans, draw_world

    fig, ax = plt.subplots(figsize=(8, 7))
    _draw_map(ax, grid)
    draw_world(ax, world)
    draw_plans(ax, log)
    if terrain is not None:  # over the map's white, translucent over its obstacles
        from wheelbase.terrain_plot import draw_terrain

        draw_terrain(ax, terrain)
    if plan_poses is not None:
        ax.plot(plan_poses[:, 0], plan_poses[:, 1], "--", color="tab:orange", lw=1.5, label="plan")
    ax.plot(
        log.true_pose[0][:, 0],
        log.true_pose[0][:, 1],
        "-",
        color="tab:blue",
        lw=1.5,
        label="driven",
    )
    ax.plot(
        log.estimated_pose[0][:, 0], log.estimated_pose[0][:, 1], ":", color="tab:green", lw=1.2,
        label="estimate",
    )  # fmt: skip
    if polygon is not None:
        indices = np.unique(np.linspace(0, len(log.t) - 1, 12).astype(int))
        for index in indices:
            outline = _outline(log.true_pose[0][index], polygon)
            ax.plot(outline[:, 0], outline[:, 1], "-", color="tab:blue", lw=0.6, alpha=0.6)
    ax.plot(*log.true_pose[0][0, :2], "o", color="tab:green", label="start")
    ax.plot(*log.true_pose[0][-1, :2], "s", color="tab:red", label=f"end ({log.statuses[0]})")
    _zoom(ax, grid, plan_poses, log)
    ax.set_aspect("equal")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.legend(loc="best", fontsize=8)
    ax.set_title(title or "plan and driven path")
    fig.tight_layout()
    return fig


def _zoom(ax, grid, plan_poses, log: Log, margin: float = 2.0) -> None:
    points = [log.true_pose[0][:, :2]]
    if plan_poses is not None:
        points.append(plan_poses[:, :2])
    xy = np.vstack(points)
    lo, hi = xy.min(0) - margin, xy.max(0) + margin
    ax.set_xlim(lo[0], hi[0])
    ax.set_ylim(lo[1], hi[1])


def figure_errors(log: Log):
    """Tracking error (position, heading) and the estimate's error against time (with the
    filter's 3σ bound of the position error when it has a covariance).

    Parameters
    ----------
    log : Log
        The recorded run.
    """
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(3, 1, figsize=(8, 7), sharex=True)
    error = np.hypot(*(log.true_pose[0][:, :2] - log.reference_pose[0][:, :2]).T)
    heading = np.degrees(wrap_angle(log.true_pose[0][:, 2] - log.reference_pose[0][:, 2]))
    drift = np.hypot(*(log.true_pose[0][:, :2] - log.estimated_pose[0][:, :2]).T)
    axes[0].plot(log.t, 100 * error)
    axes[0].set_ylabel("position error [cm]")
    axes[1].plot(log.t, heading)
    axes[1].set_ylabel("heading error [deg]")
    axes[2].plot(log.t, 100 * drift, color="tab:green", label="|true − estimate|")
    if "est_cov_xx" in log.extras:
        bound = 3.0 * np.sqrt(_largest_variance(log, 0))
        axes[2].plot(log.t, 100 * bound, "--", color="0.5", lw=0.8, label="3σ (filter)")
        axes[2].legend(fontsize=8)
    axes[2].set_ylabel("estimate error [cm]")
    axes[2].set_xlabel("t [s]")
    for ax in axes:
        ax.grid(True, alpha=0.3)
    axes[0].set_title("true pose vs reference, and estimate vs true pose")
    fig.tight_layout()
    return fig


def figure_commands(log: Log):
    """Commands, wheel rates and (on a dynamic plant) wheel torques against time.

    Parameters
    ----------
    log : Log
        The recorded run.
    """
    import matplotlib.pyplot as plt

    # On a dynamic plant the command is the wheel torques: one panel shows them.
    rows = 3 if log.torques is not None and not log.command_names[0].startswith("tau") else 2
    fig, axes = plt.subplots(rows, 1, figsize=(8, 2.4 * rows + 1), sharex=True)
    for index, name in enumerate(log.command_names):
        axes[0].plot(log.t, log.command[0][:, index], label=name)
    torque_command = log.torques is not None and rows == 2
    axes[0].set_ylabel("wheel torque command [N·m]" if torque_command else "command")
    axes[0].legend(fontsize=8)
    axes[1].plot(log.t, log.wheel_rates[0][:, 0], label="left")
    axes[1].plot(log.t, log.wheel_rates[0][:, 1], label="right")
    axes[1].set_ylabel("wheel rate [rad/s]")
    axes[1].legend(fontsize=8)
    if rows == 3:
        axes[2].plot(log.t, log.torques[0][:, 0], label="left")
        axes[2].plot(log.t, log.torques[0][:, 1], label="right")
        axes[2].set_ylabel("wheel torque [N·m]")
        axes[2].legend(fontsize=8)
    axes[-1].set_xlabel("t [s]")
    for ax in axes:
        ax.grid(True, alpha=0.3)
    fig.tight_layout()
    return fig


def _largest_variance(log: Log, robot: int) -> np.ndarray:
    """Largest eigenvalue [m²] of the position covariance of each row of a robot."""
    xx, yy = log.extras["est_cov_xx"][robot], log.extras["est_cov_yy"][robot]
    xy = log.extras["est_cov_xy"][robot]
    return 0.5 * (xx + yy) + np.sqrt(0.25 * (xx - yy) ** 2 + xy**2)


def _ellipse(centre: np.ndarray, cov: np.ndarray, scale: float = 3.0) -> np.ndarray:
    """The ``scale``-σ ellipse of a 2×2 covariance around ``centre``, a closed polyline."""
    w, v = np.linalg.eigh(0.5 * (cov + cov.T))
    angle = np.linspace(0.0, 2.0 * np.pi, 41)
    circle = np.stack([np.cos(angle), np.sin(angle)], -1) * (scale * np.sqrt(np.maximum(w, 0)))
    return centre + circle @ v.T


def sensing_overlay(log: Log, lidar=None, *, robot: int = 0):
    """What the animation draws of sensing at each row: the latest lidar beams (within 0.5 s),
    the latest particles (within 1.5 s, at most 300, as heading ticks) or else the 3σ
    covariance ellipse of the estimate, and a sampling controller's rollouts.

    Parameters
    ----------
    log : Log
        The recorded run.
    lidar : Lidar, optional
        The lidar whose scans ``log.scans`` holds (its beam angles and mount); without it no
        beams are drawn.
    robot : int
        Which robot.

    Returns
    -------
    callable
        ``overlay(k)`` → mapping of colours to polylines (for :func:`wheelbase.plot.animate`).
    """

    def latest(table: dict, k: int, age: float):
        rows = sorted(row for (r, row) in table if r == robot and row <= k)
        if not rows or log.t[k] - log.t[rows[-1]] >= age:
            return None, None
        return rows[-1], table[(robot, rows[-1])]

    has_cov = "est_cov_xx" in log.extras
    cov = None
    if has_cov:
        e = log.extras
        cov = np.stack(
            [np.stack([e["est_cov_xx"][robot], e["est_cov_xy"][robot]], -1),
             np.stack([e["est_cov_xy"][robot], e["est_cov_yy"][robot]], -1)], -2,
        )  # fmt: skip

    def overlay(k: int) -> dict[str, list[np.ndarray]]:
        drawn: dict[str, list[np.ndarray]] = {}
        _, fan = latest(log.rollout_fans, k, 1.5)
        if fan is not None:
            drawn["tab:purple"] = list(fan)
        row, ranges = latest(log.scans, k, 0.5) if lidar is not None else (None, None)
        if ranges is not None:
            pose = log.true_pose[robot, row]
            origin = lidar.sensor_poses(pose)[:2]
            ends = lidar.endpoints(pose, ranges)
            ends = ends[np.all(np.isfinite(ends), axis=-1)]
            ends = ends[:: max(1, len(ends) // 72)]  # a fan of at most ~72 beams stays legible
            drawn["tab:red"] = [np.array([origin, end]) for end in ends]
        _, cloud = latest(log.particles, k, 1.5)
        if cloud is not None:
            cloud = np.asarray(cloud, dtype=np.float64)[:: max(1, len(cloud) // 300)]
            tips = cloud[:, :2] + 0.08 * np.stack([np.cos(cloud[:, 2]), np.sin(cloud[:, 2])], -1)
            drawn["tab:green"] = list(np.stack([cloud[:, :2], tips], 1))
        elif cov is not None:
            drawn["tab:blue"] = [_ellipse(log.estimated_pose[robot, k, :2], cov[k])]
        return drawn

    return overlay


def status_at(log: Log, step: int, robot: int = 0) -> str:
    """What the animation's title says at recorded step ``step``: ``running`` (with the
    controller's own status when it reports one other than ``ok``, e.g. ``all_collide``) until
    the robot's last step, then its final status (``arrived``, ``collision``, …).

    Parameters
    ----------
    log : Log
        The recorded run.
    step : int
        Index into ``log.t``.
    robot : int
        Which robot.

    Returns
    -------
    str
    """
    if step >= int(log.length[robot]) - 1:
        return log.statuses[robot]
    codes = log.controller_status
    if codes is not None and codes[robot, step] >= 0:
        name = log.controller_status_names[int(codes[robot, step])]
        if name != "ok":
            return f"running ({name})"
    return "running"


def animate_run(
    grid, plan_poses, log: Log, robot_footprint, path, *, frames: int = 120, fps: int = 15,
    lidar=None, world=None,
):  # fmt: skip
    """GIF of the footprint moving over the map with the plan and the trace, and what the
    robot senses (:func:`sensing_overlay`: lidar beams, particles or the covariance ellipse,
    a sampling controller's rollouts).

    Parameters
    ----------
    grid : OccupancyGrid or None
        The map.
    plan_poses : numpy.ndarray, shape (N, 3) or None
        The planned path.
    log : Log
        The recorded run.
    robot_footprint : tuple
        ``(length, width, center_offset)`` [m] of the rectangular footprint.
    path : str or Path
        Output GIF (replaced if it exists: the caller decides about overwriting).
    frames : int
        Number of frames (the run is subsampled evenly).
    fps : int
        Frames per second.
    lidar : Lidar, optional
        The lidar of ``log.scans`` (its beams are drawn).
    world : World, optional
        The world beyond the map: its obstacles, its agents and what the robot perceived of
        them (:func:`wheelbase.world_plot.world_overlay`); every robot of a fleet is drawn.
    """
    from types import SimpleNamespace

    from wheelbase.plot import animate
    from wheelbase.world_plot import draw_world, world_overlay

    length, width, offset = robot_footprint

    def background(ax) -> None:
        _draw_map(ax, grid)
        draw_world(ax, world)
        if plan_poses is not None:
            ax.plot(plan_poses[:, 0], plan_poses[:, 1], "--", color="tab:orange", lw=1.2)
        _zoom(ax, grid, plan_poses, log)

    sensed = sensing_overlay(log, lidar)
    around = world_overlay(log, world) if world is not None or log.agents is not None else None

    def overlay(k: int) -> dict:
        drawn = dict(sensed(k))
        if around is not None:
            for colour, lines in around(k).items():
                drawn[colour] = drawn.get(colour, []) + lines
        return drawn

    poses = log.true_pose[0] if log.n_robots == 1 else log.true_pose.transpose(1, 0, 2)
    run = SimpleNamespace(t=log.t, poses=poses)
    return animate(
        run, path, footprint=(length, width), center_offset=offset, fps=fps, max_frames=frames,
        overwrite=True, background=background, title=lambda k: status_at(log, k),
        overlay=overlay,
    )  # fmt: skip


REPORT_FILES = (
    "metrics.json",
    "log.csv",
    "scenario.yaml",
    "map.png",
    "errors.png",
    "commands.png",
    "animation.gif",
)
"""Files a closed-loop report folder holds."""

MCAP_FILE = "run.mcap"
"""The report's MCAP file for Foxglove (written on request: ``wheelbase run --mcap``)."""

TRACTION_FILE = "traction.png"
"""The report's slip and traction figure (a run on terrain or with a payload)."""


def write_report(
    result, folder, *, force: bool = False, gif: bool = True, mcap: bool = False
) -> list:
    """Write a run's report: metrics, log, resolved scenario, figures, animation and MCAP.

    Parameters
    ----------
    result : wheelbase.runner.RunResult
        The run.
    folder : str or Path
        Output folder, created if missing.
    force : bool
        Overwrite an existing report (default: raise FileExistsError if any report file
        exists there).
    gif : bool
        Also render ``animation.gif`` (the slowest part).
    mcap : bool
        Also write ``run.mcap`` for Foxglove (:func:`wheelbase.mcap_export.write_mcap`; needs
        the ``wheelbase[foxglove]`` extra).

    Returns
    -------
    list of Path
        The files written. A run whose planning failed gets ``metrics.json`` (status
        ``planning_failed``) and ``scenario.yaml`` only.
    """
    import json
    from pathlib import Path

    import matplotlib

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt

    folder = Path(folder)
    names = (*REPORT_FILES, TRACTION_FILE, *((MCAP_FILE,) if mcap else ()))
    if mcap:
        from wheelbase.mcap_export import require_foxglove

        require_foxglove()  # a missing extra fails before anything is written
    existing = [folder / name for name in names if (folder / name).exists()]
    if existing and not force:
        raise FileExistsError(f"{existing[0]} exists: a report is already there (use --force)")
    folder.mkdir(parents=True, exist_ok=True)
    for path in existing:
        path.unlink()
    written = []
    metrics_path = folder / "metrics.json"
    metrics_path.write_text(json.dumps(result.metrics, indent=2, default=_json_default) + "\n")
    written.append(metrics_path)
    scenario_path = folder / "scenario.yaml"
    scenario_path.write_text(result.scenario.to_yaml())
    written.append(scenario_path)
    if result.log is None:
        return written
    written.append(result.log.to_csv(folder / "log.csv"))
    if mcap:
        from wheelbase.mcap_export import write_mcap

        written.append(write_mcap(result, folder / MCAP_FILE))
    plan = None if result.plan is None else result.plan.poses
    polygon = result.footprint_polygon
    terrain = getattr(result, "terrain", None)
    world = getattr(result, "world", None)
    figures = {
        "map.png": figure_map(
            result.grid,
            plan,
            result.log,
            polygon,
            title=result.scenario.name,
            terrain=terrain,
            world=world,
        ),
        "errors.png": figure_errors(result.log),
        "commands.png": figure_commands(result.log),
    }
    from wheelbase.terrain_plot import figure_traction, has_traction

    if has_traction(result.log):
        figures[TRACTION_FILE] = figure_traction(result.log, terrain)
    for name, fig in figures.items():
        fig.savefig(folder / name, dpi=110)
        plt.close(fig)
        written.append(folder / name)
    if gif:
        geometry = (*result.robot.footprint, result.robot.center_offset)
        lidar = None if result.sensors is None else result.sensors.lidar
        written.append(
            animate_run(
                result.grid,
                plan,
                result.log,
                geometry,
                folder / "animation.gif",
                lidar=lidar,
                world=world,
            )
        )
    return written


def _json_default(value):
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, np.ndarray):
        return value.tolist()
    raise TypeError(f"cannot write {type(value).__name__} to JSON")
