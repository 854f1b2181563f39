"""Steered models (document 002 eqs. 11–16): closed forms, Ackermann geometry, limits."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from wheelbase.errors import ConfigError, InputError
from wheelbase.integrate import simulate
from wheelbase.models.bicycle import Ackermann, Bicycle, RearWheelBicycle

L = 2.5
REAR = RearWheelBicycle(wheel_base=L)
CAR = Ackermann(wheel_base=L, track=1.6)
BIKE = Bicycle(wheel_base=L)
MODELS = [REAR, CAR, BIKE]
IDS = ["rear", "ackermann", "bicycle"]

steer = st.floats(-0.55, 0.55, allow_nan=False)
speed = st.floats(-3.0, 3.0, allow_nan=False).filter(lambda s: abs(s) > 1e-3)


def test_defaults_and_input_order():
    assert REAR.max_steering == 0.6 and CAR.max_steering == 0.6 and BIKE.max_steering == 1.2
    for model in MODELS:
        assert model.input_names == ("speed", "steering")
        assert model.input_units == ("m/s", "rad")


# --------------------------------------------------------------------------- closed forms
@pytest.mark.parametrize("model", [REAR, CAR], ids=["rear", "ackermann"])
def test_rear_driven_circle_radius_and_yaw_rate(model):
    v, delta = 1.5, 0.3
    np.testing.assert_allclose(model.twist([v, delta]), [v, 0.0, v * math.tan(delta) / L])
    radius = L / math.tan(delta)
    assert float(model.icc_radius(delta)) == pytest.approx(radius)
    # One full lap comes back to the start; every pose lies on the circle about (0, R).
    period = 2 * math.pi * radius / v
    result = simulate(model, [0.0, 0.0, 0.0], (v, delta), t_end=period, dt=period / 200)
    np.testing.assert_allclose(np.hypot(result.poses[:, 0], result.poses[:, 1] - radius), radius)
    np.testing.assert_allclose(result.poses[-1], [0.0, 0.0, 0.0], atol=1e-9)


def test_front_driven_bicycle_closed_forms():
    v_s, alpha = 2.0, 0.7
    u, v, r = BIKE.twist([v_s, alpha])
    assert (u, v, r) == pytest.approx((v_s * math.cos(alpha), 0.0, v_s * math.sin(alpha) / L))
    # Doc 002 eq. 12: ω = v_S / √(d² + R²) with R = d / tan α (eq. 11).
    radius = float(BIKE.icc_radius(alpha))
    assert radius == pytest.approx(L / math.tan(alpha))
    assert r == pytest.approx(v_s / math.hypot(L, radius))
    # The rear axle moves on the circle of radius R: u / r = R.
    assert u / r == pytest.approx(radius)


def test_icc_radius_is_infinite_straight_ahead_without_warning():
    for model in MODELS:
        radius = model.icc_radius([0.0, -0.0, 0.2, -0.2])
        assert np.isposinf(radius[:2]).all()
        assert radius[2] == pytest.approx(-radius[3])


# --------------------------------------------------------------------------- Ackermann
@settings(max_examples=60, deadline=None)
@given(delta=steer.filter(lambda d: abs(d) > 1e-6))
def test_ackermann_wheel_axes_pass_through_the_icc(delta):
    left, right = CAR.wheel_angles(delta)
    half_w = 0.8
    icc_y = L / math.tan(delta)  # ICC at (0, icc_y) in the rear-axle frame
    for angle, wheel_y in ((left, half_w), (right, -half_w)):
        # The wheel axis through (L, wheel_y) has direction (−sin, cos): the ICC is on it.
        to_icc = np.array([0.0 - L, icc_y - wheel_y])
        cross = to_icc[0] * math.cos(angle) + to_icc[1] * math.sin(angle)
        assert abs(cross) / np.hypot(*to_icc) < 1e-12  # sine of the angle between them
    # Printed formulas tan δ_L = L tan δ/(L − (w/2) tan δ), tan δ_R = L tan δ/(L + (w/2) tan δ).
    t = math.tan(delta)
    assert math.tan(left) == pytest.approx(L * t / (L - half_w * t), rel=1e-12, abs=1e-15)
    assert math.tan(right) == pytest.approx(L * t / (L + half_w * t), rel=1e-12, abs=1e-15)


def test_ackermann_inner_wheel_turns_more_and_is_smooth_at_zero():
    assert CAR.wheel_angles(0.0) == (0.0, 0.0)
    left, right = CAR.wheel_angles([0.3, -0.3])
    assert left[0] > 0.3 > right[0] > 0.0  # turning left: left wheel is the inner one
    np.testing.assert_allclose([left[1], right[1]], [-right[0], -left[0]])  # mirror symmetry
    eps = np.array([-1e-9, 0.0, 1e-9])
    left, right = CAR.wheel_angles(eps)
    np.testing.assert_allclose(left, eps, rtol=1e-6, atol=0)
    np.testing.assert_allclose(right, eps, rtol=1e-6, atol=0)
    # Derivative at 0 is 1 for both wheels (finite differences, no 0/0).
    h = 1e-6
    slope = (np.array(CAR.wheel_angles(h)) - np.array(CAR.wheel_angles(-h))) / (2 * h)
    np.testing.assert_allclose(slope, [1.0, 1.0], rtol=1e-6)


def test_ackermann_rear_wheel_speeds():
    v, delta = 2.0, 0.4
    left, right = CAR.rear_wheel_speeds(v, delta)
    radius = L / math.tan(delta)
    assert float(left) == pytest.approx(v * (radius - 0.8) / radius)
    assert float(right) == pytest.approx(v * (radius + 0.8) / radius)
    # The mean is the rear-axle speed, the difference over the track the yaw rate.
    yaw = CAR.twist([v, delta])[2]
    assert (left + right) / 2 == pytest.approx(v)
    assert (right - left) / 1.6 == pytest.approx(yaw)
    np.testing.assert_allclose(CAR.rear_wheel_speeds([1.0, -1.0], 0.0), [[1.0, -1.0]] * 2)


# --------------------------------------------------------------------------- inverse
@settings(max_examples=60, deadline=None)
@given(v=speed, delta=steer)
def test_inverse_recovers_inputs_including_reversing(v, delta):
    for model in MODELS:
        got = model.inverse(model.twist([v, delta]))
        np.testing.assert_allclose(got, [v, delta], rtol=1e-9, atol=1e-12)


def test_reversing_drives_the_circle_backwards():
    v, delta = -1.0, 0.3
    for model in MODELS:
        u, _, r = model.twist([v, delta])
        assert u < 0 and r < 0  # backwards, turning clockwise: same circle on the left
        result = simulate(model, [0.0, 0.0, 0.0], (v, delta), t_end=1.0, dt=0.01)
        radius = float(model.icc_radius(delta))
        np.testing.assert_allclose(
            np.hypot(result.poses[:, 0], result.poses[:, 1] - radius), radius, rtol=1e-9
        )
        assert result.poses[-1, 0] < 0


def test_inverse_of_pure_rotation_is_impossible():
    # A bicycle would need α = 90°; the rear-driven models cannot turn in place either.
    for model in MODELS:
        with pytest.raises(InputError, match="turn in place"):
            model.inverse([0.0, 0.0, 0.5])
        np.testing.assert_allclose(model.inverse([0.0, 0.0, 0.0]), [0.0, 0.0])


def test_inverse_beyond_the_steering_stop_raises():
    with pytest.raises(InputError, match="max_steering"):
        REAR.inverse([1.0, 0.0, 1.0])  # needs atan(2.5) ≈ 1.19 rad > 0.6


# --------------------------------------------------------------------------- limits
@pytest.mark.parametrize("model", MODELS, ids=IDS)
def test_steering_at_or_beyond_90_degrees_raises(model):
    with pytest.raises(InputError, match="steering"):
        model.twist([1.0, math.pi / 2])
    with pytest.raises(InputError, match="steering"):
        simulate(model, [0.0, 0.0, 0.0], (1.0, -2.0), t_end=1.0, dt=0.1)
    with pytest.raises(InputError, match="steering"):
        model.icc_radius(3.0)


@pytest.mark.parametrize("model", MODELS, ids=IDS)
def test_steering_beyond_the_stop_is_clipped(model):
    stop = model.max_steering
    np.testing.assert_allclose(model.twist([1.0, 1.5]), model.twist([1.0, stop]))
    np.testing.assert_allclose(model.twist([1.0, -1.5]), model.twist([1.0, -stop]))
    assert float(model.icc_radius(1.5)) == pytest.approx(float(model.icc_radius(stop)))


def test_bicycle_alpha_90_degrees_is_rejected():
    # With α = 90° the front wheel would push sideways: u = 0, r = v_S/d; not a steering angle.
    with pytest.raises(InputError, match="steering"):
        BIKE.twist([1.0, math.pi / 2])
    with pytest.raises(ConfigError, match="max_steering"):
        Bicycle(wheel_base=1.0, max_steering=math.pi / 2)


def test_configuration_errors():
    with pytest.raises(ConfigError, match="wheel_base"):
        RearWheelBicycle(wheel_base=0.0)
    with pytest.raises(ConfigError, match="wheel_base"):
        Bicycle(wheel_base=float("nan"))
    with pytest.raises(ConfigError, match="max_steering"):
        RearWheelBicycle(wheel_base=1.0, max_steering=-0.1)
    with pytest.raises(ConfigError, match="track"):
        Ackermann(wheel_base=1.0, track=-1.0)
    with pytest.raises(ConfigError, match="max_steering"):
        # tan(0.6) ≈ 0.68 > 2·0.3/1.0: the ICC would fall inside the inner wheel.
        Ackermann(wheel_base=0.3, track=1.0)


def test_batch_of_cars():
    inputs = np.array([[1.0, 0.0], [1.0, 0.2], [-1.0, -0.2]])
    result = simulate(CAR, np.zeros((3, 3)), inputs, t_end=2.0, dt=0.01, method="exact")
    single = simulate(CAR, np.zeros(3), inputs[1], t_end=2.0, dt=0.01, method="exact")
    np.testing.assert_allclose(result.poses[:, 1], single.poses, atol=1e-12)
    np.testing.assert_allclose(result.poses[-1, 0], [2.0, 0.0, 0.0], atol=1e-12)
