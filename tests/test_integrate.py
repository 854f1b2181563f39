import numpy as np
import pytest
from scipy.integrate import solve_ivp

from wheelbase import METHODS, BodyTwist, ConfigError, DiffDrive, InputError, Unicycle, simulate
from wheelbase.geometry import wrap_angle
from wheelbase.integrate import integrate_step, time_grid

ROBOT = DiffDrive(wheel_radius=0.05, half_track=0.2)


def varying_inputs(t):
    return np.array([0.5 + 0.3 * np.sin(1.3 * t), 0.9 * np.cos(0.7 * t) + 0.2 * t])


def reference_end_pose(t_end):
    def rhs(t, pose):
        return ROBOT.derivative(pose, varying_inputs(t))

    solution = solve_ivp(
        rhs, (0.0, t_end), [0.1, 0.2, 0.3], rtol=1e-13, atol=1e-13, method="DOP853"
    )
    return solution.y[:, -1]


def end_error(method, dt, t_end=4.0):
    result = simulate(ROBOT, [0.1, 0.2, 0.3], varying_inputs, t_end=t_end, dt=dt, method=method)
    reference = reference_end_pose(t_end)
    diff = result.poses[-1] - reference
    diff[2] = wrap_angle(diff[2])
    return np.linalg.norm(diff)


@pytest.mark.parametrize(
    ("method", "order", "tolerance"),
    [
        ("euler", 1, 0.15),
        ("midpoint", 2, 0.2),
        ("exact", 2, 0.2),
        ("rk4", 4, 0.3),
        ("simpson", 4, 0.3),
    ],
)
def test_convergence_order_on_time_varying_inputs(method, order, tolerance):
    steps = [0.1, 0.05, 0.025]
    errors = [end_error(method, dt) for dt in steps]
    measured = np.polyfit(np.log(steps), np.log(errors), 1)[0]
    assert abs(measured - order) < tolerance, (method, measured, errors)


@pytest.mark.parametrize("method", ["exact"])
def test_exact_matches_the_arc(method):
    left, right, theta0 = 0.8, 0.6, np.pi / 2
    result = simulate(ROBOT, [0.0, 0.0, theta0], (left, right), t_end=100.0, dt=0.1, method=method)
    v, omega = ROBOT.body_velocity(left, right)
    radius = v / omega
    theta = theta0 + omega * result.t
    x = radius * (np.sin(theta) - np.sin(theta0))
    y = -radius * (np.cos(theta) - np.cos(theta0))
    np.testing.assert_allclose(result.poses[:, 0], x, atol=1e-12)
    np.testing.assert_allclose(result.poses[:, 1], y, atol=1e-12)
    np.testing.assert_allclose(wrap_angle(result.poses[:, 2] - theta), 0.0, atol=1e-12)


def test_exact_is_smooth_through_zero_yaw_rate():
    for omega in [0.0, 1e-15, 1e-9, -1e-9]:
        result = simulate(Unicycle(), [0, 0, 0], (1.0, omega), t_end=2.0, dt=0.5, method="exact")
        assert np.all(np.isfinite(result.poses))
        np.testing.assert_allclose(result.poses[-1, :2], [2.0, omega * 2.0], atol=1e-12)


@pytest.mark.parametrize("method", METHODS)
def test_numba_and_numpy_backends_agree(method):
    poses0 = np.array([[0.0, 0.0, 0.0], [1.0, -1.0, 3.0], [2.0, 0.5, -2.5]])
    inputs = np.array([[0.8, 0.6], [0.6, -0.6], [1.0, 1.0]])
    fast = simulate(ROBOT, poses0, inputs, t_end=10.0, dt=0.07, method=method)
    slow = simulate(ROBOT, poses0, inputs, t_end=10.0, dt=0.07, method=method, backend="numpy")
    np.testing.assert_allclose(fast.poses, slow.poses, atol=1e-12)

    def batch_inputs(t):
        return inputs * np.cos(0.2 * t)

    fast = simulate(ROBOT, poses0, batch_inputs, t_end=3.0, dt=0.1, method=method)
    slow = simulate(ROBOT, poses0, batch_inputs, t_end=3.0, dt=0.1, method=method, backend="numpy")
    np.testing.assert_allclose(fast.poses, slow.poses, atol=1e-12)


def test_batch_equals_single_runs_and_record_every():
    poses0 = np.array([[0.0, 0.0, 0.0], [1.0, 2.0, 1.0]])
    inputs = np.array([[0.8, 0.6], [0.3, 0.9]])
    batch = simulate(ROBOT, poses0, inputs, t_end=5.0, dt=0.1, method="rk4", record_every=7)
    assert batch.poses.shape == (len(batch.t), 2, 3)
    assert batch.t[-1] == 5.0 and batch.t[1] == pytest.approx(0.7)
    for i in range(2):
        single = simulate(ROBOT, poses0[i], inputs[i], t_end=5.0, dt=0.1, method="rk4")
        kept = np.vstack([single.poses[::7][: len(batch.t) - 1], single.poses[-1:]])
        np.testing.assert_allclose(batch.poses[:, i], kept, atol=1e-12)
        np.testing.assert_allclose(batch.robot(i).inputs[0], inputs[i])


def test_sampled_inputs_are_a_zero_order_hold():
    times = time_grid(2.0, 0.1)
    samples = np.column_stack([np.linspace(0.5, 1.0, 20), np.linspace(0.2, -0.2, 20)])
    result = simulate(Unicycle(), [0, 0, 0], samples, t_end=2.0, dt=0.1, method="exact")
    pose = np.zeros(3)
    for k in range(20):
        twist = [samples[k, 0], 0.0, samples[k, 1]]
        pose = integrate_step(pose, twist, twist, twist, 0.1, "exact")
    np.testing.assert_allclose(result.poses[-1], pose, atol=1e-12)
    np.testing.assert_allclose(result.t, times)
    np.testing.assert_allclose(result.inputs[:-1], samples)


def test_last_step_shortened_to_t_end():
    result = simulate(Unicycle(), [0, 0, 0], (1.0, 0.0), t_end=1.05, dt=0.1, method="euler")
    assert result.t[-1] == 1.05 and len(result.t) == 12
    assert result.poses[-1, 0] == pytest.approx(1.05, abs=1e-12)


def test_body_twist_program_of_document_000():
    result = simulate(
        BodyTwist(), [0, 0, np.pi / 2], (0.1, 0.05, 0.3), t_end=10.0, dt=0.1, method="exact"
    )
    # Constant twist: a circle of radius √(u²+v²)/r around a fixed centre.
    centre = np.array([-0.1, -0.05]) / 0.3  # R(π/2)·(−v, u)/r
    distance = np.linalg.norm(result.poses[:, :2] - centre, axis=1)
    np.testing.assert_allclose(distance, np.hypot(0.1, 0.05) / 0.3, atol=1e-12)


def test_to_csv_refuses_overwrite(tmp_path):
    result = simulate(ROBOT, [0, 0, 0], (0.8, 0.6), t_end=1.0, dt=0.5)
    path = result.to_csv(tmp_path / "log.csv")
    lines = path.read_text().splitlines()
    assert lines[0] == "t,x,y,theta,omega_left,omega_right"
    assert len(lines) == 4
    with pytest.raises(FileExistsError, match="overwrite=True"):
        result.to_csv(path)
    result.to_csv(path, overwrite=True)


@pytest.mark.parametrize(
    ("kwargs", "error", "match"),
    [
        ({"dt": 0.0}, ConfigError, "dt must be > 0 s"),
        ({"dt": 2.0, "t_end": 1.0}, ConfigError, "dt must be <= t_end"),
        ({"t_end": -1.0}, ConfigError, "t_end must be > 0 s"),
        ({"t_end": float("inf")}, ConfigError, "t_end must be finite"),
        ({"method": "heun"}, ConfigError, "unknown method 'heun'; allowed: 'euler'"),
        ({"backend": "gpu"}, ConfigError, "unknown backend"),
        ({"record_every": 0}, ConfigError, "record_every"),
        ({"pose0": [0, 0]}, InputError, r"pose0 must have shape \(\.\.\., 3\)"),
        ({"pose0": [0, np.nan, 0]}, InputError, "pose0 must be finite"),
        ({"inputs": (0.8, np.nan)}, InputError, "finite"),
        ({"inputs": (0.8,)}, InputError, r"shape \(\.\.\., 2\)"),
        ({"inputs": np.ones((3, 2))}, InputError, "sampled inputs need 10 rows"),
        ({"inputs": lambda t: (1.0, np.nan)}, InputError, "finite"),
        ({"inputs": lambda t: 1 / 0}, InputError, r"inputs\(0\) raised ZeroDivisionError"),
        # t_end / dt steps are bounded (1e300 s asked for "Maximum allowed size exceeded")
        ({"t_end": 1e300}, ConfigError, r"t_end / dt = 1e\+301 steps: more than max_steps"),
        ({"t_end": 2.0, "max_steps": 19}, ConfigError, r"20 steps: more than max_steps = 19"),
    ],
)
def test_bad_input_is_a_clear_error(kwargs, error, match):
    arguments = {"pose0": [0, 0, 0], "inputs": (0.8, 0.6), "t_end": 1.0, "dt": 0.1} | kwargs
    with pytest.raises(error, match=match):
        simulate(ROBOT, **arguments)


def test_step_limit_can_be_raised():
    result = simulate(ROBOT, [0, 0, 0], (0.8, 0.6), 2.0, 0.1, max_steps=20)
    assert len(result.t) == 21


def test_jax_backend_without_jax_names_the_extra(monkeypatch):
    import sys

    monkeypatch.setitem(sys.modules, "jax", None)  # as if JAX were not installed
    monkeypatch.setitem(sys.modules, "jax.numpy", None)
    with pytest.raises(ConfigError, match=r"wheelbase\[jax\]"):
        simulate(ROBOT, [0, 0, 0], (0.8, 0.6), t_end=1.0, dt=0.1, backend="jax")
