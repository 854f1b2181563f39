"""``wheelbase plan``: Hybrid A* on a map file or a bundled map.

``wheelbase plan MAP --start X,Y,DEG --goal X,Y,DEG --turning-radius R --footprint L W
[--rear-axle-to-center C] [--no-reverse] --out DIR`` plans with
:class:`~wheelbase.planning.HybridAStar` and writes ``path.csv``, ``path.png`` (map, footprints
along the path, start/goal arrows) and ``metrics.json`` (``success``, ``length_m``, ``cusps``,
``planning_time_s``, ``expanded_nodes``, ``min_clearance_m``), and prints the metrics. MAP is a
ROS ``map_server`` YAML, a Moving AI ``.map`` (1 m cells), a polygon world (YAML or GeoJSON, see
:mod:`wheelbase.planning.world_io`: collision and ``min_clearance_m`` exact on the polygons, the
figure draws them), a bundled map name (``parking_lot``, ``corridor_uturn``, ``maze``,
``warehouse``, ``parallel_120``, ``perpendicular_bay``, …) or ``empty`` (open ground around
the start and goal, as in scenarios). Headings are in degrees unless
written with ``rad`` (``1.57rad``), as everywhere on the command line
(:mod:`wheelbase.commands.options`).

The search's resolution is the planner's default unless ``--headings``, ``--xy-resolution``,
``--collision-step``, ``--time-limit`` or ``--moves-to-contact`` say otherwise (tight parking
needs them: moves of centimetres, cut at contact). ``--case NAME`` takes one of the bundled
planning cases of ``benchmarks/planning.py`` whole (map, start, goal, robot and those
settings, e.g. ``wheelbase plan --case parallel_115_in --out DIR``); flags given beside it
override its values.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Annotated, Any

import numpy as np
import typer

from wheelbase.commands.options import out_option, pose_option
from wheelbase.commands.output import console, plural
from wheelbase.errors import ConfigError

__all__ = ["PLAN_FILES", "plan_to_files", "register"]

PLAN_FILES: tuple[str, ...] = ("path.csv", "path.png", "metrics.json")


def _query(
    case: str | None,
    map_name: str | None,
    start: np.ndarray | None,
    goal: np.ndarray | None,
) -> dict[str, Any]:
    """Map, poses, robot and planner options of the command: a bundled case's, with the flags
    given beside it in their place, or the flags alone (then MAP, --start and --goal are
    required)."""
    robot: dict[str, Any] = {"turning_radius": 0.0, "footprint": (0.66, 0.5),
                             "rear_axle_to_center": 0.0}  # fmt: skip
    options: dict[str, Any] = {}
    poses: dict[str, Any] = {"start": None, "goal": None}
    if case is not None:
        from wheelbase.planning.maps import bundled_scenarios

        cases = {sc.name: sc for sc in bundled_scenarios()}
        if case not in cases:
            raise ConfigError(f"--case must be one of {', '.join(sorted(cases))} (got {case!r})")
        chosen = cases[case]
        if map_name is not None and map_name != chosen.map_name:
            raise ConfigError(
                f"--case {case} plans on the bundled map {chosen.map_name!r}: leave out MAP "
                f"(got {map_name!r})"
            )
        map_name = chosen.map_name
        poses = {"start": chosen.start, "goal": chosen.goal}
        robot = {"turning_radius": chosen.turning_radius, "footprint": chosen.footprint,
                 "rear_axle_to_center": chosen.rear_axle_to_center}  # fmt: skip
        options = dict(chosen.planner)
    if map_name is None:
        raise ConfigError("give MAP (a map file or bundled map name) or --case")
    for name, values in (("start", start), ("goal", goal)):
        if values is not None:
            poses[name] = values
        elif poses[name] is None:
            raise ConfigError(f"give --{name} X,Y,HEADING (or --case)")
    return {"map": map_name, **poses, "robot": robot, "options": options}


def plan_to_files(
    map_name: str,
    start: np.ndarray,
    goal: np.ndarray,
    turning_radius: float,
    footprint: tuple[float, float],
    out: Path,
    *,
    rear_axle_to_center: float = 0.0,
    reverse: bool = True,
    force: bool = False,
    planner_options: dict[str, Any] | None = None,
    map_resolution: float | None = None,
) -> dict[str, Any]:
    """Plan and write ``path.csv``, ``path.png`` and ``metrics.json`` into ``out``.

    Parameters
    ----------
    map_name : str
        Map file, bundled map name, or ``"empty"`` (open ground 3 m around the start and goal,
        as a scenario's ``map: empty``).
    start : numpy.ndarray
        Start pose ``(x, y, θ)`` [m, m, rad].
    goal : numpy.ndarray
        Goal pose.
    turning_radius : float
        Minimum turning radius [m] (0: turn in place).
    footprint : tuple of float
        ``(length, width)`` [m].
    out : pathlib.Path
        Output folder.
    rear_axle_to_center : float
        Reference point to footprint centre [m].
    reverse : bool
        Allow reverse driving.
    force : bool
        Overwrite existing files.
    planner_options : dict or None
        Further :class:`~wheelbase.planning.HybridAStar` keywords (``headings``,
        ``xy_resolution``, ``collision_step``, ``time_limit``, ``moves_to_contact``, …).
    map_resolution : float or None
        Cell side [m/pixel] of a bare image map (required there; see
        :func:`wheelbase.planning.load_map`).

    Returns
    -------
    dict
        The metrics written to ``metrics.json``.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from wheelbase.planning import HybridAStar, load_map

    out = Path(out)
    if out.exists() and not out.is_dir():
        raise ConfigError(f"--out must be a folder (got the file {out})")
    paths = {name: out / name for name in PLAN_FILES}
    existing = [str(p) for p in paths.values() if p.exists()]
    if existing and not force:
        raise FileExistsError(f"{', '.join(existing)} exists; pass --force to overwrite")
    if map_name == "empty":  # as in scenarios and `wheelbase control --map empty`
        from wheelbase.scenario import empty_map

        grid = empty_map([start, goal])
    else:
        grid = load_map(map_name, resolution=map_resolution)
    planner = HybridAStar(
        grid,
        footprint,
        turning_radius,
        reverse=reverse,
        rear_axle_to_center=rear_axle_to_center,
        **(planner_options or {}),
    )
    path = planner.plan(start, goal)
    clearance = (
        float(np.min(grid.footprint_clearance(planner.footprint, path.poses)))
        if path.success
        else None
    )
    metrics = {
        "success": bool(path.success),
        "length_m": float(path.length) if path.success else None,
        "cusps": int(path.cusps) if path.success else None,
        "planning_time_s": path.stats.planning_time_s,
        "compile_time_s": path.stats.compile_time_s,
        "expanded_nodes": path.stats.expanded_nodes,
        "min_clearance_m": clearance,
        "message": path.stats.message,
    }
    out.mkdir(parents=True, exist_ok=True)
    path.to_csv(paths["path.csv"])
    from wheelbase.planning.plot import plot_path

    ax = plot_path(path, grid=grid, footprint=planner.footprint, start=start, goal=goal)
    ax.set_title(
        f"Hybrid A*: {metrics['message']}"
        + (f", {path.length:.2f} m, {plural(path.cusps, 'cusp')}" if path.success else "")
    )
    ax.figure.savefig(paths["path.png"], dpi=120, bbox_inches="tight")
    plt.close(ax.figure)
    paths["metrics.json"].write_text(json.dumps(metrics, indent=2) + "\n")
    return metrics


def register(app: typer.Typer) -> None:
    """Add ``plan`` to the main app.

    Parameters
    ----------
    app : typer.Typer
        The ``wheelbase`` application.
    """

    @app.command("plan")
    def plan(
        out: Annotated[Path, out_option("plan", ", ".join(PLAN_FILES))] = "wheelbase-plan",
        map_name: Annotated[
            str | None,
            typer.Argument(
                metavar="MAP",
                help="ROS map YAML, Moving AI .map, a polygon world (.yaml or .geojson), "
                "a bundled map: parking_lot, corridor_uturn, maze, warehouse, parallel_120, ..., "
                "or 'empty' (open ground around the start and goal; optional with --case).",
            ),
        ] = None,
        start: Annotated[np.ndarray | None, pose_option("--start", "Start pose")] = None,
        goal: Annotated[np.ndarray | None, pose_option("--goal", "Goal pose")] = None,
        case: Annotated[
            str | None,
            typer.Option(
                help="A bundled planning case (map, poses, robot, settings), e.g. "
                "parallel_115_in, maze_car; flags given beside it override it."
            ),
        ] = None,
        turning_radius: Annotated[
            float | None,
            typer.Option(help="Minimum turning radius [m]; 0 turns in place.  [default: 0]"),
        ] = None,
        footprint: Annotated[
            tuple[float, float] | None,
            typer.Option(help="Footprint length and width [m].  [default: 0.66, 0.5]"),
        ] = None,
        rear_axle_to_center: Annotated[
            float | None,
            typer.Option(
                help="Distance [m] from the reference point (rear axle) to the footprint "
                "centre.  [default: 0]"
            ),
        ] = None,
        reverse: Annotated[
            bool, typer.Option("--reverse/--no-reverse", help="Allow driving backwards.")
        ] = True,
        headings: Annotated[
            int | None, typer.Option(help="Heading bins (72 = 5°, the default).")
        ] = None,
        xy_resolution: Annotated[
            float | None,
            typer.Option(help="Position bin [m] (default: a quarter of the footprint's width)."),
        ] = None,
        collision_step: Annotated[
            float | None,
            typer.Option(help="Collision sample spacing [m] (default: half a map cell)."),
        ] = None,
        time_limit: Annotated[
            float | None, typer.Option(help="Search time limit [s] (default 5).")
        ] = None,
        resolution: Annotated[
            float | None,
            typer.Option(
                help="Cell side of a bare image MAP [m/pixel] (required for one: an image "
                "carries no scale; other maps carry their own)."
            ),
        ] = None,
        moves_to_contact: Annotated[
            bool | None,
            typer.Option(
                "--moves-to-contact/--no-moves-to-contact",
                help="Cut a motion at its last free sample near obstacles (tight parking).",
                show_default=False,
            ),
        ] = None,
        force: Annotated[bool, typer.Option(help="Overwrite existing output files.")] = False,
    ) -> None:
        """Plan a path with Hybrid A* and write path.csv, path.png and metrics.json."""
        given = {
            "headings": headings,
            "xy_resolution": xy_resolution,
            "collision_step": collision_step,
            "time_limit": time_limit,
            "moves_to_contact": moves_to_contact,
        }
        query = _query(case, map_name, start, goal)
        robot = query["robot"]
        options = {**query["options"], **{k: v for k, v in given.items() if v is not None}}
        metrics = plan_to_files(
            query["map"],
            query["start"],
            query["goal"],
            robot["turning_radius"] if turning_radius is None else turning_radius,
            robot["footprint"] if footprint is None else footprint,
            out,
            rear_axle_to_center=(
                robot["rear_axle_to_center"] if rear_axle_to_center is None else rear_axle_to_center
            ),
            reverse=reverse,
            force=force,
            planner_options=options,
            map_resolution=resolution,
        )
        from rich.table import Table

        table = Table(title=f"wheelbase plan → {out}")
        table.add_column("metric")
        table.add_column("value", justify="right")
        for key, value in metrics.items():
            text = f"{value:.4g}" if isinstance(value, float) else str(value)
            table.add_row(key, text)
        console().print(table)
