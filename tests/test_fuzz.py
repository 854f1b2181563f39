"""Fuzz suite (issue 16): hostile scenario fields, map files of every format, CLI flags and public
constructors. Every case runs, or raises a WheelbaseError (the CLI: exit code 2, one line),
within the budget of its kind (``fuzzing.BUDGET_S``): never another exception, never a hang.

In CI the examples are derandomized (tests/conftest.py) and few (about 20 s in all); to hunt,
``pytest tests/test_fuzz.py --hypothesis-profile=explore`` draws at random (keep what it finds
as ``@example``), and ``python benchmarks/fuzz.py`` counts raw exceptions and hangs over 10,000
cases instead of stopping at the first.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, example, given, settings

import fuzzing

# Examples per test: few in CI (derandomized, ~10 s in all); in the explore profile 10,000 in
# all, shared as the targets' cost and variety suggest.
FAST = {"deadline": None, "suppress_health_check": list(HealthCheck)}


def _examples(ci: int, explore: int) -> dict:
    from hypothesis import settings as current

    return {"max_examples": ci if current.default.derandomize else explore}


@pytest.fixture(autouse=True, scope="module")
def _compiled():
    """Kernels compiled before the first budgeted case (a fresh cache compiles for a minute)."""
    fuzzing.warm_up()


def check(call, case, kind: str) -> None:
    """Fail unless the case ran or raised a WheelbaseError within its budget."""
    result = fuzzing.outcome(lambda: call(case), fuzzing.BUDGET_S[kind])
    if result.kind in ("raw", "hang"):
        pytest.fail(f"{result.kind}: {result.detail}\ncase: {case!r}"[:2000])


@settings(**FAST, **_examples(40, 3000))
@given(fuzzing.scenario_cases())
@example({**fuzzing.BASES[0], "dt": 1e-9})
@example({**fuzzing.BASES[0], "goal": [1e300, 0.0, 0.0]})
@example({**fuzzing.BASES[3], "controller": {"law": "mppi", "gains": {"seed": 2**70}}})
@example({**fuzzing.BASES[0], "planner": {"options": {"headings": float("inf")}}})
@example({**fuzzing.BASES[0], "trajectory": {"max_speed": 1e-300}})  # 1e301 reference samples
@example({**fuzzing.BASES[5], "terrain": {"surface": "ice", "slip_speed": 1e-300}})
@example({**fuzzing.BASES[5], "robot": {"preset": "rm100", "payload": {"mass": 1e5}}})
@example({**fuzzing.BASES[5], "terrain": {"resolution": 1e-9}})  # a raster of 1e20 cells
@example({**fuzzing.BASES[5], "goals": [{"pose": [1, 0, 0], "payload": {"mass": "x"}}]})
@example({**fuzzing.BASES[6], "control_rate_hz": 1e300})
@example({**fuzzing.BASES[6], "costmap": {"inflation_radius": -1.0}})
@example({**fuzzing.BASES[6], "world": {"agents": [{"count": 10**6}]}})
@example({**fuzzing.BASES[6], "world": {"obstacles": [{"disc": [0.0, 0.0, 0.5]}]}})  # on start
@example({**fuzzing.BASES[6], "world": {"path_boxes": {"count": [5, 5], "size": [9, 9]}}})
@example({**fuzzing.BASES[7], "fleet": [{"start": [0, 0, 0], "goal": [1, 0, 0]}] * 2})
@example({**fuzzing.BASES[7], "fleet": []})
def test_scenario_fields(case):
    check(fuzzing.run_scenario, case, "scenario")


@settings(**FAST, **_examples(15, 500))
@given(fuzzing.scenario_file_cases())
@example("name: café\n".encode("latin-1"))
def test_scenario_files(case):
    check(fuzzing.run_scenario_file, case, "scenario_file")


@settings(**FAST, **_examples(150, 2500))
@given(fuzzing.map_file_cases())
@example((".pgm", b"P5\n100000000 100000000\n255\n\x00", {}))
@example((".map", b"type octile\nheight abc\nwidth 2\nmap\n..\n", {}))
@example((".yaml", b"image: m.pgm\nresolution: 0.1\norigin: [a, 0, 0]\n", {}))
@example((".geojson", b'{"type": "Feature", "geometry": {"type": "Point"}, '
                      b'"properties": {"radius": 1}}', {}))  # fmt: skip
def test_map_files(case):
    check(fuzzing.load_map_file, case, "map_file")


@settings(**FAST, **_examples(60, 500))
@given(fuzzing.array_map_cases())
def test_map_arrays(case):
    check(fuzzing.grid_from_array, case, "map_file")


@settings(**FAST, **_examples(150, 2500))
@given(fuzzing.constructor_cases())
@example(("simulate", {"pose0": (0.0, 0.0, 0.0), "inputs": (1.0, 0.8), "t_end": 1e300,
                       "dt": 0.1, "method": "rk4"}))  # fmt: skip
@example(("AMCL", {**fuzzing.constructors()["AMCL"][1], "max_particles": 1e10}))
@example(("AMCL", {**fuzzing.constructors()["AMCL"][1], "z_rand": 0.0,
                   "likelihood_max_dist": 1e9}))  # fmt: skip
@example(("AMCL", {**fuzzing.constructors()["AMCL"][1], "sigma_hit": 1e-251}))
@example(("AMCL.update", {**fuzzing.constructors()["AMCL.update"][1], "scan": "abc"}))
@example(("EKF", {**fuzzing.constructors()["EKF"][1], "bearing_std": 1e300}))
@example(("EKF.update", {**fuzzing.constructors()["EKF.update"][1], "z": {}}))
@example(("LandmarkSensor.observe", {**fuzzing.constructors()["LandmarkSensor.observe"][1],
                                     "false_rate": 1e127}))  # fmt: skip
@example(("Lidar.scan", {**fuzzing.constructors()["Lidar.scan"][1], "beams": 2309998689321}))
@example(("Lidar.scan", {**fuzzing.constructors()["Lidar.scan"][1], "max_range": "1e3"}))
@example(("HybridAStar.plan", {**fuzzing.constructors()["HybridAStar.plan"][1],
                               "max_iterations": 2**70}))  # fmt: skip
@example(("MPPI", {**fuzzing.constructors()["MPPI"][1], "path_spacing": 1e-9}))
@example(("MPPI", {**fuzzing.constructors()["MPPI"][1], "samples": 10**400}))
@example(
    (
        "Footprint.rectangle",
        {**fuzzing.constructors()["Footprint.rectangle"][1], "length": 1e9, "width": 1e-9},
    )
)  # 4e9 covering circles
@example(("HybridAStar.plan", {**fuzzing.constructors()["HybridAStar.plan"][1],
                               "xy_resolution": 1e-320}))  # fmt: skip
@example(("update_costmap", {**fuzzing.constructors()["update_costmap"][1],
                             "sensor_poses": [[1e300, 1.0, 0.0]]}))  # fmt: skip
@example(("update_costmap", {**fuzzing.constructors()["update_costmap"][1], "max_range": 1e-300}))
@example(("update_tracker", {**fuzzing.constructors()["update_tracker"][1], "time": 1e300}))
@example(("update_tracker", {**fuzzing.constructors()["update_tracker"][1],
                             "ranges": np.full(24, np.nan)}))  # fmt: skip
@example(("CostmapSpec.from_mapping", {**fuzzing.constructors()["CostmapSpec.from_mapping"][1],
                                       "resolution": 1e-9}))  # fmt: skip
@example(("TrackerSpec.from_mapping", {**fuzzing.constructors()["TrackerSpec.from_mapping"][1],
                                       "max_tracks": 2**70}))  # fmt: skip
def test_constructors(case):
    check(fuzzing.call_constructor, case, "constructor")


@settings(**FAST, **_examples(12, 1000))
@given(fuzzing.cli_cases())
@example(["batch", "demo", "--seeds", "2", "--workers", "99999999999999999999"])
@example(["batch", "demo", "--seeds", "99999999999999999999"])
def test_cli_flags(case):
    check(fuzzing.run_cli, case, "cli")


@settings(**FAST, **_examples(40, 1500))
@given(fuzzing.world_cases())
@example({**fuzzing.WORLD_BASE, "agents": [{"count": 2, "speed": 0}]})
@example({**fuzzing.WORLD_BASE, "agents": [{"count": 2, "speed": 50}]})
@example({**fuzzing.WORLD_BASE, "agents": [{"count": 5000, "radius": 0.3}]})  # do not fit
@example({**fuzzing.WORLD_BASE, "agents": [{"behaviour": "dance"}]})
@example({**fuzzing.WORLD_BASE, "agents": [{"behaviour": "waypoints"}]})  # no waypoints
@example({**fuzzing.WORLD_BASE, "obstacles": [{"box": [1.0, 1.0, 0.6, 0.6]}]})  # on the start
@example({**fuzzing.WORLD_BASE, "agents": [{"count": 3, "radius": 1e-300}]})
@example({**fuzzing.WORLD_BASE, "social_force": {"range": 1e-300}})
@example({**fuzzing.WORLD_BASE, "orca": {"time_horizon": 1e-300}})
@example({**fuzzing.WORLD_BASE, "agents": [{"count": 2**70}]})
def test_world_section(case):
    check(fuzzing.run_world, case, "world")


def test_outcome_classifies_and_stops_a_hang():
    # The harness itself: a clean error, a raw exception, and a loop stopped at its budget.
    from wheelbase.errors import ConfigError

    def loop():
        while True:
            pass

    def raise_config():
        raise ConfigError("x must be > 0 m (got -1)")

    assert fuzzing.outcome(raise_config, 1.0).kind == "error"
    assert fuzzing.outcome(lambda: 1 / 0, 1.0).kind == "raw"
    stopped = fuzzing.outcome(loop, 0.2)
    assert stopped.kind == "hang" and stopped.seconds < 1.0


@settings(**FAST, **_examples(40, 1000))
@given(fuzzing.slam_file_cases())
@example(
    (
        ".g2o",
        b"VERTEX_SE2 0 0 0 0\nEDGE_SE2 0 1 1 0 0 1 0 0 1 0 1\n",
        {"resolution": 0.05, "max_cells": 10**6, "max_range": 30.0},
    )
)  # missing vertex
@example(
    (
        ".g2o",
        b"EDGE_SE2 0 1 1 0 0 1 0 0 -1 0 1\n",
        {"resolution": 0.05, "max_cells": 10**6, "max_range": 30.0},
    )
)  # not positive definite
@example((".log", b"", {"resolution": 0.05, "max_cells": 10**6, "max_range": 30.0}))
@example(
    (
        ".log",
        b"FLASER 2 nan inf 0 0 0 0 0 0 1 h 1\nFLASER 2 1 1 0 0 0 0 0 0 2 h 2\n",
        {"resolution": 1e-5, "max_cells": 10, "max_range": 30.0},
    )
)  # map over the limit
def test_slam_files(case):
    check(fuzzing.slam_file, case, "slam_file")
