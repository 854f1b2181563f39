"""The JAX backend of simulate equals the NumPy reference (skipped without the jax extra)."""

import numpy as np
import pytest

from wheelbase import METHODS, DiffDrive, Unicycle, simulate

jax = pytest.importorskip("jax")

ROBOT = DiffDrive(wheel_radius=0.05, half_track=0.2)


@pytest.mark.parametrize("method", METHODS)
def test_jax_equals_numpy_in_float64(method):
    poses0 = np.array([[0.0, 0.0, 0.0], [1.0, -1.0, 3.0], [2.0, 0.5, -2.5]])
    inputs = np.array([[0.8, 0.6], [0.6, -0.6], [1.0, 1.0]])
    fast = simulate(ROBOT, poses0, inputs, t_end=10.0, dt=0.07, method=method, backend="jax")
    ref = simulate(ROBOT, poses0, inputs, t_end=10.0, dt=0.07, method=method, backend="numpy")
    np.testing.assert_allclose(fast.poses, ref.poses, atol=1e-9)

    def varying(t):
        return inputs * np.cos(0.2 * t)

    fast = simulate(ROBOT, poses0, varying, t_end=3.0, dt=0.1, method=method, backend="jax")
    ref = simulate(ROBOT, poses0, varying, t_end=3.0, dt=0.1, method=method, backend="numpy")
    np.testing.assert_allclose(fast.poses, ref.poses, atol=1e-9)


def test_jax_sampled_inputs_and_record_every():
    samples = np.column_stack([np.linspace(0.5, 1.0, 20), np.linspace(0.2, -0.2, 20)])
    kwargs = {"t_end": 2.0, "dt": 0.1, "method": "rk4", "record_every": 3}
    fast = simulate(Unicycle(), [0, 0, 0], samples, backend="jax", **kwargs)
    ref = simulate(Unicycle(), [0, 0, 0], samples, backend="numpy", **kwargs)
    np.testing.assert_allclose(fast.t, ref.t)
    np.testing.assert_allclose(fast.poses, ref.poses, atol=1e-9)


@pytest.mark.parametrize("record_every", [1, 7, 40, 1000])
def test_jax_keeps_only_the_recorded_steps(record_every):
    # 33 steps: 7 and 40 do not divide it, 1000 exceeds it (only the start and end are kept).
    poses0 = np.array([[0.0, 0.0, 3.1], [1.0, -1.0, -3.1]])
    inputs = np.array([[1.0, 4.0], [0.5, -9.0]])  # fast turns: the heading wraps many times
    kwargs = {"t_end": 3.3, "dt": 0.1, "method": "exact", "record_every": record_every}
    fast = simulate(Unicycle(), poses0, inputs, backend="jax", **kwargs)
    ref = simulate(Unicycle(), poses0, inputs, backend="numpy", **kwargs)
    np.testing.assert_allclose(fast.t, ref.t)
    assert fast.poses.shape == ref.poses.shape
    np.testing.assert_allclose(fast.poses, ref.poses, atol=1e-9)
    assert np.all(np.abs(fast.poses[..., 2]) <= np.pi)


def test_jax_wraps_a_heading_that_turns_more_than_a_turn_per_step():
    kwargs = {"t_end": 2.0, "dt": 1.0, "method": "euler"}
    fast = simulate(Unicycle(), [0, 0, 0], (0.0, 10.0), backend="jax", **kwargs)
    ref = simulate(Unicycle(), [0, 0, 0], (0.0, 10.0), backend="numpy", **kwargs)
    np.testing.assert_allclose(fast.poses, ref.poses, atol=1e-9)
