"""``wheelbase control``: one pose-law (or MPPI) run to files.

``wheelbase control --law polar --start 2,0,180 --goal 0,0,0 --out DIR`` drives a unicycle
(|v| ≤ 0.5 m/s, |ω| ≤ 1.5 rad/s by default) from the start to the goal with one pose law and
writes ``run.csv`` (t, x, y, θ, v, ω), ``run.png`` and ``metrics.json``.

The 128-case pose benchmark and the tracking benchmark are benchmark harness, not the library:
``python benchmarks/control.py`` prints their tables and ``examples/control_fans.py`` /
``examples/control_tracking.py`` draw their figures.

Poses are ``X,Y,HEADING`` with the heading in degrees unless written ``1.57rad``, as everywhere
on the command line (:mod:`wheelbase.commands.options`). Existing files are kept unless
``--force``.
"""

from __future__ import annotations

import csv
import json
import math
from pathlib import Path
from typing import Annotated, Any

import numpy as np
import typer

from wheelbase._validate import check_choice, positive
from wheelbase.commands.options import out_option, pose_option, rate_option
from wheelbase.commands.output import console as make_console
from wheelbase.control.base import VelocityLimits
from wheelbase.control.pose import POSE_LAWS, make_pose_law
from wheelbase.errors import ConfigError, InputError
from wheelbase.sim import Log

__all__ = ["LAWS", "control_run_to_files", "plot_run", "register"]

ARRIVAL_TOLERANCE = (0.01, math.radians(1.0))
"""Position [m] and heading [rad] tolerance of a pose-law run."""

RUN_FILES: tuple[str, ...] = ("run.csv", "run.png", "metrics.json")
LAWS: tuple[str, ...] = (*POSE_LAWS, "mppi")
"""Every ``--law``: the pose laws of document 002, and MPPI (on ``--map``)."""


# --------------------------------------------------------------------------- files
def _check_free(out: Path, names: tuple[str, ...], force: bool) -> None:
    out.mkdir(parents=True, exist_ok=True)
    existing = [name for name in names if (out / name).exists()]
    if existing and not force:
        raise FileExistsError(
            f"{out / existing[0]} exists; pass --force to overwrite "
            f"({len(existing)} file(s) would be replaced)"
        )


# --------------------------------------------------------------------------- figures
def _figure(size: tuple[float, float] = (6.0, 6.0)) -> Any:
    from matplotlib.figure import Figure

    return Figure(figsize=size, layout="constrained")


def _goal_arrow(ax: Any, goal: np.ndarray) -> None:
    ax.plot(goal[0], goal[1], "k*", ms=12, zorder=5)
    ax.annotate(
        "",
        xy=(goal[0] + 0.35 * math.cos(goal[2]), goal[1] + 0.35 * math.sin(goal[2])),
        xytext=(goal[0], goal[1]),
        arrowprops={"arrowstyle": "->", "lw": 2, "color": "k"},
    )


def plot_run(result: Log, goal: Any, title: str = "") -> Any:
    """Path, speed and yaw rate of a single-robot run."""
    goal = np.asarray(goal, dtype=float)
    fig = _figure((10.0, 5.0))
    path_ax, v_ax, w_ax = (
        fig.add_subplot(1, 2, 1),
        fig.add_subplot(2, 2, 2),
        fig.add_subplot(2, 2, 4),
    )
    xy = result.true_pose[0, :, :2]
    path_ax.plot(xy[:, 0], xy[:, 1], "tab:blue")
    _goal_arrow(path_ax, goal)
    path_ax.set_aspect("equal")
    path_ax.set_xlabel("x [m]")
    path_ax.set_ylabel("y [m]")
    path_ax.set_title(title)
    path_ax.grid(True, alpha=0.3)
    v_ax.plot(result.t, result.command[0, :, 0])
    v_ax.set_ylabel(f"{result.command_names[0]} [m/s]")
    w_ax.plot(result.t, result.command[0, :, 1])
    w_ax.set_ylabel(f"{result.command_names[1]} [rad/s]")
    w_ax.set_xlabel("t [s]")
    for ax in (v_ax, w_ax):
        ax.grid(True, alpha=0.3)
    return fig


# --------------------------------------------------------------------------- actions
def control_run_to_files(
    law: str,
    start: np.ndarray,
    goal: np.ndarray,
    out: Path,
    *,
    max_speed: float = 0.5,
    max_yaw_rate: float = 1.5,
    t_end: float = 60.0,
    dt: float = 0.01,
    force: bool = False,
) -> dict[str, Any]:
    """Run one pose law from ``start`` to ``goal`` on a unicycle and write ``run.csv``,
    ``run.png`` and ``metrics.json`` into ``out``; return the metrics.

    Raises
    ------
    InputError
        If the start position equals the goal position.
    FileExistsError
        If a file exists and ``force`` is false.
    """
    from wheelbase.integrate import time_grid
    from wheelbase.models import Unicycle

    if math.hypot(*(np.asarray(start[:2]) - np.asarray(goal[:2]))) < 1e-9:
        raise InputError("goal equals the start position; give a goal elsewhere")
    time_grid(t_end, dt)  # t_end / dt within max_steps: an error, not 5e300 steps of a loop
    limits = VelocityLimits(
        positive("max_speed", max_speed, "m/s"), positive("max_yaw_rate", max_yaw_rate, "rad/s")
    )
    _check_free(out, RUN_FILES, force)
    from wheelbase.sim import closed_loop

    result = closed_loop(make_pose_law(law, limits), Unicycle(), start, goal, t_end, dt,
                         goal=goal, tolerance=ARRIVAL_TOLERANCE)  # fmt: skip
    metrics = {"law": law, "start": start.tolist(), "goal": goal.tolist(), **result.metrics()[0]}
    with (out / "run.csv").open("w", newline="") as handle:
        writer = csv.writer(handle)
        writer.writerow(["t", "x", "y", "theta", *result.command_names])
        for k, t in enumerate(result.t):
            row = [t, *result.true_pose[0, k], *result.command[0, k]]
            writer.writerow([repr(float(value)) for value in row])
    plot_run(result, goal, title=law).savefig(out / "run.png", dpi=110)
    (out / "metrics.json").write_text(json.dumps(metrics, indent=2))
    return metrics


def _mppi_run(map_name, start, goal, out, *, force, max_speed, max_yaw_rate, t_end) -> None:
    """MPPI on a map through the closed loop of :func:`wheelbase.run` (a unicycle robot)."""
    from wheelbase.commands.run import _run_and_report

    scenario = {
        "name": "mppi",
        "map": map_name,
        "robot": {"model": "unicycle", "footprint": [0.4, 0.4]},
        "controller": {"law": "mppi", "gains": {"max_yaw_rate": max_yaw_rate}},
        "odometry": {"mode": "perfect"},
        "start": [start[0], start[1], math.degrees(start[2])],
        "goal": [goal[0], goal[1], math.degrees(goal[2])],
        "trajectory": {"max_speed": max_speed, "max_yaw_rate": max_yaw_rate},
        "goal_tolerance": [0.1, 180.0],
        "dt": 0.05,
        "duration": t_end,
    }
    _run_and_report(scenario, Path(out), force=force, gif=True, console=make_console())


# --------------------------------------------------------------------------- command
def register(app: typer.Typer) -> None:
    """Add ``wheelbase control`` to ``app``."""

    @app.command("control")
    def control(
        out: Annotated[Path, out_option("control", "run.csv, run.png, metrics.json")] = (
            "wheelbase-control"
        ),
        law: Annotated[
            str,
            typer.Option(
                help=f"Control law: {', '.join(LAWS)} (the pose laws of document 002; mppi "
                "follows a Hybrid A* path on --map)."
            ),
        ] = "polar",
        map_name: Annotated[
            str,
            typer.Option(
                "--map",
                help="With --law mppi: bundled map name or map file (Hybrid A* plans the path "
                "MPPI follows); 'empty' for none.",
            ),
        ] = "empty",
        start: Annotated[
            np.ndarray | None, pose_option("--start", "Start pose (required):")
        ] = None,
        goal: Annotated[np.ndarray, pose_option("--goal", "Goal pose (default 0,0,0):")] = "0,0,0",
        max_speed: Annotated[float, typer.Option(help="Speed limit |v| [m/s].")] = 0.5,
        max_yaw_rate: Annotated[float, rate_option("--max-yaw-rate", "Yaw-rate limit |ω|.")] = 1.5,
        t_end: Annotated[float, typer.Option(help="Time limit [s].")] = 60.0,
        dt: Annotated[float, typer.Option(help="Control period and step [s].")] = 0.01,
        force: Annotated[bool, typer.Option("--force", help="Overwrite existing files.")] = False,
    ) -> None:
        """Drive to a pose with one of the pose laws (document 002), or MPPI on a map."""
        console = make_console()
        if start is None:
            raise ConfigError("--start X,Y,HEADING is required")
        check_choice("law", law, LAWS)
        if law == "mppi":
            _mppi_run(map_name, start, goal, out, force=force,
                      max_speed=max_speed, max_yaw_rate=max_yaw_rate, t_end=t_end)  # fmt: skip
            return
        metrics = control_run_to_files(
            law,
            start,
            goal,
            out,
            max_speed=max_speed,
            max_yaw_rate=max_yaw_rate,
            t_end=t_end,
            dt=dt,
            force=force,
        )
        arrived = metrics["status"] == "arrived"
        summary = (
            f"arrived in {metrics['duration_s']:.2f} s, "
            f"path {metrics['distance_travelled_m']:.2f} m"
            if arrived
            else f"did not arrive ({metrics['status']})"
        )
        console.print(
            f"{law}: {summary}; final error {100 * metrics['final_position_error_true_m']:.2f} cm, "
            f"{metrics['final_heading_error_true_deg']:.2f}°; wrote {out}"
        )
