import numpy as np
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st

from wheelbase import ConfigError, InputError, Unicycle, simulate
from wheelbase.timing import SpeedLimits, time_parametrize


def cusp_path():
    forward = [[x, 0.0, 0.0] for x in np.linspace(0.0, 2.0, 41)]
    backward = [[x, 0.0, 0.0] for x in np.linspace(2.0, 1.0, 21)[1:]]
    turn = [[1.0, 0.0, 1.5]]
    directions = [1] * 41 + [-1] * 20 + [-1]
    return np.array(forward + backward + turn), np.array(directions, dtype=float)


def test_limits_rest_at_ends_and_stop_at_cusp():
    poses, directions = cusp_path()
    limits = SpeedLimits(max_speed=0.5, max_acceleration=0.5, max_yaw_rate=1.0)
    ref = time_parametrize(poses, directions, limits, dt=0.01)
    assert ref.v[0] == 0.0 and ref.v[-1] == 0.0 and ref.omega[-1] == pytest.approx(0.0, abs=1e-9)
    assert np.all(np.abs(ref.v) <= 0.5 + 1e-12)
    assert np.all(np.abs(ref.omega) <= 1.0 + 1e-12)
    assert np.max(np.abs(np.diff(ref.v))) <= 0.5 * 0.01 + 1e-9
    # The robot is at rest when it reaches the cusp at x = 2.
    at_cusp = np.argmax(ref.poses[:, 0])
    assert ref.poses[at_cusp, 0] == pytest.approx(2.0, abs=1e-6)
    assert abs(ref.v[at_cusp]) < 0.5 * 0.01 + 1e-9
    assert ref.v.min() < -0.4  # it reverses
    np.testing.assert_allclose(ref.poses[-1], [1.0, 0.0, 1.5], atol=1e-12)
    # 2 m forward (1 s ramps + 3 s cruise), 1 m back (1 + 1 + 1 s), a 1.5 rad turn (0.5 s
    # ramps at 2 rad/s², 1 s cruise).
    assert ref.t[-1] == pytest.approx(5.0 + 3.0 + 2.0, abs=1e-9)


def test_curvature_slow_down_on_an_arc():
    theta = np.linspace(0.0, np.pi, 400)
    radius = 2.0
    poses = np.column_stack([radius * np.sin(theta), radius * (1 - np.cos(theta)), theta])
    limits = SpeedLimits(max_speed=1.0, max_acceleration=1.0, max_yaw_rate=0.25)
    ref = time_parametrize(poses, limits=limits, dt=0.01)
    assert ref.v.max() == pytest.approx(0.25 * radius, rel=1e-3)
    cruising = ref.v > 0.49
    np.testing.assert_allclose(ref.curvature[cruising], 1 / radius, rtol=1e-3)


@settings(max_examples=20, deadline=None)
@given(st.floats(0.2, 2.0), st.floats(0.2, 2.0), st.floats(-1.0, 1.0))
@example(1.0, 1.0, 2.2250738585e-313)  # subnormal curvature: max_yaw_rate / κ overflowed
def test_integrating_the_reference_reproduces_it(speed, accel, bend):
    s = np.linspace(0.0, 3.0, 301)
    heading = bend * np.sin(s)
    x = np.concatenate([[0.0], np.cumsum(np.cos(heading[:-1]) * np.diff(s))])
    y = np.concatenate([[0.0], np.cumsum(np.sin(heading[:-1]) * np.diff(s))])
    poses = np.column_stack([x, y, heading])
    limits = SpeedLimits(max_speed=speed, max_acceleration=accel, max_yaw_rate=2.0)
    ref = time_parametrize(poses, limits=limits, dt=0.002)
    run = simulate(Unicycle(), ref.poses[0], ref.inputs[:-1], ref.t[-1], 0.002, method="exact")
    # Open-loop replay error is O(dt) from the zero-order hold of a ramping speed.
    assert np.max(np.hypot(*(run.poses[:, :2] - ref.poses[:, :2]).T)) < 0.02


def test_bad_input():
    with pytest.raises(InputError, match="at least 2 samples"):
        time_parametrize([[0, 0, 0]])
    with pytest.raises(InputError, match="does not move"):
        time_parametrize([[0, 0, 0], [0, 0, 0]])
    with pytest.raises(InputError, match=r"\+1 \(forwards\) or -1"):
        time_parametrize([[0, 0, 0], [1, 0, 0]], directions=[1, 0])
    with pytest.raises(ConfigError, match="max_speed must be > 0"):
        SpeedLimits(max_speed=0.0)
    with pytest.raises(ConfigError, match="dt must be > 0"):
        time_parametrize([[0, 0, 0], [1, 0, 0]], dt=-1)


def test_a_path_stretched_past_max_samples_is_refused_not_allocated():
    poses = np.array([[0.0, 0.0, 0.0], [10.0, 0.0, 0.0]])
    slow = SpeedLimits(max_speed=1e-6, max_acceleration=1e-6)
    with pytest.raises(ConfigError, match="more than max_samples = 1000000"):
        time_parametrize(poses, limits=slow, dt=0.05)  # 10 m at 1 µm/s: 2e8 samples
    fine = time_parametrize(poses, limits=SpeedLimits(max_speed=0.5), dt=0.05, max_samples=1000)
    assert fine.t.size <= 1000 and fine.poses[-1, 0] == pytest.approx(10.0)
    with pytest.raises(ConfigError, match="more than max_samples = 100"):
        time_parametrize(poses, limits=SpeedLimits(max_speed=0.5), dt=0.05, max_samples=100)


@pytest.mark.parametrize("samples", [2, 3, 11])
def test_a_sparse_straight_path_gets_the_exact_trapezoid(samples):
    # Two poses (one interval) used to give an infinite time (rest at both ends of the one
    # interval); now the ramps are resolved: 10 m at 0.5 m/s with 0.5 m/s² takes L/v + v/a.
    limits = SpeedLimits(max_speed=0.5, max_acceleration=0.5)
    poses = np.column_stack([np.linspace(0.0, 10.0, samples), np.zeros(samples), np.zeros(samples)])
    trajectory = time_parametrize(poses, limits=limits, dt=0.01)
    assert trajectory.t[-1] == pytest.approx(10.0 / 0.5 + 0.5 / 0.5, rel=2e-3)
    assert trajectory.v.max() == pytest.approx(0.5) and np.all(trajectory.v >= 0.0)
    assert np.allclose(trajectory.poses[[0, -1]], poses[[0, -1]])
    accel = np.diff(trajectory.v) / np.diff(trajectory.t)
    assert np.abs(accel).max() <= 0.5 * (1 + 1e-6)
