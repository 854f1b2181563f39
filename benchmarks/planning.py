"""Planning benchmark: Hybrid A* on the bundled scenarios (and any map given), OMPL side by side,
and an independent collision check of random queries. Prints one JSON document.

    python benchmarks/planning.py                       # everything (≈ 20 min on 2 cores)
    python benchmarks/planning.py --queries 100 --no-ompl
    python benchmarks/planning.py --map ../shared/data/maps/turtlebot3_world.yaml \
        --footprint 0.3 0.25 --turning-radius 0 --map-queries 5

Per scenario: success, planning time (median of 5 runs, Numba compile excluded and reported
separately), path length, cusps, minimum footprint clearance, expanded nodes — with the default
Nav2-like costs (reverse ×2, arcs ×1.2, 2 m per cusp) and with the path-length objective that
OMPL optimises (``hybrid_astar_length_objective``; the length ratio against OMPL's best uses
it). OMPL (``pip install ompl``; the ``bench`` extra) plans in its Reeds–Shepp state space with
RRT* and BIT* for 1 s and 5 s, one run each (sampling planners: the figure varies from run to
run), using the same footprint check; paths are checked at 5 cm. Differential-drive
scenarios (turning radius 0) have no OMPL peer: OMPL has no state space with turning in place
and SE(2) would allow sideways motion.

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
import platform
import statistics
import sys
import time

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
    for _ in range(repeats - 1):
        times.append(planner.plan(start, goal).stats.planning_time_s)
    path = first
    out = {
        "success": bool(path.success),
        "planning_time_s_median": statistics.median(times),
        "planning_time_s_all": times,
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
        "collisions_independent": independent_collisions(
            grid, footprint, densify(poses, 0.05), 0.05
        ),
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
    args = parser.parse_args(argv)

    ompl_reason = None
    if args.no_ompl:
        ompl_reason = "--no-ompl"
    else:
        try:
            import ompl  # noqa: F401
        except ImportError as exc:
            ompl_reason = f"ompl not importable: {exc}"

    report: dict = {
        "machine": {
            "python": sys.version.split()[0],
            "platform": platform.platform(),
            "cpus": __import__("os").cpu_count(),
        },
        "scenarios": [],
        "peer": "ompl" if ompl_reason is None else None,
        "peer_reason": ompl_reason,
    }
    for sc in bundled_scenarios():
        grid = load_map(sc.map_name)
        fp = Footprint.rectangle(*sc.footprint, sc.rear_axle_to_center)
        entry = {
            "map": sc.map_name,
            "scenario": sc.name,
            "turning_radius_m": sc.turning_radius,
            "hybrid_astar": run_ours(grid, fp, sc.turning_radius, True, sc.start, sc.goal),
        }
        # the same objective as OMPL's (path length): no reverse/turn/cusp penalties
        entry["hybrid_astar_length_objective"] = run_ours(
            grid, fp, sc.turning_radius, True, sc.start, sc.goal, **LENGTH_OBJECTIVE
        )
        if ompl_reason is None and sc.turning_radius > 0:
            peers = {}
            for name in ("RRTstar", "BITstar"):
                for budget in args.ompl_budgets:
                    peers[f"{name}_{budget:g}s"] = run_ompl(
                        grid, fp, sc.turning_radius, True, sc.start, sc.goal, name, budget
                    )
            entry["ompl"] = peers
            best = [p["length_m"] for p in peers.values() if p["success"]]
            if best and entry["hybrid_astar"]["success"]:
                entry["length_ratio_vs_ompl_best"] = entry["hybrid_astar"]["length_m"] / min(best)
            ours = entry["hybrid_astar_length_objective"]
            if best and ours["success"]:
                entry["length_objective_ratio_vs_ompl_best"] = ours["length_m"] / min(best)
        elif sc.turning_radius == 0:
            entry["ompl"] = None
            entry["ompl_reason"] = "turning in place: no OMPL state space for it"
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

    ours = [
        e["hybrid_astar"]
        for e in report["scenarios"]
        if e["map"] in {s.map_name for s in bundled_scenarios()}
    ]
    report["summary"] = {
        "bundled_success_rate": sum(o["success"] for o in ours) / len(ours),
        "parking_lot_median_time_s": statistics.median(
            e["hybrid_astar"]["planning_time_s_median"]
            for e in report["scenarios"]
            if e["map"] == "parking_lot"
        ),
        "max_length_ratio_vs_ompl_best": max(
            (
                e["length_ratio_vs_ompl_best"]
                for e in report["scenarios"]
                if "length_ratio_vs_ompl_best" in e
            ),
            default=None,
        ),
        "max_length_objective_ratio_vs_ompl_best": max(
            (
                e["length_objective_ratio_vs_ompl_best"]
                for e in report["scenarios"]
                if "length_objective_ratio_vs_ompl_best" in e
            ),
            default=None,
        ),
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
