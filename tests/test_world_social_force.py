"""The social force model: forces equal a hand computation of HFV 2000's equations; walkers
pass each other and walls without contact."""

import math

import numpy as np
import pytest

from wheelbase.errors import ConfigError
from wheelbase.planning import OccupancyGrid
from wheelbase.world import AgentGroup, SocialForce, World, social_force_acceleration
from wheelbase.world.social_force import wall_force

# Helbing, Farkas and Vicsek 2000, written out again here
M, TAU, A, B, K, KAPPA = 80.0, 0.5, 2000.0, 0.08, 1.2e5, 2.4e5


def test_parameters_are_hfv_2000():
    sf = SocialForce()
    assert (sf.mass, sf.relaxation_time, sf.strength, sf.range, sf.body, sf.friction) == (
        M, TAU, A, B, K, KAPPA)  # fmt: skip
    assert sf.max_speed_factor == 1.3  # Helbing and Molnár 1995


def test_forces_equal_a_hand_computation_apart_and_in_contact():
    pos = np.array([[0.0, 0.0], [0.5, 0.2], [3.0, -1.0]])
    vel = np.array([[0.6, 0.0], [-0.5, 0.1], [0.0, 0.4]])
    goal = np.array([[10.0, 0.0], [-10.0, 1.0], [3.0, 5.0]])
    radius = np.array([0.3, 0.25, 0.35])
    speed = np.array([0.6, 0.8, 1.0])
    got = social_force_acceleration(SocialForce(), pos, vel, goal, radius, speed)
    for i in range(3):
        e = (goal[i] - pos[i]) / np.linalg.norm(goal[i] - pos[i])
        f = M * (speed[i] * e - vel[i]) / TAU
        for j in range(3):
            if j == i:
                continue
            d = np.linalg.norm(pos[i] - pos[j])
            n = (pos[i] - pos[j]) / d
            t = np.array([-n[1], n[0]])
            g = max(radius[i] + radius[j] - d, 0.0)
            if d - radius[i] - radius[j] <= 1.0:  # the documented cutoff
                f = f + (A * math.exp((radius[i] + radius[j] - d) / B) + K * g) * n
                f = f + KAPPA * g * np.dot(vel[j] - vel[i], t) * t
        np.testing.assert_allclose(got[i], f / M, rtol=1e-12)
    # agents 0 and 1 touch (0.539 m apart, radii 0.55): body and friction forces act
    assert np.linalg.norm(pos[0] - pos[1]) < 0.55


def test_wall_force_equals_a_hand_computation():
    # a wall 0.25 m from an agent of radius 0.3 (in contact), normal +y, moving along it
    v = np.array([0.5, -0.1])
    n = np.array([0.0, 1.0])
    t = np.array([-1.0, 0.0])
    g = 0.05
    expected = ((A * math.exp(g / B) + K * g) * n - KAPPA * g * np.dot(v, t) * t) / M
    got = wall_force(v[0], v[1], 0.3, 0.25, n[0], n[1], A / M, B, K / M, KAPPA / M, 1.0)
    np.testing.assert_allclose(got, expected, rtol=1e-12)
    assert wall_force(0.0, 0.0, 0.3, 1.31, 0.0, 1.0, A / M, B, K / M, KAPPA / M, 1.0) == (0, 0)


@pytest.mark.parametrize("offset", [0.05, 0.2])
def test_two_walkers_head_on_pass_without_contact(offset):
    grid = OccupancyGrid(np.zeros((60, 200), bool), 0.1)  # 20 m × 6 m, open
    groups = [
        AgentGroup(count=1, behaviour="social_force", speed=1.0, region=(1, 2, 3, 4),
                   waypoints=[[19.0, 3.0 + offset], [19.0, 3.0 + offset]]),
        AgentGroup(count=1, behaviour="social_force", speed=1.0, region=(17, 2, 19, 4),
                   waypoints=[[1.0, 3.0], [1.0, 3.0]]),
    ]  # fmt: skip
    world = World(grid, agents=groups)
    state = world.start([0])
    # put them on one line (but for the offset), facing each other
    position = np.array([[[2.0, 3.0 + offset], [18.0, 3.0]]])
    velocity = np.array([[[1.0, 0.0], [-1.0, 0.0]]])
    state = type(state)(position, velocity, state.goal, state.waypoint, state.goal_time,
                        state.seed, state.step)  # fmt: skip
    closest = np.inf
    for _ in range(250):
        state = world.step(state, 0.1)
        p = state.position[0]
        closest = min(closest, np.linalg.norm(p[0] - p[1]))
    assert closest > 0.6  # never in contact (radii 0.3 + 0.3)
    assert state.position[0, 0, 0] > 17.0 and state.position[0, 1, 0] < 3.0  # both passed


def test_walkers_in_a_corridor_keep_off_the_walls():
    occupied = np.zeros((30, 200), bool)
    occupied[[0, -1], :] = True  # a 2.8 m corridor between one-cell walls
    group = AgentGroup(count=8, behaviour="social_force", speed=1.2, region=(0.5, 0.5, 19.5, 2.5))
    world = World(OccupancyGrid(occupied, 0.1), agents=[group])
    state = world.start([4])
    low = np.inf
    for _ in range(300):
        state = world.step(state, 0.1)
        y = state.position[0, :, 1]
        low = min(low, (y - 0.1).min(), (2.9 - y).min())
        assert np.all(np.hypot(*state.velocity[0].T) <= 1.3 * 1.2 + 1e-9)  # v_max
    assert low >= 0.3 - 1e-9


def test_parameters_are_checked():
    with pytest.raises(ConfigError, match="max_substep"):
        SocialForce(max_substep=0.5)
    with pytest.raises(ConfigError, match="relaxation_time"):
        SocialForce(relaxation_time=0.0)
