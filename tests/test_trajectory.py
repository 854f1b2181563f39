"""Trapezoidal waypoint trajectories and pose trajectories (document 000 §5.2)."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from wheelbase.dynamics import RM100, inverse_dynamics
from wheelbase.errors import ConfigError, InputError
from wheelbase.trajectory import (
    PoseTrajectory,
    feasible_trajectory,
    heading_from_velocity,
    trapezoidal,
)

DOC_WAYPOINTS = [[0, 0], [10, 10], [20, 0], [30, 0]]  # document 000 §5.2 (transposed)


def _cumtrapz(y, t):
    return np.concatenate([[0.0], np.cumsum(0.5 * (y[1:] + y[:-1]) * np.diff(t))])


def test_document_example_timing_and_limits():
    traj = trapezoidal(DOC_WAYPOINTS, (0.1, 0.1), dt=0.05)
    # each segment's longest coordinate moves 10 m: T = 1.5·10/0.1 = 150 s, t_a = 50 s
    np.testing.assert_allclose(traj.waypoint_times, [0, 150, 300, 450])
    np.testing.assert_allclose(np.abs(traj.velocity).max(0), [0.1, 0.1])
    np.testing.assert_allclose(np.abs(traj.acceleration).max(0), [0.002, 0.002])
    at_waypoints = traj.at(traj.waypoint_times)
    np.testing.assert_allclose(at_waypoints.position, DOC_WAYPOINTS, atol=1e-12)
    np.testing.assert_allclose(at_waypoints.velocity, 0.0, atol=1e-12)


def test_velocity_and_acceleration_integrate_to_position():
    traj = trapezoidal(DOC_WAYPOINTS, (0.1, 0.05), acceleration_time=20.0, dt=0.01)
    for k in range(2):
        pos = traj.position[0, k] + _cumtrapz(traj.velocity[:, k], traj.t)
        np.testing.assert_allclose(pos, traj.position[:, k], atol=1e-6)
        vel = _cumtrapz(traj.acceleration[:, k], traj.t)
        np.testing.assert_allclose(vel, traj.velocity[:, k], atol=2e-4)  # steps in acc


def test_acceleration_time_and_peak_acceleration_closed_forms():
    traj = trapezoidal([[0.0], [10.0]], 0.5, acceleration_time=4.0, times=[0, 2, 4, 22, 24])
    assert math.isclose(traj.duration, 10 / 0.5 + 4)
    np.testing.assert_allclose(traj.velocity[:, 0], [0, 0.25, 0.5, 0.25, 0], atol=1e-12)
    np.testing.assert_allclose(traj.position[:, 0], [0, 0.25, 1.0, 9.75, 10], atol=1e-12)
    tri = trapezoidal([[0.0], [1.0]], 10.0, peak_acceleration=1.0)  # never reaches 10 m/s
    assert math.isclose(tri.duration, 2.0)
    assert math.isclose(tri.velocity.max(), 1.0)
    full = trapezoidal([[0.0], [10.0]], 1.0, peak_acceleration=0.5)
    assert math.isclose(full.duration, 10 / 1 + 1 / 0.5)
    np.testing.assert_allclose(np.abs(full.acceleration).max(), 0.5)


def test_per_segment_peak_velocity_and_coordination():
    traj = trapezoidal([[0, 0], [4, 1], [4, 3]], [[1.0, 1.0], [0.5, 0.5]])
    np.testing.assert_allclose(traj.waypoint_times, [0, 6.0, 12.0])
    # coordinated: the path between waypoints is the straight segment
    first = traj.t <= 6.0
    np.testing.assert_allclose(traj.position[first, 1], traj.position[first, 0] / 4, atol=1e-12)


@given(
    st.lists(
        st.tuples(st.integers(-20, 20), st.integers(-20, 20)), min_size=2, max_size=6, unique=True
    ),
    st.floats(0.05, 2.0),
)
@settings(max_examples=40, deadline=None)
def test_feasible_trajectory_properties(points, speed):
    points = np.array(points, dtype=float)
    if np.any(np.all(np.diff(points, axis=0) == 0, axis=1)):
        return
    ref = feasible_trajectory(points, speed, peak_yaw_rate=0.5, dt=0.02)
    np.testing.assert_allclose(ref.poses[-1, :2], points[-1], atol=1e-9)
    np.testing.assert_allclose(ref.twist[:, 1], 0.0, atol=1e-12)  # never slides sideways
    # a drive can follow it: ψ continuous, pose = ∫ J(ψ)·twist
    assert np.max(np.abs(np.diff(np.unwrap(ref.poses[:, 2])))) <= 0.5 * 0.02 + 1e-9
    vel = ref.world_velocity
    for k in range(2):
        pos = points[0, k] + _cumtrapz(vel[:, k], ref.t)
        np.testing.assert_allclose(pos, ref.poses[:, k], atol=1e-3 * max(1, np.abs(points).max()))
    # the translation phases are those of trapezoidal(): same total translation time
    plain = trapezoidal(points, speed)
    turning = np.abs(ref.twist[:, 2]) > 0
    moving = np.abs(ref.twist[:, 0]) > 0
    assert not np.any(turning & moving)
    assert ref.duration >= plain.duration - 1e-9


def test_feasible_turn_profile_and_initial_heading():
    ref = feasible_trajectory([[0, 0], [1, 0]], 0.1, peak_yaw_rate=0.2, initial_heading=math.pi)
    # a 180° turn first (shortest way is ±π: either sign), 1.5·π/0.2 s long, peak 0.2 rad/s
    turn_time = 1.5 * math.pi / 0.2
    assert math.isclose(ref.duration, turn_time + 15.0, rel_tol=1e-12)
    assert math.isclose(np.abs(ref.twist[:, 2]).max(), 0.2, rel_tol=1e-3)
    mid = ref.at([turn_time / 2])
    assert math.isclose(abs(mid.poses[0, 2]), math.pi / 2, rel_tol=1e-9)
    no_turn = feasible_trajectory([[0, 0], [1, 1]], 0.1)
    assert math.isclose(no_turn.poses[0, 2], math.pi / 4)
    assert not np.any(no_turn.twist[:, 2])


def test_heading_from_velocity_uses_atan2_and_jumps_at_stopovers():
    traj = trapezoidal([[0, 0], [-10, 0], [-10, 10]], 0.1, dt=1.0)
    ref = heading_from_velocity(traj)
    first = (traj.t > 0) & (traj.t < 150)
    np.testing.assert_allclose(np.abs(ref.poses[first, 2]), math.pi)  # atan(Δy/Δx) would say 0
    second = traj.t > 150
    np.testing.assert_allclose(ref.poses[second, 2], math.pi / 2)  # a jump of −π/2 at t = 150 s
    np.testing.assert_allclose(ref.twist[:, 1:], 0.0, atol=1e-12)  # no lateral speed, r = 0
    np.testing.assert_allclose(ref.twist[:, 0], np.hypot(*traj.velocity.T), atol=1e-12)
    assert isinstance(ref.at([0.0, 75.0]), PoseTrajectory)


def test_inverse_dynamics_document_example_magnitudes():
    """Figures 5.10–5.11: F_x = m·u̇ on the straight segments, M_z only in the turns."""
    ref = feasible_trajectory(DOC_WAYPOINTS, (0.1, 0.1), dt=0.5)
    inv = inverse_dynamics(RM100, ref)
    straight = (ref.twist[:, 2] == 0) & (ref.twist_rate[:, 2] == 0)
    np.testing.assert_allclose(inv.force[straight, 0], 26.2 * ref.twist_rate[straight, 0])
    np.testing.assert_allclose(inv.force[straight, 2], 0.0, atol=1e-12)
    np.testing.assert_allclose(inv.torques.sum(1), 0.065 * inv.force[:, 0], atol=1e-12)
    peak_fx = 26.2 * 0.002 * math.sqrt(2)  # diagonal segment: |a| = 0.002·√2 m/s²
    assert math.isclose(np.abs(inv.force[:, 0]).max(), peak_fx, rel_tol=1e-9)


@pytest.mark.parametrize(
    ("waypoints", "kwargs", "error", "match"),
    [
        ([[0, 0]], {}, InputError, "at least two"),
        ([[0, 0], [1, 1], [1, 1]], {}, InputError, "repeated consecutive"),
        ([[0, 0], [1, 1]], {"peak_velocity": 0.0}, ConfigError, "peak_velocity"),
        ([[0, 0], [1, 1]], {"peak_velocity": [1, 2, 3]}, ConfigError, "peak_velocity"),
        ([[0, 0], [1, math.nan]], {}, InputError, "finite"),
        (
            [[0, 0], [1, 1]],
            {"acceleration_time": 1.0, "peak_acceleration": 1.0},
            ConfigError,
            "not both",
        ),
        ([[0, 0], [1, 1]], {"acceleration_time": -1.0}, ConfigError, "acceleration_time"),
    ],
)
def test_bad_input(waypoints, kwargs, error, match):
    kwargs = {"peak_velocity": 0.1, **kwargs}
    with pytest.raises(error, match=match):
        trapezoidal(waypoints, **kwargs)


def test_bad_feasible_input():
    with pytest.raises(InputError, match=r"\(P, 2\)"):
        feasible_trajectory([[0, 0, 0], [1, 1, 1]], 0.1)
    with pytest.raises(ConfigError, match="peak_yaw_rate"):
        feasible_trajectory([[0, 0], [1, 1]], 0.1, peak_yaw_rate=0.0)
    with pytest.raises(InputError, match="two-dimensional"):
        heading_from_velocity(trapezoidal([[0.0], [1.0]], 0.1))
