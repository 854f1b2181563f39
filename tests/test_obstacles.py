"""Navigation among obstacles the map does not show (issue 22): the world, what the robot makes
of it, replanning, recovery, fleets and the metrics, through scenarios as a user runs them."""

import math
from dataclasses import dataclass, replace

import numpy as np
import pytest

import wheelbase
from wheelbase.errors import ScenarioError
from wheelbase.runner import prepare

BOX_ROUTE = {
    "name": "box_on_the_route",
    "map": "empty",
    "robot": {"model": "unicycle", "footprint": [0.4, 0.4]},
    "controller": {"law": "mppi", "gains": {"samples": 400}},
    "control_rate_hz": 10,
    "odometry": {"mode": "perfect"},
    "sensors": {"lidar": {"beams": 180, "max_range": 6.0, "range_std": 0.01, "rate_hz": 10}},
    "world": {"obstacles": [{"box": [5.0, 1.0, 0.6, 0.8, 20.0]}]},
    "start": [1.0, 1.0, 0.0],
    "goal": [9.0, 1.0, 0.0],
    "trajectory": {"max_speed": 0.5},
    "goal_tolerance": [0.15, 180.0],
    "dt": 0.05,
    "duration": 60,
}


def test_a_box_off_the_map_is_seen_planned_around_and_passed():
    result = wheelbase.run(BOX_ROUTE)
    m = result.metrics
    assert m["status"] == "arrived", m
    assert m["replans"] >= 1  # the first plan ran straight through the box
    assert 0.0 < m["min_obstacle_distance_m"] < 1.0  # it passed beside it, without contact
    assert m["collision_at_fault"] is False and m["struck_at_rest"] is False
    assert m["path_length_ratio"] > 1.0  # the detour is longer than the plan on the map
    # the plans it made avoid the box; the first one (on the map) does not
    from wheelbase.world import box_polygon

    box = box_polygon(5.0, 1.0, 0.6, 0.8, math.radians(20.0))
    first, *later = [poses for _, poses in result.log.summaries[0]["plans"]] or [None]
    from shapely import LineString, Polygon

    assert LineString(result.plan.poses[:, :2]).intersects(Polygon(box))
    assert later or first is not None


def test_without_a_lidar_the_robot_is_blind_and_drives_into_the_box():
    blind = {**BOX_ROUTE, "sensors": {}}
    m = wheelbase.run(blind).metrics
    assert m["status"] == "collision"
    assert m["collision_at_fault"] is True  # it drove into a box that stood still


def test_a_doorway_closed_by_a_box_ends_blocked_not_in_a_collision_or_a_timeout():
    m = wheelbase.run("doorway_blocked").metrics
    assert m["status"] == "blocked"
    assert m["duration_s"] < 60.0
    assert m["recoveries"] == 6  # Nav2's bounded retries, then it gives up
    assert m["min_obstacle_distance_m"] > 0.0


def test_the_world_is_seen_only_through_the_sensors():
    """Replay: a second run whose world is only the first run's recorded lidar truth (no
    agents, no obstacles, nothing to read) is the same run, to the last bit."""
    scenario = {
        **BOX_ROUTE,
        "map": "room20",
        "start": [2.0, 2.0, 45.0],
        "goal": [18.0, 18.0, 45.0],
        "world": {"agents": [{"count": 12, "radius": 0.3, "speed": 0.5,
                              "region": [4, 4, 16, 16], "behaviour": "wander"}]},
        "duration": 12,
    }  # fmt: skip
    prepared = prepare(scenario)
    live = prepared.engine.surroundings
    tape: dict[str, list] = {"cast": [], "collides": [], "signals": []}

    @dataclass(frozen=True)
    class Recording:
        def start(self, seeds, poses):
            return 0

        def step(self, state, dt, poses, twists):
            return state + 1

        def collides(self, state, poses, index):
            return tape["collides"][state]

        def caster(self, state, poses):
            return lambda *args: tape["cast"][state]

        def signals(self, state, poses, twists):
            return tape["signals"][state]

        def agents(self, state):
            return None

    class Recorder:
        """The live world, its every answer written down, indexed by step."""

        world = live.world

        def start(self, seeds, poses):
            return (0, live.start(seeds, poses))

        def step(self, state, dt, poses, twists):
            return (state[0] + 1, live.step(state[1], dt, poses, twists))

        def collides(self, state, poses, index):
            hit = live.collides(state[1], poses, index)
            tape["collides"].append(hit)
            return hit

        def caster(self, state, poses):
            cast = live.caster(state[1], poses)

            def record(*args):
                ranges = cast(*args)
                tape["cast"].extend([None] * (state[0] - len(tape["cast"])))
                tape["cast"].append(ranges)
                return ranges

            return record

        def signals(self, state, poses, twists):
            values = live.signals(state[1], poses, twists)
            tape["signals"].append(values)
            return values

        def agents(self, state):
            return None

        def track_scores(self, state, tracks, index):
            return live.track_scores(state[1], tracks, index)

    seeds = np.zeros(1, dtype=np.int64)
    first = replace(prepared.engine, surroundings=Recorder(), record_sensors=False)
    log = first.run(prepared.start, seeds)
    again = replace(prepared.engine, surroundings=Recording(), record_sensors=False)
    replayed = again.run(prepared.start, seeds)
    assert log.n_robots == replayed.n_robots
    np.testing.assert_array_equal(log.true_pose, replayed.true_pose)
    np.testing.assert_array_equal(log.command, replayed.command)
    assert log.statuses == replayed.statuses
    assert len(log.t) > 100  # it ran: 12 s among walkers


def test_agents_placed_on_the_start_or_too_many_for_their_region_are_clear_errors():
    crowded = {**BOX_ROUTE, "world": {"agents": [{"count": 500, "radius": 0.5,
                                                  "region": [3, 0, 7, 2]}]}}  # fmt: skip
    with pytest.raises(ScenarioError, match=r"world\.agents\[0\]"):
        wheelbase.run(crowded)
    on_start = {**BOX_ROUTE, "world": {"obstacles": [{"disc": [1.0, 1.0, 0.3]}]}}
    with pytest.raises(ScenarioError, match=r"world\.obstacles\[0\].*start"):
        wheelbase.run(on_start)
    with pytest.raises(ScenarioError, match=r"behaviour"):
        wheelbase.run({**BOX_ROUTE, "world": {"agents": [{"count": 2, "behaviour": "dance"}]}})


def test_fleet_robots_that_start_overlapping_are_refused():
    fleet = {
        **{k: v for k, v in BOX_ROUTE.items() if k not in ("start", "goal", "world")},
        "fleet": [
            {"start": [1, 1, 0], "goal": [9, 1, 0]},
            {"start": [1.2, 1, 0], "goal": [9, 3, 0]},
        ],
    }
    with pytest.raises(ScenarioError, match="fleet"):
        wheelbase.run(fleet)


def test_crowd_worlds_in_lockstep_equal_their_runs_alone():
    """Seeds stepped together (each its own walkers, tracker, costmap and MPPI) end exactly as
    each alone: nothing of one world leaks into another (the crowd benchmark counts on it)."""
    from wheelbase.runner import run_seeds

    scenario = {
        **BOX_ROUTE,
        "map": "room20",
        "start": [2.0, 2.0, 45.0],
        "goal": [18.0, 18.0, 45.0],
        "world": {"agents": [{"count": 12, "radius": 0.3, "speed": 0.5,
                              "region": [4, 4, 16, 16], "behaviour": "wander"}]},
        "duration": 10,
    }  # fmt: skip
    rows = run_seeds(scenario, [5, 2, 9])
    for row in rows:
        alone = wheelbase.run({**scenario, "seed": row["seed"]}).metrics
        for key in ("status", "duration_s", "min_agent_distance_m", "path_length_m", "replans"):
            assert row[key] == alone[key], (row["seed"], key)
    assert len({row["min_agent_distance_m"] for row in rows}) == 3  # three different crowds


def test_path_boxes_fall_on_the_plan_and_differ_by_seed():
    scenario = {**BOX_ROUTE, "world": {"path_boxes": {"count": [2, 2], "size": [0.4, 0.6]}}}
    boxes = []
    for seed in (0, 1):
        world = prepare(scenario, seed=seed).engine.surroundings.world
        boxes.append(np.array(world.obstacles.polygons))
        centres = boxes[-1].mean(axis=1)
        assert len(centres) == 2
        assert np.all(np.abs(centres[:, 1] - 1.0) < 0.05)  # on the straight plan y = 1
        assert np.all((centres[:, 0] > 2.5) & (centres[:, 0] < 7.5))  # 1.5 m from both ends
    assert not np.allclose(boxes[0], boxes[1])


def test_a_fleet_gets_one_route_per_robot_in_its_order_of_priority():
    prepared = prepare("corridor_swap")
    assert len(prepared.plans) == 2
    assert [route.priority for route in prepared.engine.references] == [0, 1]
    np.testing.assert_allclose(prepared.plans[0].poses[-1], [15.0, 0.8, 0.0], atol=1e-9)
    np.testing.assert_allclose(prepared.plans[1].poses[-1][:2], [1.0, 0.8], atol=1e-9)
