"""``wheelbase posegraph``: optimise a g2o pose graph and report χ², iterations and time.

``wheelbase posegraph FILE.g2o --out DIR`` reads the graph (:func:`wheelbase.datasets.read_g2o`),
optimises it (:func:`wheelbase.mapping.optimize_pose_graph`, chordal initialisation by default)
and writes ``metrics.json`` (``chi2_initial``, ``chi2``, ``iterations``, ``solve_time_s``),
``optimized.g2o`` and ``graph.png`` (initial and optimised poses with the loop edges).
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Annotated

import typer

from wheelbase._validate import check_choice
from wheelbase.commands.options import out_option

__all__ = ["POSEGRAPH_FILES", "register"]

POSEGRAPH_FILES: tuple[str, ...] = ("metrics.json", "optimized.g2o", "graph.png")


def register(app: typer.Typer) -> None:
    """Add ``posegraph`` to the ``wheelbase`` app.

    Parameters
    ----------
    app : typer.Typer
        The main application (or a test app).
    """

    @app.command()
    def posegraph(
        graph_file: Annotated[Path, typer.Argument(help="A 2-D g2o file (VERTEX_SE2, EDGE_SE2).")],
        out: Annotated[
            Path, out_option("posegraph", ", ".join(POSEGRAPH_FILES))
        ] = "wheelbase-posegraph",
        initial: str = typer.Option("chordal", "--initial", help="chordal or graph."),
        robust: str = typer.Option("none", "--robust", help="none, huber, cauchy or dcs."),
        robust_scale: float = typer.Option(1.0, "--robust-scale", help="The kernel's k."),
        force: bool = typer.Option(False, "--force", help="Overwrite existing files."),
    ) -> None:
        """Optimise a pose graph (sparse Gauss-Newton / LM on SE(2)); write metrics, figure."""
        from wheelbase.commands.odometry import _prepare
        from wheelbase.datasets.g2o import read_g2o, write_g2o
        from wheelbase.mapping.plot import plot_pose_graph
        from wheelbase.mapping.posegraph import (
            INITIALIZATIONS,
            ROBUST_KERNELS,
            optimize_pose_graph,
        )

        check_choice("initial", initial, INITIALIZATIONS)
        check_choice("robust", robust, ROBUST_KERNELS)
        graph = read_g2o(graph_file)
        paths = _prepare(out, POSEGRAPH_FILES, force)
        result = optimize_pose_graph(
            graph, initial=initial, robust=robust, robust_scale=robust_scale
        )
        report = {**result.metrics(), "vertices": graph.n_vertices, "edges": graph.n_edges,
                  "initial": initial, "robust": robust, "file": str(graph_file)}  # fmt: skip
        paths["metrics.json"].write_text(json.dumps(report, indent=2) + "\n")
        write_g2o(graph.with_poses(result.poses), paths["optimized.g2o"], overwrite=True)
        plot_pose_graph(graph.poses, result.poses, graph.edges, paths["graph.png"],
                        graph_file.stem)  # fmt: skip
        typer.echo(
            f"{graph_file.name}: {graph.n_vertices} poses, {graph.n_edges} edges; χ² "
            f"{result.chi2_initial:.6g} → {result.chi2:.6g} in {result.iterations} iterations, "
            f"{result.solve_time_s:.3f} s"
        )
        typer.echo(f"wrote {', '.join(map(str, paths.values()))}")
