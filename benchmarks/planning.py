"""Planning benchmark: Hybrid A* on the bundled scenarios (and any map given), OMPL and the
PythonRobotics Hybrid A* side by side, and an independent collision check of random queries.
Prints one JSON document.

    python benchmarks/planning.py                       # everything (≈ 30 min on 2 cores)
    python benchmarks/planning.py --queries 100 --no-ompl --no-pythonrobotics
    python benchmarks/planning.py --only parallel perpendicular --queries 0
    python benchmarks/planning.py --map ../shared/data/maps/turtlebot3_world.yaml \
        --footprint 0.3 0.25 --turning-radius 0 --map-queries 5

Per scenario (with the scenario's planner options, e.g. the tight parking lattice): success,
planning time (median of 5 runs, Numba compile excluded and reported separately; also the
median CPU time of the process, steadier on a shared machine), path length, cusps, minimum
footprint clearance, expanded nodes — with the default Nav2-like costs (reverse ×2, arcs ×1.2,
2 m per cusp) and with the path-length objective that OMPL optimises
(``hybrid_astar_length_objective``; the length ratio against OMPL's best uses it). OMPL
(``pip install ompl``; the ``bench`` extra) plans in its Reeds–Shepp state space with RRT* and
BIT* for 1 s and 5 s, one run each (sampling planners: the figure varies from run to run),
using the same exact footprint check (polygons included); paths are checked at 5 cm and their
cusps counted where the motion along the heading changes sign. Differential-drive scenarios
(turning radius 0) have no OMPL or PythonRobotics peer: neither has turning in place.

The PythonRobotics Hybrid A* (``PathPlanning/HybridAStar``, pure Python; its code is never part
of wheelbase: pass ``--pythonrobotics DIR`` with a checkout of AtsushiSakai/PythonRobotics, or
set ``WHEELBASE_PYTHONROBOTICS``) runs as shipped (2 m and 15° bins, its costs) with its car set
to ours (rectangle, rear-axle reference, the same turning radius) on the obstacle points of our
map (centres of the occupied raster cells next to free ones, and the map's border), in a
subprocess stopped after ``--peer-timeout`` seconds. Its paths are checked against our exact
world like every other.

``random_queries``: N random collision-free start/goal pairs on the warehouse map (tug) and the
parking lot (car); every returned path is densified to 2 cm and its footprint, sampled as a 2 cm
point lattice, is tested against the occupied cells — an implementation independent of the
planner's separating-axis/row-span check.
"""

from __future__ import annotations

import argparse
import itertools
import json
import math
import os
import platform
import statistics
import sys
import time
from pathlib import Path

import numpy as np

from wheelbase.geometry import wrap_angle
from wheelbase.planning import (
    Footprint,
    HybridAStar,
    OccupancyGrid,
    bundled_scenarios,
    load_map,
)
from wheelbase.planning.collision import _collides_one


def densify(poses: np.ndarray, spacing: float) -> np.ndarray:
    out = [poses[:1]]
    for a, b in itertools.pairwise(poses):
        dth = float(wrap_angle(b[2] - a[2]))
        n = max(1, math.ceil(max(math.dist(a[:2], b[:2]), abs(dth) * 3.0) / spacing))
        t = np.arange(1, n + 1)[:, None] / n
        out.append(a + t * np.array([b[0] - a[0], b[1] - a[1], dth]))
    return np.concatenate(out)


def independent_collisions(
    grid: OccupancyGrid, footprint: Footprint, poses: np.ndarray, spacing: float = 0.02
) -> int:
    return int(grid.lattice_collisions(footprint, poses, spacing).sum())


LENGTH_OBJECTIVE = {"reverse_penalty": 1.0, "non_straight_penalty": 1.0, "switch_penalty": 0.0}


def run_ours(grid, footprint, radius, reverse, start, goal, repeats=5, **costs):
    planner = HybridAStar(grid, footprint, radius, reverse=reverse, **costs)
    first = planner.plan(start, goal)
    times = [first.stats.planning_time_s]
    cpu = []
    for _ in range(repeats - 1):
        t0 = time.process_time()
        times.append(planner.plan(start, goal).stats.planning_time_s)
        cpu.append(time.process_time() - t0)
    path = first
    out = {
        "success": bool(path.success),
        "planning_time_s_median": statistics.median(times),
        "planning_time_s_all": times,
        "plan_cpu_s_median": statistics.median(cpu) if cpu else None,
        "compile_time_s_first_call": first.stats.compile_time_s,
        "expanded_nodes": path.stats.expanded_nodes,
        "message": path.stats.message,
    }
    if path.success:
        out.update(
            length_m=path.length,
            cusps=path.cusps,
            min_clearance_m=float(np.min(grid.footprint_clearance(planner.footprint, path.poses))),
            collisions_independent=independent_collisions(
                grid, planner.footprint, densify(path.poses, 0.05), 0.05
            ),
        )
    return out


def run_ompl(grid, footprint, radius, reverse, start, goal, planner_name, budget):
    from ompl import base as ob
    from ompl import geometric as og
    from ompl import util as ou

    ou.setLogLevel(ou.LOG_NONE)  # its log goes to stdout, which holds the JSON

    space = ob.ReedsSheppStateSpace(radius) if reverse else ob.DubinsStateSpace(radius)
    bounds = ob.RealVectorBounds(2)
    x0, x1, y0, y1 = grid.extent
    bounds.setLow(0, x0)
    bounds.setHigh(0, x1)
    bounds.setLow(1, y0)
    bounds.setHigh(1, y1)
    space.setBounds(bounds)
    setup = og.SimpleSetup(space)
    args = (grid._kernel_world, footprint.polygon, footprint.circles, footprint.circle_radius)

    def valid(state) -> bool:
        return not _collides_one(*args, state.getX(), state.getY(), state.getYaw())

    setup.setStateValidityChecker(valid)
    si = setup.getSpaceInformation()
    si.setStateValidityCheckingResolution(0.05 / space.getMaximumExtent())
    s, g = space.allocState(), space.allocState()
    for state, pose in ((s, start), (g, goal)):
        state.setX(float(pose[0]))
        state.setY(float(pose[1]))
        state.setYaw(float(pose[2]))
    setup.setStartAndGoalStates(s, g)
    planner = og.RRTstar(si) if planner_name == "RRTstar" else og.BITstar(si)
    setup.setPlanner(planner)
    t0 = time.perf_counter()
    setup.solve(budget)
    elapsed = time.perf_counter() - t0
    if not setup.haveExactSolutionPath():
        return {"success": False, "time_s": elapsed}
    path = setup.getSolutionPath()
    length = float(path.length())  # sum of Reeds-Shepp/Dubins distances between its states
    path.interpolate(max(2, math.ceil(length / 0.05)))
    states = path.getStates()
    poses = np.array([[st.getX(), st.getY(), st.getYaw()] for st in states])
    return {
        "success": True,
        "time_s": elapsed,
        "length_m": length,
        "cusps": count_cusps(poses),
        "collisions_independent": independent_collisions(
            grid, footprint, densify(poses, 0.05), 0.05
        ),
    }


def count_cusps(poses: np.ndarray) -> int:
    """Changes of driving direction along sampled poses: the sign of the motion along the
    heading (steps shorter than 1 µm carry no sign)."""
    step = np.diff(poses[:, :2], axis=0)
    along = step[:, 0] * np.cos(poses[:-1, 2]) + step[:, 1] * np.sin(poses[:-1, 2])
    signs = np.sign(along[np.abs(along) > 1e-6])
    return int(np.count_nonzero(np.diff(signs)))


def obstacle_points(world, spacing: float) -> np.ndarray:
    """Points for a point-cloud planner: centres of occupied raster cells next to a free one,
    and the border of the map every ``spacing`` metres."""
    occ = world.occupied
    padded = np.pad(occ, 1, constant_values=False)
    inner = padded[:-2, 1:-1] & padded[2:, 1:-1] & padded[1:-1, :-2] & padded[1:-1, 2:]
    cells = np.argwhere(occ & ~inner)
    points = [world.cell_to_world(cells)]
    x0, x1, y0, y1 = world.extent
    for a, b in (((x0, y0), (x1, y0)), ((x1, y0), (x1, y1)), ((x1, y1), (x0, y1)),
                 ((x0, y1), (x0, y0))):  # fmt: skip
        n = max(2, math.ceil(math.dist(a, b) / spacing))
        t = np.linspace(0.0, 1.0, n, endpoint=False)[:, None]
        points.append(np.asarray(a) + t * (np.asarray(b) - np.asarray(a)))
    return np.concatenate(points)


def _pythonrobotics_child(repo, car, start, goal, points, queue):  # pragma: no cover
    import contextlib
    import io

    planning = repo / "PathPlanning"
    sys.path[:0] = [str(repo), str(planning / "HybridAStar"), str(planning)]
    import car as pr_car  # PythonRobotics' modules, from the checkout
    import hybrid_a_star as pr

    length, width, rear_to_center, radius = car
    wb = pr_car.WB
    steer = math.atan(wb / radius)
    front, back = rear_to_center + length / 2, length / 2 - rear_to_center
    pr_car.W, pr_car.LF, pr_car.LB, pr_car.MAX_STEER = width, front, back, steer
    pr_car.BUBBLE_DIST = (front - back) / 2.0
    pr_car.BUBBLE_R = math.hypot((front + back) / 2.0, width / 2.0)
    pr_car.VRX = [front, front, -back, -back, front]
    pr_car.VRY = [width / 2, -width / 2, -width / 2, width / 2, width / 2]
    pr.MAX_STEER, pr.BUBBLE_R, pr.show_animation = steer, pr_car.BUBBLE_R, False
    t0 = time.perf_counter()
    with contextlib.redirect_stdout(io.StringIO()):
        path = pr.hybrid_a_star_planning(
            list(start), list(goal), points[:, 0].tolist(), points[:, 1].tolist(),
            pr.XY_GRID_RESOLUTION, pr.YAW_GRID_RESOLUTION,
        )  # fmt: skip
    elapsed = time.perf_counter() - t0
    poses = np.column_stack([path.x_list, path.y_list, path.yaw_list]) if path.x_list else None
    queue.put((elapsed, poses))


def run_pythonrobotics(world, footprint, sc, repo, timeout):
    import multiprocessing as mp

    ctx = mp.get_context("fork")
    queue = ctx.Queue()
    car = (*sc.footprint, sc.rear_axle_to_center, sc.turning_radius)
    points = obstacle_points(world, world.resolution)
    child = ctx.Process(
        target=_pythonrobotics_child,
        args=(repo, car, sc.start.copy(), sc.goal.copy(), points, queue),
    )
    t0 = time.perf_counter()
    child.start()
    child.join(timeout)
    if child.is_alive():
        child.kill()
        child.join()
        return {"success": False, "time_s": time.perf_counter() - t0, "message": "timeout"}
    if queue.empty():
        return {"success": False, "time_s": time.perf_counter() - t0, "message": "crashed"}
    elapsed, poses = queue.get()
    if poses is None or len(poses) < 2:
        return {"success": False, "time_s": elapsed, "message": "no path"}
    ends_ok = np.allclose(poses[-1, :2], sc.goal[:2], atol=0.05)
    return {
        "success": bool(ends_ok),
        "time_s": elapsed,
        "length_m": float(np.sum(np.hypot(*np.diff(poses[:, :2], axis=0).T))),
        "cusps": count_cusps(poses),
        "collisions_independent": independent_collisions(
            world, footprint, densify(poses, 0.05), 0.05
        ),
        "obstacle_points": len(points),
    }


def random_queries(name, grid, footprint, radius, n, seed):
    rng = np.random.default_rng(seed)
    planner = HybridAStar(grid, footprint, radius, time_limit=2.0)
    x0, x1, y0, y1 = grid.extent
    found = fails = collisions = 0
    times = []
    messages: dict[str, int] = {}
    while found + fails < n:
        poses = np.column_stack(
            [rng.uniform(x0, x1, 2), rng.uniform(y0, y1, 2), rng.uniform(-np.pi, np.pi, 2)]
        )
        if grid.in_collision(footprint, poses).any():
            continue
        path = planner.plan(poses[0], poses[1])
        times.append(path.stats.planning_time_s)
        messages[path.stats.message] = messages.get(path.stats.message, 0) + 1
        if not path.success:
            fails += 1
            continue
        found += 1
        collisions += independent_collisions(grid, footprint, densify(path.poses, 0.02)) > 0
    return {
        "map": name,
        "queries": n,
        "successes": found,
        "failures_or_limits": fails,
        "paths_with_collisions": int(collisions),
        "outcomes": messages,
        "planning_time_s_median": statistics.median(times),
        "planning_time_s_p95": float(np.percentile(times, 95)),
    }


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--map", action="append", default=[], help="extra ROS/Moving AI map")
    parser.add_argument("--footprint", nargs=2, type=float, default=(0.66, 0.5))
    parser.add_argument("--turning-radius", type=float, default=0.0)
    parser.add_argument("--map-queries", type=int, default=5)
    parser.add_argument("--queries", type=int, default=1000)
    parser.add_argument("--no-ompl", action="store_true")
    parser.add_argument("--ompl-budgets", nargs="+", type=float, default=(1.0, 5.0))
    parser.add_argument("--only", nargs="+", default=[], help="scenario/map name parts")
    parser.add_argument("--no-pythonrobotics", action="store_true")
    parser.add_argument(
        "--pythonrobotics",
        default=os.environ.get("WHEELBASE_PYTHONROBOTICS"),
        help="a checkout of AtsushiSakai/PythonRobotics (or $WHEELBASE_PYTHONROBOTICS)",
    )
    parser.add_argument("--peer-timeout", type=float, default=60.0)
    args = parser.parse_args(argv)

    ompl_reason = None
    if args.no_ompl:
        ompl_reason = "--no-ompl"
    else:
        try:
            import ompl  # noqa: F401
        except ImportError as exc:
            ompl_reason = f"ompl not importable: {exc}"
    pr_repo = Path(args.pythonrobotics) if args.pythonrobotics else None
    if args.no_pythonrobotics:
        pr_reason = "--no-pythonrobotics"
    elif pr_repo is None or not (pr_repo / "PathPlanning" / "HybridAStar").is_dir():
        pr_reason = f"no PythonRobotics checkout (--pythonrobotics, got {pr_repo})"
    else:
        pr_reason = None

    report: dict = {
        "machine": {
            "python": sys.version.split()[0],
            "platform": platform.platform(),
            "cpus": os.cpu_count(),
            "load_average_1min": os.getloadavg()[0],
        },
        "scenarios": [],
        "peer": "ompl" if ompl_reason is None else None,
        "peer_reason": ompl_reason,
        "pythonrobotics_reason": pr_reason,
    }
    scenarios = [
        sc
        for sc in bundled_scenarios()
        if not args.only or any(part in f"{sc.map_name}/{sc.name}" for part in args.only)
    ]
    for sc in scenarios:
        grid = load_map(sc.map_name)
        fp = Footprint.rectangle(*sc.footprint, sc.rear_axle_to_center)
        ours = run_ours(grid, fp, sc.turning_radius, True, sc.start, sc.goal, **sc.planner)
        entry = {
            "map": sc.map_name,
            "scenario": sc.name,
            "turning_radius_m": sc.turning_radius,
            "planner_options": sc.planner,
            "hybrid_astar": ours,
        }
        # the same objective as OMPL's (path length): no reverse/turn/cusp penalties
        entry["hybrid_astar_length_objective"] = run_ours(
            grid, fp, sc.turning_radius, True, sc.start, sc.goal, **sc.planner, **LENGTH_OBJECTIVE
        )
        if sc.turning_radius == 0:
            entry["ompl"] = entry["pythonrobotics"] = None
            entry["peer_reason"] = "turning in place: no OMPL state space or PythonRobotics car"
            report["scenarios"].append(entry)
            print(f"{sc.map_name}/{sc.name} done", file=sys.stderr, flush=True)
            continue
        if ompl_reason is None:
            peers = {}
            for name in ("RRTstar", "BITstar"):
                for budget in args.ompl_budgets:
                    peers[f"{name}_{budget:g}s"] = run_ompl(
                        grid, fp, sc.turning_radius, True, sc.start, sc.goal, name, budget
                    )
            entry["ompl"] = peers
            best = [p["length_m"] for p in peers.values() if p["success"]]
            if best and ours["success"]:
                entry["length_ratio_vs_ompl_best"] = ours["length_m"] / min(best)
            by_length = entry["hybrid_astar_length_objective"]
            if best and by_length["success"]:
                entry["length_objective_ratio_vs_ompl_best"] = by_length["length_m"] / min(best)
        if pr_reason is None:
            peer = run_pythonrobotics(grid, fp, sc, pr_repo, args.peer_timeout)
            entry["pythonrobotics"] = peer
            if peer["success"] and ours["success"]:
                entry["time_ratio_pythonrobotics_over_ours"] = (
                    peer["time_s"] / ours["planning_time_s_median"]
                )
                entry["length_ratio_vs_pythonrobotics"] = ours["length_m"] / peer["length_m"]
        report["scenarios"].append(entry)
        print(f"{sc.map_name}/{sc.name} done", file=sys.stderr, flush=True)

    for path in args.map:
        grid = load_map(path)
        fp = Footprint.rectangle(*args.footprint)
        rng = np.random.default_rng(0)
        x0, x1, y0, y1 = grid.extent
        done = 0
        while done < args.map_queries:
            poses = np.column_stack(
                [rng.uniform(x0, x1, 2), rng.uniform(y0, y1, 2), rng.uniform(-np.pi, np.pi, 2)]
            )
            if grid.in_collision(fp, poses).any():
                continue
            done += 1
            entry = {
                "map": path,
                "scenario": f"random_{done}",
                "start": poses[0].tolist(),
                "goal": poses[1].tolist(),
                "hybrid_astar": run_ours(grid, fp, args.turning_radius, True, poses[0], poses[1]),
            }
            report["scenarios"].append(entry)

    bundled = [e for e in report["scenarios"] if e["map"] in {s.map_name for s in scenarios}]
    ours = [e["hybrid_astar"] for e in bundled]
    slowest = max(bundled, key=lambda e: e["hybrid_astar"]["planning_time_s_median"])
    report["summary"] = {
        "bundled_success_rate": sum(o["success"] for o in ours) / len(ours) if ours else None,
        "unsolved": [e["scenario"] for e in bundled if not e["hybrid_astar"]["success"]],
        "slowest": slowest["scenario"],
        "slowest_median_time_s": slowest["hybrid_astar"]["planning_time_s_median"],
        # the targets: every bundled scenario <= 100 ms median, the 60 m maze <= 150 ms; the
        # 1.10 slot, which only the escape by moves to contact (in Python) solves, takes ~1.4 s
        "over_100_ms": {
            e["scenario"]: round(e["hybrid_astar"]["planning_time_s_median"], 4)
            for e in bundled
            if e["hybrid_astar"]["planning_time_s_median"] > 0.1
        },
        "max_length_ratio_vs_ompl_best": max(
            (e["length_ratio_vs_ompl_best"] for e in bundled if "length_ratio_vs_ompl_best" in e),
            default=None,
        ),
        "max_length_objective_ratio_vs_ompl_best": max(
            (
                e["length_objective_ratio_vs_ompl_best"]
                for e in bundled
                if "length_objective_ratio_vs_ompl_best" in e
            ),
            default=None,
        ),
        "ompl_5s_unsolved": [
            e["scenario"]
            for e in bundled
            if e.get("ompl")
            and any("_5s" in k for k in e["ompl"])
            and not any(p["success"] for k, p in e["ompl"].items() if "_5s" in k)
        ],
        "pythonrobotics_unsolved": [
            e["scenario"]
            for e in bundled
            if e.get("pythonrobotics") is not None and not e["pythonrobotics"]["success"]
        ],
    }
    if args.queries > 0:
        half = args.queries // 2
        report["random_queries"] = [
            random_queries(
                "warehouse",
                load_map("warehouse"),
                Footprint.rectangle(1.6, 1.0, 0.5),
                1.5,
                args.queries - half,
                1,
            ),
            random_queries(
                "parking_lot",
                load_map("parking_lot"),
                Footprint.rectangle(4.5, 1.8, 1.35),
                5.0,
                half,
                2,
            ),
        ]
        report["summary"]["random_query_paths_with_collisions"] = sum(
            r["paths_with_collisions"] for r in report["random_queries"]
        )
    print(json.dumps(report, indent=2))


if __name__ == "__main__":
    main()
