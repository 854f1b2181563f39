"""Rigid-body dynamics (document 000 §3.3, §5.1): derivation, energy, forward cases, errors."""

import math

import numpy as np
import pytest
import sympy as sp
from hypothesis import given, settings
from hypothesis import strategies as st

from wheelbase.dynamics import (
    RM100,
    RM100_HALF_TRACK,
    DiffDriveDynamics,
    RigidBody,
    simulate_dynamics,
)
from wheelbase.errors import ConfigError, InputError

BODY = RigidBody(mass=26.2, inertia=1.14, cg_offset=(0.01, -0.03))
FREE = DiffDriveDynamics(BODY, wheel_radius=0.065, half_track=0.2, constrained=False)
vel = st.floats(-2, 2, allow_nan=False)


# --------------------------------------------------------------------------- derivation
def _symbolic_world_forces():
    """Euler–Lagrange in world coordinates q = (X, Y, ψ) of B: Q(q, q̇, q̈) (independent)."""
    t = sp.symbols("t")
    m, iz, xb, yb = sp.symbols("m I_z x_bc y_bc", positive=True)
    big_x, big_y, psi = (sp.Function(n)(t) for n in ("X", "Y", "psi"))
    xc = big_x + sp.cos(psi) * xb - sp.sin(psi) * yb
    yc = big_y + sp.sin(psi) * xb + sp.cos(psi) * yb
    kinetic = sp.Rational(1, 2) * m * (xc.diff(t) ** 2 + yc.diff(t) ** 2)
    kinetic += sp.Rational(1, 2) * iz * psi.diff(t) ** 2
    forces = [sp.diff(kinetic.diff(q.diff(t)), t) - kinetic.diff(q) for q in (big_x, big_y, psi)]
    qs = [big_x, big_y, psi]
    syms = sp.symbols("x y p xd yd pd xdd ydd pdd")
    subs = {}
    for q, s0, s1, s2 in zip(qs, syms[:3], syms[3:6], syms[6:], strict=True):
        subs[q.diff(t, 2)] = s2
        subs[q.diff(t)] = s1
        subs[q] = s0
    exprs = [sp.simplify(f.subs(subs)) for f in forces]
    return sp.lambdify((*syms, m, iz, xb, yb), exprs, "numpy")


def test_inverse_dynamics_matches_independent_symbolic_lagrangian():
    forces = _symbolic_world_forces()
    rng = np.random.default_rng(3)
    body = BODY
    for _ in range(20):
        q, qd, qdd = rng.normal(size=(3, 3))
        psi, psid = q[2], qd[2]
        c, s = math.cos(psi), math.sin(psi)
        # body twist V = Jᵀ(ψ)·q̇ and its derivative V̇ = Jᵀq̈ + J̇ᵀq̇
        rt = np.array([[c, s], [-s, c]])
        drt = psid * np.array([[-s, c], [-c, -s]])
        twist = np.r_[rt @ qd[:2], psid]
        twist_rate = np.r_[rt @ qdd[:2] + drt @ qd[:2], qdd[2]]
        world = np.array(
            forces(*q, *qd, *qdd, body.mass, body.inertia, *body.cg_offset), dtype=float
        )
        expected = np.r_[rt @ world[:2], world[2]]  # body force = Jᵀ Q
        np.testing.assert_allclose(body.inverse(twist, twist_rate), expected, atol=1e-10)


@given(vel, vel, vel)
def test_coriolis_is_skew_symmetric_and_does_no_work(u, v, r):
    c = BODY.coriolis([u, v, r])
    np.testing.assert_allclose(c, -c.T, atol=0)
    assert abs(np.array([u, v, r]) @ c @ np.array([u, v, r])) < 1e-12


def test_printed_coriolis_matrix_is_not_skew_and_the_corrected_one_is():
    """Document 000 prints C = r·[[0, −m, m x_bc], [m, 0, m y_bc], [m x_bc, m y_bc, 0]]."""
    m, (xb, yb) = BODY.mass, BODY.cg_offset
    r = 0.7
    printed = r * np.array([[0, -m, m * xb], [m, 0, m * yb], [m * xb, m * yb, 0]])
    assert not np.allclose(printed, -printed.T)
    twist = np.array([0.4, 0.1, r])
    assert abs(twist @ printed @ twist) > 1e-3  # the printed form would do work
    assert abs(twist @ BODY.coriolis(twist) @ twist) < 1e-14


@given(vel, vel, vel, vel, vel, vel)
@settings(max_examples=50)
def test_forward_inverts_inverse(u, v, r, fx, fy, mz):
    acc = BODY.forward([u, v, r], [fx, fy, mz])
    np.testing.assert_allclose(BODY.inverse([u, v, r], acc), [fx, fy, mz], atol=1e-9)


@pytest.mark.parametrize("dyn", [FREE, DiffDriveDynamics(BODY, 0.065, 0.2)])
def test_kinetic_energy_is_conserved_without_torque(dyn):
    v0 = 0.0 if dyn.constrained else 0.2
    state0 = [0.0, 0.0, 0.3, 0.5, v0, 0.8]
    out = simulate_dynamics(dyn, (0.0, 0.0), t_end=200.0, dt=1.0, state0=state0,
                            rtol=1e-12, atol=1e-13)  # fmt: skip
    energy = BODY.kinetic_energy(out.twists)
    assert np.max(np.abs(energy - energy[0])) < 1e-9 * energy[0]
    assert out.twists[:, 1].any() != dyn.constrained  # the free body skids, the other not


def test_unconstrained_diffdrive_agrees_with_rigid_body_forward():
    state = np.array([0.0, 0.0, 0.0, 0.3, -0.05, 0.4])
    tau = np.array([0.2, -0.1])
    acc, fy = FREE.acceleration(state[3:], tau)
    np.testing.assert_allclose(acc, BODY.forward(state[3:], FREE.body_force(tau)), atol=1e-12)
    assert fy == 0.0


@given(vel, vel, vel, vel)
@settings(max_examples=50)
def test_constrained_acceleration_equals_projected_dynamics(u, r, tl, tr):
    """With v = 0 the constrained accelerations satisfy rows 1 and 3 of M V̇ + C V = τ, and
    row 2 gives the reported lateral constraint force."""
    dyn = DiffDriveDynamics(BODY, 0.065, 0.2)
    acc, fy = dyn.acceleration([u, 0.0, r], [tl, tr])
    assert acc[1] == 0.0
    force = BODY.inverse([u, 0.0, r], acc)
    expected = dyn.body_force([tl, tr])
    np.testing.assert_allclose(force[[0, 2]], expected[[0, 2]], atol=1e-9)
    np.testing.assert_allclose(force[1], fy, atol=1e-9)


@given(vel, vel, vel, vel)
def test_wheel_torques_round_trip(tl, tr, u, r):
    force = RM100.body_force([tl, tr])
    np.testing.assert_allclose(RM100.wheel_torques(force), [tl, tr], atol=1e-12)
    # power balance: wheel torque · wheel speed = body force · twist (τ* = Wᵀτ)
    omega = np.array([(u - RM100.half_track * r), (u + RM100.half_track * r)]) / 0.065
    assert math.isclose(np.dot([tl, tr], omega), np.dot(force, [u, 0, r]), abs_tol=1e-9)


def test_inverse_then_forward_reproduces_acceleration_with_resistance():
    dyn = DiffDriveDynamics(BODY, 0.065, 0.2, linear_damping=2.0, angular_damping=0.5,
                            rolling_resistance=0.02)  # fmt: skip
    twist, rate = np.array([0.4, 0.0, -0.3]), np.array([0.05, 0.0, 0.2])
    _, torques = dyn.inverse(twist, rate)
    acc, _ = dyn.acceleration(twist, torques)
    np.testing.assert_allclose(acc, rate, atol=1e-12)


# --------------------------------------------------------------------------- §5.1 forward cases
def test_case1_equal_torques_drive_straight_with_constant_acceleration():
    out = simulate_dynamics(RM100, (0.01, 0.01), t_end=60.0, dt=0.5)
    acc = 0.02 / 0.065 / 26.2
    np.testing.assert_allclose(out.states[:, 0], 0.5 * acc * out.t**2, rtol=1e-9, atol=1e-12)
    assert np.all(out.states[:, [1, 2, 4, 5]] == 0.0)


def test_case2_larger_right_torque_turns_left():
    """r > 0 and the path bends left; with x_bc > 0 the moment −m·x_bc·r·u (the centrifugal
    force on the CG ahead of the axle) opposes the yaw, so r peaks and falls as u grows."""
    out = simulate_dynamics(RM100, (0.01, 0.012), t_end=30.0, dt=0.5)
    assert np.all(out.states[1:, 5] > 0) and np.all(out.states[1:, 1] > 0)
    assert np.argmax(out.states[:, 5]) < out.t.size - 1
    centred = simulate_dynamics(RM100.with_body(RigidBody(26.2, 1.14)), (0.01, 0.012), 30.0, 0.5)
    assert np.all(np.diff(centred.states[:, 5]) > 0)


def test_case3_right_torque_zero_turns_right():
    out = simulate_dynamics(RM100, (0.01, 0.0), t_end=30.0, dt=0.5)
    assert out.states[-1, 5] < 0 and out.states[-1, 1] < 0


def test_case4_opposite_torques_turn_in_place_except_for_the_cg_offset():
    """With x_bc = 0 the robot spins in place; with the RM100's x_bc = 1 cm the wheels cannot
    supply the centripetal force on the CG, so B creeps forward with u̇ = x_bc·r²."""
    centred = RM100.with_body(RigidBody(26.2, 1.14))
    out = simulate_dynamics(centred, (0.01, -0.01), t_end=30.0, dt=0.5)
    assert np.all(out.states[:, :2] == 0.0) and out.states[-1, 5] < 0
    off = simulate_dynamics(RM100, (0.01, -0.01), t_end=6.0, dt=0.5)
    rdot = -2 * RM100.half_track * 0.01 / 0.065 / RM100.body.inertia_centroid
    # early on (m·x_bc·r·u ≪ M_z): r = ṙ₀t and u̇ = x_bc r²  →  u(t) = x_bc ṙ₀² t³ / 3
    np.testing.assert_allclose(off.states[:, 5], rdot * off.t, rtol=2e-3)
    np.testing.assert_allclose(off.states[:, 3], 0.01 * rdot**2 * off.t**3 / 3, rtol=2e-3)
    acc, fy = RM100.acceleration(off.twists, off.torques)
    np.testing.assert_allclose(acc[:, 0], 0.01 * off.states[:, 5] ** 2, rtol=1e-12)
    np.testing.assert_allclose(off.lateral_force, fy, rtol=1e-12)


@pytest.mark.parametrize("method", ["euler", "rk4", "DOP853"])
def test_fixed_step_and_adaptive_integrators_agree(method):
    ref = simulate_dynamics(RM100, (0.01, 0.012), t_end=40.0, dt=0.05, rtol=1e-11, atol=1e-12)
    out = simulate_dynamics(RM100, (0.01, 0.012), t_end=40.0, dt=0.05, method=method)
    tol = 2e-2 if method == "euler" else 1e-8  # euler: first order, error ≈ 1.5 cm here
    np.testing.assert_allclose(out.states, ref.states, atol=tol)


def test_batch_sampled_and_callable_torques_match():
    dt, n_steps = 0.1, 100
    tau = np.column_stack([0.01 * np.ones(n_steps), 0.01 + 0.002 * np.sin(np.arange(n_steps))])
    single = simulate_dynamics(RM100, tau, t_end=10.0, dt=dt, method="rk4")
    called = simulate_dynamics(RM100, lambda t, s: tau[min(round(t / dt), n_steps - 1)],
                               t_end=10.0, dt=dt, method="rk4")  # fmt: skip
    np.testing.assert_allclose(called.states, single.states, atol=1e-14)
    batch = simulate_dynamics(RM100, np.stack([tau, tau[:, ::-1]], 1), t_end=10.0, dt=dt,
                              method="rk4", state0=np.zeros((2, 6)))  # fmt: skip
    np.testing.assert_allclose(batch.states[:, 0], single.states, atol=1e-14)
    np.testing.assert_allclose(batch.states[:, 1, 1], -single.states[:, 1], atol=1e-12)
    adaptive = simulate_dynamics(RM100, tau, t_end=10.0, dt=dt)
    np.testing.assert_allclose(adaptive.states, single.states, atol=1e-8)


def test_rm100_preset():
    assert RM100.body.mass == 26.2 and RM100.body.inertia == 1.14
    assert RM100.body.cg_offset == (0.01, 0.0) and RM100.wheel_radius == 0.065
    assert RM100.half_track == RM100_HALF_TRACK == 0.2275 and RM100.constrained


# --------------------------------------------------------------------------- bad input
@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"mass": 0.0, "inertia": 1.0}, "mass"),
        ({"mass": 1.0, "inertia": -1.0}, "inertia"),
        ({"mass": 1.0, "inertia": math.nan}, "inertia"),
        ({"mass": 10.0, "inertia": 0.01, "cg_offset": (0.1, 0.0), "inertia_about": "centroid"},
         "too small for the CG offset"),
        ({"mass": 1.0, "inertia": 1.0, "inertia_about": "wheel"}, "inertia_about"),
    ],
)  # fmt: skip
def test_bad_rigid_body(kwargs, match):
    with pytest.raises(ConfigError, match=match):
        RigidBody(**kwargs)


def test_inertia_about_centroid_uses_parallel_axes():
    body = RigidBody(10.0, 1.0, (0.1, 0.2), inertia_about="centroid")
    assert math.isclose(body.inertia, 1.0 - 10.0 * 0.05)
    assert math.isclose(body.inertia_centroid, 1.0)


def test_bad_diffdrive_and_simulation_inputs():
    with pytest.raises(ConfigError, match="half_track"):
        DiffDriveDynamics(BODY, 0.065, 0.0)
    with pytest.raises(ConfigError, match="linear_damping"):
        DiffDriveDynamics(BODY, 0.065, 0.2, linear_damping=-1.0)
    with pytest.raises(ConfigError, match="method"):
        simulate_dynamics(RM100, (0.0, 0.0), 1.0, 0.1, method="heun")
    with pytest.raises(InputError, match="lateral speed"):
        simulate_dynamics(RM100, (0.0, 0.0), 1.0, 0.1, state0=[0, 0, 0, 0, 0.1, 0])
    with pytest.raises(InputError, match="torques"):
        simulate_dynamics(RM100, (0.0, math.inf), 1.0, 0.1)
    with pytest.raises(InputError, match="rows"):
        simulate_dynamics(RM100, np.zeros((3, 2)), 1.0, 0.1)
    with pytest.raises(InputError, match="raised"):
        simulate_dynamics(RM100, lambda t, s: 1 / 0, 1.0, 0.1)


def test_dynamics_command_writes_the_simulated_states(tmp_path):
    import typer
    from typer.testing import CliRunner

    from wheelbase.commands.dynamics import register

    app = typer.Typer()

    @app.callback()
    def _main() -> None:
        """Test app."""

    register(app)
    out = tmp_path / "dyn"
    args = ["dynamics", "--out", str(out), "--torques", "0.01", "0.012", "--t-end", "20",
            "--dt", "0.5", "--no-gif"]  # fmt: skip
    result = CliRunner().invoke(app, args)
    assert result.exit_code == 0, result.output
    rows = np.loadtxt(out / "dynamics.csv", delimiter=",", skiprows=1)
    expected = simulate_dynamics(RM100, (0.01, 0.012), 20.0, 0.5)
    np.testing.assert_allclose(rows[:, 1:7], expected.states, rtol=1e-8, atol=1e-12)
    assert (out / "path.png").stat().st_size > 0 and not (out / "animation.gif").exists()
    bad = CliRunner().invoke(app, ["dynamics", "--out", str(out), "--method", "leapfrog",
                                   "--force"])  # fmt: skip
    assert bad.exit_code != 0 and "method" in str(bad.exception)


def test_adaptive_solver_work_is_bounded(monkeypatch):
    # 1e7 N·m for 2 s took 3 million RK45 evaluations (wheelbase dynamics --torques 1e9 0.5
    # hung; found by the fuzz suite): past the bound, one clear error
    from wheelbase import dynamics

    monkeypatch.setattr(dynamics, "MAX_EVALUATIONS", 20_000)
    with pytest.raises(InputError, match="RK45 took more than 20000 evaluations"):
        simulate_dynamics(RM100, (1e7, 0.5), t_end=2.0, dt=0.1)
    assert simulate_dynamics(RM100, (0.01, 0.01), t_end=2.0, dt=0.1).states.shape == (21, 6)
