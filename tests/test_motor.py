"""DC gear-motor model and the wheel speed loop (document 003 §II)."""

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from wheelbase.errors import ConfigError, InputError
from wheelbase.motor import MOTOR_PRESETS, DCMotor, SpeedLoop

MOTOR = MOTOR_PRESETS["gearmotor_12v"]


@pytest.mark.parametrize("name", sorted(MOTOR_PRESETS))
def test_exact_step_matches_a_tight_ode_solution(name):
    motor = MOTOR_PRESETS[name]
    state0 = np.array([0.0, 5.0, 1.0])
    if motor.inductance == 0:
        state0[0] = (motor.voltage(0.7) - motor.back_emf_constant * 5.0) / motor.resistance

    def rhs(t, x):
        return motor.derivative(x, 0.7, 0.05)

    ref = solve_ivp(rhs, (0, 0.3), state0, method="DOP853", rtol=1e-12, atol=1e-12).y[:, -1]
    got = motor.step(state0, 0.7, 0.3, 0.05)
    np.testing.assert_allclose(got[1:], ref[1:], rtol=1e-9, atol=1e-9)
    if motor.inductance == 0:  # the current is algebraic: (V − k_e ω)/R
        expected_current = (
            motor.voltage(0.7) - motor.back_emf_constant * got[1]
        ) / motor.resistance
        assert got[0] == pytest.approx(expected_current, rel=1e-12)
    else:
        assert got[0] == pytest.approx(ref[0], rel=1e-9)
    # Exact: two half steps are one full step (a semigroup), for any step length.
    half = motor.step(motor.step(state0, 0.7, 0.15, 0.05), 0.7, 0.15, 0.05)
    np.testing.assert_allclose(half, got, rtol=1e-12, atol=1e-12)


def test_steady_state_and_stall_closed_forms():
    state = MOTOR.step([0.0, 0.0, 0.0], 1.0, 5.0)  # 100 time constants
    assert state[1] == pytest.approx(MOTOR.no_load_speed, rel=1e-9)
    kt, ke, r, b = 0.3, 0.3, 2.0, 1e-3
    assert MOTOR.no_load_speed == pytest.approx(kt * 12 / (kt * ke + b * r))
    assert state[0] == pytest.approx(b * MOTOR.no_load_speed / kt, rel=1e-6)  # i = bω/k_t
    # Held wheel (load = stall torque at full duty): it does not move.
    held = MOTOR.step([0.0, 0.0, 0.0], 1.0, 2.0, MOTOR.stall_torque)
    assert abs(held[1]) < 1e-9
    # Duty saturates at ±1, and reverses the motor.
    np.testing.assert_allclose(
        MOTOR.steady_speed([2.0, -1.0]), [39.130434782608695, -39.1304347826]
    )


def test_small_inductance_tends_to_the_first_order_model():
    base = dict(resistance=2.0, torque_constant=0.3, back_emf_constant=0.3, inertia=2e-3)
    first = DCMotor(**base).step([0, 0, 0], 0.5, 0.05)
    second = DCMotor(**base, inductance=1e-6).step([0, 0, 0], 0.5, 0.05)
    np.testing.assert_allclose(second, first, rtol=1e-3)


def test_batch_of_wheels():
    states = np.zeros((4, 2, 3))
    duty = np.array([0.1, 0.2, -0.3, 1.0])[:, None] * np.ones(2)
    out = MOTOR.step(states, duty, 0.02)
    assert out.shape == (4, 2, 3)
    np.testing.assert_allclose(out[2, 0], MOTOR.step([0, 0, 0], -0.3, 0.02))


def run_loop(loop, setpoint, seconds=1.0, motor=MOTOR, load=0.0):
    state, integral = np.zeros(3), 0.0
    speeds = []
    for _ in range(round(seconds / loop.period)):
        before = state[2]
        measured = state[1] * 60 / (2 * math.pi)
        duty, integral = loop.update(integral, setpoint, measured)
        state = motor.step(state, duty, loop.period, load)
        speeds.append((state[2] - before) / loop.period * 60 / (2 * math.pi))
    return np.array(speeds), integral


def test_pi_loop_removes_the_steady_error_under_load():
    loop = SpeedLoop.for_motor(MOTOR, period=0.01)
    speeds, _ = run_loop(loop, 150.0, seconds=2.0, load=0.3)
    assert speeds[-1] == pytest.approx(150.0, abs=0.5)
    p_only = SpeedLoop(kp=loop.kp, period=0.01, feedforward=loop.feedforward)
    speeds_p, _ = run_loop(p_only, 150.0, seconds=2.0, load=0.3)
    assert abs(speeds_p[-1] - 150.0) > 5.0  # P + feed-forward leaves an error under load


def test_anti_windup_keeps_the_integral_bounded():
    loop = SpeedLoop(kp=0.01, ki=0.5, period=0.01)
    _, integral = run_loop(loop, 10_000.0, seconds=1.0)  # unreachable: the duty saturates
    assert abs(integral) < 10.0 / loop.ki  # the integral stops growing once saturated


def test_bad_gains_and_inputs():
    with pytest.raises(ConfigError, match="kp"):
        SpeedLoop(kp=-0.1)
    with pytest.raises(ConfigError, match="ki"):
        SpeedLoop(kp=0.1, ki=-1.0)
    with pytest.raises(ConfigError, match="period"):
        SpeedLoop(kp=0.1, period=0.0)
    with pytest.raises(ConfigError, match="resistance"):
        DCMotor(resistance=0.0, torque_constant=0.1, back_emf_constant=0.1, inertia=1e-3)
    with pytest.raises(ConfigError, match="dt"):
        MOTOR.step([0, 0, 0], 0.5, 0.0)
    with pytest.raises(InputError, match="duty"):
        MOTOR.step([0, 0, 0], float("nan"), 0.1)
