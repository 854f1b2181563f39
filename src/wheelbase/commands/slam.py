"""``wheelbase posegraph``, ``slam`` and ``map``: pose graphs, SLAM and mapping on recorded data.

``wheelbase slam DATA --out DIR`` runs lidar pose-graph SLAM on a CARMEN log or a ROS 2 bag
(:class:`wheelbase.mapping.lidar_slam.LidarSlam`) and writes ``metrics.json``, the map
(``map.yaml`` + ``map.pgm``), ``map.png`` (map, trajectory, loop closures), ``error.png``
(position error against time, when the log has reference poses), ``map.gif`` (the map
growing), ``graph.g2o`` and, with ``--mcap``, ``map.mcap``; on an MRCLAM folder it runs
landmark SLAM (:func:`wheelbase.mapping.landmark_slam.landmark_slam`, ``--robot N``).
``wheelbase map LOG --out DIR`` builds the occupancy map from the log's own poses.

``wheelbase posegraph FILE.g2o --out DIR`` reads the graph (:func:`wheelbase.datasets.read_g2o`),
optimises it (:func:`wheelbase.mapping.optimize_pose_graph`, chordal initialisation by default)
and writes ``metrics.json`` (``chi2_initial``, ``chi2``, ``iterations``, ``solve_time_s``),
``optimized.g2o`` and ``graph.png`` (initial and optimised poses with the loop edges).
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Annotated

import numpy as np
import typer

from wheelbase._validate import check_choice
from wheelbase.commands.options import out_option

__all__ = ["MAP_FILES", "POSEGRAPH_FILES", "SLAM_LANDMARK_FILES", "SLAM_LIDAR_FILES", "register"]

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

    register_slam(app)


SLAM_LIDAR_FILES: tuple[str, ...] = (
    "metrics.json", "map.yaml", "map.pgm", "map.png", "error.png", "map.gif", "graph.g2o",
)  # fmt: skip
SLAM_LANDMARK_FILES: tuple[str, ...] = ("metrics.json", "map.png", "error.png")
MAP_FILES: tuple[str, ...] = ("metrics.json", "map.yaml", "map.pgm", "map.png")


def _growth_frames(slam, log, result, count: int) -> list:
    """(time, grid, trajectory) of the map as it grew, at ``count`` snapshots."""
    frames = []
    picks = np.unique(np.linspace(0, len(result.snapshots) - 1, count).round().astype(int))
    for index in picks:
        last, poses = result.snapshot_poses(int(index))
        part = log.subset(slice(0, last + 1))
        grid = slam.render(part, poses).to_grid()
        frames.append((float(log.t[last] - log.t[0]), grid, poses))
    return frames


def _lidar_slam(data: Path, paths: dict[str, Path], frames: int, mcap: bool,
                use_odometry: bool, max_scans: int | None) -> dict:  # fmt: skip
    from wheelbase.datasets.g2o import write_g2o
    from wheelbase.datasets.open import read_scans
    from wheelbase.mapping.evaluation import align_trajectory, lidar_metrics
    from wheelbase.mapping.lidar_slam import LidarSlam
    from wheelbase.mapping.plot import animate_map, plot_error, plot_map
    from wheelbase.planning.map_io import write_ros_yaml

    log = read_scans(data)
    if max_scans is not None:
        log = log.subset(slice(0, max_scans))
    with_odometry = use_odometry and log.odometry is not None
    slam = LidarSlam(use_odometry=True) if with_odometry else LidarSlam.without_odometry()
    every = max(1, log.n_scans // max(frames, 1))
    result = slam.run(log, snapshot_every=every)
    grid = slam.render(log, result.poses).to_grid()
    write_ros_yaml(grid, paths["map.yaml"])
    metrics = lidar_metrics(log, result)
    metrics["use_odometry"] = bool(use_odometry and log.odometry is not None)
    plot_map(grid, paths["map.png"], result.poses, result.loops, log.reference,
             f"{log.source}: {result.keyframes.size} keyframes, {len(result.loops)} loop "
             "closures")  # fmt: skip
    # a log whose stamps are not times is drawn against the scan number
    t = log.t - log.t[0] if log.timed else np.arange(log.n_scans, dtype=np.float64)
    xlabel = "time [s]" if log.timed else "scan"
    if log.reference is not None:
        errors = {
            "SLAM": np.hypot(*(align_trajectory(result.poses, log.reference)[:, :2]
                               - log.reference[:, :2]).T),
            "scan matching online": np.hypot(*(align_trajectory(result.frontend_poses,
                                               log.reference)[:, :2] - log.reference[:, :2]).T),
        }  # fmt: skip
        plot_error(t, errors, paths["error.png"], f"{log.source}: against the reference",
                   xlabel=xlabel)  # fmt: skip
    else:
        steps = np.hypot(*np.diff(result.poses[:, :2], axis=0).T)
        plot_error(t[1:], {"distance between scans": steps}, paths["error.png"],
                   "no reference in the log", ylabel="step [m]", xlabel=xlabel)  # fmt: skip
    growth = _growth_frames(slam, log, result, frames)
    animate_map([(g, p) for _, g, p in growth], paths["map.gif"], log.source)
    if mcap:
        from wheelbase.mcap_export import write_map_growth_mcap

        write_map_growth_mcap(growth, paths["map.mcap"], overwrite=True)
    write_g2o(result.graph, paths["graph.g2o"], overwrite=True)
    return metrics


def _landmark_slam(data: Path, robot: int, paths: dict[str, Path], method: str) -> dict:
    from wheelbase.mapping.landmark_slam import landmark_slam
    from wheelbase.mapping.plot import plot_error, plot_landmarks

    result = landmark_slam(data, robot, method)
    metrics = result.metrics()
    plot_landmarks(result, paths["map.png"], f"MRCLAM robot {robot}: {method}")
    error = {
        method: np.hypot(*(result.estimate[:, :2] - result.truth[:, :2]).T),
        "dead reckoning": np.hypot(*(result.dead_reckoning[:, :2] - result.truth[:, :2]).T),
    }
    plot_error(result.t, error, paths["error.png"], f"MRCLAM robot {robot}: against Vicon")
    return {**metrics, "robot": robot, "parameters": result.parameters}


def register_slam(app: typer.Typer) -> None:
    """Add ``slam`` and ``map`` to the ``wheelbase`` app.

    Parameters
    ----------
    app : typer.Typer
        The main application (or a test app).
    """

    @app.command()
    def slam(
        data: Annotated[
            Path, typer.Argument(help="A CARMEN log, a ROS 2 bag, or an MRCLAM folder.")
        ],
        out: Annotated[
            Path, out_option("slam", "metrics.json, the map, figures (an MCAP with --mcap)")
        ] = "wheelbase-slam",
        robot: int = typer.Option(1, "--robot", help="MRCLAM robot number, 1-5."),
        method: str = typer.Option("smoothing", "--method", help="Landmarks: ekf or smoothing."),
        frames: int = typer.Option(24, "--frames", help="Frames of the animation (lidar)."),
        mcap: bool = typer.Option(False, "--mcap", help="Also write map.mcap (lidar)."),
        odometry: bool = typer.Option(False, "--odometry", help="Predict with the log's odometry."),
        max_scans: int = typer.Option(0, "--max-scans", help="Use the first N scans (0: all)."),
        force: bool = typer.Option(False, "--force", help="Overwrite existing files."),
    ) -> None:
        """SLAM on recorded data: lidar pose-graph SLAM or landmark SLAM (chosen by the data)."""
        from wheelbase._validate import integer
        from wheelbase.commands.odometry import _prepare
        from wheelbase.mapping.landmark_slam import LANDMARK_SLAM_METHODS

        landmarks = data.is_dir() and not (data / "metadata.yaml").is_file()
        if landmarks:
            robot = integer("robot", robot, 1, 5)
            check_choice("method", method, LANDMARK_SLAM_METHODS)
            paths = _prepare(out, SLAM_LANDMARK_FILES, force)
            metrics = _landmark_slam(data, robot, paths, method)
            summary = (
                f"robot RMSE {metrics['position_rmse_m']:.3f} m, landmark RMSE "
                f"{metrics['landmark_rmse_m']:.3f} m ({metrics['landmarks_seen']} seen)"
            )
        else:
            frames = integer("frames", frames, 1, 1000)
            max_scans = integer("max_scans", max_scans, 0)
            names = SLAM_LIDAR_FILES + (("map.mcap",) if mcap else ())
            if mcap:
                from wheelbase.mcap_export import require_foxglove

                require_foxglove()
            paths = _prepare(out, names, force)
            metrics = _lidar_slam(data, paths, frames, mcap, odometry, max_scans or None)
            factor = metrics["real_time_factor"]
            speed = f"{factor:.1f}× real time" if math.isfinite(factor) else "no time stamps"
            summary = (f"{metrics['scans']} scans, {metrics['loop_closures']} loop closures, "
                       f"{metrics['processing_time_s']:.1f} s ({speed})")  # fmt: skip
            if "relative_translation_error_m" in metrics:
                summary += (f"; relative error {metrics['relative_translation_error_m']:.3f} m, "
                            f"{metrics['relative_rotation_error_deg']:.2f} deg")  # fmt: skip
        metrics["data"] = str(data)
        paths["metrics.json"].write_text(json.dumps(metrics, indent=2, default=float) + "\n")
        typer.echo(f"{data.name}: {summary}")
        typer.echo(f"wrote {', '.join(map(str, paths.values()))}")

    @app.command("map")
    def map_command(
        data: Annotated[Path, typer.Argument(help="A CARMEN log or a ROS 2 bag.")],
        out: Annotated[Path, out_option("map", ", ".join(MAP_FILES))] = "wheelbase-map",
        poses: str = typer.Option("reference", "--poses", help="reference or odometry."),
        resolution: float = typer.Option(0.05, "--resolution", help="Cell side [m]."),
        max_range: float = typer.Option(30.0, "--max-range", help="Longest reading used [m]."),
        force: bool = typer.Option(False, "--force", help="Overwrite existing files."),
    ) -> None:
        """Occupancy map from a log's own poses (known poses): map_server YAML + PGM, figure."""
        from wheelbase.commands.odometry import _prepare
        from wheelbase.datasets.open import read_scans
        from wheelbase.errors import DataError
        from wheelbase.mapping.occupancy import OccupancyMapper
        from wheelbase.mapping.plot import plot_map
        from wheelbase.planning.map_io import write_ros_yaml

        check_choice("poses", poses, ("reference", "odometry"))
        mapper = OccupancyMapper(resolution=resolution, max_range=max_range)
        log = read_scans(data)
        chosen = log.reference if poses == "reference" else log.odometry
        if chosen is None:
            raise DataError(f"{data}: the log has no {poses} poses (try --poses "
                            f"{'odometry' if poses == 'reference' else 'reference'})")  # fmt: skip
        paths = _prepare(out, MAP_FILES, force)
        built = mapper.build(chosen, log.ranges, log.angles, mount=log.mount,
                             sensor_max_range=log.max_range)  # fmt: skip
        grid = built.to_grid()
        write_ros_yaml(grid, paths["map.yaml"])
        plot_map(grid, paths["map.png"], chosen, title=f"{log.source}: {poses} poses")
        known = ~grid.unknown
        metrics = {"scans": log.n_scans, "cells": int(grid.occupied.size),
                   "occupied_cells": int((grid.occupied & known).sum()),
                   "free_cells": int((~grid.occupied & known).sum()),
                   "skipped_beams": built.skipped_beams, "invalid_readings": log.invalid_readings,
                   "resolution": resolution, "poses": poses, "data": str(data)}  # fmt: skip
        paths["metrics.json"].write_text(json.dumps(metrics, indent=2) + "\n")
        typer.echo(f"{log.source}: {log.n_scans} scans → {grid.shape[1]} × {grid.shape[0]} "
                   f"cells at {resolution:g} m")  # fmt: skip
        typer.echo(f"wrote {', '.join(map(str, paths.values()))}")
