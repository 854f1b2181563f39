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
class TrackerTracks(Tracks):
    confirmed: np.ndarray


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


def test_a_tentative_track_does_not_block_the_route_until_it_is_confirmed():
    # a new track (a walker the tracker lost and found again, speed 0 at birth) is not yet an
    # obstacle that stays; confirmed and still standing, it is planned around
    nav, _local, first = navigator(rate_hz=0.0)
    marked = box(room(), 2.7, 3.3, 1.7, 2.3)
    born = TrackerTracks(np.array([[3.0, 2.0]]), np.zeros((1, 2)), np.array([0.3]),
                         np.array([False]))  # fmt: skip
    nav(0.0, START, first, perception=View(Costmap(marked), born))
    assert nav.replans == 0 and nav.status != "recovering"
    assert believed_grid(View(Costmap(marked), born), 0.2).occupied.sum() == (room() > 0).sum()
    confirmed = TrackerTracks(born.position, born.velocity, born.radius, np.array([True]))
    nav(0.1, START, first, perception=View(Costmap(marked), confirmed))
    assert nav.replans == 1


def test_a_replan_clears_the_planners_footprint_around_the_robot():
    # Hybrid A* plans with the footprint grown by its margin and refuses a start inside an
    # obstacle: what is marked within that reach of the robot is cleared before a replan
    from wheelbase.navigation import _cleared

    grid = OccupancyGrid(np.ones((40, 40), bool), RES)
    pose = np.array([2.0, 2.0, 0.0])
    for margin in (0.0, 0.3):
        free = ~_cleared(grid, pose, FOOTPRINT, margin).occupied
        rows, cols = np.nonzero(free)
        centres = np.stack([(cols + 0.5) * RES, (rows + 0.5) * RES], -1)
        reach = np.hypot(*(centres - pose[:2]).T)
        assert reach.max() <= FOOTPRINT.max_radius + margin + RES
        assert reach.max() > FOOTPRINT.max_radius + margin  # the whole disc, not less
    with pytest.raises(ConfigError, match="plan_margin"):
        Navigator(Straight(), planner, FOOTPRINT, plan_margin=-0.1)


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


def corridor_view(*boxes):
    """The bundled corridor_bay map as a costmap, with lethal boxes (x0, x1, y0, y1) marked."""
    from wheelbase.planning.maps import load_map

    grid = load_map("corridor_bay")
    cost = np.where(grid.occupied, 254, 0).astype(np.uint8)
    for x0, x1, y0, y1 in boxes:
        r0, r1 = int(y0 / grid.resolution), int(y1 / grid.resolution)
        c0, c1 = int(x0 / grid.resolution), int(x1 / grid.resolution)
        cost[r0:r1, c0:c1] = 254
    return View(Costmap(cost, grid.resolution, grid.origin)), grid


def drive(nav, route, view, pose, t, seconds, dt=0.05):
    """Integrate the navigator's (v, ω) on a unicycle; the statuses seen on the way."""
    seen = []
    for _ in range(round(seconds / dt)):
        v, omega = nav(t, pose, route, perception=view)
        seen.append(nav.status)
        pose = pose + dt * np.array([v * math.cos(pose[2]), v * math.sin(pose[2]), omega])
        pose[2] = math.remainder(pose[2], 2 * math.pi)
        t += dt
    return pose, t, seen


def test_a_robot_without_the_right_of_way_waits_in_the_passing_bay_then_goes_on():
    from wheelbase.control import PurePursuit

    square = Footprint.rectangle(0.7, 0.7)

    def corridor_planner(grid, start, goals):
        planner = HybridAStar(grid, footprint=(0.8, 0.8), turning_radius=0.0)
        path = planner.plan(start, goals[0])
        return path if path.success else None

    free, grid = corridor_view()
    start, goal = np.array([8.6, 0.8, math.pi]), np.array([1.0, 0.8, math.pi])
    first = corridor_planner(OccupancyGrid(grid.occupied, grid.resolution), start, [goal])
    local = PurePursuit(speed=0.3)
    nav = Navigator(local, corridor_planner, square, NavigatorOptions(rate_hz=0.0))
    other = corridor_view((5.4, 6.1, 0.45, 1.15))[0]  # a stopped robot in the corridor ahead
    pose, t, seen = drive(nav, Route(first, (goal,), priority=1), other, start, 0.0, 20.0)
    assert nav.yields == 1 and seen[-1] == "yielding"
    assert 6.75 < pose[0] < 9.25 and pose[1] > 1.6  # in the bay, out of the corridor
    # the same wait for the robot with the right of way: it recovers, it does not yield
    boss = Navigator(PurePursuit(speed=0.3), corridor_planner, square, NavigatorOptions())
    drive(boss, Route(first, (goal,), priority=0), other, start, 0.0, 3.0)
    assert boss.yields == 0 and boss.recoveries >= 1
    # the other robot has gone by: the way is clear, the yielding robot goes on to its goal
    pose, t, seen = drive(nav, Route(first, (goal,), priority=1), free, pose, t, 40.0)
    assert seen[-1] != "yielding" and nav.yields == 1
    assert math.hypot(*(pose[:2] - goal[:2])) < 0.3


def test_a_refuge_the_planner_cannot_reach_is_not_the_end_of_yielding():
    """The nearest refuge's way in is refused (a turn into a tight bay): the yielding robot
    tries the other heading and the next refuges, and tries again after each recovery."""
    square = Footprint.rectangle(0.7, 0.7)
    refused: list[int] = []
    free, grid = corridor_view()
    other = corridor_view((5.4, 6.1, 0.45, 1.15))[0]  # a stopped robot in the corridor ahead
    start, goal = np.array([8.6, 0.8, math.pi]), np.array([1.0, 0.8, math.pi])

    def stubborn_planner(grid, start, goals):
        # the first ``refused[0]`` requests for a refuge fail; plans to the goal are found
        to_refuge = math.hypot(*(np.asarray(goals[0])[:2] - goal[:2])) > 1e-9
        if to_refuge and refused and refused[0] > 0:
            refused[0] -= 1
            return None
        path = HybridAStar(grid, footprint=(0.8, 0.8), turning_radius=0.0).plan(start, goals[0])
        return path if path.success else None

    first = stubborn_planner(OccupancyGrid(grid.occupied, grid.resolution), start, [goal])
    route = Route(first, (goal,), priority=1)
    nav = Navigator(Straight(), stubborn_planner, square, NavigatorOptions(rate_hz=0.0))
    nav(0.0, start, route, perception=free)  # the route is known from the first call
    refuges = nav._refuges(start, believed_grid(other, 0.1))
    assert len(refuges) == 3
    apart = [math.hypot(*(a - b)) for i, a in enumerate(refuges) for b in refuges[:i]]
    assert min(apart) >= 2 * square.max_radius - 1e-12
    assert all(nav._aside(np.array(refuges), 0.15))
    # one refused request: the other heading of the same refuge is taken at once
    refused[:] = [1]
    drive(nav, route, other, start, 0.0, 0.5)
    assert nav.yields == 1 and nav.recoveries == 0
    assert nav.yielding.refuge[:2] == pytest.approx(refuges[0])
    assert abs(math.remainder(nav.yielding.refuge[2] - start[2] - math.pi, 2 * math.pi)) < 1e-9
    # every refuge refused at first (six requests): a recovery, then the yield after it
    nav = Navigator(Straight(), stubborn_planner, square, NavigatorOptions(rate_hz=0.0))
    refused[:] = [6]
    drive(nav, route, other, start, 0.0, 6.0)
    assert nav.recoveries == 1 and nav.yields == 1


class Stalled(Straight):
    """A local law that never moves the robot (a way aside it cannot follow)."""

    def __call__(self, t, pose, path):
        super().__call__(t, pose, path)
        return np.zeros(2)


def test_a_yielding_robot_that_makes_no_headway_plans_its_way_aside_again():
    """Nav2's progress checker on the way aside: without 0.5 m of headway in 10 s the way is
    planned again from where the robot stands (each time a new yield), and the yield's time
    still counts from the first; standing still, it then recovers at yield_time."""
    from wheelbase.navigation import YIELD_PROGRESS_TIME

    def corridor_planner(grid, start, goals):
        path = HybridAStar(grid, footprint=(0.8, 0.8), turning_radius=0.0).plan(start, goals[0])
        return path if path.success else None

    square = Footprint.rectangle(0.7, 0.7)
    grid = corridor_view()[1]
    other = corridor_view((5.4, 6.1, 0.45, 1.15))[0]  # a stopped robot in the corridor ahead
    start, goal = np.array([8.6, 0.8, math.pi]), np.array([1.0, 0.8, math.pi])
    first = corridor_planner(OccupancyGrid(grid.occupied, grid.resolution), start, [goal])
    options = NavigatorOptions(rate_hz=0.0, yield_time=25.0)
    nav = Navigator(Stalled(), corridor_planner, square, options)
    route = Route(first, (goal,), priority=1)
    drive(nav, route, other, start, 0.0, 1.0)
    assert nav.yields == 1 and nav.yielding is not None
    began = nav.yielding.started
    drive(nav, route, other, start, 1.0, YIELD_PROGRESS_TIME + 0.5)
    assert nav.yields == 2 and nav.yielding.started == began and nav.recoveries == 0
    drive(nav, route, other, start, YIELD_PROGRESS_TIME + 1.5, 15.0)  # past yield_time
    assert nav.recoveries >= 1


def test_a_robot_that_stopped_against_a_box_is_not_blocked_by_it_when_the_way_is_open():
    """A robot that stopped with its side on a box's corner marks (the lidar's cells reach a
    few cm past the box) and a plan that leaves the box behind: the plan starts on the grid cleared
    around the robot, and the blocked check judges it on that grid, not on the marks the
    robot stands on (it found every plan blocked and spent its recoveries). A box across the
    plan farther ahead still blocks it."""
    nav, _, first = navigator(rate_hz=0.0)
    pose = np.array([3.0, 2.0, 0.0])
    beside = OccupancyGrid(box(room(), 2.9, 3.2, 2.1, 2.6) >= 254, RES)  # under its side
    assert nav._hits(beside, pose[None])[0]  # the robot stands on the marks
    assert not nav._blocked(pose, beside, first.plan)
    across = OccupancyGrid(box(box(room(), 2.9, 3.2, 2.1, 2.6), 4.2, 4.6, 1.5, 2.5) >= 254, RES)
    assert nav._blocked(pose, across, first.plan)


def test_the_blocked_check_skips_only_poses_that_cannot_touch_an_obstacle():
    """The footprint check samples only the poses near an occupied cell or the edge: the
    same answer as sampling every pose, on random grids from nearly empty to cluttered."""
    from wheelbase.navigation import _footprint_hits, _footprint_samples, _sampled_hits

    rng = np.random.default_rng(7)
    samples = _footprint_samples(Footprint.rectangle(0.4, 0.6), 0.05)
    hits = 0
    for density in (0.0, 0.0005, 0.003, 0.02, 0.2) * 30:
        grid = OccupancyGrid(rng.random((80, 120)) < density, 0.05, tuple(rng.uniform(-1, 1, 2)))
        start = rng.uniform([-1.5, -1.5], [7.5, 5.5])
        steps = rng.normal(0.0, 0.05, (60, 2))
        poses = np.column_stack([start + np.cumsum(steps, axis=0), rng.uniform(-3.2, 3.2, 60)])
        expected = _sampled_hits(grid, samples, poses)
        np.testing.assert_array_equal(_footprint_hits(grid, samples, poses), expected)
        hits += int(expected.sum())
    assert 0 < hits < 150 * 60  # both answers occur


def test_a_spin_recovery_stops_before_a_corner_swings_into_a_box():
    # only spins; a box against the square footprint's front edge: the robot stands clear of
    # it, but 5 degrees of turn put a corner into it, so the spin must not start (as the back-up
    # does not reverse into what is behind); without the box it turns (the test above)
    nav, _, first = navigator(rate_hz=0.0, max_retries=1, behaviours=("spin",))
    wall = box(room(), 4.0, 4.6, 0.0, 4.0)  # the room cut in two: no plan, so it recovers
    ahead = View(Costmap(box(wall, 1.25, 1.55, 1.6, 2.4)))
    grid = believed_grid(ahead, 0.2)
    assert not grid.in_collision(FOOTPRINT, START[None]).any()
    assert grid.in_collision(FOOTPRINT, np.array([[1.0, 2.0, math.radians(5.0)]])).any()
    t, pose, poses = 0.0, START.copy(), []
    for _ in range(200):
        command = nav(t, pose, first, perception=ahead)
        pose = pose + 0.05 * np.array([0.0, 0.0, command[1]])
        poses.append(pose)
        t += 0.05
        if nav.status == "blocked":
            break
    assert nav.status == "blocked" and nav.recoveries == 1
    # never turned into the box (a square turned by 90 degrees is clear again: every pose)
    assert not grid.in_collision(FOOTPRINT, np.array(poses)).any()


def test_the_believed_grid_clears_passing_tracks_then_marks_standing_ones_cell_by_cell():
    # the compiled painter against the rule written out: a cell changes when its centre lies
    # within radius + one cell of a track; passing (fast or tentative) tracks clear, then the
    # standing confirmed ones mark (a standing disc wins where the two overlap)
    rng = np.random.default_rng(7)
    cost = np.where(rng.random((50, 60)) < 0.2, 254, 0).astype(np.uint8)
    origin = (-1.3, 0.7)
    position = np.column_stack([rng.uniform(-2.0, 5.5, 12), rng.uniform(0.0, 6.0, 12)])
    velocity = np.zeros((12, 2))
    velocity[:5, 0] = 1.0  # passing: faster than moving_speed
    confirmed = np.ones(12, bool)
    confirmed[5:7] = False  # passing: tentative
    radius = rng.uniform(0.05, 0.6, 12)
    view = View(Costmap(cost, origin=origin), TrackerTracks(position, velocity, radius, confirmed))
    grid = believed_grid(view, 0.2)
    rows, cols = np.mgrid[0:50, 0:60]
    cx, cy = origin[0] + (cols + 0.5) * RES, origin[1] + (rows + 0.5) * RES
    expected = cost >= 254
    for first, last, value in ((0, 7, False), (7, 12, True)):
        for k in range(first, last):
            inside = np.hypot(cx - position[k, 0], cy - position[k, 1]) <= radius[k] + RES
            expected[inside] = value
    np.testing.assert_array_equal(grid.occupied, expected)
