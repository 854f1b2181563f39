"""The world section from plain data: what it builds, and errors that name the key."""

import math

import numpy as np
import pytest

from wheelbase.errors import ScenarioError
from wheelbase.planning import OccupancyGrid
from wheelbase.world import ORCA, SocialForce, world_from_spec


def room() -> OccupancyGrid:
    occupied = np.zeros((200, 200), bool)
    occupied[[0, -1], :] = occupied[:, [0, -1]] = True
    return OccupancyGrid(occupied, 0.1)


SPEC = {
    "obstacles": [
        {"box": [6.0, 3.0, 0.6, 0.4, 30]},
        {"disc": [9.0, 2.5, 0.3]},
        {"polygon": [[12, 12], [13, 12], [12.5, 13]]},
    ],
    "agents": [
        {"count": 20, "radius": 0.3, "speed": 0.5, "behaviour": "straight",
         "region": [3, 3, 17, 17], "reacts_to_robot": False},
        {"count": 2, "behaviour": "waypoints", "waypoints": [[2, 2], [18, 2]]},
        {"count": 3, "behaviour": "orca", "reacts_to_robot": True},
    ],
    "social_force": {"relaxation_time": 0.4},
    "orca": {"time_horizon": 3.0, "max_neighbours": 6},
}  # fmt: skip


def test_a_full_section_builds_the_world():
    world = world_from_spec(SPEC, room())
    assert world.agent_count == 25
    box = world.obstacles.polygons[0]
    sides = np.hypot(*np.diff(np.vstack([box, box[:1]]), axis=0).T)
    np.testing.assert_allclose(sides, [0.6, 0.4, 0.6, 0.4])
    edge = box[1] - box[0]
    assert math.isclose(math.atan2(edge[1], edge[0]), math.radians(30))  # yaw in degrees
    assert world.obstacles.names == ("world.obstacles[0] (box)", "world.obstacles[2] (polygon)",
                                     "world.obstacles[1] (disc)")  # fmt: skip
    assert world.social_force == SocialForce(relaxation_time=0.4)
    assert world.orca == ORCA(time_horizon=3.0, max_neighbours=6)
    assert world.agents[2].reacts_to_robot and world.agents[0].region == (3, 3, 17, 17)
    assert world_from_spec(None, room()).agent_count == 0


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({"agents": [{"count": 2, "speed": 0}]}, r"world\.agents\[0\]\.speed must be > 0"),
        ({"agents": [{"count": 2, "speed": 50}]}, r"world\.agents\[0\]\.speed must be <= 10 m/s"),
        ({"agents": [{"count": 2, "speed": "fast"}]}, r"world\.agents\[0\]\.speed must be a num"),
        ({"agents": [{"behaviour": "dance"}]}, r"world\.agents\[0\]\.behaviour 'dance' is unknown"),
        ({"agents": [{"behaviour": "waypoints"}]}, r"world\.agents\[0\]\.waypoints are required"),
        ({"agents": [{"count": 2.5}]}, r"world\.agents\[0\]\.count must be an integer"),
        ({"agents": [{"count": 2, "colour": "red"}]}, r"world\.agents\[0\]: unknown key 'colour'"),
        ({"agents": [{"region": [3, 3, 40, 17]}]}, r"world\.agents\[0\]\.region .* inside the map"),
        ({"agents": [{"region": [3, 3, 3.2, 17]}]}, r"world\.agents\[0\]\.region .* diameter"),
        ({"agents": [{"behaviour": "waypoints", "waypoints": [[2, 2], [0.05, 5]]}]},
         r"world\.agents\[0\]\.waypoints\[1\] .* from a wall"),
        ({"agents": [{"reacts_to_robot": "yes"}]}, r"world\.agents\[0\]\.reacts_to_robot must be"),
        ({"agents": {"count": 3}}, r"world\.agents must be a list"),
        ({"obstacles": [{"box": [1, 1, -0.6, 0.6]}]}, r"world\.obstacles\[0\]\.box: length"),
        ({"obstacles": [{"box": [1, 1, 0.6]}]}, r"world\.obstacles\[0\]\.box must be"),
        ({"obstacles": [{"disc": [1, 1, math.nan]}]}, r"obstacles\[0\]\.disc\[2\] must be finite"),
        ({"obstacles": [{"disc": [1, 1, 1], "box": [1, 1, 1, 1]}]}, r"exactly one of"),
        ({"obstacles": [{"polygon": [[0, 0], [1, 1], [2, 2]]}]},
         r"world\.obstacles\[0\] \(polygon\): .*no area"),
        ({"obstacles": [{"polygon": [[0, 0], [2, 2], [2, 0], [0, 2]]}]},
         r"world\.obstacles\[0\] \(polygon\): .*not simple"),
        ({"obstacles": [{"disc": [50, 50, 1]}]}, r"world\.obstacles\[0\] \(disc\) lies outside"),
        ({"orca": {"time_horizon": -1}}, r"world\.orca\.time_horizon must be > 0"),
        ({"social_force": {"mass": None}}, r"world\.social_force\.mass must be a number"),
        ({"crowd": []}, r"world: unknown key 'crowd'"),
    ],
)  # fmt: skip
def test_bad_entries_name_their_key(change, message):
    with pytest.raises(ScenarioError, match=message):
        world_from_spec(change, room())


def test_the_section_must_be_a_mapping():
    with pytest.raises(ScenarioError, match="world must be a mapping"):
        world_from_spec([1, 2], room())
