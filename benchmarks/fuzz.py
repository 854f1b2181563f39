"""The fuzz figure of issue 16: hostile cases run, raw exceptions, hangs.

Draws cases from the strategies of ``tests/fuzzing.py`` at random (hypothesis, not
derandomized: each run explores new cases) and runs each one within its budget, counting what
happened instead of stopping at the first failure (that is what ``pytest tests/test_fuzz.py
--hypothesis-profile=explore`` does). Memory is capped (``--memory-gb``) so that a case that
asks for terabytes becomes a counted ``MemoryError``, not a machine out of memory.

Usage: ``python benchmarks/fuzz.py [--cases 10000] [--seed N] [--quick] [--memory-gb 6]``;
prints one JSON object: ``cases``, ``raw_exceptions``, ``hangs``, per target the same plus
``errors`` (clean WheelbaseErrors), ``ok``, ``seconds`` and the first distinct raw
exceptions and hangs (``examples``, up to 20 per target).
"""

from __future__ import annotations

import argparse
import json
import resource
import sys
import time
from collections import Counter
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests"))

from hypothesis import HealthCheck, Phase, given, seed, settings

import fuzzing

# target → (strategy, how to run a case, budget key, share of the cases)
TARGETS = {
    "scenario": (fuzzing.scenario_cases, fuzzing.run_scenario, "scenario", 0.3),
    "scenario_file": (fuzzing.scenario_file_cases, fuzzing.run_scenario_file, "scenario_file",
                      0.05),
    "map_file": (fuzzing.map_file_cases, fuzzing.load_map_file, "map_file", 0.2),
    "map_array": (fuzzing.array_map_cases, fuzzing.grid_from_array, "map_file", 0.05),
    "constructor": (fuzzing.constructor_cases, fuzzing.call_constructor, "constructor", 0.25),
    "cli": (fuzzing.cli_cases, fuzzing.run_cli, "cli", 0.1),
    "world": (fuzzing.world_cases, fuzzing.run_world, "world", 0.1),
    "slam_file": (fuzzing.slam_file_cases, fuzzing.slam_file, "slam_file", 0.05),
    "exploration": (fuzzing.exploration_cases, fuzzing.run_exploration, "exploration", 0.02),
}  # fmt: skip


def explore(name: str, cases: int, rng_seed: int) -> dict:
    strategy, call, budget_key, _share = TARGETS[name]
    budget = fuzzing.BUDGET_S[budget_key]
    counts: Counter = Counter()
    examples: dict[str, int] = {}
    seconds = 0.0

    @seed(rng_seed)
    @settings(max_examples=cases, deadline=None, database=None, derandomize=False,
              phases=[Phase.generate], suppress_health_check=list(HealthCheck))  # fmt: skip
    @given(strategy())
    def case(value):
        nonlocal seconds
        result = fuzzing.outcome(lambda: call(value), budget)
        counts[result.kind] += 1
        seconds += result.seconds
        if result.kind in ("raw", "hang"):
            key = f"{result.kind}: {result.detail[:160]}"
            if key not in examples and len(examples) < 20:
                examples[key] = 0
                print(f"[{name}] {key}\n    case: {value!r}"[:1200], file=sys.stderr)
            if key in examples:
                examples[key] += 1

    case()
    total = sum(counts.values())
    return {"cases": total, "raw_exceptions": counts["raw"], "hangs": counts["hang"],
            "errors": counts["error"], "ok": counts["ok"], "seconds": round(seconds, 1),
            "examples": examples}  # fmt: skip


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cases", type=int, default=10_000)
    parser.add_argument("--seed", type=int, default=int(time.time()))
    parser.add_argument("--quick", action="store_true", help="60 cases: a smoke run")
    parser.add_argument("--memory-gb", type=float, default=6.0)
    parser.add_argument("--only", choices=sorted(TARGETS), action="append")
    args = parser.parse_args()
    limit = int(args.memory_gb * 2**30)
    resource.setrlimit(resource.RLIMIT_AS, (limit, limit))
    total = 60 if args.quick else args.cases
    names = args.only or list(TARGETS)
    shares = sum(TARGETS[name][3] for name in names)
    fuzzing.warm_up()  # compile the kernels outside every budget
    start = time.perf_counter()
    report = {name: explore(name, max(1, round(total * TARGETS[name][3] / shares)), args.seed)
              for name in names}  # fmt: skip
    print(json.dumps({
        "cases": sum(r["cases"] for r in report.values()),
        "raw_exceptions": sum(r["raw_exceptions"] for r in report.values()),
        "hangs": sum(r["hangs"] for r in report.values()),
        "seed": args.seed,
        "wall_s": round(time.perf_counter() - start, 1),
        "budgets_s": fuzzing.BUDGET_S,
        "targets": report,
    }, indent=1))  # fmt: skip


if __name__ == "__main__":
    main()
