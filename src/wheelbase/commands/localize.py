"""``wheelbase localize``: a filter over a real recording (UTIAS MRCLAM) against its ground truth.

``wheelbase localize DATA_DIR --robot 1 --filter ekf --out DIR`` runs the EKF, UKF or particle
filter of :func:`wheelbase.localization.mrclam.localize` over the robot's whole recording with
the one documented parameter set, and writes ``metrics.json`` (the figures, the counts of
measurements used and rejected, the parameters), ``paths.png`` (true path, estimate and dead
reckoning on the landmark map) and ``error.png`` (position error against time with the
filter's 3σ bound).
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Annotated

import typer

from wheelbase._validate import check_choice, integer
from wheelbase.commands.options import out_option

__all__ = ["LOCALIZE_FILES", "register"]

LOCALIZE_FILES: tuple[str, ...] = ("metrics.json", "paths.png", "error.png")


def register(app: typer.Typer) -> None:
    """Add ``localize`` to the ``wheelbase`` app.

    Parameters
    ----------
    app : typer.Typer
        The main application (or a test app).
    """

    @app.command()
    def localize(
        data_dir: Annotated[Path, typer.Argument(help="Folder of one MRCLAM data set.")],
        out: Annotated[
            Path, out_option("localize", ", ".join(LOCALIZE_FILES))
        ] = "wheelbase-localize",
        robot: int = typer.Option(1, "--robot", help="Robot number, 1-5."),
        filter: str = typer.Option("ekf", "--filter", help="ekf, ukf or pf."),
        seed: int = typer.Option(0, "--seed", help="Seed of the particle filter."),
        force: bool = typer.Option(False, "--force", help="Overwrite existing files."),
    ) -> None:
        """Localise an MRCLAM robot with an EKF, UKF or particle filter; write metrics, figures."""
        from wheelbase.commands.odometry import _prepare
        from wheelbase.localization.mrclam import FILTERS
        from wheelbase.localization.mrclam import localize as run
        from wheelbase.localization.plot import plot_error, plot_paths

        seed = integer("seed", seed, minimum=0)
        robot = integer("robot", robot, 1, 5)
        check_choice("filter", filter, FILTERS)
        paths = _prepare(out, LOCALIZE_FILES, force)  # before the run, which takes seconds
        result = run(data_dir, robot, filter, seed=seed)
        metrics = result.metrics()
        title = f"MRCLAM {result.dataset}, robot {robot}: {filter.upper()}"
        plot_paths(result, paths["paths.png"], title)
        plot_error(result, paths["error.png"], title)
        report = {**metrics, "dataset": result.dataset, "robot": robot,
                  "data_dir": str(data_dir), "seed": seed,
                  "parameters": result.parameters}  # fmt: skip
        paths["metrics.json"].write_text(json.dumps(report, indent=2) + "\n")
        typer.echo(
            f"{filter.upper()} robot {robot}: position RMSE {metrics['position_rmse_m']:.3f} m, "
            f"max {metrics['position_max_m']:.3f} m, heading RMSE "
            f"{metrics['heading_rmse_deg']:.2f} deg (dead reckoning "
            f"{metrics['dead_reckoning_rmse_m']:.2f} m), position NEES "
            f"{metrics['position_nees_mean']:.2f} (2 when consistent)"
        )
        typer.echo(f"wrote {', '.join(map(str, paths.values()))}")
