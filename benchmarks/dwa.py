"""DWA figures of issue 22: controller rate per backend and the crowd encounters beside MPPI.

Prints one JSON object:

- ``cpu_hz``: DWA calls per second with Nav2's sampling (20 × 20 velocities, 1.7 s simulated
  in steps of 0.05 s, 0.4 × 0.4 m footprint) on the cluttered map, per backend (``numba`` all
  threads, ``numba_1_thread``, ``numpy``), without and with a perception view (``*_with_view``:
  a 3 × 3 m costmap of 0.05 m cells with a box, 20 tracks within 3 m: the view of
  ``benchmarks/mppi.py``);
- ``crowd``: DWA on the encounters of ``benchmarks/crowd_cases.py`` (a disc head-on, one
  crossing, one to overtake, a group of three, a box in the costmap) over ``--seeds`` seeds
  (``--quick``: the head-on disc, one seed), seeing perfect tracks: success rate (no contact
  and the path's end reached within 30 s), collisions, least and median gap [m], stops (calls
  that found no collision-free command); ``benchmarks/mppi.py`` prints MPPI's on the same
  cases.

Usage: ``python benchmarks/dwa.py [--quick] [--seeds N]``.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import time
from importlib import resources
from pathlib import Path

import numba
import numpy as np

from crowd_cases import busy_view, crowd_suite
from wheelbase.control import DWA
from wheelbase.models import Unicycle
from wheelbase.planning import Footprint, PlannedPath, load_map

ROBOT = Footprint.rectangle(0.4, 0.4)
STRAIGHT = PlannedPath.from_points([[1.0, 4.0], [11.0, 4.0]])


def rate(backend: str, grid, calls: int, view=None) -> float:
    controller = DWA(Unicycle(), grid=grid, footprint=ROBOT, backend=backend)
    pose = np.array([2.4, 3.9, 0.1])
    for _ in range(3):  # compile / warm up
        controller.plan(pose, STRAIGHT, perception=view, t=0.0)
    best = np.inf
    for _ in range(3):
        begin = time.perf_counter()
        for k in range(calls):
            controller._velocity = np.array([0.3, 0.0])  # the same window at every call
            controller.plan(pose, STRAIGHT, perception=view, t=0.05 * k)
        best = min(best, (time.perf_counter() - begin) / calls)
    return 1.0 / best


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="1 seed, 5 timed calls")
    parser.add_argument("--seeds", type=int, default=10, help="seeds of each encounter")
    args = parser.parse_args()
    calls = 5 if args.quick else 50
    grid = load_map(Path(str(resources.files("wheelbase") / "data" / "maps" / "cluttered.yaml")))
    view = busy_view(np.array([2.4, 3.9, 0.1]))
    out: dict = {
        "machine": {
            "cpus": os.cpu_count(),
            "numba_threads": numba.get_num_threads(),
            "load_average_1min": os.getloadavg()[0],
            "python": platform.python_version(),
        },
        "config": {"v_samples": 20, "w_samples": 20, "sim_time_s": 1.7, "sim_dt_s": 0.05},
    }
    rates = {"numba": rate("numba", grid, calls), "numpy": rate("numpy", grid, calls)}
    threads = numba.get_num_threads()
    numba.set_num_threads(1)
    rates["numba_1_thread"] = rate("numba", grid, calls)
    numba.set_num_threads(threads)
    rates["numba_with_view"] = rate("numba", grid, calls, view)
    rates["numpy_with_view"] = rate("numpy", grid, max(1, calls // 5), view)
    out["cpu_hz"] = rates

    def make(seed: int) -> DWA:
        return DWA(Unicycle(), footprint=ROBOT)

    if args.quick:  # one encounter, one seed: a smoke run
        out["crowd"] = crowd_suite(make, 1, ROBOT, cases=("head_on",))
    else:
        out["crowd"] = crowd_suite(make, args.seeds, ROBOT)
    print(json.dumps(out, indent=2))


if __name__ == "__main__":
    main()
