"""Navigation among obstacles the map does not show (issue 22): arrival, contacts and speed.

Run ``python benchmarks/obstacles.py`` (``--seeds 100`` by default, ``--sections`` and
``--crowds 20_mppi,50_dwa,...`` to pick, ``--workers 2``); prints one JSON object. Every run
is a bundled scenario through :func:`wheelbase.runner.run_seeds`, seeds 0 … n − 1 (each seed
its own walkers, boxes and sensor noise):

``crowd``
    ``crowd_crossing`` with 20 and with 50 walkers that do not avoid the robot, for MPPI and
    DWA: ``arrived`` (fraction), ``collisions_at_fault`` and ``struck_at_rest`` (counts; a
    contact is the robot's fault when it moved towards the walker faster than 5 cm/s),
    ``timeouts``, ``blocked``, the mean time to goal of the arrivals, the least distance to a
    walker (median over seeds), ``discomfort_s`` (mean time within 0.2 m of a walker,
    CrowdNav's measure), the tracks' position and velocity RMSE, the first 20 seeds that did
    not arrive and every seed with a contact at fault (``at_fault_seeds``, to replay). Targets:
    >= 99 % arrived and 0 at fault with 20 walkers, >= 97 % and 0 with 50.
``irsim``
    ir-sim 2.12's own RVO robot (``pip install -e ".[bench]"``) on the same room, walkers and
    seeds count (its own random placement: ir-sim draws them), 60 s at 0.1 s: arrived and
    collided counts. ``null`` with ``irsim_error`` when it is not installed or fails.
``boxes``
    ``unexpected_boxes``: 1–3 boxes of 0.4–0.8 m dropped on the planned path of the demo route
    (each seed its own): arrived fraction and collisions (target >= 99 %, 0).
``doorway``
    ``doorway_blocked``: every seed must end ``blocked`` within 60 s, without a collision.
``swap``
    ``corridor_swap``: both robots arrive, no contact (seeds vary the lidar noise).
``variants``
    ``crowd_crossing`` changed one way at a time, as a user's own crowd would differ from the
    bundled one (``--variants`` to pick, ``--variant-seeds`` seeds each, default 6): walkers
    that go ``straight``, follow the social force (``social_force``, and ``social_force_reacts``
    where the robot is one more agent to them), ``orca_reacts``, ``fast_small`` (r 0.2 m at
    1.0 m/s, as fast as the robot), 35 walkers (``walkers_35``), a ``unicycle``, a small
    car-like robot (``car``: rear bicycle, 0.5 m wheel base, 0.7 × 0.4 m, 0.8 m turning
    radius), a 60-beam lidar (``beams_60``), MPPI at 10 Hz (``control_10_hz``) and noisy
    encoders instead of perfect odometry (``encoders``): the crowd section's figures for each.
    No target: what still collides, in which kind of crowd.
``speed``
    The whole loop of ``crowd_crossing`` with 50 walkers (one robot, a 360-beam lidar at
    10 Hz, costmap, tracker, MPPI at 20 Hz): simulated seconds per second of the process's CPU
    time and of the wall clock (``crowd_real_time_factor``: target >= 20 on this 2-core
    machine). The world alone against ir-sim and the 100 lockstep worlds are
    ``benchmarks/world.py``'s figures.
"""

from __future__ import annotations

import argparse
import copy
import json
import math
import statistics
import time
from concurrent.futures import ProcessPoolExecutor
from typing import Any

import numpy as np

SECTIONS = ("crowd", "irsim", "boxes", "doorway", "swap", "variants", "speed")
CROWDS = ("20_mppi", "20_dwa", "50_mppi", "50_dwa")


def _crowd(walkers: int, law: str) -> dict:
    from wheelbase.scenario import load_scenario

    data = load_scenario("crowd_crossing").model_dump(mode="json")
    data["world"]["agents"][0]["count"] = walkers
    data["name"] = f"crowd_crossing_{walkers}_{law}"
    if law == "dwa":
        # Nav2's default DWB set-up: the standard generator (ramped targets over sim_time);
        # from a stop Fox et al.'s one-period window only holds arcs near zero speed
        data["controller"] = {"law": "dwa", "gains": {"trajectory_generator": "standard"}}
    return {k: v for k, v in data.items() if v is not None}


_CAR = {"model": "rear_bicycle", "wheel_base": 0.5, "max_steering_deg": 35,
        "footprint": [0.7, 0.4], "center_offset": 0.25, "half_track": 0.18,
        "wheel_radius": 0.08}  # fmt: skip

VARIANT_CHANGES: dict[str, dict[str, dict]] = {
    # name: {part of the scenario ("agents": the walkers' group, "lidar", "scenario"): keys}
    "straight": {"agents": {"behaviour": "straight"}},
    "social_force": {"agents": {"behaviour": "social_force"}},
    "social_force_reacts": {"agents": {"behaviour": "social_force", "reacts_to_robot": True}},
    "orca_reacts": {"agents": {"behaviour": "orca", "reacts_to_robot": True}},
    "fast_small": {"agents": {"radius": 0.2, "speed": 1.0}},
    "walkers_35": {"agents": {"count": 35}},
    "unicycle": {"scenario": {"robot": {"model": "unicycle", "footprint": [0.4, 0.4]}}},
    "car": {"scenario": {"robot": _CAR, "planner": {"turning_radius": 0.8}}},
    "beams_60": {"lidar": {"beams": 60}},
    "control_10_hz": {"scenario": {"control_rate_hz": 10}},
    "encoders": {"scenario": {"odometry": {"mode": "encoders", "pulses_per_revolution": 1024}}},
}
"""The ``variants`` section's changes to ``crowd_crossing`` (module docstring)."""

VARIANTS = tuple(VARIANT_CHANGES)


def _variant(name: str) -> dict:
    """``crowd_crossing`` with 20 walkers and MPPI, changed as ``variants`` says (docstring)."""
    data = _crowd(20, "mppi")
    parts = {"agents": data["world"]["agents"][0], "lidar": data["sensors"]["lidar"],
             "scenario": data}  # fmt: skip
    for part, keys in VARIANT_CHANGES[name].items():
        parts[part].update(copy.deepcopy(keys))
    data["name"] = f"crowd_crossing_{name}"
    return data


def _run_chunk(scenario: Any, seeds: list[int]) -> list[dict]:
    from wheelbase.runner import run_seeds

    rows = run_seeds(scenario, seeds)
    for row in rows:
        row.pop("robots", None)
    return rows


def run_many(scenario: Any, seeds: int, workers: int) -> list[dict]:
    """Metrics of ``seeds`` seeds, in chunks over ``workers`` processes."""
    chunks = [list(range(seeds))[k::workers] for k in range(workers)]
    chunks = [chunk for chunk in chunks if chunk]
    if workers == 1:
        return [row for chunk in chunks for row in _run_chunk(scenario, chunk)]
    with ProcessPoolExecutor(workers) as pool:
        futures = [pool.submit(_run_chunk, scenario, chunk) for chunk in chunks]
        return [row for future in futures for row in future.result()]


def summary(rows: list[dict]) -> dict:
    """The figures of a set of runs (module docstring)."""
    n = len(rows)
    arrived = [row for row in rows if row["status"] == "arrived"]

    def mean(key: str, among: list[dict] = rows) -> float | None:
        values = [row[key] for row in among if row.get(key) is not None]
        return round(statistics.fmean(values), 4) if values else None

    distances = [row["min_agent_distance_m"] for row in rows if row.get("min_agent_distance_m")]
    return {
        "runs": n,
        "arrived": round(len(arrived) / n, 4) if n else None,
        "collisions_at_fault": sum(bool(row.get("collision_at_fault")) for row in rows),
        "struck_at_rest": sum(bool(row.get("struck_at_rest")) for row in rows),
        "collisions": sum(row["status"] == "collision" for row in rows),
        "timeouts": sum(row["status"] == "timeout" for row in rows),
        "blocked": sum(row["status"] == "blocked" for row in rows),
        "time_to_goal_s": mean("duration_s", arrived),
        "min_agent_distance_m_median": round(statistics.median(distances), 3)
        if distances
        else None,
        "discomfort_s": mean("discomfort_s"),
        "track_position_rmse_m": mean("track_position_rmse_m"),
        "track_velocity_rmse_m_s": mean("track_velocity_rmse_m_s"),
        "replans": mean("replans"),
        "path_length_ratio": mean("path_length_ratio", arrived),
        "failed_seeds": [row["seed"] for row in rows if row["status"] != "arrived"][:20],
        "at_fault_seeds": [row["seed"] for row in rows if row.get("collision_at_fault")],
    }


def irsim_crossings(walkers: int, seeds: int, steps: int = 600) -> dict:
    """ir-sim's RVO robot crossing the notes' room: arrivals and collisions."""
    import contextlib
    import logging
    import sys
    import tempfile
    from pathlib import Path

    import matplotlib

    matplotlib.use("Agg")
    from world import IRSIM_WORLD  # benchmarks/world.py: the notes' set-up

    with contextlib.redirect_stdout(sys.stderr):
        import irsim
    logging.getLogger().setLevel(logging.ERROR)
    arrived = collided = 0
    start = time.perf_counter()
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "room.yaml"
        path.write_text(IRSIM_WORLD.format(walkers=walkers, sensors=""))
        for seed in range(seeds):
            env = irsim.make(str(path), display=False, disable_all_plot=True,
                             log_level="ERROR", seed=seed)  # fmt: skip
            for _ in range(steps):
                env.step()
                robot = env.robot
                if robot.arrive or robot.collision:
                    break
            arrived += bool(env.robot.arrive)
            collided += bool(env.robot.collision)
    return {"runs": seeds, "arrived": arrived / seeds, "collisions": collided,
            "wall_s": round(time.perf_counter() - start, 1)}  # fmt: skip


def speed(walkers: int = 50) -> dict:
    """Simulated seconds per CPU second and per wall second of the crowd loop."""
    from wheelbase.runner import prepare

    scenario = _crowd(walkers, "mppi")
    prepared = prepare(scenario)
    seeds = np.zeros(1, dtype=np.int64)
    prepared.engine.run(prepared.start, seeds)  # compiled and warm
    cpu, wall = time.process_time(), time.perf_counter()
    log = prepared.engine.run(prepared.start, seeds)
    cpu, wall = time.process_time() - cpu, time.perf_counter() - wall
    simulated = float(log.t[-1])
    return {
        "walkers": walkers,
        "simulated_s": round(simulated, 2),
        "crowd_real_time_factor": round(simulated / wall, 2),
        "crowd_real_time_factor_cpu": round(simulated / cpu, 2),
        "status": log.statuses[0],
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=100)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--sections", default=",".join(SECTIONS))
    parser.add_argument("--crowds", default=",".join(CROWDS),
                        help="crowd runs to make (walkers_law), default all")  # fmt: skip
    parser.add_argument(
        "--variants",
        default=",".join(VARIANTS),
        help="crowd variants of the variants section, default all",
    )
    parser.add_argument("--variant-seeds", type=int, default=6)
    args = parser.parse_args()
    sections = [name for name in args.sections.split(",") if name]
    unknown = sorted(set(sections) - set(SECTIONS))
    if unknown:
        parser.error(f"unknown sections {unknown}; allowed: {', '.join(SECTIONS)}")
    crowds = [name for name in args.crowds.split(",") if name]
    unknown = sorted(set(crowds) - set(CROWDS))
    if unknown:
        parser.error(f"unknown crowds {unknown}; allowed: {', '.join(CROWDS)}")
    variants = [name for name in args.variants.split(",") if name]
    unknown = sorted(set(variants) - set(VARIANTS))
    if unknown:
        parser.error(f"unknown variants {unknown}; allowed: {', '.join(VARIANTS)}")
    out: dict[str, Any] = {"seeds": args.seeds}
    if "crowd" in sections:
        out["crowd"] = {}
        for name in crowds:
            walkers, law = name.split("_")
            rows = run_many(_crowd(int(walkers), law), args.seeds, args.workers)
            out["crowd"][name] = summary(rows)
    if "irsim" in sections:
        try:
            out["irsim"] = {str(n): irsim_crossings(n, args.seeds) for n in (20, 50)}
        except Exception as error:  # the peer is optional: say why it is missing
            out["irsim"], out["irsim_error"] = None, f"{type(error).__name__}: {error}"[:300]
    for name, scenario in (("boxes", "unexpected_boxes"), ("doorway", "doorway_blocked"),
                           ("swap", "corridor_swap")):  # fmt: skip
        if name in sections:
            rows = run_many(scenario, args.seeds, args.workers)
            out[name] = summary(rows)
            if name == "doorway":
                doorway_rows = rows
    if "doorway" in out:
        rows = doorway_rows
        out["doorway"]["all_blocked_within_60_s"] = all(
            row["status"] == "blocked" and row["duration_s"] <= 60.0 for row in rows
        )
        out["doorway"]["blocked_after_s_max"] = max(row["duration_s"] for row in rows)
    if "variants" in sections:
        out["variants"] = {name: summary(run_many(_variant(name), args.variant_seeds,
                                                  args.workers))
                           for name in variants}  # fmt: skip
    if "speed" in sections:
        out["speed"] = speed()
    out["targets"] = _targets(out)
    print(json.dumps(out, indent=2, default=lambda value: None))


def _targets(out: dict) -> dict:
    crowd = out.get("crowd", {})
    checks = {}
    for walkers, rate in (("20", 0.99), ("50", 0.97)):
        for law in ("mppi", "dwa"):
            row = crowd.get(f"{walkers}_{law}")
            if row:
                checks[f"crowd_{walkers}_{law}"] = (
                    row["arrived"] >= rate and row["collisions_at_fault"] == 0
                )
    if "boxes" in out:
        checks["boxes"] = out["boxes"]["arrived"] >= 0.99 and out["boxes"]["collisions"] == 0
    if "doorway" in out:
        checks["doorway"] = (
            out["doorway"]["all_blocked_within_60_s"] and not out["doorway"]["collisions"]
        )
    if "swap" in out:  # both robots of every seed arrive, no contact
        checks["swap"] = out["swap"]["arrived"] == 1.0 and out["swap"]["collisions"] == 0
    if "speed" in out:
        checks["speed"] = out["speed"]["crowd_real_time_factor"] >= 20
    return {name: bool(value) if not isinstance(value, float) or math.isfinite(value) else None
            for name, value in checks.items()}  # fmt: skip


if __name__ == "__main__":
    main()
