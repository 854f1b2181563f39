"""Replanning and recovery (wheelbase.navigation): what the robot does when its plan is blocked."""

import math
from dataclasses import dataclass

import numpy as np
import pytest

from wheelbase.errors import ConfigError
from wheelbase.navigation import Navigator, NavigatorOptions, Route, believed_grid
from wheelbase.planning import Footprint, HybridAStar, OccupancyGrid

RES = 0.1
FOOTPRINT = Footprint.rectangle(0.4, 0.4)


@dataclass(frozen=True)
class Costmap:
    cost: np.ndarray
    resolution: float = RES
    origin: tuple = (0.0, 0.0)


@dataclass(frozen=True)
class Tracks:
    position: np.ndarray
    velocity: np.ndarray
    radius: np.ndarray


@dataclass(frozen=True)
class View:
    costmap: Costmap
    tracks: Tracks | None = None


def room(rows=40, cols=100):
    """A walled 10 m × 4 m room (lethal walls)."""
    cost = np.zeros((rows, cols), np.uint8)
    cost[0, :] = cost[-1, :] = cost[:, 0] = cost[:, -1] = 254
    return cost


def box(cost, x0, x1, y0, y1):
    cost = cost.copy()
    cost[int(y0 / RES) : int(y1 / RES), int(x0 / RES) : int(x1 / RES)] = 254
    return cost


def planner(grid, start, goals):
    path = HybridAStar(grid, footprint=(0.5, 0.5), turning_radius=0.0).plan(start, goals[0])
    return path if path.success else None


class Straight:
    """The local law: drive at 0.3 m/s towards the path's last point (enough to see calls)."""

    command_names = ("v", "omega")

    def __init__(self):
        self.paths = []

    def reset(self):
        self.paths = []

    def __call__(self, t, pose, path):
        self.paths.append(path)
        return np.array([0.3, 0.0])


START = np.array([1.0, 2.0, 0.0])
GOAL = np.array([9.0, 2.0, 0.0])


def navigator(**options):
    first = planner(OccupancyGrid(room() >= 254, RES), START, [GOAL])
    local = Straight()
    nav = Navigator(local, planner, FOOTPRINT, NavigatorOptions(**options))
    return nav, local, Route(first, (GOAL,))


def test_a_box_on_the_path_is_planned_around_and_the_old_plan_kept_until_then():
    nav, local, first = navigator(rate_hz=0.0)
    free = View(Costmap(room()))
    nav(0.0, START, first, perception=free)
    assert local.paths[-1] is first.plan and nav.replans == 0
    blocked = View(Costmap(box(room(), 4.0, 4.6, 1.0, 2.6)))  # across the straight line
    nav(0.1, START, first, perception=blocked)
    assert nav.replans == 1
    new = local.paths[-1]
    assert new is not first.plan
    grid = believed_grid(blocked, 0.2)
    assert not grid.in_collision(FOOTPRINT, new.poses).any()
    assert np.max(new.poses[:, 1]) > 2.6  # goes round the box above it


def test_a_closed_corridor_tries_every_recovery_then_ends_blocked():
    nav, _, first = navigator(rate_hz=0.0, max_retries=3, wait_time=0.5)
    wall = View(Costmap(box(room(), 4.0, 4.6, 0.0, 4.0)))  # the room cut in two
    t, pose, modes = 0.0, START.copy(), []
    for _ in range(400):
        command = nav(t, pose, first, perception=wall)
        modes.append(nav.status)
        # integrate the recovery's command (unicycle) so back_up and spin progress
        v, omega = command
        pose = pose + 0.05 * np.array([v * math.cos(pose[2]), v * math.sin(pose[2]), omega])
        t += 0.05
        if nav.status == "blocked":
            break
    assert nav.status == "blocked"
    assert nav.recoveries == 3
    assert "recovering" in modes
    np.testing.assert_array_equal(nav(t, pose, first, perception=wall), [0.0, 0.0])
    # wait, back up, spin happened: the robot moved back and turned
    assert pose[0] < START[0] - 0.1
    assert abs(pose[2]) > 0.5


def test_a_walker_crossing_the_path_does_not_block_the_route():
    nav, local, first = navigator(rate_hz=0.0)
    walker = box(room(), 2.7, 3.3, 1.7, 2.3)  # the walker's cells are marked lethal
    tracks = Tracks(np.array([[3.0, 2.0]]), np.array([[0.0, 0.5]]), np.array([0.3]))
    nav(0.0, START, first, perception=View(Costmap(walker), tracks))
    assert nav.replans == 0 and local.paths[-1] is first.plan
    standing = Tracks(np.array([[3.0, 2.0]]), np.array([[0.0, 0.05]]), np.array([0.3]))
    nav(0.1, START, first, perception=View(Costmap(walker), standing))
    assert nav.replans == 1  # a person standing still is planned around


def test_periodic_replans_are_skipped_while_nothing_changes():
    nav, _, first = navigator(rate_hz=2.0)
    free = View(Costmap(room()))
    for k in range(20):
        nav(0.1 * k, START, first, perception=free)
    assert nav.replans == 1  # the first periodic replan; the belief never changed after it


def test_without_perception_the_navigator_follows_blindly():
    nav, local, first = navigator()
    nav(0.0, START, first)
    nav(0.5, START, first)
    assert nav.replans == 0 and local.paths == [first.plan, first.plan]


def test_bad_options_name_the_key():
    with pytest.raises(ConfigError, match="unknown 'dance'"):
        NavigatorOptions(behaviours=("wait", "dance"))
    with pytest.raises(ConfigError, match="lookahead"):
        NavigatorOptions(lookahead=-1.0)
