"""``wheelbase control``: one pose-law run, or the pose and tracking benchmarks, to files.

``wheelbase control --law polar --start 2 0 180deg --goal 0 0 0deg --out DIR`` drives a unicycle
(|v| ≤ 0.5 m/s, |ω| ≤ 1.5 rad/s by default) from the start to the goal with one pose law and
writes ``run.csv`` (t, x, y, θ, v, ω), ``run.png`` and ``metrics.json``.

``wheelbase control --benchmark --out DIR`` runs the 128-case pose benchmark for laws 1–6, prints
the table and writes ``benchmark.json`` (per law: ``success_rate``, ``mean_time_s``,
``mean_path_length_m``, ``reversals`` and more) and one fan figure per law, ``fan_<law>.png``;
with ``--tracking`` also ``tracking.json`` and ``tracking_errors.png``.

Angles accept ``90deg``, ``90°`` or ``1.57rad``; a bare number is in radians (as in the rest of
the command line). Existing files are kept unless ``--force``.
"""

from __future__ import annotations

import csv
import json
import math
from pathlib import Path
from typing import Annotated, Any

import numpy as np
import typer
from rich.console import Console
from rich.table import Table

from wheelbase._validate import finite, parse_angle, positive
from wheelbase.control.base import VelocityLimits
from wheelbase.control.loop import (
    POSE_LAWS,
    ClosedLoopResult,
    evaluate_pose_law,
    make_pose_law,
    pose_benchmark,
    tracking_benchmark,
)
from wheelbase.errors import ConfigError, InputError

__all__ = [
    "BENCHMARK_KEYS",
    "control_benchmark_to_files",
    "control_run_to_files",
    "plot_fan",
    "plot_run",
    "plot_tracking_errors",
    "register",
]

BENCHMARK_KEYS: tuple[str, ...] = (
    "success_rate",
    "mean_time_s",
    "mean_path_length_m",
    "reversals",
)
"""The per-law keys of ``benchmark.json`` (more follow them)."""

RUN_FILES: tuple[str, ...] = ("run.csv", "run.png", "metrics.json")


# --------------------------------------------------------------------------- parsing
def _pose(values: tuple[str, str, str], name: str) -> np.ndarray:
    try:
        x, y = float(values[0]), float(values[1])
    except ValueError:
        raise ConfigError(f"{name} must be X Y ANGLE, e.g. 2 0 180deg (got {values!r})") from None
    return np.array([finite(f"{name} x", x, "m"), finite(f"{name} y", y, "m"),
                     parse_angle(values[2])])  # fmt: skip


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


def plot_fan(
    result: ClosedLoopResult, goal: Any = (0.0, 0.0, 0.0), title: str = "", ax: Any = None
) -> Any:
    """The "fan" figure: every robot's path of a batch run on one plot (successes in blue).

    Draws into ``ax`` when given, else into a new :class:`matplotlib.figure.Figure` (no pyplot
    state); returns the figure.
    """
    goal = np.asarray(goal, dtype=float)
    if ax is None:
        fig = _figure()
        ax = fig.add_subplot()
    else:
        fig = ax.figure
    ok = result.arrived
    for i in range(result.poses.shape[1]):
        xy = result.poses[:, i, :2]
        ax.plot(xy[:, 0], xy[:, 1], lw=0.7, color="tab:blue" if ok[i] else "tab:red", alpha=0.7)
    starts = result.poses[0]
    ax.quiver(starts[:, 0], starts[:, 1], np.cos(starts[:, 2]), np.sin(starts[:, 2]),
              scale=25, width=0.003, color="0.3")  # fmt: skip
    _goal_arrow(ax, goal)
    ax.set_aspect("equal")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_title(f"{title} — {int(ok.sum())}/{ok.size} reached" if title else "")
    ax.grid(True, alpha=0.3)
    return fig


def plot_run(result: ClosedLoopResult, goal: Any, title: str = "") -> Any:
    """Path, speed and yaw rate of a single-robot run."""
    goal = np.asarray(goal, dtype=float)
    fig = _figure((10.0, 5.0))
    path_ax, v_ax, w_ax = (
        fig.add_subplot(1, 2, 1),
        fig.add_subplot(2, 2, 2),
        fig.add_subplot(2, 2, 4),
    )
    xy = result.poses[:, 0, :2]
    path_ax.plot(xy[:, 0], xy[:, 1], "tab:blue")
    _goal_arrow(path_ax, goal)
    path_ax.set_aspect("equal")
    path_ax.set_xlabel("x [m]")
    path_ax.set_ylabel("y [m]")
    path_ax.set_title(title)
    path_ax.grid(True, alpha=0.3)
    v_ax.plot(result.t, result.commands[:, 0, 0])
    v_ax.set_ylabel(f"{result.command_names[0]} [m/s]")
    w_ax.plot(result.t, result.commands[:, 0, 1])
    w_ax.set_ylabel(f"{result.command_names[1]} [rad/s]")
    w_ax.set_xlabel("t [s]")
    for ax in (v_ax, w_ax):
        ax.grid(True, alpha=0.3)
    return fig


def plot_tracking_errors(traces: dict) -> Any:
    """Lateral error against time [cm] for every (reference, law, plant) of the tracking run."""
    references = sorted({key[0] for key in traces})
    fig = _figure((10.0, 4.0 * len(references)))
    for row, reference in enumerate(references, start=1):
        ax = fig.add_subplot(len(references), 1, row)
        for (ref, law, plant), (t, lateral) in traces.items():
            if ref == reference:
                ax.plot(t, 100.0 * np.abs(lateral), lw=1, label=f"{law} ({plant})",
                        ls="-" if plant == "unicycle" else "--")  # fmt: skip
        ax.set_yscale("log")
        ax.set_ylim(1e-3, 100)
        ax.axvline(5.0, color="0.5", lw=0.8)
        ax.set_title(reference.replace("_", " "))
        ax.set_ylabel("|lateral error| [cm]")
        ax.set_xlabel("t [s]")
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=7, ncol=2)
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
    from wheelbase.models import Unicycle

    if math.hypot(*(np.asarray(start[:2]) - np.asarray(goal[:2]))) < 1e-9:
        raise InputError("goal equals the start position; give a goal elsewhere")
    limits = VelocityLimits(
        positive("max_speed", max_speed, "m/s"), positive("max_yaw_rate", max_yaw_rate, "rad/s")
    )
    _check_free(out, RUN_FILES, force)
    metrics, result = evaluate_pose_law(
        make_pose_law(law, limits), Unicycle(), start[None], goal, t_end=t_end, dt=dt
    )
    metrics = {"law": law, "start": start.tolist(), "goal": goal.tolist(), **metrics}
    with (out / "run.csv").open("w", newline="") as handle:
        writer = csv.writer(handle)
        writer.writerow(["t", "x", "y", "theta", *result.command_names])
        for k, t in enumerate(result.t):
            row = [t, *result.poses[k, 0], *result.commands[k, 0]]
            writer.writerow([repr(float(value)) for value in row])
    plot_run(result, goal, title=law).savefig(out / "run.png", dpi=110)
    (out / "metrics.json").write_text(json.dumps(metrics, indent=2))
    return metrics


def control_benchmark_to_files(
    out: Path, *, tracking: bool = False, force: bool = False
) -> dict[str, Any]:
    """Run the pose benchmark (and the tracking one) and write the JSON and PNG files."""
    names = ("benchmark.json", *(f"fan_{law}.png" for law in POSE_LAWS))
    if tracking:
        names = (*names, "tracking.json", "tracking_errors.png")
    _check_free(out, names, force)
    table, results = pose_benchmark()
    for law, result in results.items():
        fig = plot_fan(result, title=law.replace("_", " "))
        fig.savefig(out / f"fan_{law}.png", dpi=110)
    (out / "benchmark.json").write_text(json.dumps(table, indent=2))
    report: dict[str, Any] = {"pose": table}
    if tracking:
        rows, traces = tracking_benchmark()
        (out / "tracking.json").write_text(json.dumps(rows, indent=2))
        plot_tracking_errors(traces).savefig(out / "tracking_errors.png", dpi=110)
        report["tracking"] = rows
    return report


def _pose_table(table: dict[str, dict[str, float]]) -> Table:
    view = Table(title="Pose control: 128 starts on a 2 m circle, unicycle |v|≤0.5, |ω|≤1.5")
    for column in ("law", "success", "mean time [s]", "mean path [m]", "reversals", "run [s]"):
        view.add_column(column, justify="left" if column == "law" else "right")
    for law, m in table.items():
        view.add_row(
            law,
            f"{100 * m['success_rate']:.1f} %",
            f"{m['mean_time_s']:.2f}",
            f"{m['mean_path_length_m']:.2f}",
            f"{m['reversals']:.2f}",
            f"{m['runtime_s']:.2f}",
        )
    return view


def _tracking_table(rows: list[dict[str, Any]]) -> Table:
    view = Table(title="Tracking: lateral error after 5 s")
    for column in ("reference", "law", "plant", "RMS [cm]", "max [cm]"):
        view.add_column(column, justify="right" if "[" in column else "left")
    for row in rows:
        view.add_row(
            row["reference"],
            row["law"],
            row["plant"],
            f"{100 * row['rms_lateral_error_m']:.3f}",
            f"{100 * row['max_lateral_error_m']:.3f}",
        )
    return view


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
    _run_and_report(scenario, Path(out), force=force, gif=True, console=Console())


# --------------------------------------------------------------------------- command
def register(app: typer.Typer) -> None:
    """Add ``wheelbase control`` to ``app``."""

    @app.command("control")
    def control(
        out: Annotated[Path, typer.Option("--out", help="Output directory.")],
        law: Annotated[
            str, typer.Option(help=f"Pose law: {', '.join(POSE_LAWS)}; or mppi (with --map).")
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
            tuple[str, str, str] | None,
            typer.Option(help="Start pose X [m] Y [m] ANGLE (90deg, 1.57rad; bare = rad)."),
        ] = None,
        goal: Annotated[
            tuple[str, str, str],
            typer.Option(help="Goal pose X [m] Y [m] ANGLE (90deg, 1.57rad; bare = rad)."),
        ] = ("0", "0", "0deg"),
        benchmark: Annotated[
            bool, typer.Option("--benchmark", help="Run the 128-case pose benchmark instead.")
        ] = False,
        tracking: Annotated[
            bool, typer.Option("--tracking", help="With --benchmark: the tracking one too.")
        ] = False,
        max_speed: Annotated[float, typer.Option(help="Speed limit |v| [m/s].")] = 0.5,
        max_yaw_rate: Annotated[float, typer.Option(help="Yaw-rate limit |ω| [rad/s].")] = 1.5,
        t_end: Annotated[float, typer.Option(help="Time limit [s].")] = 60.0,
        dt: Annotated[float, typer.Option(help="Control period and step [s].")] = 0.01,
        force: Annotated[bool, typer.Option("--force", help="Overwrite existing files.")] = False,
    ) -> None:
        """Drive to a pose with one of the pose laws (document 002), or benchmark them all."""
        console = Console()
        if benchmark:
            report = control_benchmark_to_files(out, tracking=tracking, force=force)
            console.print(_pose_table(report["pose"]))
            if tracking:
                console.print(_tracking_table(report["tracking"]))
            console.print(f"wrote {out / 'benchmark.json'} and the fan figures")
            return
        if start is None:
            raise ConfigError("--start X Y ANGLE is required unless --benchmark")
        if law == "mppi":
            _mppi_run(map_name, _pose(start, "start"), _pose(goal, "goal"), out, force=force,
                      max_speed=max_speed, max_yaw_rate=max_yaw_rate, t_end=t_end)  # fmt: skip
            return
        if law not in POSE_LAWS:
            raise ConfigError(f"unknown law {law!r}; allowed: {', '.join(POSE_LAWS)}")
        metrics = control_run_to_files(
            law,
            _pose(start, "start"),
            _pose(goal, "goal"),
            out,
            max_speed=max_speed,
            max_yaw_rate=max_yaw_rate,
            t_end=t_end,
            dt=dt,
            force=force,
        )
        arrived = metrics["success_rate"] == 1.0
        summary = (
            f"arrived in {metrics['mean_time_s']:.2f} s, path {metrics['mean_path_length_m']:.2f} m"
            if arrived
            else "did not arrive"
        )
        console.print(
            f"{law}: {summary}; final error {100 * metrics['max_final_position_error_m']:.2f} cm, "
            f"{metrics['max_final_heading_error_deg']:.2f}°; wrote {out}"
        )
