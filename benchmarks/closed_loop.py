"""Closed-loop speed: the default demo end to end, a batch over noise seeds, the CLI's start-up.

Prints one JSON object:

- ``demo``: seconds for ``wheelbase.run("demo")`` plus writing its report without the GIF
  (median of ``--repeat`` runs after one warm-up run that compiles and caches the kernels), and
  the GIF alone; ``demo_run_only_s`` (the run alone) is the headline, about 0.8 s warm before
  the one engine;
- ``batch``: ``--seeds`` runs of the demo scenario with encoder noise (0.3 tick per step) two
  ways in the same run: ``batch_vectorised_runs_per_s`` (one process, the seeds in lockstep on
  the engine) and ``batch_process_pool_runs_per_s`` (a pool of ``--workers`` processes, one run
  per task, as ``wheelbase batch`` worked before); target: the vectorised batch >= 20x the pool;
- ``cli_help_s``: wall time of ``wheelbase --help`` in a fresh process (median of 5); target
  <= 0.5 s;
- ``batch_memory``: the peak resident memory of one process (``ru_maxrss``) that runs
  ``run_batch`` over 1,000, 10,000 and ``--memory-seeds`` (100,000) seeds of
  :data:`MEMORY_SCENARIO` (a 1.5 m drive with encoder noise, 2.6 s simulated, 200 steps at
  most) under the default memory budget, each in a fresh process; target: flat, under 2 GB at
  100,000 seeds. The seeds run in vectorised chunks that fit the budget (512 MiB) and only
  the finished rows are kept; before, one process kept every seed's whole log.

Usage: ``python benchmarks/closed_loop.py [--seeds 100] [--workers 2] [--repeat 3]
[--memory-seeds 100000] [--quick]``.
"""

from __future__ import annotations

import argparse
import json
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from concurrent.futures import ProcessPoolExecutor
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
    run_batch([noisy], seeds=2)  # warm-up of this process
    vectorised = run_batch([noisy], seeds=seeds)
    with ProcessPoolExecutor(max_workers=workers) as pool:
        pooled = run_batch([noisy], seeds=seeds, executor=pool, chunk_size=1)
    statuses = [row["status"] for row in vectorised.rows]
    drift = [row.get("odometry_drift_m", float("nan")) for row in vectorised.rows]
    same = all(
        a["status"] == b["status"] and a["odometry_drift_m"] == b["odometry_drift_m"]
        for a, b in zip(vectorised.rows, pooled.rows, strict=True)
    )
    return {
        "runs": len(vectorised.rows),
        "workers": workers,
        "batch_vectorised_wall_s": vectorised.wall_time_s,
        "batch_vectorised_runs_per_s": vectorised.runs_per_second,
        "batch_process_pool_wall_s": pooled.wall_time_s,
        "batch_process_pool_runs_per_s": pooled.runs_per_second,
        "vectorised_over_pool": vectorised.runs_per_second / pooled.runs_per_second,
        "target_ratio": 20.0,
        "same_rows": same,
        "success_rate": statuses.count("arrived") / len(statuses),
        "statuses": {status: statuses.count(status) for status in sorted(set(statuses))},
        "odometry_drift_m_median": statistics.median(drift),
    }


MEMORY_SCENARIO = {
    "name": "short",
    "map": "empty",
    "robot": {"model": "diffdrive"},
    "controller": {"law": "kanayama"},
    "odometry": {"mode": "encoders", "pulses_per_revolution": 512, "tick_noise_std": 1.0},
    "start": [0.0, 0.0, 0.0],
    "goal": [1.5, 0.0, 0.0],
    "trajectory": {"max_speed": 1.0, "max_acceleration": 1.0},
    "dt": 0.02,
    "duration": 4.0,
}
"""The scenario of ``batch_memory``: small, so that 100,000 seeds take minutes, not hours."""


def memory_child(seeds: int) -> None:
    """Run the memory scenario over ``seeds`` seeds in this process; print its figures."""
    import resource

    start = time.perf_counter()
    result = run_batch([MEMORY_SCENARIO], seeds=seeds)
    statuses = [row["status"] for row in result.rows]
    print(json.dumps({
        "seeds": seeds,
        "peak_rss_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0,
        "wall_s": time.perf_counter() - start,
        "runs_per_s": result.runs_per_second,
        "arrived": statuses.count("arrived") / len(statuses),
    }))  # fmt: skip


def batch_memory(counts: list[int]) -> dict:
    """Peak memory of one process per batch size (module docstring)."""
    runs = []
    for seeds in counts:
        done = subprocess.run(
            [sys.executable, __file__, "--memory-child", str(seeds)],
            capture_output=True, text=True, check=True,
        )  # fmt: skip
        runs.append(json.loads(done.stdout.strip().splitlines()[-1]))
    peak = max(run["peak_rss_mb"] for run in runs)
    return {"runs": runs, "peak_rss_mb": peak, "target_mb": 2048.0, "met": peak < 2048.0}


def time_cli_help(repeat: int = 5) -> dict:
    command = shutil.which("wheelbase")
    argv = [command, "--help"] if command else [sys.executable, "-m", "wheelbase", "--help"]
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        subprocess.run(argv, capture_output=True, check=True)
        times.append(time.perf_counter() - start)
    return {"cli_help_s": statistics.median(times), "target_s": 0.5}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=100)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--memory-seeds", type=int, default=100_000)
    parser.add_argument("--memory-child", type=int, help=argparse.SUPPRESS)
    parser.add_argument("--memory-only", action="store_true", help="only batch_memory")
    parser.add_argument("--quick", action="store_true", help="4 seeds, 1 repeat (smoke run)")
    args = parser.parse_args()
    if args.memory_child:
        memory_child(args.memory_child)
        return
    if args.quick:
        args.seeds, args.repeat, args.memory_seeds = 4, 1, 300
    counts = sorted({min(1_000, args.memory_seeds), min(10_000, args.memory_seeds),
                     args.memory_seeds})  # fmt: skip
    if args.memory_only:
        print(json.dumps({"benchmark": "closed_loop", "batch_memory": batch_memory(counts)}))
        return
    demo = time_demo(args.repeat)
    batch = time_batch(args.seeds, args.workers)
    cli = time_cli_help()
    memory = batch_memory(counts)
    out = {
        "benchmark": "closed_loop",
        "demo_run_only_s": demo["run_only_s"],
        "batch_vectorised_runs_per_s": batch["batch_vectorised_runs_per_s"],
        "batch_process_pool_runs_per_s": batch["batch_process_pool_runs_per_s"],
        "cli_help_s": cli["cli_help_s"],
        "demo": demo,
        "batch": batch,
        "cli": cli,
        "batch_memory": memory,
    }
    print(json.dumps(out, indent=2))


if __name__ == "__main__":
    main()
