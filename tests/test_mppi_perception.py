"""MPPI with a perception view (issue 22): the costmap critic against a hand computation, the
dynamic-obstacle critic's time indexing and prediction, avoidance of a disc coming head-on and of
a box on the path (and the collisions without the view), the NumPy and Numba backends equal on
the same noise, the safe stop, bad views."""

from __future__ import annotations

import math
from dataclasses import replace
from types import SimpleNamespace

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from crowd_cases import encounter, inflated_costmap, local_view
from wheelbase.control import MPPI, VelocityLimits
from wheelbase.control.footprint_field import footprint_disks
from wheelbase.control.obstacle_critics import (
    PerceptionInputs,
    certainty,
    costmap_check,
    costmap_costs,
    evasion_choice,
    near_lethal,
    predict_tracks,
    struck_step,
    track_costs,
)
from wheelbase.errors import ConfigError, InputError
from wheelbase.models import DiffDrive, Unicycle
from wheelbase.planning import Footprint, PlannedPath

LIMITS = VelocityLimits(max_speed=0.5, max_yaw_rate=1.5)
ROBOT = Footprint.rectangle(0.4, 0.4)
LINE = PlannedPath.from_points([[0.0, 0.0], [8.0, 0.0]])
HEAD_ON = (np.array([[5.0, 0.0]]), np.array([[-0.5, 0.0]]), np.array([0.3]))
BOX = (2.7, -0.3, 3.3, 0.3)
NO_PATH_CRITICS = {"path": 0.0, "path_align": 0.0, "follow": 0.0, "goal": 0.0,
                   "goal_heading": 0.0, "prefer_forward": 0.0, "effort": 0.0, "rate": 0.0,
                   "obstacle": 0.0, "dynamic_obstacle": 0.0}  # fmt: skip


def mppi(seed=0, **gains):
    gains.setdefault("samples", 500)
    return MPPI.from_gains(Unicycle(), footprint=ROBOT, seed=seed, **gains)


# --------------------------------------------------------------------------- closed loop
@pytest.mark.parametrize("seed", [0, 1])
def test_a_disc_coming_head_on_is_avoided_with_tracks_and_hit_without(seed):
    seen = encounter(mppi(seed), LINE, (0.0, 0.0, 0.0), ROBOT, discs=HEAD_ON, duration=14.0)
    blind = encounter(mppi(seed), LINE, (0.0, 0.0, 0.0), ROBOT, discs=HEAD_ON, duration=14.0,
                      perceive=False)  # fmt: skip
    assert seen.min_gap > 0.1  # passed with a margin
    assert blind.min_gap < 0.0  # the same robot without its view drives into it
    # and it went on along the path (measured 4.85 / 4.95 m of 7: it waits about 3 s before it
    # swerves, since standing still is not yet in the disc's predicted way 7.8 s ahead)
    assert seen.poses[-1, 0] > 4.5


def test_a_box_marked_in_the_costmap_is_passed():
    costmap = inflated_costmap([BOX], (-1.0, -3.0, 8.0, 3.0))
    path = PlannedPath.from_points([[0.0, 0.0], [6.0, 0.0]])
    seen = encounter(mppi(), path, (0.0, 0.0, 0.0), ROBOT, costmap=costmap, boxes=[BOX],
                     duration=25.0)  # fmt: skip
    blind = encounter(mppi(), path, (0.0, 0.0, 0.0), ROBOT, costmap=costmap, boxes=[BOX],
                      duration=25.0, perceive=False)  # fmt: skip
    assert seen.min_gap > 0.0 and seen.statuses[-1] == "arrived"
    assert blind.min_gap < 0.0


# --------------------------------------------------------------------------- costmap critic
def tiny_costmap():
    """5 × 6 cells of 0.5 m, origin (-1, -1): row 0 is the lowest y."""
    cost = np.array(
        [
            [0, 10, 20, 30, 40, 50],
            [60, 70, 80, 90, 100, 110],
            [120, 130, 140, 150, 160, 170],
            [180, 190, 200, 210, 220, 230],
            [240, 250, 252, 255, 0, 0],
        ],
        dtype=np.uint8,
    )
    return SimpleNamespace(cost=cost, resolution=0.5, origin=(-1.0, -1.0))


def test_costmap_critic_equals_a_hand_computation():
    costmap = tiny_costmap()
    controller = MPPI(Unicycle(), 6, 0.5, 4, (0.2, 0.3), 1.0, NO_PATH_CRITICS | {"costmap": 2.0},
                      LIMITS, savgol_window=0)  # fmt: skip
    noise = np.random.default_rng(3).standard_normal((4, 6, 2)) * (0.2, 0.3)
    plan = controller.plan((0.1, 0.2, 0.3), LINE, noise, perception=SimpleNamespace(
        costmap=costmap, tracks=None, time=0.0))  # fmt: skip
    poses = controller.predict(plan, plan.samples)[:, 1:]  # after each step, world frame
    expected = np.zeros(4)
    for i in range(4):
        for x, y, _ in poses[i]:
            col, row = math.floor((x + 1.0) / 0.5), math.floor((y + 1.0) / 0.5)
            inside = 0 <= row < 5 and 0 <= col < 6
            value = int(costmap.cost[row, col]) if inside else 0
            expected[i] += (1.0 if value > 252 else value / 252.0) if inside else 0.0
    np.testing.assert_allclose(plan.costs, 2.0 * expected / 6, rtol=1e-9)
    assert expected.min() > 0.0  # the rollouts do cross costed cells


def test_an_outline_over_a_lethal_cell_collides_though_its_centre_is_free():
    cost = np.zeros((20, 20), np.uint8)
    cost[10, 14] = 254  # x in [0.7, 0.75), y in [0.5, 0.55)
    geometry = np.array([0.0, 0.0, 0.05, 1.0, 1.0])
    inputs = PerceptionInputs(ROBOT, footprint_disks(ROBOT, outline=False), 0.5, 1.0, 0.03)
    near = inputs._near(cost, 0.05)
    # the robot's front edge (x + 0.2) over the cell, then 2 cm short of it, then rotated 45°
    poses = np.array([[0.52, 0.52, 0.0], [0.48, 0.52, 0.0], [0.52, 0.52, math.pi / 4]])
    soft, hit = costmap_check(poses, cost, near, geometry, inputs.polygon)
    assert hit.tolist() == [True, False, False]
    np.testing.assert_array_equal(soft, 0.0)  # the centres are on free cells
    twin = costmap_costs(poses, cost, near, geometry, inputs.polygon)
    np.testing.assert_array_equal(twin[1], hit)


@settings(max_examples=25, deadline=None)
@given(st.integers(0, 2**32 - 1))
def test_costmap_numpy_twin_equals_the_compiled_one(seed):
    rng = np.random.default_rng(seed)
    cost = rng.choice(np.array([0, 30, 120, 252, 253, 254, 255], np.uint8), (30, 40),
                      p=[0.5, 0.1, 0.1, 0.1, 0.05, 0.1, 0.05])  # fmt: skip
    geometry = np.array([-1.0, -0.5, 0.05, 1.0, float(rng.integers(2))])
    inputs = PerceptionInputs(ROBOT, footprint_disks(ROBOT, outline=False), 0.5, 1.0, 0.03)
    near = inputs._near(cost, 0.05)
    poses = np.column_stack([rng.uniform(-1.5, 1.5, 300), rng.uniform(-1.0, 1.5, 300),
                             rng.uniform(-math.pi, math.pi, 300)])  # fmt: skip
    compiled = costmap_check(poses, cost, near, geometry, inputs.polygon)
    vectorised = costmap_costs(poses, cost, near, geometry, inputs.polygon)
    np.testing.assert_array_equal(compiled[1], vectorised[1])
    np.testing.assert_allclose(compiled[0], vectorised[0], rtol=1e-15)


@settings(max_examples=60, deadline=None)
@given(st.integers(0, 2**32 - 1), st.integers(1, 50), st.integers(1, 50),
       st.sampled_from([0.025, 0.05, 0.1]), st.floats(0.0, 0.6))  # fmt: skip
def test_the_outline_gate_is_the_thresholded_distance_transform(seed, rows, cols, res, radius):
    from scipy.ndimage import distance_transform_edt

    rng = np.random.default_rng(seed)
    cost = np.where(rng.random((rows, cols)) < rng.uniform(0.0, 0.4), 254, 0).astype(np.uint8)
    if seed % 2:  # a solid wall band: interior lethal cells paint nothing
        start = int(rng.integers(rows))
        cost[start : start + int(rng.integers(1, 8))] = 254
    limit = radius + math.sqrt(2.0) * res
    lethal = cost == 254
    expected = np.zeros(cost.shape, bool)
    if lethal.any():
        expected = distance_transform_edt(~lethal) * res <= limit
    near = np.zeros(cost.shape, np.uint8)
    near_lethal(cost, res, limit, near)
    np.testing.assert_array_equal(near.astype(bool), expected)


# --------------------------------------------------------------------------- dynamic critic
def straight_rollout(speed=0.5, dt=0.1, steps=60):
    t = dt * np.arange(1, steps + 1)
    return np.stack([speed * t, np.zeros_like(t), np.zeros_like(t)], -1)[None], t


def test_the_cost_at_step_k_uses_the_prediction_at_step_k():
    poses, t = straight_rollout()
    point = np.zeros((1, 3))
    inputs = PerceptionInputs(None, point, 0.5, 0.0, 0.0, hold_time=0.0)
    # A crosses the robot's line at x = 2 at t = 2 s, when the robot is at x = 1: no contact,
    # though its swept path crosses the rollout's (a static check would call it a collision).
    early = inputs.arrays(local_view(np.array([[2.0, -2.0]]), np.array([[0.0, 1.0]]),
                                     np.array([0.3]), 0.0), np.zeros(3), 0.0, t, 0.5)  # fmt: skip
    _soft, hit = track_costs(poses, early.table, early.relief, early.disks, 0.5)
    assert not hit.any()
    swept = np.hypot(poses[0, :, 0, None] - 2.0, poses[0, :, 1, None] - np.linspace(-2, 2, 50))
    assert swept.min() < 0.3  # the static view of its path does cross the rollout
    # B reaches (2, 0) at t = 4 s, as the robot does: contact exactly while |Δp(t)| <= 0.3.
    late = inputs.arrays(local_view(np.array([[2.0, -1.0]]), np.array([[0.0, 0.25]]),
                                    np.array([0.3]), 0.0), np.zeros(3), 0.0, t, 0.5)  # fmt: skip
    _soft, hit = track_costs(poses, late.table, late.relief, late.disks, 0.5)
    gap = np.hypot(0.5 * t - 2.0, -1.0 + 0.25 * t)
    np.testing.assert_array_equal(hit[0], gap <= 0.3)
    assert hit[0].any() and not hit[0, : np.argmax(gap <= 0.3)].any()


def test_a_vague_prediction_costs_its_certainty_times_a_sure_one():
    # one pose 0.4 m from a track's mean, the track sure (σ = 0) or vague (κσ = 0.5 ... 3 m)
    disks = np.array([[0.0, 0.0, 0.2]])
    pose = np.zeros((1, 1, 3))
    rho = 0.2 + 0.3 + 0.5  # footprint reach + track radius + r_dyn
    costs = []
    for spread in (0.0, 0.5, 1.0, 3.0):
        table = np.array([[[0.4 + 0.5, 0.0, 0.3, spread]]])  # centre 0.9 m: gap 0.4 m
        soft, _hit = track_costs(pose, table, np.zeros(1), disks, 0.5)
        zone = 0.5 + spread
        gap = 0.5 * (zone - 0.4) / zone
        sure = 1.0 if spread == 0.0 else 1.0 - math.exp(-0.5 * (rho / spread) ** 2)
        assert soft[0, 0] == pytest.approx(sure * gap * gap, rel=1e-12)
        assert certainty(rho, spread) == pytest.approx(sure, rel=1e-12)
        costs.append(soft[0, 0])
    # past κσ ~ ρ a vaguer prediction costs less (the widened zone alone: 0.09, 0.14, 0.20)
    assert costs[1] > costs[2] > costs[3] and costs[3] < 0.012


def test_the_view_time_shifts_the_prediction():
    _, t = straight_rollout(steps=10)
    inputs = PerceptionInputs(None, np.zeros((1, 3)), 0.5, 0.0, 0.0, hold_time=0.0)
    view = local_view(np.array([[2.0, 0.3]]), np.array([[-1.0, 0.0]]), np.array([0.3]), 1.0)
    arrays = inputs.arrays(view, np.array([0.5, 0.0, 0.0]), 1.5, t, 0.5)  # 0.5 s stale
    # relative to the robot at x = 0.5: the track at 2 - (0.5 + τ) with τ the step time
    np.testing.assert_allclose(arrays.table[:, 0, 0], 2.0 - (0.5 + t) - 0.5, atol=1e-12)


def test_prediction_covariance_is_the_constant_velocity_propagation():
    rng = np.random.default_rng(2)
    a = rng.standard_normal((3, 4, 4))
    covariance = a @ np.swapaxes(a, 1, 2) * 0.1
    times, q = np.array([0.0, 0.7, 2.5]), 0.03
    _mean, sigma = predict_tracks(rng.standard_normal((3, 2)), rng.standard_normal((3, 2)),
                                 covariance, times, q)  # fmt: skip
    for k, tau in enumerate(times):
        transition = np.block([[np.eye(2), tau * np.eye(2)], [np.zeros((2, 2)), np.eye(2)]])
        noise = q * np.block([[tau**3 / 3 * np.eye(2), tau**2 / 2 * np.eye(2)],
                              [tau**2 / 2 * np.eye(2), tau * np.eye(2)]])  # fmt: skip
        for j in range(3):
            full = transition @ covariance[j] @ transition.T + noise
            assert sigma[k, j] == pytest.approx(math.sqrt(np.linalg.eigvalsh(full[:2, :2])[-1]))


def test_unconfirmed_tracks_are_ignored_and_far_ones_dropped():
    _, t = straight_rollout(steps=10)
    inputs = PerceptionInputs(None, np.zeros((1, 3)), 0.5, 1.0, 0.03)
    tracks = SimpleNamespace(
        position=np.array([[1.0, 0.0], [1.0, 0.5], [40.0, 0.0]]),
        velocity=np.zeros((3, 2)),
        covariance=None,
        radius=np.full(3, 0.3),
        confirmed=np.array([True, False, True]),
    )
    arrays = inputs.arrays(SimpleNamespace(costmap=None, tracks=tracks, time=0.0), np.zeros(3),
                           0.0, t, 0.5)  # fmt: skip
    assert arrays.table.shape[1] == 1
    np.testing.assert_allclose(arrays.table[0, 0, :2], [1.0, 0.0])


# --------------------------------------------------------------------------- backends, stop
@pytest.mark.parametrize("model", [Unicycle(), DiffDrive(0.05, 0.2)], ids=["unicycle", "diff"])
def test_numpy_and_numba_agree_on_the_same_noise_with_a_view(model):
    costmap = inflated_costmap([BOX], (-1.0, -3.0, 8.0, 3.0))
    view = local_view(np.array([[3.5, 0.4], [1.5, -1.2]]), np.array([[-0.5, 0.0], [0.0, 0.6]]),
                      np.array([0.3, 0.25]), 0.0, costmap=costmap)  # fmt: skip
    controllers = {
        name: MPPI(
            model, 24, 0.05, 128, (0.2, 0.4), 0.05, None, LIMITS, backend=name, footprint=ROBOT
        )
        for name in ("numpy", "numba")
    }
    rng = np.random.default_rng(7)
    for k in range(3):
        noise = rng.standard_normal((128, 24, 2)) * (0.2, 0.4)
        plans = {name: c.plan((1.6 + 0.1 * k, 0.05, 0.1), LINE, noise, perception=view, t=0.1 * k)
                 for name, c in controllers.items()}  # fmt: skip
        np.testing.assert_allclose(plans["numba"].costs, plans["numpy"].costs, rtol=1e-9,
                                   atol=1e-9)  # fmt: skip
        np.testing.assert_allclose(plans["numba"].command, plans["numpy"].command, atol=1e-9)
        assert (plans["numpy"].costs >= 1e6).any()  # the view does make some rollouts lethal


def test_the_kernels_first_contacts_are_those_of_its_rollouts():
    # the evasion reads each sample's first colliding step from the cost kernel; it must be the
    # step the vectorised check finds on the same commands
    from wheelbase.control.mppi_numpy import contact_steps, numpy_costs

    costmap = inflated_costmap([BOX], (-1.0, -3.0, 8.0, 3.0))
    view = local_view(np.array([[2.5, 0.4], [1.5, -0.6]]), np.array([[-0.5, 0.0], [0.0, 0.6]]),
                      np.array([0.3, 0.25]), 0.0, costmap=costmap)  # fmt: skip
    controller = MPPI(Unicycle(), 24, 0.05, 256, (0.4, 0.8), 0.05, None, LIMITS,
                      footprint=ROBOT)  # fmt: skip
    pose = np.array([1.0, 0.05, 0.1])
    local = np.array([0.0, 0.0, pose[2]])
    local_map = controller._field.geometry.copy()
    local_map[:2] -= pose[:2]
    seen = controller._perception.arrays(view, pose, 0.0, controller._step_times, 0.5)
    window, info = controller._path.window(pose, controller._path.tables(LINE))
    info[6] = controller._field.relief(pose, local_map)
    weights = controller.critics.vector()
    hi = controller._hi
    args = (local, controller._mean, controller._lo, hi, hi, window, info, controller._last,
            weights)  # fmt: skip
    _costs, controls, first = controller._costs_numba(args, None, local_map, seen, 256)
    expected = contact_steps(controller, local, controls, info, local_map, seen)
    assert 0 < np.count_nonzero(first < 24) < 256  # some collide, some stay clear
    np.testing.assert_array_equal(first, expected)
    noise = controls - controller._mean[None]
    _costs, _controls, numpy_first = numpy_costs(controller, *args, noise, local_map, seen)
    np.testing.assert_array_equal(numpy_first, expected)
    # the guard's and the evasion's check of given sequences: the kernel fed them as the
    # perturbations of a zero mean finds the same steps
    np.testing.assert_array_equal(
        controller._first_contacts(args, controls, local_map, seen), expected
    )


def test_held_samples_keep_their_first_perturbation():
    controller = MPPI(Unicycle(), 20, 0.05, 50, (0.2, 0.4), 0.05, None, LIMITS, footprint=ROBOT,
                      held_noise_fraction=0.2, allow_reverse=False)  # fmt: skip
    view = local_view(None, None, None, 0.0)
    plan = controller.plan((0.0, 0.0, 0.0), LINE, perception=view)
    held, free = plan.samples[40:], plan.samples[:40]
    np.testing.assert_array_equal(held, np.broadcast_to(held[:, :1], held.shape))
    assert np.ptp(free[:, :, 1], axis=1).min() > 0.0
    # and without a view nothing is held
    plan = MPPI(Unicycle(), 20, 0.05, 50, (0.2, 0.4), 0.05, None, LIMITS).plan((0, 0, 0), LINE)
    assert np.ptp(plan.samples[40:, :, 1], axis=1).min() > 0.0


def test_a_robot_inside_a_lethal_region_stops():
    cost = np.full((40, 40), 254, np.uint8)
    view = SimpleNamespace(costmap=SimpleNamespace(cost=cost, resolution=0.05, origin=(-1, -1)),
                           tracks=None, time=0.0)  # fmt: skip
    controller = mppi()
    command = controller(0.0, (0.0, 0.0, 0.0), LINE, perception=view)
    assert controller.status == "all_collide"
    np.testing.assert_array_equal(command, [0.0, 0.0])


def test_when_every_rollout_collides_with_walkers_it_evades_rather_than_wait_to_be_struck():
    # two walkers converge on the robot from ahead and the left, fast: every rollout of the
    # horizon touches one, but standing still is struck soonest; a stop would be a contact
    view = local_view(np.array([[1.2, 0.0], [0.0, 1.2]]), np.array([[-1.0, 0.0], [0.0, -1.0]]),
                      np.array([0.3, 0.3]), 0.0)  # fmt: skip
    controller = mppi(reverse_against_path=True)
    plan = controller.plan((0.0, 0.0, 0.0), LINE, perception=view, t=0.0)
    assert plan.status == "evading"
    assert np.hypot(*plan.command) > 0.0
    # it drives the sample that stays clear longest, longer than standing still does
    from wheelbase.control.mppi_numpy import contact_steps

    local = np.zeros(3)
    seen = controller._perception.arrays(view, local, 0.0, controller._step_times, 0.5)
    _window, info = controller._path.window(local, controller._path.tables(LINE))
    stop = np.zeros((1, controller.horizon_steps, 2))
    both = np.concatenate([stop, plan.controls[None]])
    first = contact_steps(controller, local, both, info, controller._field.geometry, seen)
    assert first[1] > first[0]
    # a static obstacle never strikes a stopped robot: inside a lethal region it still stops
    # (test_a_robot_inside_a_lethal_region_stops)


def test_a_mean_that_runs_into_a_walker_its_samples_avoid_is_not_driven():
    # half the samples swerve left of a walker standing on the path, half right, at equal
    # cost: their weighted mean drives straight into it. The guard drives the cheapest sample.
    from wheelbase.control.mppi_numpy import contact_steps

    view = local_view(np.array([[0.9, 0.0]]), np.zeros((1, 2)), np.array([0.3]), 0.0)
    controller = MPPI(Unicycle(), 24, 0.05, 2, (0.2, 0.4), 0.05, None, LIMITS, backend="numpy",
                      footprint=ROBOT, savgol_window=0)  # fmt: skip
    noise = np.zeros((2, 24, 2))
    noise[:, :, 0] = 0.4
    noise[0, :, 1], noise[1, :, 1] = 1.5, -1.5
    plan = controller.plan((0.0, 0.0, 0.0), LINE, noise, perception=view, t=0.0)
    assert plan.costs[0] == pytest.approx(plan.costs[1])  # a mirror pair
    assert plan.costs.max() < controller.critics.collision_cost  # each of them clear
    assert plan.status == "guarded"
    assert abs(plan.command[1]) == pytest.approx(1.5)  # one of the swerves, not their mean
    local = np.zeros(3)
    seen = controller._perception.arrays(view, local, 0.0, controller._step_times, 0.5)
    _window, info = controller._path.window(local, controller._path.tables(LINE))
    straight = np.tile([0.4, 0.0], (1, 24, 1))  # the mean of the pair
    first = contact_steps(controller, local, straight, info, controller._field.geometry, seen)
    assert first[0] < 24


def test_a_track_touching_the_robot_lets_it_back_away():
    # a walker already in contact: only rollouts that get deeper are lethal, so it is not frozen
    view = local_view(np.array([[0.45, 0.0]]), np.zeros((1, 2)), np.array([0.3]), 0.0)
    controller = mppi(reverse_against_path=True)
    controller(0.0, (0.0, 0.0, 0.0), LINE, perception=view)
    assert controller.status == "ok"
    assert float(controller.last_plan.controls[:, 0].mean()) < 0.0  # it backs off


# --------------------------------------------------------------------------- bad input
@pytest.mark.parametrize(
    ("view", "match"),
    [
        (SimpleNamespace(costmap=SimpleNamespace(cost=np.zeros((4, 4)), resolution=0.05,
                                                 origin=(0, 0)), tracks=None, time=0.0),
         "perception.costmap.cost must be a non-empty uint8"),
        (SimpleNamespace(costmap=SimpleNamespace(cost=np.zeros((4, 4), np.uint8),
                                                 resolution=-1.0, origin=(0, 0)),
                         tracks=None, time=0.0), r"resolution must be > 0 m"),
        (SimpleNamespace(costmap=object(), tracks=None, time=0.0), "needs cost, resolution"),
        (SimpleNamespace(costmap=None, tracks=SimpleNamespace(
            position=np.zeros((2, 2)), velocity=np.zeros((3, 2)), radius=np.ones(2)), time=0.0),
         r"velocity must have shape \(2, 2\)"),
        (SimpleNamespace(costmap=None, tracks=SimpleNamespace(
            position=np.zeros((1, 2)), velocity=np.zeros((1, 2)), radius=[-0.1]), time=0.0),
         "radius must be >= 0"),
        (SimpleNamespace(costmap=None, tracks=SimpleNamespace(
            position=[[np.nan, 0.0]], velocity=np.zeros((1, 2)), radius=[0.1]), time=0.0),
         "position must be finite"),
        (SimpleNamespace(costmap=None, tracks=SimpleNamespace(
            position=np.zeros((1, 2)), velocity=np.zeros((1, 2)), radius=[0.1]), time="now"),
         "perception.time must be a finite time"),
    ],
)  # fmt: skip
def test_bad_views_name_what_is_wrong(view, match):
    with pytest.raises(InputError, match=match):
        mppi(samples=16)(0.0, (0.0, 0.0, 0.0), LINE, perception=view)


def test_bad_perception_critics_and_the_jax_backend():
    with pytest.raises(ConfigError, match="dynamic_inflation"):
        mppi(dynamic_inflation=0.0)
    with pytest.raises(ConfigError, match="held_noise_fraction"):
        mppi(held_noise_fraction=1.5)
    pytest.importorskip("jax")
    controller = MPPI(Unicycle(), 10, 0.05, 16, 0.2, 0.1, None, LIMITS, backend="jax")
    with pytest.raises(ConfigError, match="perception is not supported on the jax backend"):
        controller(0.0, (0, 0, 0), LINE, perception=local_view(None, None, None, 0.0))


def test_tracks_out_of_a_rollouts_reach_are_not_tested_and_change_nothing():
    # a walker 3 m ahead cannot be reached in the first steps (v̄·t_k plus the disks, its
    # radius, κσ and r_dyn): the kernel skips it there, and its costs are those of testing
    # every track at every step, to the bit
    from wheelbase.control.obstacle_critics import reachable_tracks

    view = local_view(np.array([[3.0, 0.0], [0.6, 0.3]]), np.array([[-0.5, 0.0], [0.0, 0.0]]),
                      np.array([0.3, 0.3]), 0.0)  # fmt: skip
    controller = MPPI(Unicycle(), 24, 0.05, 256, (0.4, 0.8), 0.05, None, LIMITS,
                      footprint=ROBOT)  # fmt: skip
    local = np.zeros(3)
    seen = controller._perception.arrays(view, local, 0.0, controller._step_times, 0.5)
    assert seen.counts[0] == 1 and seen.order[0, 0] == 1  # only the near walker at first
    assert seen.counts[-1] == 2  # both by the held final pose's checks
    everything = np.full_like(seen.counts, seen.table.shape[1])
    order = np.tile(np.arange(seen.table.shape[1]), (seen.table.shape[0], 1))
    assert not np.array_equal(seen.counts, everything)
    window, info = controller._path.window(local, controller._path.tables(LINE))
    args = (local, controller._mean, controller._lo, controller._hi, controller._hi, window,
            info, controller._last, controller.critics.vector())  # fmt: skip
    geometry = controller._field.geometry
    culled = controller._costs_numba(args, None, geometry, seen, 256)
    full = replace(seen, order=order, counts=everything)
    tested = controller._costs_numba(args, None, geometry, full, 256)
    for a, b in zip(culled, tested, strict=True):
        np.testing.assert_array_equal(a, b)
    # the bound itself: a track just outside v̄·t + reach + radius + κσ + r_dyn is left out
    table = np.zeros((3, 1, 4))
    table[:, 0, 0], table[:, 0, 2] = 1.0, 0.2
    times = np.array([0.1, 0.2])
    disks = np.array([[0.0, 0.0, 0.2]])
    _order, counts = reachable_tracks(table, times, 1.0, disks, 0.45)
    np.testing.assert_array_equal(counts, [0, 1, 1])  # 1 − 0.1 ≥ 0.85, 1 − 0.2 < 0.85


def test_a_walker_that_strikes_a_standing_robot_as_soon_as_any_command_is_evaded():
    """Every command and standing still touch at step 0: a stop is struck, so when the contact
    of standing still is a track's the cheapest command drives; against a wall (no track) the
    stop stays (static obstacles never strike)."""
    disks = np.array([[0.0, 0.0, 0.2]])
    steps = 4
    # a walker (r 0.3 m) 0.49 m ahead, coming at 1 m/s: it touches the standing robot at once
    ahead = 0.49 - 0.05 * np.arange(1, steps + 1)
    table = np.zeros((steps, 1, 4))
    table[:, 0, 0], table[:, 0, 2] = ahead, 0.3
    seen = SimpleNamespace(table=table, relief=np.zeros(1), disks=disks)
    assert struck_step(seen, 0.0, steps) == 0
    away = table + np.array([5.0, 0.0, 0.0, 0.0])  # the walker 5 m further off
    far = SimpleNamespace(table=away, relief=np.zeros(1), disks=disks)
    assert struck_step(far, 0.0, steps) is None
    first, costs = np.zeros(3, np.int64), np.array([5.0, 2.0, 9.0])
    assert evasion_choice(first, 0, costs, 0.05, struck_step(seen, 0.0, steps)) == 1
    assert evasion_choice(first, 0, costs, 0.05, None) is None
    # standing still struck later than every command collides: still a stop
    assert evasion_choice(first, 2, costs, 0.05, 2) is None
