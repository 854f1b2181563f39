"""The world's speed (issue 22): one world with walkers and a lidar, and crowds in lockstep.

Run ``python benchmarks/world.py`` (``--quick`` for a smoke run); prints one JSON object.

``one_world``
    For 20 and 50 walkers: a 20 m × 20 m walled room (0.1 m cells), walkers of radius 0.3 m
    at 0.5 m/s wandering between random goals in [3, 17]² (``wander``: they ignore the robot,
    as ir-sim's ``dash``), one robot (0.4 m × 0.4 m) driven open loop from (2, 2, 45°) at
    0.5 m/s and 0.1 rad/s, dt = 0.1 s. ``steps_per_s``: :meth:`World.step` plus a 360-beam,
    10 m :meth:`World.cast` from the robot each step, on one Numba thread (the figure per
    core); ``steps_per_s_no_lidar``: the step alone. Best of ``--repeat`` runs of ``--steps``.
``irsim``
    ir-sim 2.12 (``pip install -e ".[bench]"``) on the same room in the same run, set up as
    ``../shared/notes/obstacles.md`` says (its RVO robot from (2, 2) to (18, 18), ``dash``
    walkers wandering in [3, 17]², step_time 0.1 s, no rendering), with and without a 360-beam
    10 m ``lidar2d`` on the robot: ``env.step()`` per second. ``null`` with ``irsim_error``
    when it is not installed or fails.
``ratios``
    Ours / ir-sim's: with the lidar on both (the same world), ours with the lidar against
    ir-sim without one in this run and as the notes measured it (1,415 and 856 steps/s, without
    a lidar), and both without a lidar. Target >= 20.
``lockstep``
    100 worlds × 50 agents stepped together (one :meth:`World.step` call, one thread):
    agent-steps per second for each behaviour (``wander`` is the crowd of the target,
    >= 1e6).
"""

from __future__ import annotations

import argparse
import json
import math
import os
import platform
import sys
import tempfile
import time
from pathlib import Path

os.environ.setdefault("NUMBA_NUM_THREADS", "1")  # one core, the figure per core

import numpy as np

from wheelbase.planning import Footprint, OccupancyGrid
from wheelbase.world import AgentGroup, RobotBodies, World

NOTES = {"irsim_no_lidar_steps_per_s": {"20": 1415, "50": 856}}
"""ir-sim's rates measured on this machine for the notes (no lidar)."""


def room() -> OccupancyGrid:
    occupied = np.zeros((200, 200), bool)
    occupied[[0, -1], :] = occupied[:, [0, -1]] = True
    return OccupancyGrid(occupied, 0.1)


def one_world(walkers: int, steps: int, repeat: int, lidar: bool) -> float:
    """Steps per second of one world with ``walkers`` and (``lidar``) a 360-beam scan."""
    walkers_group = AgentGroup(count=walkers, radius=0.3, speed=0.5, behaviour="wander",
                               region=(3, 3, 17, 17))  # fmt: skip
    world = World(room(), agents=[walkers_group])
    footprint = Footprint.rectangle(0.4, 0.4)
    beams = np.linspace(-math.pi, math.pi, 360, endpoint=False)
    world_index = np.zeros(1, np.int64)
    self_index = np.zeros(1, np.int64)
    best = 0.0
    for trial in range(repeat + 1):  # the first run warms the caches up
        state = world.start([trial], keep_clear=[[2.0, 2.0, 0.5]])
        pose = np.array([2.0, 2.0, math.pi / 4])
        start = time.perf_counter()
        for _ in range(steps):
            velocity = 0.5 * np.array([math.cos(pose[2]), math.sin(pose[2])])
            robots = RobotBodies(pose[None, None], velocity[None, None], footprint)
            state = world.step(state, 0.1, robots)
            pose = pose + 0.1 * np.array([velocity[0], velocity[1], 0.1])
            if lidar:
                world.cast(pose[None], beams, 10.0, world_index, state, robots, self_index)
        rate = steps / (time.perf_counter() - start)
        if trial:
            best = max(best, rate)
    return best


def lockstep(behaviour: str, worlds: int, agents: int, steps: int, repeat: int) -> float:
    """Agent-steps per second of ``worlds`` × ``agents`` in one call per step."""
    group = AgentGroup(count=agents, radius=0.3, speed=0.5, behaviour=behaviour,
                       region=(3, 3, 17, 17))  # fmt: skip
    world = World(room(), agents=[group])
    best = 0.0
    for trial in range(repeat + 1):
        state = world.start(np.arange(worlds) + 1000 * trial)
        start = time.perf_counter()
        for _ in range(steps):
            state = world.step(state, 0.1)
        rate = steps * worlds * agents / (time.perf_counter() - start)
        if trial:
            best = max(best, rate)
    return best


IRSIM_WORLD = """
world:
  height: 20
  width: 20
  step_time: 0.1
  sample_time: 0.1
  offset: [0, 0]
  collision_mode: 'stop'
  control_mode: 'auto'
robot:
  - kinematics: {{name: 'diff'}}
    shape: {{name: 'circle', radius: 0.2}}
    state: [2, 2, 0.785]
    goal: [18, 18, 0.785]
    vel_max: [1, 1.5]
    vel_min: [-1, -1.5]
    behavior: {{name: 'rvo'}}
{sensors}
obstacle:
  - number: {walkers}
    distribution: {{name: 'random', range_low: [3, 3, -3.14], range_high: [17, 17, 3.14]}}
    kinematics: {{name: 'omni'}}
    shape: {{name: 'circle', radius: 0.3}}
    behavior: {{name: 'dash', wander: True, range_low: [3, 3, -3.14],
                range_high: [17, 17, 3.14]}}
    vel_max: [0.5, 0.5]
    vel_min: [-0.5, -0.5]
"""
IRSIM_LIDAR = """    sensors:
      - {name: 'lidar2d', range_min: 0, range_max: 10, angle_range: 6.2832, number: 360}"""


def irsim_rate(walkers: int, steps: int, lidar: bool) -> float:
    """ir-sim's ``env.step()`` per second on the notes' world (never ``env.end()``: it waits
    for matplotlib)."""
    import contextlib
    import logging

    import matplotlib

    matplotlib.use("Agg")
    with contextlib.redirect_stdout(sys.stderr):  # (it prints its backend trials on import)
        import irsim

    logging.getLogger().setLevel(logging.ERROR)
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "room.yaml"
        path.write_text(IRSIM_WORLD.format(walkers=walkers,
                                           sensors=IRSIM_LIDAR if lidar else ""))  # fmt: skip
        env = irsim.make(str(path), display=False, disable_all_plot=True, log_level="ERROR",
                         seed=0)  # fmt: skip
        env.step()
        start = time.perf_counter()
        for _ in range(steps):
            env.step()
        return steps / (time.perf_counter() - start)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="a smoke run (seconds)")
    parser.add_argument("--steps", type=int, default=3000)
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--no-irsim", action="store_true", help="skip ir-sim")
    args = parser.parse_args()
    steps, repeat = (50, 1) if args.quick else (args.steps, args.repeat)
    out: dict = {"machine": {"cpus": os.cpu_count(), "python": platform.python_version(),
                             "load_1min": os.getloadavg()[0],
                             "numba_threads": int(os.environ["NUMBA_NUM_THREADS"])}}  # fmt: skip
    out["one_world"] = {
        str(n): {"steps_per_s": round(one_world(n, steps, repeat, True)),
                 "steps_per_s_no_lidar": round(one_world(n, steps, repeat, False))}
        for n in (20, 50)
    }  # fmt: skip
    out["irsim"], out["irsim_error"] = None, None
    if not args.no_irsim:
        try:
            ir_steps = 10 if args.quick else 300
            out["irsim"] = {str(n): {
                "steps_per_s": round(irsim_rate(n, max(5, ir_steps // 20), True), 1),
                "steps_per_s_no_lidar": round(irsim_rate(n, ir_steps, False), 1)}
                for n in (20, 50)}  # fmt: skip
        except Exception as error:  # any failure of the peer is reported, not raised
            out["irsim_error"] = f"{type(error).__name__}: {error}"[:300]
    noted = NOTES["irsim_no_lidar_steps_per_s"]
    reference = out["irsim"] or {
        n: {"steps_per_s_no_lidar": v, "steps_per_s": None} for n, v in noted.items()
    }
    out["ratios"] = {}
    for n in ("20", "50"):
        ours = out["one_world"][n]
        theirs = reference[n]
        out["ratios"][n] = {
            "lidar_vs_irsim_lidar": None if not theirs["steps_per_s"] else
            round(ours["steps_per_s"] / theirs["steps_per_s"], 1),
            "lidar_vs_irsim_no_lidar": round(
                ours["steps_per_s"] / theirs["steps_per_s_no_lidar"], 1),
            "lidar_vs_notes_irsim_no_lidar": round(
                ours["steps_per_s"] / NOTES["irsim_no_lidar_steps_per_s"][n], 1),
            "no_lidar_vs_irsim_no_lidar": round(ours["steps_per_s_no_lidar"] /
                                                theirs["steps_per_s_no_lidar"], 1),
        }  # fmt: skip
    worlds, lock_steps = (10, 10) if args.quick else (100, 200)
    out["lockstep"] = {b: round(lockstep(b, worlds, 50, lock_steps, repeat))
                       for b in ("straight", "wander", "social_force", "orca")}  # fmt: skip
    out["lockstep_worlds"] = worlds
    ratios = out["ratios"].values()
    out["targets"] = {
        "ratio": 20,
        "met_same_world_with_lidar": all((r["lidar_vs_irsim_lidar"] or 0) >= 20 for r in ratios),
        "met_lidar_vs_notes_irsim_no_lidar": all(
            r["lidar_vs_notes_irsim_no_lidar"] >= 20 for r in ratios
        ),
        "lockstep_agent_steps_per_s": 1e6,
        "met_lockstep": out["lockstep"]["wander"] >= 1e6,
    }
    json.dump(out, sys.stdout, indent=1)
    print()


if __name__ == "__main__":
    main()
