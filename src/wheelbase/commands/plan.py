"""``wheelbase plan``: Hybrid A* on a map file or a bundled map.

``wheelbase plan MAP --start X Y DEG --goal X Y DEG --turning-radius R --footprint L W
[--rear-axle-to-center C] [--no-reverse] --out DIR`` plans with
:class:`~wheelbase.planning.HybridAStar` and writes ``path.csv``, ``path.png`` (map, footprints
along the path, start/goal arrows) and ``metrics.json`` (``success``, ``length_m``, ``cusps``,
``planning_time_s``, ``expanded_nodes``, ``min_clearance_m``), and prints the metrics. MAP is a
ROS ``map_server`` YAML, a Moving AI ``.map`` (1 m cells), a polygon world (YAML or GeoJSON, see
:mod:`wheelbase.planning.world_io`: collision and ``min_clearance_m`` exact on the polygons, the
figure draws them) or a bundled map name (``parking_lot``, ``corridor_uturn``, ``maze``,
``warehouse``, ``parallel_120``, ``perpendicular_bay``, …). Headings are in degrees unless
written with ``rad`` (``1.57rad``); ``90deg`` is accepted too.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Annotated, Any

import numpy as np
import typer

from wheelbase._validate import finite, parse_angle
from wheelbase.errors import ConfigError

__all__ = ["PLAN_FILES", "plan_to_files", "register"]

PLAN_FILES: tuple[str, ...] = ("path.csv", "path.png", "metrics.json")


def _heading_deg(text: str, name: str) -> float:
    """Heading text → radians; a bare number is in degrees (the unit of --start/--goal)."""
    return parse_angle(text, f"{name} heading", default_unit="deg")


def _pose(values: tuple[str, str, str], name: str) -> np.ndarray:
    x_text, y_text, heading = values
    coords = []
    for text in (x_text, y_text):
        try:
            coords.append(finite(name, float(text), "m"))
        except ValueError:
            raise ConfigError(f"{name} must be X Y DEG (got {values!r})") from None
    return np.array([coords[0], coords[1], _heading_deg(heading, name)])


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
) -> dict[str, Any]:
    """Plan and write ``path.csv``, ``path.png`` and ``metrics.json`` into ``out``.

    Parameters
    ----------
    map_name : str
        Map file or bundled map name.
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
    grid = load_map(map_name)
    planner = HybridAStar(
        grid,
        footprint,
        turning_radius,
        reverse=reverse,
        rear_axle_to_center=rear_axle_to_center,
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
        + (f", {path.length:.2f} m, {path.cusps} cusps" if path.success else "")
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
        map_name: Annotated[
            str,
            typer.Argument(
                metavar="MAP",
                help="ROS map YAML, Moving AI .map, a polygon world (.yaml or .geojson), or "
                "a bundled map: parking_lot, corridor_uturn, maze, warehouse, parallel_120, ...",
            ),
        ],
        start: Annotated[
            tuple[str, str, str],
            typer.Option(help="Start pose X [m] Y [m] heading [deg, or e.g. 1.57rad]."),
        ],
        goal: Annotated[
            tuple[str, str, str],
            typer.Option(help="Goal pose X [m] Y [m] heading [deg, or e.g. 1.57rad]."),
        ],
        out: Annotated[
            Path, typer.Option(help="Output folder for path.csv, path.png, metrics.json.")
        ],
        turning_radius: Annotated[
            float, typer.Option(help="Minimum turning radius [m]; 0 turns in place.")
        ] = 0.0,
        footprint: Annotated[
            tuple[float, float], typer.Option(help="Footprint length and width [m].")
        ] = (0.66, 0.5),
        rear_axle_to_center: Annotated[
            float,
            typer.Option(
                help="Distance [m] from the reference point (rear axle) to the footprint centre."
            ),
        ] = 0.0,
        reverse: Annotated[
            bool, typer.Option("--reverse/--no-reverse", help="Allow driving backwards.")
        ] = True,
        force: Annotated[bool, typer.Option(help="Overwrite existing output files.")] = False,
    ) -> None:
        """Plan a path with Hybrid A* and write path.csv, path.png and metrics.json."""
        metrics = plan_to_files(
            map_name,
            _pose(start, "start"),
            _pose(goal, "goal"),
            turning_radius,
            footprint,
            out,
            rear_axle_to_center=rear_axle_to_center,
            reverse=reverse,
            force=force,
        )
        from rich.console import Console
        from rich.table import Table

        table = Table(title=f"wheelbase plan → {out}")
        table.add_column("metric")
        table.add_column("value", justify="right")
        for key, value in metrics.items():
            text = f"{value:.4g}" if isinstance(value, float) else str(value)
            table.add_row(key, text)
        Console().print(table)
