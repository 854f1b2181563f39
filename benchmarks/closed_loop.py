"""Closed-loop speed: the default demo end to end, and a batch over noise seeds.

Prints one JSON object:

- ``demo``: seconds for ``wheelbase.run("demo")`` plus writing its report without the GIF
  (median of ``--repeat`` runs after one warm-up run that compiles and caches the kernels), and
  the GIF alone; target: under 5 s end to end without the GIF.
- ``batch``: ``--seeds`` runs of the demo scenario with encoder noise (0.3 tick on each tick
  difference) on ``--workers`` local processes: wall time, runs per second, success rate.

Usage: ``python benchmarks/closed_loop.py [--seeds 100] [--workers 2] [--repeat 3] [--quick]``.
"""

from __future__ import annotations

import argparse
import json
import statistics
import tempfile
import time
from pathlib import Path

from wheelbase.batch import run_batch
from wheelbase.report import animate_run, write_report
from wheelbase.runner import run
from wheelbase.scenario import load_scenario


def time_demo(repeat: int) -> dict:
    run("demo")  # warm-up: compiles (or loads from cache) every kernel on the way
    totals, runs = [], []
    with tempfile.TemporaryDirectory() as folder:
        for index in range(repeat):
            start = time.perf_counter()
            result = run("demo")
            ran = time.perf_counter()
            write_report(result, Path(folder) / str(index), gif=False)
            totals.append(time.perf_counter() - start)
            runs.append(ran - start)
        start = time.perf_counter()
        geometry = (*result.robot.footprint, result.robot.center_offset)
        plan = result.plan.poses
        animate_run(result.grid, plan, result.log, geometry, Path(folder) / "a.gif")
        gif = time.perf_counter() - start
    return {
        "end_to_end_without_gif_s": statistics.median(totals),
        "run_only_s": statistics.median(runs),
        "gif_s": gif,
        "simulated_s": result.metrics["duration_s"],
        "steps": len(result.log.t),
        "status": result.metrics["status"],
        "target_s": 5.0,
        "met": statistics.median(totals) < 5.0,
    }


def time_batch(seeds: int, workers: int) -> dict:
    scenario = load_scenario("demo")
    noisy = scenario.model_copy(
        update={"odometry": scenario.odometry.model_copy(update={"tick_noise_std": 0.3})}
    )
    result = run_batch([noisy], seeds=seeds, workers=workers)
    statuses = [row["status"] for row in result.rows]
    drift = [row.get("odometry_drift_m", float("nan")) for row in result.rows]
    return {
        "runs": len(result.rows),
        "workers": workers,
        "wall_time_s": result.wall_time_s,
        "runs_per_second": result.runs_per_second,
        "success_rate": statuses.count("arrived") / len(statuses),
        "statuses": {status: statuses.count(status) for status in sorted(set(statuses))},
        "odometry_drift_m_median": statistics.median(drift),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=100)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--quick", action="store_true", help="4 seeds, 1 repeat (smoke run)")
    args = parser.parse_args()
    if args.quick:
        args.seeds, args.repeat = 4, 1
    out = {
        "benchmark": "closed_loop",
        "demo": time_demo(args.repeat),
        "batch": time_batch(args.seeds, args.workers),
    }
    print(json.dumps(out, indent=2))


if __name__ == "__main__":
    main()
