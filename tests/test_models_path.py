"""Inverse kinematics of a desired path (document 002 eq. 10) and the pure motions (eq. 9)."""

import numpy as np
import pytest

from wheelbase.errors import ConfigError, InputError
from wheelbase.geometry import wrap_angle
from wheelbase.integrate import simulate
from wheelbase.models.diffdrive import DiffDrive
from wheelbase.models.path import (
    PoseTrajectory,
    pure_motions,
    reference_from_derivatives,
    reference_from_xy,
)
from wheelbase.models.unicycle import Unicycle

R, W = 2.0, 0.5


def circle(t):
    c, s = np.cos(W * t), np.sin(W * t)
    return (R * c, R * s, -R * W * s, R * W * c, -R * W * W * c, -R * W * W * s)


def figure_eight(t):
    """Lemniscate of Gerono x = sin t, y = sin t cos t = sin(2t)/2; never stops."""
    return (
        np.sin(t),
        0.5 * np.sin(2 * t),
        np.cos(t),
        np.cos(2 * t),
        -np.sin(t),
        -2.0 * np.sin(2 * t),
    )


def test_circle_from_derivatives_is_exact():
    t = np.linspace(0.0, 20.0, 101)
    ref = reference_from_derivatives(*circle(t), t=t)
    assert isinstance(ref, PoseTrajectory)
    np.testing.assert_allclose(ref.v, R * W, rtol=1e-14)
    np.testing.assert_allclose(ref.omega, W, rtol=1e-14)
    np.testing.assert_allclose(ref.curvature, 1.0 / R, rtol=1e-14)
    np.testing.assert_allclose(ref.omega, ref.v * ref.curvature, rtol=1e-14)
    np.testing.assert_allclose(ref.poses[:, 2], wrap_angle(W * t + np.pi / 2), atol=1e-14)
    np.testing.assert_array_equal(ref.t, t)
    assert ref.inputs.shape == (101, 2)


def test_circle_from_samples_converges_at_second_order():
    errors = []
    for n in (101, 201):
        t = np.linspace(0.0, 10.0, n)
        x, y = circle(t)[:2]
        ref = reference_from_xy(t, x, y)
        np.testing.assert_allclose(ref.v, R * W, rtol=1e-3)
        np.testing.assert_allclose(ref.curvature, 1.0 / R, rtol=3e-3)  # edges least accurate
        np.testing.assert_allclose(ref.omega, W, rtol=3e-3)
        errors.append(np.max(np.abs(ref.omega - W)))
    order = np.log2(errors[0] / errors[1])
    assert order == pytest.approx(2.0, abs=0.2)


def test_non_uniform_samples():
    t = np.sort(np.random.default_rng(1).uniform(0.0, 4.0, 400))
    x, y = circle(t)[:2]
    ref = reference_from_xy(t, x, y)
    np.testing.assert_allclose(ref.v, R * W, rtol=1e-2)
    np.testing.assert_allclose(ref.poses[:, :2], np.column_stack([x, y]))


def test_reverse_negates_speed_and_flips_heading():
    t = np.linspace(0.0, 6.0, 61)
    fwd = reference_from_derivatives(*figure_eight(t))
    rev = reference_from_derivatives(*figure_eight(t), reverse=True)
    np.testing.assert_allclose(rev.v, -fwd.v)
    np.testing.assert_allclose(rev.omega, fwd.omega)
    np.testing.assert_allclose(rev.curvature, -fwd.curvature)
    np.testing.assert_allclose(wrap_angle(rev.poses[:, 2] - fwd.poses[:, 2] - np.pi), 0, atol=1e-14)
    assert np.all(rev.poses[:, 2] > -np.pi) and np.all(rev.poses[:, 2] <= np.pi)
    sampled = reference_from_xy(t, fwd.poses[:, 0], fwd.poses[:, 1], reverse=True)
    assert np.all(sampled.v < 0)


def test_figure_eight_feeds_the_unicycle_back_onto_the_path():
    ref0 = reference_from_derivatives(*figure_eight(np.array([0.0])))

    def inputs(t):
        return reference_from_derivatives(*figure_eight(t)).inputs[0]

    t_end = 2 * np.pi
    result = simulate(
        Unicycle(), ref0.poses[0], inputs, t_end=t_end, dt=1e-3, method="rk4", backend="numpy"
    )
    expected = reference_from_derivatives(*figure_eight(result.t))
    np.testing.assert_allclose(result.poses[:, :2], expected.poses[:, :2], rtol=0, atol=1e-10)
    np.testing.assert_allclose(
        wrap_angle(result.poses[:, 2] - expected.poses[:, 2]), 0.0, atol=1e-6
    )


def test_reversing_along_a_figure_eight():
    def inputs(t):
        return reference_from_derivatives(*figure_eight(t), reverse=True).inputs[0]

    start = reference_from_derivatives(*figure_eight(0.0), reverse=True).poses[0]
    result = simulate(Unicycle(), start, inputs, t_end=1.0, dt=1e-3, method="rk4", backend="numpy")
    x, y = figure_eight(result.t)[:2]
    np.testing.assert_allclose(result.poses[:, :2], np.column_stack([x, y]), atol=1e-9)


def test_a_stop_names_the_sample():
    t = np.linspace(0.0, 1.0, 11)
    x = (t - 0.5) ** 3  # ẋ = 0 at t = 0.5, sample 5
    with pytest.raises(InputError, match="sample 5"):
        reference_from_derivatives(x, 0 * t, 3 * (t - 0.5) ** 2, 0 * t, 6 * (t - 0.5), 0 * t)
    with pytest.raises(InputError, match="sample 0"):
        reference_from_xy(t, np.ones(11), np.zeros(11))


def test_input_errors():
    t = np.linspace(0.0, 1.0, 5)
    with pytest.raises(InputError, match="same shape"):
        reference_from_xy(t, t, t[:4])
    with pytest.raises(InputError, match="at least 3"):
        reference_from_xy(t[:2], t[:2], t[:2])
    with pytest.raises(InputError, match="strictly increasing"):
        reference_from_xy(t[::-1], t, t)
    with pytest.raises(InputError, match="finite"):
        reference_from_xy(t, t * np.nan, t)
    with pytest.raises(InputError, match="matching shapes"):
        reference_from_derivatives(t, t, t[:3], t, t, t)
    with pytest.raises(InputError, match="t must have shape"):
        reference_from_derivatives(t, t, np.ones(5), t, t, t, t=t[:2])


# --------------------------------------------------------------------------- eq. 9
def test_pure_motions_of_equation_9():
    robot = DiffDrive(wheel_radius=0.05, half_track=0.2)
    straight, rotation = pure_motions(robot, [0.1, -0.3])
    np.testing.assert_allclose(straight.wheel_linear_speeds, [[0.1, 0.1], [-0.3, -0.3]])
    np.testing.assert_allclose(straight.v, [0.1, -0.3])
    np.testing.assert_allclose(straight.omega, 0.0)
    np.testing.assert_allclose(rotation.wheel_linear_speeds, [[-0.1, 0.1], [0.3, -0.3]])
    np.testing.assert_allclose(rotation.v, 0.0)
    np.testing.assert_allclose(rotation.omega, 2 * np.array([0.1, -0.3]) / robot.track)
    # Cross-check with the forward kinematics of the robot.
    for motion in (straight, rotation):
        v, omega = robot.body_velocity(motion.wheel_speeds[..., 0], motion.wheel_speeds[..., 1])
        np.testing.assert_allclose(v, motion.v, atol=1e-15)
        np.testing.assert_allclose(omega, motion.omega, atol=1e-15)


def test_pure_motions_needs_a_diffdrive():
    with pytest.raises(ConfigError, match="DiffDrive"):
        pure_motions(Unicycle(), 0.1)
    with pytest.raises(InputError, match="wheel_linear_speed"):
        pure_motions(DiffDrive(0.05, 0.2), np.inf)
