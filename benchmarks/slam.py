"""Mapping and SLAM (issue 23): pose graphs beside GTSAM, lidar SLAM on the Intel and ACES
logs without odometry, SLAM in simulation against ground truth, landmark SLAM on MRCLAM.

Sections (one JSON object; ``targets`` says which targets this run met):

``posegraphs``
    Each graph of ``../shared/data/posegraph``: wheelbase's optimiser from the file's guess
    (``graph``) and from the chordal initialisation (``chordal``), and GTSAM 4.3's
    Levenberg–Marquardt from the file's guess (a prior on vertex 0, default parameters),
    taking turns; χ² in g2o's convention (Σ rᵀΩr = 2 × GTSAM's error), iterations, the best
    wall time of ``--repeat`` runs.
``carmen``
    :class:`~wheelbase.mapping.lidar_slam.LidarSlam` on each corrected log, **without
    odometry** (the logs' odometry fields repeat the corrected poses); Kümmerle's relative
    errors against the logs' own poses, which are a SLAM solution, not the benchmark's
    hand-verified relations. Pairs (:func:`~wheelbase.mapping.evaluation.relation_pairs`):
    each scan with the first one ≥ 0.5 m further along the reference (local) and each scan
    with the nearest one ≥ 30 s earlier within 1 m and 30° (loops); reported together and
    apart. ``processing_time_s`` is wall time on this machine, ``cpu_time_s`` the process's.
``simulation``
    A route with a loop on the bundled maze and warehouse, driven under AMCL (so that the
    robot follows it), with encoders whose wheels are 1 % larger than the odometry believes;
    the odometry is dead-reckoned from the logged ticks; SLAM with that odometry against the
    true poses (absolute trajectory RMSE) and the true map (agreement of the cells both call
    known), for a 60- and a 360-beam lidar; the same without loop closures beside it. The
    drift where the route comes back: the mean relative translation error of the loop
    relations (each scan with the nearest ≥ 30 s earlier within 1 m, at any heading).
``landmarks``
    :func:`~wheelbase.mapping.landmark_slam.landmark_slam` on MRCLAM data set 6 robot 1, EKF
    and smoothing, landmark positions unknown.
``occupancy_speed``
    CPU time of one 360-beam, 8 m scan into a 0.05 m grid.
``exploration``
    :func:`wheelbase.exploration.explore` on the bundled explorations (doorway; with the full
    run also maze and warehouse): status, explored fraction of the reachable free area, map
    agreement, collisions, distance, simulated and wall time; then AMCL on the saved map
    along a route across it, arrivals out of the seeds (``amcl_arrived``); on the warehouse
    also the demo's route as ``amcl_warehouse`` drives it (dynamic plant, noisy encoders, 5 cm
    goal tolerance) on the saved map (``amcl_on_explored_map``, also printed to stderr). In
    both the robot's map (plan, AMCL) is the explored one while the lidar, the collisions and
    the arrival see the true world (:func:`amcl_on_explored_map`).

Usage: ``python benchmarks/slam.py [--quick] [--sections posegraphs,carmen,...]
[--logs intel,aces] [--explore doorway,maze,warehouse]``.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

DATA = Path(__file__).resolve().parents[2] / "shared" / "data"


def _gtsam_lm(graph):
    import gtsam

    factors, values = gtsam.NonlinearFactorGraph(), gtsam.Values()
    for k, (i, j) in enumerate(graph.edges):
        factors.add(gtsam.BetweenFactorPose2(
            int(i), int(j), gtsam.Pose2(*graph.measurements[k]),
            gtsam.noiseModel.Gaussian.Information(graph.information[k])))  # fmt: skip
    for v, pose in enumerate(graph.poses):
        values.insert(v, gtsam.Pose2(*pose))
    factors.add(gtsam.PriorFactorPose2(0, gtsam.Pose2(*graph.poses[0]),
                                       gtsam.noiseModel.Isotropic.Sigma(3, 1e-6)))  # fmt: skip
    start = time.perf_counter()
    optimizer = gtsam.LevenbergMarquardtOptimizer(factors, values, gtsam.LevenbergMarquardtParams())
    result = optimizer.optimize()
    elapsed = time.perf_counter() - start
    poses = np.array([[result.atPose2(v).x(), result.atPose2(v).y(), result.atPose2(v).theta()]
                      for v in range(graph.n_vertices)])  # fmt: skip
    return poses, int(optimizer.iterations()), elapsed


POSE_GRAPHS = ("intel", "MIT", "CSAIL", "manhattan")
"""The bundled graphs of ``../shared/data/posegraph/`` (SE-Sync's data folder)."""


def posegraphs(repeat: int, folder: Path | None = None) -> dict:
    """Our solver from the file's guess and from the chordal start beside GTSAM's LM: the
    bundled graphs, or every 2-D ``*.g2o`` file of ``folder`` (``--graphs``)."""
    from wheelbase.datasets import read_g2o
    from wheelbase.errors import WheelbaseError
    from wheelbase.mapping import graph_chi2, optimize_pose_graph

    if folder is None:
        paths = [DATA / "posegraph" / f"{name}.g2o" for name in POSE_GRAPHS]
    else:
        paths = sorted(Path(folder).glob("*.g2o"))
    out = {}
    for path in paths:
        name = path.stem
        if not path.is_file():
            continue
        try:
            graph = read_g2o(path)
        except WheelbaseError as error:  # a 3-D graph, a broken file: said, not fatal
            out[name] = {"error": str(error)}
            continue
        row: dict = {"vertices": graph.n_vertices, "edges": graph.n_edges,
                     "chi2_initial": graph_chi2(graph)}  # fmt: skip
        times: dict = {"graph": [], "chordal": [], "gtsam": []}
        for _ in range(repeat):
            for init in ("graph", "chordal"):
                result = optimize_pose_graph(graph, initial=init)
                times[init].append(result.solve_time_s)
                row[init] = {"chi2": result.chi2, "iterations": result.iterations,
                             "converged": result.converged}  # fmt: skip
            try:
                poses, iterations, elapsed = _gtsam_lm(graph)
            except ImportError:
                row["gtsam"] = None
                continue
            times["gtsam"].append(elapsed)
            row["gtsam"] = {"chi2": graph_chi2(graph, poses), "iterations": iterations}
        for key, values in times.items():
            if values and row.get(key):
                row[key]["time_s"] = min(values)
        out[name] = row
    return out


def carmen(
    quick: bool, logs: tuple[str, ...] = ("intel", "aces"), folder: Path | None = None
) -> dict:
    """``LidarSlam.without_odometry()`` on the named bundled logs, or on every
    ``NAME-corrected.log.gz`` of ``folder`` (``--carmen``)."""
    from wheelbase.datasets import read_carmen
    from wheelbase.mapping import LidarSlam
    from wheelbase.mapping.evaluation import lidar_metrics

    if folder is None:
        paths = [DATA / "carmen" / f"{name}-corrected.log.gz" for name in logs]
    else:
        paths = sorted(Path(folder).glob("*-corrected.log.gz"))
    out = {}
    for path in paths:
        name = path.name.removesuffix("-corrected.log.gz")
        if not path.is_file():
            continue
        log = read_carmen(path)
        if quick:
            log = log.subset(slice(12, 80))
        cpu = time.process_time()
        result = LidarSlam.without_odometry().run(log)
        metrics = lidar_metrics(log, result)
        metrics["cpu_time_s"] = time.process_time() - cpu
        metrics["cpu_real_time_factor"] = (
            log.duration / metrics["cpu_time_s"] if log.timed else math.nan
        )
        metrics.pop("position_rmse_m", None)  # against a SLAM solution: not a ground truth
        out[name] = metrics
    return out


ROUTES = {
    "maze": {"start": [2.0, 2.0, 0.0],
             "goals": [[18.5, 6.0, 90.0], [2.0, 6.3, 180.0], [2.0, 2.0, -90.0]]},
    "warehouse": {"start": [3.0, 2.0, 0.0],
                  "goals": [[6.4, 12.0, 90.0], [17.2, 14.0, -90.0], [3.0, 2.0, 180.0]]},
}  # fmt: skip


def simulated_log(world: str, beams: int, quick: bool):
    """A looped route on a bundled map driven under AMCL, its scans as a ScanLog whose
    odometry is dead-reckoned from the logged encoder ticks (wheels 1 % larger than the
    odometry believes) and whose reference is the true pose; and the run's status."""
    import wheelbase
    from wheelbase.datasets import scans_from_log
    from wheelbase.dynamics import RM100, RM100_HALF_TRACK
    from wheelbase.odometry import WheelOdometry, integrate_increments
    from wheelbase.sensors import Lidar

    scenario = {
        "name": f"slam_{world}", "map": world,
        "robot": {"model": "diffdrive", "preset": "rm100"}, "plant": "kinematic",
        "controller": {"law": "kanayama"},
        "odometry": {"mode": "encoders", "pulses_per_revolution": 2048,
                     "wheel_radius_scale": [1.01, 1.01]},
        "sensors": {"lidar": {"beams": beams, "fov_deg": 360, "max_range": 8.0,
                              "range_std": 0.01, "rate_hz": 5}},
        "localization": {"method": "amcl"},
        "trajectory": {"max_speed": 0.6, "max_acceleration": 0.5, "max_yaw_rate": 1.0},
        "dt": 0.05, "duration": 400, **ROUTES[world],
    }  # fmt: skip
    if quick:
        scenario["goals"] = scenario["goals"][:1]
    run = wheelbase.run(scenario)
    log = scans_from_log(run.log, Lidar(beams=beams, max_range=8.0), source=f"{world}-{beams}")
    odo = WheelOdometry(RM100.wheel_radius, RM100_HALF_TRACK, 2048)
    ticks = run.log.ticks[0, : int(run.log.length[0])]
    distance, rotation = odo.increments(np.diff(ticks, axis=0))
    poses = integrate_increments(run.log.true_pose[0, 0], distance, rotation)
    rows = np.array(sorted(row for (r, row) in run.log.scans if r == 0))
    log = type(log)(log.t, log.ranges, log.angles, log.max_range, poses[rows], log.reference,
                    log.mount, log.invalid_readings, log.source)  # fmt: skip
    return log, run.metrics.get("status")


def simulation_slam(world: str, log) -> dict:
    """SLAM with odometry, and without loop closures, against the truth of a simulated log."""
    from wheelbase.mapping import LidarSlam, map_agreement
    from wheelbase.mapping.evaluation import (
        absolute_trajectory_error,
        relation_pairs,
        relative_errors,
    )
    from wheelbase.planning import load_map

    truth = load_map(world)
    steps = np.hypot(*np.diff(log.reference[:, :2], axis=0).T)
    row: dict = {
        "scans": log.n_scans,
        "distance_m": float(steps.sum()),
        "odometry_rmse_m": absolute_trajectory_error(log.odometry, log.reference),
    }
    # the map as LidarSlam renders it, at the truth's resolution
    mapper = replace(LidarSlam().mapper, resolution=truth.resolution)
    variants = {
        "slam": LidarSlam(use_odometry=True, mapper=mapper),
        "no_loop_closure": LidarSlam(use_odometry=True, loop_every=10**9, mapper=mapper),
    }
    # the drift where the route comes back: each scan with the nearest ≥ 30 s earlier within
    # 1 m of it (Kümmerle's loop relations, as in the carmen section, at any heading: the
    # 360° lidar sees the place the same driven either way, and the routes come back reversed)
    _, loop_pairs = relation_pairs(log.reference, log.t, loop_angle=math.pi)
    for label, slam in variants.items():
        result = slam.run(log)
        loop_error, _ = relative_errors(result.poses, log.reference, loop_pairs)
        grid = slam.render(log, result.poses).to_grid()
        agreement, cells = map_agreement(grid, truth)
        error = result.poses[:, :2] - log.reference[:, :2]
        row[label] = {
            "position_rmse_m": absolute_trajectory_error(result.poses, log.reference),
            "position_rmse_unaligned_m": float(np.sqrt(np.mean(np.sum(error**2, 1)))),
            "map_agreement": agreement, "cells_compared": cells,
            "loop_relation_error_m": float(np.mean(loop_error)) if len(loop_pairs) else None,
            "loop_relations": len(loop_pairs),
            "loop_closures": len(result.loops),
            "loops_rejected": result.stats["loops_rejected"],
            "loops_gated": result.stats["loops_gated"],
            "processing_time_s": result.processing_time_s,
        }  # fmt: skip
    return row


def simulation(quick: bool) -> dict:
    out = {}
    for world in ROUTES:
        for beams in (60,) if quick else (60, 360):
            log, status = simulated_log(world, beams, quick)
            out[f"{world}_{beams}"] = {"status": status, **simulation_slam(world, log)}
    return out


def landmarks() -> dict:
    from wheelbase.mapping import landmark_slam

    if not (DATA / "mrclam" / "Dataset6_Robot1_Measurement.dat").is_file():
        return {}
    return {m: landmark_slam(DATA / "mrclam", 1, m).metrics() for m in ("ekf", "smoothing")}


def occupancy_speed(quick: bool) -> dict:
    from wheelbase.mapping import OccupancyMapper

    mapper = OccupancyMapper(resolution=0.05, max_range=8.0)
    grid = mapper.empty_map((-10, 10, -10, 10))
    rng = np.random.default_rng(0)
    angles = np.linspace(-math.pi, math.pi, 360, endpoint=False)
    ranges = rng.uniform(1.0, 8.0, 360)
    mapper.integrate(grid, [0, 0, 0], ranges, angles)  # compile / load the cache
    n = 200 if quick else 5000
    start, wall = time.process_time(), time.perf_counter()
    for k in range(n):
        mapper.integrate(grid, [0.01 * (k % 50), 0.0, 0.1 * k], ranges, angles)
    return {"cpu_ms_per_scan": (time.process_time() - start) / n * 1e3,
            "wall_ms_per_scan": (time.perf_counter() - wall) / n * 1e3,
            "beams": 360, "max_range_m": 8.0, "resolution_m": 0.05}  # fmt: skip


AMCL_ROUTES = {
    "doorway": ([1.5, 3.0, 0.0], [10.0, 3.0, 0.0]),
    "maze": ([2.0, 2.0, 0.0], [18.5, 6.0, 90.0]),
    "warehouse": ([2.0, 2.0, 0.0], [13.6, 9.0, -90.0]),
}


def amcl_on_explored_map(grid, seeds, scenario: str | dict) -> dict:
    """A scenario run over ``seeds`` with ``grid`` (an explored map) as the robot's map, while
    the lidar, the collision check and the clearance see the scenario's own ``map`` (the
    truth the exploration mapped).

    A run scenario has one map for the robot and the world (``world`` only adds what is not
    on it), so the engine :func:`wheelbase.runner.prepare` builds on the explored map (the
    plan, AMCL's likelihood field) is given the true world's lidar and collisions, as
    :func:`wheelbase.exploration.explore` gives them to its legs. Without that swap the lidar
    would see the explored map itself, and AMCL would match scans against their own source.
    """
    import tempfile

    from wheelbase.planning import load_map
    from wheelbase.planning.map_io import write_ros_yaml
    from wheelbase.runner import prepare, run_prepared
    from wheelbase.scenario import load_scenario
    from wheelbase.scenario_sensors import build_sensors

    spec = load_scenario(scenario)
    truth = load_map(spec.map, max_cells=spec.resources.max_map_cells)
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "map.yaml"
        write_ros_yaml(grid, path)
        on_map = spec.model_copy(update={"map": str(path), "name": f"{spec.name}_on_explored"})
        prepared = prepare(on_map)
    seeds = [int(seed) for seed in seeds]
    if prepared.engine is None:
        return {"arrived": 0, "seeds": len(seeds), "statuses": {"planning_failed": len(seeds)}}
    footprint = prepared.footprint
    engine = replace(prepared.engine, sensors=build_sensors(on_map, truth),
                     collides=lambda poses: truth.in_collision(footprint, poses))  # fmt: skip
    wall = time.perf_counter()
    rows = run_prepared(replace(prepared, grid=truth, engine=engine), seeds)
    statuses: dict[str, int] = {}
    for row in rows:
        statuses[row["status"]] = statuses.get(row["status"], 0) + 1

    def worst(key: str) -> float:
        return max(float(row.get(key, math.nan)) for row in rows)

    return {
        "arrived": statuses.get("arrived", 0), "seeds": len(rows), "statuses": statuses,
        "not_arrived_seeds": [row["seed"] for row in rows if row["status"] != "arrived"],
        "goal_tolerance_m": spec.goal_tolerance[0],
        "final_position_error_true_max_m": worst("final_position_error_true_m"),
        "localization_max_error_max_m": worst("localization_max_error_m"),
        "localization_final_error_max_m": worst("localization_final_error_m"),
        "min_clearance_min_m": min(row["min_clearance_m"] for row in rows),
        "wall_time_s": time.perf_counter() - wall,
    }  # fmt: skip


def amcl_route(world: str, duration: float = 200.0) -> dict:
    """The scenario that drives :data:`AMCL_ROUTES`' route across ``world`` under AMCL (on its
    bundled map; :func:`amcl_on_explored_map` gives it the explored one)."""
    start, goal = AMCL_ROUTES[world]
    return {
        "name": f"amcl_on_explored_{world}", "map": world,
        "robot": {"model": "diffdrive", "preset": "rm100"}, "controller": {"law": "kanayama"},
        "odometry": {"mode": "encoders", "tick_noise_std": 0.3},
        "sensors": {"lidar": {"beams": 60, "max_range": 6.0, "range_std": 0.02}},
        "localization": {"method": "amcl"}, "start": start, "goal": goal,
        "goal_tolerance": [0.1, 10.0], "trajectory": {"max_speed": 0.6},
        "dt": 0.05, "duration": duration,
    }  # fmt: skip


DEMO_ON_EXPLORED = {"warehouse": "amcl_warehouse"}
"""The bundled scenario that drives the demo's route under AMCL on each world's map: run again
on the explored map."""


def exploration(quick: bool, seeds: int = 20, worlds: tuple[str, ...] | None = None) -> dict:
    from wheelbase.exploration import explore

    if worlds is None:
        worlds = ("doorway",) if quick else ("doorway", "maze", "warehouse")
    n = 3 if quick else seeds
    out = {}
    for world in worlds:
        result = explore(world)
        row = dict(result.metrics)
        if result.metrics["status"] == "explored":
            amcl = amcl_on_explored_map(result.grid, range(n), amcl_route(world))
            row["amcl_arrived"], row["amcl_seeds"] = amcl["arrived"], amcl["seeds"]
            if world in DEMO_ON_EXPLORED:
                demo = amcl_on_explored_map(result.grid, range(n), DEMO_ON_EXPLORED[world])
                row["amcl_on_explored_map"] = {**demo, "scenario": DEMO_ON_EXPLORED[world]}
                print("amcl_on_explored_map:", json.dumps(row["amcl_on_explored_map"]),
                      file=sys.stderr)  # fmt: skip
        out[world] = row
    return out


def targets(report: dict) -> dict:
    out: dict = {}
    for name, row in report.get("posegraphs", {}).items():
        if row.get("gtsam"):
            ours = min(row["graph"]["chi2"], row["chordal"]["chi2"])
            out[f"posegraph_{name}_chi2_le_gtsam"] = ours <= row["gtsam"]["chi2"] * (1 + 1e-6)
            out[f"posegraph_{name}_time_le_gtsam"] = (
                row["chordal"]["time_s"] <= row["gtsam"]["time_s"]
            )
    carmen = report.get("carmen", {})
    if "intel" in carmen:
        out["intel_translation_le_0.03m"] = carmen["intel"]["relative_translation_error_m"] <= 0.03
        out["intel_rotation_le_0.5deg"] = carmen["intel"]["relative_rotation_error_deg"] <= 0.5
        out["intel_faster_than_15x"] = carmen["intel"]["real_time_factor"] >= 15
    if "aces" in carmen:
        out["aces_translation_le_0.04m"] = carmen["aces"]["relative_translation_error_m"] <= 0.04
        out["aces_faster_than_15x"] = carmen["aces"]["real_time_factor"] >= 15
    for name, row in report.get("simulation", {}).items():
        out[f"sim_{name}_ate_le_0.05m"] = row["slam"]["position_rmse_m"] <= 0.05
        out[f"sim_{name}_map_agreement_ge_0.98"] = row["slam"]["map_agreement"] >= 0.98
        if "no_loop_closure" in row:  # loop closure removes drift: lower errors than without
            out[f"sim_{name}_closures_lower_ate"] = (
                row["slam"]["position_rmse_m"] < row["no_loop_closure"]["position_rmse_m"]
            )
            if row["slam"]["loop_relation_error_m"] is not None:
                out[f"sim_{name}_closures_lower_loop_error"] = (
                    row["slam"]["loop_relation_error_m"]
                    < row["no_loop_closure"]["loop_relation_error_m"]
                )
    lm = report.get("landmarks", {}).get("smoothing")
    if lm:
        out["mrclam_robot_rmse_le_0.15m"] = lm["position_rmse_m"] <= 0.15
        out["mrclam_landmark_rmse_le_0.15m"] = lm["landmark_rmse_m"] <= 0.15
    for world, row in report.get("exploration", {}).items():
        out[f"explore_{world}_ge_95pct"] = row["explored_fraction"] >= 0.95
        out[f"explore_{world}_no_collision"] = row["collisions"] == 0
        if "amcl_seeds" in row:
            out[f"explore_{world}_amcl_19_of_20"] = row["amcl_arrived"] >= 0.95 * row["amcl_seeds"]
        demo = row.get("amcl_on_explored_map")
        if demo:
            out[f"explore_{world}_amcl_demo_19_of_20"] = demo["arrived"] >= 0.95 * demo["seeds"]
    speed = report.get("occupancy_speed")
    if speed:
        out["occupancy_scan_le_0.2ms_cpu"] = speed["cpu_ms_per_scan"] <= 0.2
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="small subsets: a smoke run")
    parser.add_argument("--repeat", type=int, default=3, help="timings per pose graph")
    parser.add_argument("--sections", default="posegraphs,carmen,simulation,landmarks,"
                        "occupancy_speed,exploration", help="comma-separated sections")  # fmt: skip
    parser.add_argument("--logs", default="intel,aces",
                        help="comma-separated CARMEN logs of the carmen section")  # fmt: skip
    parser.add_argument("--carmen", type=Path, default=None,
                        help="a folder of NAME-corrected.log.gz CARMEN logs for the carmen "
                        "section (default: the bundled logs of --logs)")  # fmt: skip
    parser.add_argument("--graphs", type=Path, default=None,
                        help="a folder of 2-D g2o files for the posegraphs section "
                        "(default: the bundled four)")  # fmt: skip
    parser.add_argument("--explore", default=None,
                        help="comma-separated worlds of the exploration section "
                        "(default doorway, with maze and warehouse without --quick)")  # fmt: skip
    args = parser.parse_args()
    chosen = args.sections.split(",")
    report: dict = {}
    if "occupancy_speed" in chosen:
        report["occupancy_speed"] = occupancy_speed(args.quick)
    if "posegraphs" in chosen:
        report["posegraphs"] = posegraphs(1 if args.quick else args.repeat, args.graphs)
    if "landmarks" in chosen and not args.quick:
        report["landmarks"] = landmarks()
    if "carmen" in chosen:
        report["carmen"] = carmen(args.quick, tuple(args.logs.split(",")), args.carmen)
    if "simulation" in chosen:
        report["simulation"] = simulation(args.quick)
    if "exploration" in chosen:
        worlds = None if args.explore is None else tuple(args.explore.split(","))
        report["exploration"] = exploration(args.quick, worlds=worlds)
    report["targets"] = targets(report)
    json.dump(report, sys.stdout, indent=2, default=float)
    print()


if __name__ == "__main__":
    main()
