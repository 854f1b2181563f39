import numpy as np
import pytest

from wheelbase.dynamics import RM100, simulate_dynamics
from wheelbase.errors import ConfigError, InputError


def test_step_equals_one_rk4_step_of_simulate_dynamics():
    state = np.array([1.0, 2.0, 0.3, 0.4, 0.0, 0.2])
    torques = np.array([0.05, 0.08])
    stepped = RM100.step(state, torques, 0.01)
    reference = simulate_dynamics(RM100, torques, 0.01, 0.01, state0=state, method="rk4")
    np.testing.assert_allclose(stepped, reference.states[-1], atol=1e-14)


def test_step_keeps_energy_without_torque():
    state = np.array([0.0, 0.0, 0.0, 0.5, 0.0, 0.4])
    energy = RM100.body.kinetic_energy(state[3:])
    for _ in range(1000):
        state = RM100.step(state, [0.0, 0.0], 0.01)
    assert RM100.body.kinetic_energy(state[3:]) == pytest.approx(energy, rel=1e-9)


def test_step_rejects_bad_input():
    with pytest.raises(InputError, match="state"):
        RM100.step([0.0, 0.0, 0.0], [0.0, 0.0], 0.01)
    with pytest.raises(ConfigError, match="h must be > 0"):
        RM100.step(np.zeros(6), [0.0, 0.0], 0.0)
