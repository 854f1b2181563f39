import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from wheelbase import ConfigError, DiffDrive, InputError
from wheelbase.control import (
    SteeringLimits,
    VelocityLimits,
    saturate_steering,
    saturate_velocity,
    steering_to_velocity,
    velocity_to_steering,
    velocity_to_wheel_speeds,
)

values = st.floats(-10, 10, allow_nan=False, allow_subnormal=False)
ROBOT = DiffDrive(wheel_radius=0.05, half_track=0.2)


@given(values, values)
def test_saturation_keeps_curvature_and_meets_every_limit(v, omega):
    limits = VelocityLimits(max_speed=0.5, max_yaw_rate=1.5)
    out = saturate_velocity([v, omega], limits)
    assert abs(out[0]) <= 0.5 + 1e-12 and abs(out[1]) <= 1.5 + 1e-12
    assert np.sign(out[0]) == np.sign(v) and np.sign(out[1]) == np.sign(omega)
    assert math.isclose(out[0] * omega, out[1] * v, abs_tol=1e-9)  # same ω/v
    # the largest factor: one limit is active, or nothing was scaled
    active = np.isclose(abs(out[0]), 0.5) or np.isclose(abs(out[1]), 1.5)
    assert active or np.allclose(out, [v, omega])


@given(values, values)
def test_wheel_speed_limit_keeps_curvature(v, omega):
    limits = VelocityLimits.for_diffdrive(ROBOT, max_wheel_speed=10.0)
    out = saturate_velocity([v, omega], limits)
    wheels = velocity_to_wheel_speeds(out, ROBOT)
    assert np.max(np.abs(wheels)) <= 10.0 + 1e-9
    assert math.isclose(out[0] * omega, out[1] * v, abs_tol=1e-9)
    # the wheel speeds are the inverse of DiffDrive's twist
    np.testing.assert_allclose(ROBOT.twist(wheels)[[0, 2]], out, atol=1e-9)


def test_saturation_batch_and_no_limits():
    commands = np.array([[0.2, 3.0], [-1.0, 0.1], [0.0, 0.0]])
    out = saturate_velocity(commands, VelocityLimits(0.5, 1.5))
    np.testing.assert_allclose(out, [[0.1, 1.5], [-0.5, 0.05], [0.0, 0.0]])
    np.testing.assert_array_equal(saturate_velocity(commands, None), commands)


def test_steering_limits_and_rate():
    limits = SteeringLimits(max_steering=math.radians(35), max_speed=1.0, max_steering_rate=1.0)
    out = saturate_steering([[2.0, 1.0], [-3.0, -0.1]], limits)
    np.testing.assert_allclose(out, [[1.0, math.radians(35)], [-1.0, -0.1]])
    out = saturate_steering([0.5, 0.5], limits, previous=0.0, dt=0.1)
    np.testing.assert_allclose(out, [0.5, 0.1])
    with pytest.raises(ConfigError, match="dt"):
        saturate_steering([0.5, 0.5], limits, previous=0.0)


@given(st.floats(-2, 2).filter(lambda v: abs(v) > 1e-3), values)
def test_velocity_steering_round_trip(v, omega):
    steering = velocity_to_steering([v, omega], wheel_base=0.3)
    assert abs(steering[1]) < math.pi / 2
    assert np.sign(steering[1]) == np.sign(omega / v) or omega == 0
    np.testing.assert_allclose(steering_to_velocity(steering, 0.3), [v, omega], atol=1e-6)


def test_bad_limits():
    with pytest.raises(ConfigError, match="max_speed"):
        VelocityLimits(max_speed=-1)
    with pytest.raises(ConfigError, match="max_wheel_speed needs"):
        VelocityLimits(max_wheel_speed=3.0)
    with pytest.raises(ConfigError, match="max_steering"):
        SteeringLimits(max_steering=2.0)
    with pytest.raises(InputError, match="command"):
        saturate_velocity([1.0, 2.0, 3.0], VelocityLimits(1.0))
