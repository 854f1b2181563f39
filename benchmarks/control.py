"""Control benchmarks of issue 5: the 128-case pose benchmark and the tracking benchmark.

Prints one JSON object:

- ``pose``: per law (``point``, ``polar``, ``aicardi``, ``via_point``, ``via_direction``,
  ``line_arc``) ``success_rate``, ``mean_time_s``, ``mean_path_length_m``, ``reversals``,
  ``position_success_rate``, the worst final errors and ``runtime_s``;
- ``pose_runtime_s``: wall clock of all six laws × 128 cases (target < 10 s), best of
  ``--repeat``;
- ``tracking``: one row per (reference, law, plant) with the RMS and max lateral error after 5 s;
- ``tracking_runtime_s``;
- ``rm100``: the pose benchmark and the figure-eight trackers on the dynamic RM100 of document 000
  through a computed-torque velocity loop (``control_cases.dynamic_benchmark``), and
  ``rm100_runtime_s``.

Usage: ``python benchmarks/control.py [--quick] [--repeat N]`` (``--quick``: pose benchmark on
16 starts, no tracking, no RM100).
"""

from __future__ import annotations

import argparse
import json
import time

from control_cases import (  # benchmarks/ is on sys.path when a script in it runs
    dynamic_benchmark,
    pose_benchmark,
    pose_benchmark_starts,
    tracking_benchmark,
)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="16 starts, no tracking benchmark")
    parser.add_argument("--repeat", type=int, default=3, help="timings of the pose benchmark")
    args = parser.parse_args()
    starts = pose_benchmark_starts(2.0, 4, 4) if args.quick else pose_benchmark_starts()
    pose_benchmark(starts=starts[:2], t_end=1.0)  # warm-up: imports, Numba caches
    best, table = float("inf"), {}
    for _ in range(max(1, args.repeat)):
        begin = time.perf_counter()
        table, _results = pose_benchmark(starts=starts)
        best = min(best, time.perf_counter() - begin)
    out = {
        "cases": int(starts.shape[0]),
        "pose": table,
        "pose_runtime_s": best,
        "pose_runtime_target_s": 10.0,
        "pose_runtime_met": best < 10.0,
    }
    if not args.quick:
        begin = time.perf_counter()
        rows, _traces = tracking_benchmark()
        out["tracking"] = rows
        out["tracking_runtime_s"] = time.perf_counter() - begin
        begin = time.perf_counter()
        out["rm100"] = dynamic_benchmark()
        out["rm100_runtime_s"] = time.perf_counter() - begin
    print(json.dumps(out, indent=2))


if __name__ == "__main__":
    main()
