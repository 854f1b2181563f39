"""``wheelbase explore SCENARIO --out DIR``: frontier exploration of a world without a map.

Reads an exploration scenario (``map: unknown``, the true world in ``world.map``; see
:mod:`wheelbase.exploration`), explores until no reachable frontier is left and writes
``metrics.json`` (status, explored fraction, map agreement, collisions, times, distance),
the map (``map.yaml`` + ``map.pgm``, loadable by ``wheelbase run`` with ``map: DIR/map.yaml``),
``map.png`` (the map with the true and SLAM trajectories and the frontiers visited, numbered)
and, unless ``--frames 0``, ``map.gif`` (the map after each leg).
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Annotated

import typer

from wheelbase.commands.options import out_option

__all__ = ["EXPLORE_FILES", "register"]

EXPLORE_FILES: tuple[str, ...] = ("metrics.json", "map.yaml", "map.pgm", "map.png", "map.gif")


def register(app: typer.Typer) -> None:
    """Add ``explore`` to the ``wheelbase`` app.

    Parameters
    ----------
    app : typer.Typer
        The main application (or a test app).
    """

    @app.command()
    def explore(
        scenario: Annotated[
            Path, typer.Argument(help="An exploration scenario (map: unknown, world.map).")
        ],
        out: Annotated[Path, out_option("explore", ", ".join(EXPLORE_FILES))] = "wheelbase-explore",
        frames: int = typer.Option(24, "--frames", help="Frames of map.gif (0: no GIF)."),
        force: bool = typer.Option(False, "--force", help="Overwrite existing files."),
    ) -> None:
        """Explore a world without a map (frontiers, Hybrid A*, lidar SLAM); save the map."""
        from wheelbase._validate import integer
        from wheelbase.commands.odometry import _prepare
        from wheelbase.exploration import explore as run_exploration
        from wheelbase.exploration import load_exploration
        from wheelbase.mapping.plot import animate_map, plot_map
        from wheelbase.planning.map_io import write_ros_yaml

        frames = integer("frames", frames, 0, 1000)
        loaded = load_exploration(scenario)
        names = EXPLORE_FILES if frames else EXPLORE_FILES[:-1]
        paths = _prepare(out, names, force)
        result = run_exploration(
            loaded, progress=lambda leg, status: typer.echo(f"leg {leg}: {status}", err=True)
        )
        write_ros_yaml(result.grid, paths["map.yaml"])
        paths["metrics.json"].write_text(json.dumps(result.metrics, indent=2) + "\n")
        m = result.metrics
        plot_map(
            result.grid, paths["map.png"], result.estimated_path, None, result.true_path,
            f"{result.scenario.name}: {m['status']}, {100 * m['explored_fraction']:.1f} % "
            f"explored in {m['simulated_time_s']:.0f} s", frontiers=result.frontiers,
        )  # fmt: skip
        if frames:
            picks = sorted({round(k * (len(result.frames) - 1) / max(frames - 1, 1))
                            for k in range(frames)})  # fmt: skip
            animate_map([result.frames[k][1:] for k in picks], paths["map.gif"],
                        result.scenario.name)  # fmt: skip
        typer.echo(
            f"{result.scenario.name}: {m['status']} after {m['legs']} legs, "
            f"{100 * m['explored_fraction']:.1f} % of the reachable free area mapped, map "
            f"agreement {m['map_agreement']:.4f}, {m['collisions']} collisions, "
            f"{m['distance_m']:.1f} m in {m['simulated_time_s']:.0f} s simulated"
        )
        typer.echo(f"wrote {', '.join(map(str, paths.values()))}")
