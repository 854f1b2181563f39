"""DWA (Fox, Burgard & Thrun 1997, as Nav2's DWB; issue 22): the dynamic window, exact arcs,
the critics against hand values, the Numba kernel against its NumPy twin, avoidance of a disc
coming head-on and of a box on the path (collisions without the view), the safe stop, arrival,
the oscillation rule, the engine, bad input."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest

from crowd_cases import encounter, inflated_costmap, local_view
from wheelbase.control import DWA, DWACritics
from wheelbase.control.dwa_kernels import (
    arc_poses,
    goal_distance_field,
    profile_poses,
    ramp_profile,
)
from wheelbase.errors import ConfigError, InputError
from wheelbase.models import Bicycle, DiffDrive, Unicycle
from wheelbase.planning import Footprint, OccupancyGrid, PlannedPath
from wheelbase.sim import closed_loop

ROBOT = Footprint.rectangle(0.4, 0.4)
LINE = PlannedPath.from_points([[0.0, 0.0], [8.0, 0.0]])
HEAD_ON = (np.array([[5.0, 0.0]]), np.array([[-0.5, 0.0]]), np.array([0.3]))
BOX = (2.7, -0.3, 3.3, 0.3)


def dwa(**gains):
    return DWA.from_gains(Unicycle(), footprint=ROBOT, **gains)


# --------------------------------------------------------------------------- closed loop
def test_a_disc_coming_head_on_is_avoided_with_tracks_and_hit_without():
    seen = encounter(dwa(), LINE, (0.0, 0.0, 0.0), ROBOT, discs=HEAD_ON, duration=14.0)
    blind = encounter(dwa(), LINE, (0.0, 0.0, 0.0), ROBOT, discs=HEAD_ON, duration=14.0,
                      perceive=False)  # fmt: skip
    assert seen.min_gap > 0.1
    assert blind.min_gap < 0.0
    assert seen.poses[-1, 0] > 3.5 and "all_collide" not in seen.statuses  # past the disc


def test_a_box_marked_in_the_costmap_is_driven_round():
    costmap = inflated_costmap([BOX], (-1.0, -3.0, 8.0, 3.0))
    path = PlannedPath.from_points([[0.0, 0.0], [6.0, 0.0]])
    seen = encounter(dwa(), path, (0.0, 0.0, 0.0), ROBOT, costmap=costmap, boxes=[BOX],
                     duration=25.0)  # fmt: skip
    blind = encounter(dwa(), path, (0.0, 0.0, 0.0), ROBOT, costmap=costmap, boxes=[BOX],
                      duration=25.0, perceive=False)  # fmt: skip
    assert seen.min_gap > 0.0 and seen.statuses[-1] == "arrived"
    assert blind.min_gap < 0.0


def test_it_follows_a_path_through_the_engine_and_arrives():
    path = PlannedPath.from_points([[0.0, 0.0], [2.0, 0.0], [3.0, 1.0]])
    controller = DWA(Unicycle(), max_speed=0.5)
    log = closed_loop(controller, Unicycle(), (0.0, 0.0, 0.0), path, 20.0, 0.05)
    end = log.true_pose[0, -1]
    assert controller.status == "arrived"
    assert math.hypot(end[0] - 3.0, end[1] - 1.0) <= 0.05
    assert abs(math.remainder(end[2] - math.pi / 4, 2 * math.pi)) <= 0.25
    assert float(np.max(path.distance(log.true_pose[0, :, :2]))) < 0.15


# --------------------------------------------------------------------------- the window
def test_the_dynamic_window_is_reachable_within_a_period_and_holds_zero():
    controller = DWA(Unicycle(), max_speed=0.5, max_yaw_rate=1.0, v_samples=7, w_samples=5)
    samples = controller.window_samples(0.1)
    v, w = np.unique(samples[:, 0]), np.unique(samples[:, 1])
    np.testing.assert_allclose([v.min(), v.max()], [0.0, 0.25])  # a = 2.5 m/s², from rest
    np.testing.assert_allclose([w.min(), w.max()], [-0.32, 0.32])  # α = 3.2 rad/s²
    assert 0.0 in w and len(samples) == 35
    controller._velocity = np.array([0.45, 0.9])
    samples = controller.window_samples(0.1)
    np.testing.assert_allclose([samples[:, 0].min(), samples[:, 0].max()], [0.2, 0.5])
    np.testing.assert_allclose([samples[:, 1].min(), samples[:, 1].max()], [0.58, 1.0])


def test_arcs_are_exact_circles():
    samples = np.array([[0.4, 0.8], [0.3, 0.0], [0.5, -1e-6]])
    poses = arc_poses(0.3, samples, 0.1, 20)
    t = 0.1 * np.arange(1, 21)
    r = 0.4 / 0.8
    np.testing.assert_allclose(poses[0, :, 0], r * (np.sin(0.3 + 0.8 * t) - math.sin(0.3)))
    np.testing.assert_allclose(poses[0, :, 1], -r * (np.cos(0.3 + 0.8 * t) - math.cos(0.3)))
    np.testing.assert_allclose(poses[1, :, :2], np.outer(0.3 * t, [math.cos(0.3), math.sin(0.3)]))
    np.testing.assert_allclose(poses[2, -1, :2], [0.5 * 2 * math.cos(0.3), 0.5 * 2 * math.sin(0.3)],
                               atol=1e-6)  # fmt: skip


def test_the_goal_field_goes_round_obstacles():
    cost = np.zeros((10, 10), np.uint8)
    cost[2:8, 5] = 254  # a wall across the middle
    geometry = np.array([0.0, 0.0, 1.0, 1.0, 1.0])
    field, fgeo = goal_distance_field(cost, geometry, np.array([7.5, 4.5]), 100.0)
    assert field[4, 7] == 0.0 and field[4, 5] == -1.0
    # from the other side of the wall: round its nearer end (row 1), not through it (4 cells):
    # 3 rows and 2 columns there (2 diagonal + 1 straight), the same back
    assert field[4, 3] == pytest.approx(4 * math.sqrt(2.0) + 2.0)
    np.testing.assert_array_equal(fgeo, [0.0, 0.0, 1.0, 1.0])


# --------------------------------------------------------------------------- critics, backends
def test_critic_scores_equal_hand_values():
    controller = DWA(Unicycle(), v_samples=3, w_samples=3, sim_time=1.0, sim_dt=0.1)
    controller._velocity = np.array([0.3, 0.0])
    plan = controller.plan((0.0, 0.2, 0.0), LINE, t=0.0)
    straight = np.flatnonzero((plan.samples[:, 1] == 0.0) & np.isclose(plan.samples[:, 0], 0.3))
    scores = plan.scores[straight[0]]
    # its end is (0.3, 0.2) after 1 s; the local goal the window's last point, 2·v_max·sim_time
    # = 1 m along the path from the robot's progress point (0, 0); the forward point 0.1 m on
    assert controller.lookahead == 1.0
    assert scores[0] == pytest.approx(0.2)  # path_dist
    assert scores[1] == pytest.approx(math.hypot(0.7, 0.2))  # goal_dist
    assert scores[2] == pytest.approx(0.2)  # path_align
    assert scores[3] == pytest.approx(math.hypot(0.6, 0.2))  # goal_align
    np.testing.assert_array_equal(scores[4:7], 0.0)  # nothing to see
    weights = controller.critics.vector()
    weights[7] = 0.0  # rotate-to-goal only near the goal
    assert plan.costs[straight[0]] == pytest.approx(scores @ weights)


@pytest.mark.parametrize("generator", ["limited_accel", "standard"])
def test_numba_kernel_equals_its_numpy_twin(generator):
    grid = OccupancyGrid(np.zeros((80, 120), bool), 0.1, (-2.0, -4.0))
    occupied = grid.occupied.copy()
    occupied[50:55, 40:45] = True  # a block 1-1.5 m left of the line
    grid = OccupancyGrid(occupied, 0.1, (-2.0, -4.0))
    costmap = inflated_costmap([BOX], (-1.0, -3.0, 8.0, 3.0))
    view = local_view(np.array([[4.0, 0.8], [1.8, -1.5]]), np.array([[-0.5, 0.0], [0.0, 0.5]]),
                      np.array([0.3, 0.25]), 0.0, costmap=costmap)  # fmt: skip
    plans = {}
    for backend in ("numba", "numpy"):
        controller = DWA(DiffDrive(0.05, 0.2), footprint=ROBOT, grid=grid, backend=backend,
                         trajectory_generator=generator)  # fmt: skip
        controller._velocity = np.array([0.3, 0.2])
        plans[backend] = controller.plan((1.9, -0.1, 0.3), LINE, perception=view, t=0.2)
    np.testing.assert_allclose(plans["numba"].scores, plans["numpy"].scores, rtol=1e-9,
                               atol=1e-12)  # fmt: skip
    np.testing.assert_array_equal(plans["numba"].collided, plans["numpy"].collided)
    np.testing.assert_array_equal(plans["numba"].command, plans["numpy"].command)
    assert plans["numpy"].collided.any() and not plans["numpy"].collided.all()
    assert np.all(plans["numpy"].scores[:, 4:7].max(axis=0) > 0.0)  # every obstacle critic


def test_no_collision_free_command_stops():
    cost = np.full((40, 40), 254, np.uint8)
    view = SimpleNamespace(costmap=SimpleNamespace(cost=cost, resolution=0.05, origin=(-1, -1)),
                           tracks=None, time=0.0)  # fmt: skip
    controller = dwa()
    controller._velocity = np.array([0.4, 0.0])
    command = controller(0.0, (0.0, 0.0, 0.0), LINE, perception=view)
    assert controller.status == "all_collide"
    np.testing.assert_array_equal(command, [0.0, 0.0])
    assert controller.last_plan.collided.all()


def test_rotate_to_goal_turns_in_place_then_arrives():
    path = PlannedPath.from_points([[0.0, 0.0], [1.0, 0.0]])
    controller = DWA(Unicycle(), goal_tolerance=(0.05, 0.1))
    command = controller(0.0, (0.98, 0.0, 1.0), path)  # at the goal, facing 57° off, at rest
    assert command[0] == 0.0 and command[1] < 0.0
    command = controller(0.1, (0.98, 0.0, 0.05), path)
    assert controller.status == "arrived"
    np.testing.assert_array_equal(command, [0.0, 0.0])


def test_oscillation_bars_the_old_sign_until_the_robot_has_moved():
    controller = dwa()
    pose = np.zeros(3)
    controller._debrief(pose, np.array([0.2, 0.5]))
    controller._debrief(pose, np.array([0.2, -0.5]))  # ω flipped: only ω <= 0 now
    samples = np.array([[0.2, 0.3], [0.2, -0.3], [0.2, 0.0]])
    assert controller._oscillating(samples).tolist() == [True, False, False]
    controller._debrief(np.array([0.02, 0.0, 0.0]), np.array([0.2, -0.5]))  # 2 cm: not yet
    assert controller._oscillating(samples)[0]
    controller._debrief(np.array([0.06, 0.0, 0.0]), np.array([0.2, -0.5]))  # 6 cm: reset
    assert not controller._oscillating(samples).any()


# --------------------------------------------------------------------------- bad input
@pytest.mark.parametrize(
    ("gains", "match"),
    [
        ({"max_speed": 0.0}, "max_speed must be > 0"),
        ({"min_speed": 0.2}, r"min_speed must be in \[-max_speed, 0\]"),
        ({"v_samples": 0}, "v_samples must be an integer >= 1"),
        ({"sim_dt": -1.0}, "sim_dt must be > 0"),
        ({"sim_time": 1e6, "sim_dt": 1e-3}, "trajectory steps: more than"),
        ({"sim_dt": 5.9e9, "v_samples": 1.4e96}, r"sim_dt must be <= sim_time"),
        ({"speed": 1.0}, "unknown DWA gain 'speed'"),
        ({"critics": {"nonsense": 1.0}}, "unknown DWA critic 'nonsense'"),
        ({"path_dist": -1.0}, "path_dist must be >= 0"),
        ({"oscillation": "yes"}, "oscillation must be true or false"),
        ({"goal_tolerance": 0.1}, "goal_tolerance must be"),
        ({"backend": "jax"}, "unknown backend"),
    ],
)
def test_bad_gains_name_the_key(gains, match):
    with pytest.raises(ConfigError, match=match):
        dwa(**gains)


def test_steered_models_and_bad_poses_are_refused():
    with pytest.raises(ConfigError, match=r"DWA drives \(v, ω\) robots"):
        DWA(Bicycle(wheel_base=0.3, max_steering=0.5))
    with pytest.raises(InputError, match="one robot"):
        dwa()(0.0, np.zeros((2, 3)), LINE)
    with pytest.raises(InputError, match="pose must be finite"):
        dwa()(0.0, (np.nan, 0.0, 0.0), LINE)


def test_from_gains_and_the_defaults():
    controller = dwa(sim_time=2.0, costmap=10.0, critics={"goal_dist": 1.0})
    assert controller.sim_time == 2.0
    assert controller.critics == DWACritics(costmap=10.0, goal_dist=1.0)
    assert DWA.uses_perception and DWA.per_robot


# --------------------------------------------------------------------------- standard generator
def test_ramps_reach_their_targets_at_the_acceleration_limits():
    # DWB's computeNewVelocity: from (0.2, 0.5) towards (1.0, -1.0) at a_up 2.5, α 3.2
    profile = ramp_profile(np.array([0.2, 0.5]), np.array([[1.0, -1.0]]),
                           np.array([2.5, 1.0, 3.2]), 0.1, 10)  # fmt: skip
    tau = 0.1 * np.arange(1, 11)
    np.testing.assert_allclose(profile[0, :, 0], np.minimum(0.2 + 2.5 * tau, 1.0), atol=1e-15)
    np.testing.assert_allclose(profile[0, :, 1], np.maximum(0.5 - 3.2 * tau, -1.0), atol=1e-15)
    # slowing down uses a_down
    slow = ramp_profile(np.array([1.0, 0.0]), np.array([[0.0, 0.0]]), np.array([2.5, 1.0, 3.2]),
                        0.1, 12)  # fmt: skip
    np.testing.assert_allclose(slow[0, :, 0], np.maximum(1.0 - 0.1 * np.arange(1, 13), 0.0),
                               atol=1e-15)  # fmt: skip


def test_a_held_profile_is_the_closed_form_arc():
    samples = np.array([[0.5, 0.0], [0.8, 1.2], [-0.3, -0.7]])
    held = np.repeat(samples[:, None, :], 20, axis=1)
    np.testing.assert_allclose(profile_poses(0.4, held, 0.05), arc_poses(0.4, samples, 0.05, 20),
                               atol=1e-12)  # fmt: skip


def test_the_standard_window_spans_the_whole_trajectory_and_the_command_keeps_the_limits():
    # from a stop, Fox et al.'s window holds only what one period reaches (0.125 m/s at
    # 2.5 m/s² over 0.05 s); DWB's standard generator samples targets up to top speed, and the
    # robot is sent the ramp's first step towards the chosen one
    limited = DWA(Unicycle(), max_speed=1.0, footprint=ROBOT)
    standard = DWA(Unicycle(), max_speed=1.0, footprint=ROBOT, trajectory_generator="standard")
    assert limited.window_samples()[:, 0].max() == pytest.approx(0.125)
    assert standard.window_samples()[:, 0].max() == pytest.approx(1.0)
    plan = standard.plan((0.0, 0.0, 0.0), LINE, t=0.0)
    assert plan.status == "ok"
    assert 0.0 < plan.command[0] <= 2.5 * 0.05 + 1e-12
    # the fan it draws starts from the velocity the plan started at and ramps
    poses = standard.predict(plan, plan.samples[:3])
    assert poses.shape == (3, standard.steps + 1, 3)
    target = plan.samples[np.argmax(plan.samples[:, 0])]
    ramp = standard.predict(plan, target)
    step = np.hypot(*np.diff(ramp[:, :2], axis=0).T)
    assert step[0] == pytest.approx(2.5 * 0.05 * 0.05, rel=1e-4)  # the chord of v_1·dt
    assert np.all(np.diff(step[:7]) > 0.0)  # speeding up at 2.5 m/s² for 0.4 s
    assert np.all(step <= target[0] * 0.05 + 1e-12)  # never faster than the target


def test_a_standard_dwa_arrives_through_the_engine():
    path = PlannedPath.from_points([[0.0, 0.0], [2.0, 0.0], [3.0, 1.0]])
    controller = DWA(Unicycle(), max_speed=0.5, trajectory_generator="standard")
    log = closed_loop(controller, Unicycle(), (0.0, 0.0, 0.0), path, 20.0, 0.05)
    end = log.true_pose[0, -1]
    assert controller.status == "arrived"
    assert math.hypot(end[0] - 3.0, end[1] - 1.0) <= 0.05
    # the ramped commands keep the acceleration limits between calls
    speed = log.command[0, :, 0]
    assert np.max(np.abs(np.diff(speed))) <= 2.5 * 0.05 + 1e-9


def test_an_unknown_trajectory_generator_is_refused():
    with pytest.raises(ConfigError, match="trajectory_generator"):
        DWA(Unicycle(), trajectory_generator="fast")


def test_when_every_trajectory_collides_with_walkers_it_evades_rather_than_wait_to_be_struck():
    # two walkers converge on the robot from ahead-left, each 0.6 m/s: every trajectory touches
    # one, standing still at step 12; the standard generator's ramp to a right turn at speed
    # stays clear one step longer and is driven (MPPI's rule, obstacle_critics.evasion_choice);
    # the one-period window of limited_accel holds nothing that does (7 steps at best), so it
    # stops
    view = local_view(np.array([[0.9, 0.3], [0.3, 0.9]]), np.array([[-0.6, 0.0], [0.0, -0.6]]),
                      np.array([0.3, 0.3]), 0.0)  # fmt: skip
    statuses = {}
    for generator in ("standard", "limited_accel"):
        controller = dwa(trajectory_generator=generator, max_speed=1.0)
        controller._velocity = np.array([0.5, 0.0])
        plan = controller.plan((0.0, 0.0, 0.0), LINE, perception=view, t=0.0)
        assert plan.collided.all()
        statuses[generator] = plan.status, plan.command
    assert statuses["standard"][0] == "evading"
    assert statuses["standard"][1][0] > 0.0 and statuses["standard"][1][1] < 0.0  # on, right
    assert statuses["limited_accel"][0] == "all_collide"
    # a static obstacle never strikes a stopped robot: inside a lethal region it stops
    inside = np.full((40, 40), 254, np.uint8)
    costmap = SimpleNamespace(cost=inside, resolution=0.05, origin=(-1, -1))
    walled = SimpleNamespace(costmap=costmap, tracks=None, time=0.0)
    plan = dwa(trajectory_generator="standard").plan((0.0, 0.0, 0.0), LINE, perception=walled,
                                                     t=0.0)  # fmt: skip
    assert plan.status == "all_collide"
    np.testing.assert_array_equal(plan.command, [0.0, 0.0])
