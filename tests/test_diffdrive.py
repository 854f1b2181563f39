import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from wheelbase import ConfigError, DiffDrive, InputError, simulate

speeds = st.floats(-20, 20, allow_nan=False)
ROBOT = DiffDrive(wheel_radius=0.05, half_track=0.2)


def test_wheel_matrix_is_document_000_w():
    a, d = 0.05, 0.2
    expected = np.array([[a / 2, a / 2], [0, 0], [-a / (2 * d), a / (2 * d)]])
    np.testing.assert_allclose(ROBOT.wheel_matrix, expected)
    np.testing.assert_allclose(ROBOT.twist([0.8, 0.6]), expected @ [0.8, 0.6])


@given(speeds, speeds)
def test_forward_inverse_identity(left, right):
    v, omega = ROBOT.body_velocity(left, right)
    back = ROBOT.wheel_speeds(v, omega)
    np.testing.assert_allclose(back, (left, right), atol=1e-9)
    np.testing.assert_allclose(ROBOT.inverse(ROBOT.twist([left, right])), [left, right], atol=1e-9)


def test_document_001_equations_6_7_8():
    # doc 001 with L = 2d and (v_R, v_L) = r·(ω_R, ω_L): ω = (v_R − v_L)/L, v = (v_R + v_L)/2.
    left, right = 2.0, 5.0
    v_left, v_right = 0.05 * left, 0.05 * right
    v, omega = ROBOT.body_velocity(left, right)
    assert np.isclose(omega, (v_right - v_left) / ROBOT.track)
    assert np.isclose(v, (v_right + v_left) / 2)
    radius = ROBOT.icc_radius(left, right)
    assert np.isclose(radius, ROBOT.track * (v_right + v_left) / (2 * (v_right - v_left)))
    assert np.isclose(radius * omega, v)


def test_icc_radius_limits_without_warnings():
    with np.errstate(all="raise"):
        radii = ROBOT.icc_radius([1.0, -1.0, 1.0, 0.0, 1.0], [1.0, -1.0, -1.0, 0.0, 1.0 + 1e-12])
    assert radii[0] == np.inf
    assert radii[1] == -np.inf
    assert radii[2] == 0.0
    assert np.isnan(radii[3])  # standing still: no ICC
    assert np.isfinite(radii[4]) and radii[4] > 1e10


def test_pfaffian_matrix_is_document_001_eq16_with_wheels_reordered():
    theta = 0.7
    a_matrix = ROBOT.pfaffian_matrix([1.0, 2.0, theta])
    s, c, big_l, r = np.sin(theta), np.cos(theta), ROBOT.track, ROBOT.wheel_radius
    printed = np.array(  # doc 001 eq. 16, columns (x, y, θ, φ_R, φ_L)
        [[s, -c, 0, 0, 0], [c, s, big_l / 2, -r, 0], [c, s, -big_l / 2, 0, -r]]
    )
    # Columns to (x, y, θ, φ_L, φ_R); rows to (lateral, left wheel, right wheel).
    reordered = printed[[0, 2, 1]][:, [0, 1, 2, 4, 3]]
    np.testing.assert_allclose(a_matrix, reordered, atol=1e-15)
    t_nh = ROBOT.nonholonomic_transform([0.0, 0.0, theta])
    printed_t = np.array(  # doc 001 eq. 18, columns (ω_R, ω_L)
        [[r / 2 * c, r / 2 * c], [r / 2 * s, r / 2 * s], [r / big_l, -r / big_l]]
    )
    np.testing.assert_allclose(t_nh, printed_t[:, ::-1])


@pytest.mark.parametrize("method", ["euler", "midpoint", "rk4", "exact", "simpson"])
def test_pfaffian_constraint_holds_along_simulated_motion(method):
    def wheel_speeds(t):
        return np.array([0.8 + 0.5 * np.sin(0.7 * t), 0.6 - 0.4 * np.cos(0.3 * t)])

    result = simulate(ROBOT, [0.3, -0.2, 1.0], wheel_speeds, t_end=20.0, dt=0.05, method=method)
    q_dot = np.column_stack(
        [ROBOT.derivative(result.poses, result.inputs), result.inputs]
    )  # (ẋ, ẏ, θ̇, φ̇_L, φ̇_R) at every recorded pose
    residual = np.einsum("tij,tj->ti", ROBOT.pfaffian_matrix(result.poses), q_dot)
    np.testing.assert_allclose(residual, 0.0, atol=1e-12)
    # The same through T_NH: q̇ = T_NH(q)·(ω_L, ω_R).
    rate = np.einsum("tij,tj->ti", ROBOT.nonholonomic_transform(result.poses), result.inputs)
    np.testing.assert_allclose(rate, q_dot[:, :3], atol=1e-12)


def test_pfaffian_constraint_on_finite_differences_of_the_exact_path():
    result = simulate(ROBOT, [0, 0, 0], (0.8, 0.6), t_end=10.0, dt=1e-3, method="exact")
    theta = np.unwrap(result.poses[:, 2])
    xd = np.gradient(result.poses[:, 0], result.t)
    yd = np.gradient(result.poses[:, 1], result.t)
    lateral = np.sin(theta) * xd - np.cos(theta) * yd
    assert np.max(np.abs(lateral[1:-1])) < 1e-7


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"wheel_radius": 0.0, "half_track": 0.2}, "wheel_radius must be > 0 m"),
        ({"wheel_radius": 0.05, "half_track": -0.2}, r"half_track must be > 0 m \(got -0.2\)"),
        ({"wheel_radius": float("nan"), "half_track": 0.2}, "wheel_radius must be finite"),
        ({"wheel_radius": "big", "half_track": 0.2}, "wheel_radius must be a real number"),
    ],
)
def test_bad_parameters(kwargs, match):
    with pytest.raises(ConfigError, match=match):
        DiffDrive(**kwargs)


def test_bad_inputs():
    with pytest.raises(InputError, match="finite"):
        ROBOT.twist([np.inf, 0.0])
    with pytest.raises(InputError, match=r"shape \(\.\.\., 2\)"):
        ROBOT.twist([1.0, 2.0, 3.0])
