"""General wheeled base (document 000 §3.1): J_w, least-squares forward kinematics, presets."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from wheelbase.errors import ConfigError, InputError
from wheelbase.integrate import METHODS, simulate
from wheelbase.models.diffdrive import DiffDrive
from wheelbase.models.wheeled import Wheel, WheeledBase, mecanum4, omni3

A, D = 0.05, 0.2
MECANUM = mecanum4(wheel_radius=0.05, half_length=0.25, half_width=0.2)
OMNI = omni3(wheel_radius=0.04, base_radius=0.3)
DIFF = WheeledBase.differential(A, D)

speeds = st.floats(-2.0, 2.0, allow_nan=False)
twists = st.tuples(speeds, speeds, st.floats(-3.0, 3.0, allow_nan=False))


# --------------------------------------------------------------------------- document 000's W
def test_differential_jacobian_is_document_000_inverse():
    # ω1 = (u − r d)/a, ω2 = (u + r d)/a (document 000 §3.1), no v column.
    expected = np.array([[1 / A, 0.0, -D / A], [1 / A, 0.0, D / A]])
    np.testing.assert_allclose(DIFF.jacobian, expected, rtol=0, atol=1e-15)
    assert DIFF.input_names == DiffDrive.input_names


def test_differential_forward_equals_diffdrive_wheel_matrix():
    robot = DiffDrive(A, D)
    rng = np.random.default_rng(0)
    omega = rng.uniform(-5, 5, size=(50, 2))
    twist, residual = DIFF.forward(omega)
    np.testing.assert_allclose(twist, omega @ robot.wheel_matrix.T, atol=1e-14)
    np.testing.assert_allclose(twist, robot.twist(omega), atol=1e-14)
    np.testing.assert_allclose(residual, 0.0, atol=1e-12)
    # The least-squares solution operator on the drive rows is W itself.
    np.testing.assert_allclose(DIFF.twist(np.eye(2)).T, robot.wheel_matrix, atol=1e-15)


def test_differential_inverse_equals_diffdrive_inverse():
    robot = DiffDrive(A, D)
    zeta = np.array([[0.1, 0.0, 0.3], [0.6, 0.0, -0.3], [-0.2, 0.0, 0.0]])
    np.testing.assert_allclose(DIFF.inverse(zeta), robot.inverse(zeta), atol=1e-14)


def test_differential_simulation_matches_diffdrive():
    robot = DiffDrive(A, D)
    pose0 = [0.0, 0.0, np.pi / 2]
    ours = simulate(DIFF, pose0, (0.8, 0.6), t_end=10.0, dt=0.1, method="euler")
    ref = simulate(robot, pose0, (0.8, 0.6), t_end=10.0, dt=0.1, method="euler")
    np.testing.assert_allclose(ours.poses, ref.poses, atol=1e-12)


def test_fixed_wheel_sideways_twist_is_slip():
    # A differential drive cannot move sideways: inverse ignores v, lateral_slip reports it.
    np.testing.assert_allclose(DIFF.lateral_slip([0.0, 0.3, 0.0]), [0.3, 0.3])
    np.testing.assert_allclose(DIFF.inverse([0.0, 0.3, 0.0]), [0.0, 0.0])


# --------------------------------------------------------------------------- presets
def test_mecanum_rows_are_the_standard_formulas():
    a, lx, ly = 0.05, 0.25, 0.2
    u, v, r = 0.3, -0.2, 0.7
    k = lx + ly
    expected = np.array([u - v - k * r, u + v + k * r, u + v - k * r, u - v + k * r]) / a
    np.testing.assert_allclose(MECANUM.inverse([u, v, r]), expected, rtol=1e-14)
    assert MECANUM.input_names == (
        "omega_front_left",
        "omega_front_right",
        "omega_rear_left",
        "omega_rear_right",
    )
    assert MECANUM.is_holonomic and OMNI.is_holonomic and not DIFF.is_holonomic


def test_omni_rows_are_tangential():
    a, big_r = 0.04, 0.3
    u, v, r = 0.3, -0.2, 0.7
    beta = np.array([0.0, 2 * np.pi / 3, -2 * np.pi / 3])
    expected = (-np.sin(beta) * u + np.cos(beta) * v + big_r * r) / a
    np.testing.assert_allclose(OMNI.inverse([u, v, r]), expected, rtol=1e-13, atol=1e-13)


@pytest.mark.parametrize("base", [MECANUM, OMNI], ids=["mecanum4", "omni3"])
@pytest.mark.parametrize("method", METHODS)
def test_holonomic_presets_move_purely_sideways(base, method):
    inputs = base.inverse([0.0, 0.3, 0.0])
    result = simulate(base, [0.0, 0.0, 0.0], inputs, t_end=2.0, dt=0.05, method=method)
    np.testing.assert_allclose(result.poses[:, 0], 0.0, atol=1e-12)
    np.testing.assert_allclose(result.poses[:, 1], 0.3 * result.t, atol=1e-12)
    np.testing.assert_allclose(result.poses[:, 2], 0.0, atol=1e-12)


@pytest.mark.parametrize("base", [MECANUM, OMNI], ids=["mecanum4", "omni3"])
def test_holonomic_presets_rotate_in_place(base):
    inputs = base.inverse([0.0, 0.0, 0.5])
    result = simulate(base, [1.0, -2.0, 0.3], inputs, t_end=3.0, dt=0.1, method="rk4")
    np.testing.assert_allclose(result.poses[:, :2], [[1.0, -2.0]] * len(result.t), atol=1e-12)
    np.testing.assert_allclose(result.poses[-1, 2], 0.3 + 1.5, atol=1e-12)


def test_batch_of_mecanum_robots_with_different_wheel_speeds():
    goals = np.array([[0.2, 0.0, 0.0], [0.0, -0.2, 0.0], [0.1, 0.1, 0.0]])
    result = simulate(MECANUM, np.zeros((3, 3)), MECANUM.inverse(goals), t_end=1.0, dt=0.1)
    assert result.poses.shape == (11, 3, 3)
    np.testing.assert_allclose(result.poses[-1], goals, atol=1e-12)


# --------------------------------------------------------------------------- forward ∘ inverse
@settings(max_examples=60, deadline=None)
@given(twist=twists)
def test_forward_inverse_identity_holonomic(twist):
    for base in (MECANUM, OMNI):
        got, residual = base.forward(base.inverse(twist))
        np.testing.assert_allclose(got, twist, atol=1e-12)
        assert residual < 1e-10


@settings(max_examples=60, deadline=None)
@given(u=speeds, r=st.floats(-3.0, 3.0, allow_nan=False))
def test_forward_inverse_identity_differential(u, r):
    got, residual = DIFF.forward(DIFF.inverse([u, 0.0, r]))
    np.testing.assert_allclose(got, [u, 0.0, r], atol=1e-12)
    assert residual < 1e-10


@settings(max_examples=60, deadline=None)
@given(omega=st.tuples(speeds, speeds, speeds, speeds))
def test_inverse_of_forward_projects_onto_consistent_speeds(omega):
    # J_w·forward(ω) is the orthogonal projection of ω on the range of J_w: idempotent,
    # and the residual is the length of what was removed.
    twist, residual = MECANUM.forward(omega)
    projected = MECANUM.inverse(twist)
    np.testing.assert_allclose(MECANUM.inverse(MECANUM.forward(projected)[0]), projected, atol=1e-9)
    assert residual == pytest.approx(np.linalg.norm(np.subtract(omega, projected)), abs=1e-9)


def test_slipping_wheel_speeds_have_a_positive_residual():
    # Mecanum: ω_FL + ω_FR − ω_RL − ω_RR = 0 for every rigid motion; (1, 0, 0, 0) breaks it.
    twist, residual = MECANUM.forward([1.0, 0.0, 0.0, 0.0])
    assert residual == pytest.approx(0.5, rel=1e-12)  # |(1, 1, −1, −1)/4| = 0.5 rad/s
    np.testing.assert_allclose(MECANUM.inverse(twist), [0.75, -0.25, 0.25, 0.25], atol=1e-12)
    # Omni: three wheels, three unknowns, so never slip; the consistent diff drive neither.
    assert OMNI.forward([1.0, 0.0, 0.0])[1] < 1e-12


def test_two_fixed_wheels_in_line_slip_when_spun_differently():
    # Front and rear fixed wheels on the x axis: both must roll at u/a; anything else slips.
    base = WheeledBase((Wheel(0.3, 0.0, 0.0, 0.1), Wheel(-0.3, 0.0, 0.0, 0.1)))
    twist, residual = base.forward([[2.0, 2.0], [3.0, 1.0]])
    np.testing.assert_allclose(twist, [[0.2, 0.0, 0.0], [0.2, 0.0, 0.0]], atol=1e-12)
    np.testing.assert_allclose(residual, [0.0, math.sqrt(2.0)], atol=1e-12)


def test_general_wheel_row_matches_document_000_formula():
    # Row = (1/a)[1, tan φ] R(θ_B)ᵀ [[1, 0, −dy], [0, 1, dx]] written out by hand.
    x, y, theta, a, phi = 0.3, -0.1, 0.4, 0.06, -0.5
    wheel = Wheel(x, y, theta, a, roller_angle=phi, kind="mecanum")
    c, s, t = math.cos(theta), math.sin(theta), math.tan(phi)
    expected = (
        np.array(
            [c - t * s, s + t * c, (-y * c + x * s) + t * (y * s + x * c)],
        )
        / a
    )
    np.testing.assert_allclose(wheel.drive_row, expected, rtol=1e-14)


# --------------------------------------------------------------------------- validation
def test_configuration_errors():
    with pytest.raises(ConfigError, match="at least 1 wheel"):
        WheeledBase(())
    with pytest.raises(ConfigError, match="radius"):
        Wheel(0.0, 0.0, 0.0, -0.1)
    with pytest.raises(ConfigError, match="roller_angle"):
        Wheel(0.0, 0.0, 0.0, 0.1, roller_angle=math.pi / 2, kind="mecanum")
    with pytest.raises(ConfigError, match="roller_angle"):
        Wheel(0.0, 0.0, 0.0, 0.1, roller_angle=0.3, kind="fixed")
    with pytest.raises(ConfigError, match="roller_angle"):
        Wheel(0.0, 0.0, 0.0, 0.1, kind="mecanum")
    with pytest.raises(ConfigError, match="kind"):
        Wheel(0.0, 0.0, 0.0, 0.1, kind="castor")
    with pytest.raises(ConfigError, match="x"):
        Wheel(float("nan"), 0.0, 0.0, 0.1)
    with pytest.raises(ConfigError, match="wheels\\[1\\]"):
        WheeledBase((Wheel(0.0, 0.1, 0.0, 0.1), "wheel"))
    with pytest.raises(ConfigError, match="half_track"):
        WheeledBase.differential(0.05, 0.0)
    with pytest.raises(ConfigError, match="half_width"):
        mecanum4(0.05, 0.2, -1.0)
    with pytest.raises(ConfigError, match="base_radius"):
        omni3(0.05, float("inf"))


@pytest.mark.parametrize(
    "wheels",
    [
        (Wheel(0.0, 0.0, 0.0, 0.1),),  # one fixed wheel: rank 2
        (Wheel(0.0, 0.2, 0.0, 0.1, kind="omni"), Wheel(0.0, -0.2, 0.0, 0.1, kind="omni")),
        tuple(Wheel(0.1 * i, 0.0, 0.0, 0.1, kind="omni") for i in range(3)),  # all roll along x
    ],
    ids=["one-fixed", "two-omni", "parallel-omni"],
)
def test_rank_deficient_wheel_sets_are_rejected(wheels):
    with pytest.raises(ConfigError, match="rank"):
        WheeledBase(wheels)


def test_input_shape_is_checked():
    with pytest.raises(InputError, match="shape"):
        MECANUM.forward([1.0, 2.0, 3.0])
    with pytest.raises(InputError, match="finite"):
        OMNI.twist([1.0, np.nan, 0.0])


@pytest.mark.parametrize(
    ("half_length", "wheel_radius"), [(8.988465674311581e306, 0.05), (0.2, 5e-324)]
)
def test_geometry_that_overflows_the_jacobian_is_a_config_error(half_length, wheel_radius):
    # found by tests/test_fuzz.py: an overflow warning, then a Jacobian of inf
    with pytest.raises(ConfigError, match="wheel Jacobian overflows"):
        mecanum4(wheel_radius, half_length, 0.15)


def test_a_radius_whose_inverse_jacobian_overflows_is_a_config_error():
    # omni3(wheel_radius=6e307) overflowed in the pseudo-inverse (found by the explore run)
    with pytest.raises(ConfigError, match="inverse overflows"):
        omni3(6.227391691998602e307, 0.2)
