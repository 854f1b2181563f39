"""A reference slowed to the friction (traction control's slow_down): closed forms, invariants
and the demo on ice in the closed loop."""

import copy

import numpy as np
import pytest

from wheelbase.control.friction_timing import (
    MIN_RATE,
    FrictionTiming,
    force_terms,
    friction_profile,
)
from wheelbase.dynamics import GRAVITY, RM100, DiffDriveDynamics, RigidBody
from wheelbase.errors import InputError
from wheelbase.runner import prepare, run_metrics
from wheelbase.scenario import load_scenario
from wheelbase.terrain import SURFACES

# a body without CG offset or resistances: the closed forms hold exactly
PLAIN = DiffDriveDynamics(RigidBody(mass=20.0, inertia=1.0), wheel_radius=0.1, half_track=0.25)
SHARE, MU, S = 0.64, 0.1, 0.5


def _grip(model, n):
    return np.full((n, 2), SHARE * MU * S * model.body.mass * GRAVITY / 2)


def _rows(times, u, r, du, dr):
    rows = np.zeros((times.size, 9))
    rows[:, 3], rows[:, 5], rows[:, 6], rows[:, 8] = u, r, du, dr
    return rows


def _use(terms, z, w, model, grip):
    """The largest share of each wheel's circle the slowed reference uses."""
    fx = terms[:, 0:2] * z[:, None] + terms[:, 2:4] * w[:, None] + terms[:, 4:6]
    fy = 0.5 * (terms[:, 6] * z + terms[:, 7] * w)
    return np.hypot(fx, fy[:, None]) / grip


def _slope(times, z):
    w = np.zeros_like(z)
    w[:-1] = np.diff(z) / (2 * np.diff(times))
    return w


def test_a_straight_start_accelerates_at_the_friction_circle():
    # the reference asks 1 m/s² from rest to 1 m/s; the friction gives share·μ·s·g
    times = np.arange(0, 3.0, 0.002)
    u = np.minimum(times, 1.0)
    rows = _rows(times, u, 0.0, np.where(times < 1.0, 1.0, 0.0), 0.0)
    terms = force_terms(PLAIN, rows)
    z = friction_profile(times, terms, _grip(PLAIN, times.size), start=0.0)
    speed = np.sqrt(z) * u
    a = SHARE * MU * S * GRAVITY
    # along the path s = ∫u dτ (the clock's own), v² = 2·a·s while it accelerates
    path = np.concatenate([[0.0], np.cumsum(0.5 * (u[1:] + u[:-1]) * np.diff(times))])
    accelerating = (path > 0.05) & (speed < 0.99 * speed.max())
    assert speed[accelerating] ** 2 == pytest.approx(2 * a * path[accelerating], rel=0.01)
    assert speed.max() == pytest.approx(1.0)  # and reaches the reference's speed
    use = _use(terms, z, _slope(times, z), PLAIN, _grip(PLAIN, times.size))
    assert use[:-1].max() <= 1.0 + 1e-6
    assert z.max() <= 1.0


def test_an_arc_at_constant_speed_is_driven_at_the_lateral_limit():
    # u²κ ≤ share·μ·s·g: z = share·μ·s·g/(u·r) in the middle of the arc, braking before it
    times = np.arange(0, 20.0, 0.01)
    u, r = 0.6, np.where((times > 8) & (times < 14), 1.0 / 0.6, 0.0)
    rows = _rows(times, u, r, 0.0, 0.0)
    terms = force_terms(PLAIN, rows)
    z = friction_profile(times, terms, _grip(PLAIN, times.size), start=1.0)
    middle = (times > 9) & (times < 13)
    assert z[middle] == pytest.approx(SHARE * MU * S * GRAVITY / (u * (1 / 0.6)), rel=1e-6)
    assert z[times < 1].min() == 1.0  # full speed far from the arc
    before = (times > 6) & (times < 8)
    assert np.all(np.diff(z[before]) <= 1e-12) and z[before][0] > z[before][-1]
    use = _use(terms, z, _slope(times, z), PLAIN, _grip(PLAIN, times.size))
    assert use[:-1].max() <= 1.0 + 1e-6


@pytest.mark.parametrize("seed", range(4))
def test_every_sample_of_a_random_reference_stays_within_every_wheel_circle(seed):
    # the RM100 (CG offset) on turns, spins and accelerations the friction cannot give
    rng = np.random.default_rng(seed)
    times = np.arange(0, 10.0, 0.01)
    knots = rng.uniform(-1, 1, (6, 2)) * [0.8, 1.5]
    u = np.interp(times, np.linspace(0, 10, 6), knots[:, 0])
    r = np.interp(times, np.linspace(0, 10, 6), knots[:, 1])
    rows = _rows(times, u, r, np.gradient(u, times), np.gradient(r, times))
    terms = force_terms(RM100, rows)
    grip = _grip(RM100, times.size)
    z = friction_profile(times, terms, grip, start=1.0)
    assert np.all((z >= MIN_RATE**2) & (z <= 1.0))
    use = _use(terms, z, _slope(times, z), RM100, grip)
    assert use[:-1].max() <= 1.0 + 1e-6


def test_the_force_terms_are_the_inverse_dynamics_of_the_scaled_reference():
    rng = np.random.default_rng(7)
    rows = np.zeros((5, 9))
    rows[:, 3:9] = rng.normal(size=(5, 6)) * 0.5
    rows[:, 4] = 0.0
    z, w = 0.37, -0.21
    velocity = np.sqrt(z) * rows[:, 3:6]
    acceleration = z * rows[:, 6:9] + w * rows[:, 3:6]
    force, torques = RM100.inverse(velocity, acceleration)
    terms = force_terms(RM100, rows)
    # without resistances the model's torques are α z + β w (γ: the resistance, at √z → 1)
    resist = RM100.inverse(rows[:, 3:6], rows[:, 6:9])[1] - RM100.wheel_torques(
        RM100.body.inverse(rows[:, 3:6], rows[:, 6:9])
    )
    body = torques - RM100.wheel_torques(
        RM100.inverse(velocity, acceleration)[0] - RM100.body.inverse(velocity, acceleration)
    )
    a = RM100.wheel_radius
    assert body / a == pytest.approx(terms[:, 0:2] * z + terms[:, 2:4] * w, abs=1e-12)
    assert resist / a == pytest.approx(terms[:, 4:6], abs=1e-12)
    assert force[:, 1] == pytest.approx(terms[:, 6] * z + terms[:, 7] * w, abs=1e-12)


def test_the_clock_keeps_the_path_and_scales_the_speeds():
    times = np.arange(0, 4.0, 0.01)
    rows = _rows(times, 0.5, 2.0, 0.0, 0.0)  # an arc too fast for the friction
    rows[:, 0] = 0.5 * times
    timing = FrictionTiming(PLAIN, times, rows, share=SHARE, drive_load_share=S)
    timing.plan(MU)
    out = [timing.advance(t) for t in np.arange(0, 3.0, 0.01)]
    row = out[-1]
    rate = np.sqrt(SHARE * MU * S * GRAVITY / (0.5 * 2.0))
    assert row[3] == pytest.approx(rate * 0.5, rel=1e-6)
    assert row[5] == pytest.approx(rate * 2.0, rel=1e-6)
    assert timing.clock == pytest.approx(rate * 2.99, rel=1e-3)
    assert row[0] == pytest.approx(0.5 * timing.clock, rel=1e-9)


def test_bad_profiles_are_refused():
    times = np.arange(3.0)
    terms = np.zeros((3, 8))
    with pytest.raises(InputError, match="increase"):
        friction_profile(times[::-1], terms, np.ones((3, 2)))
    with pytest.raises(InputError, match="grip"):
        friction_profile(times, terms, np.zeros((3, 2)))
    with pytest.raises(InputError, match="start"):
        friction_profile(times, terms, np.ones((3, 2)), start=2.0)
    with pytest.raises(InputError, match="one row per sample"):
        friction_profile(times, terms[:2], np.ones((3, 2)))


# --------------------------------------------------------------------------- closed loop
def _energy_residual(prepared, log):
    model = prepared.engine.plant.model
    e, n = log.extras, int(log.length[0])
    work = e["energy_work_wheels"][0, n - 1] - e["energy_work_wheels"][0, 0]
    state = np.column_stack([log.true_pose[0, :n], log.twist[0, :n]])
    aux = np.zeros((n, 13))
    aux[:, :2] = log.wheel_rates[0, :n]
    kinetic = model.kinetic_energy(state[[0, n - 1]], aux[[0, n - 1]])
    spent = kinetic[1] - kinetic[0]
    for name in ("slip", "rolling", "soil", "damping"):
        spent += e[f"energy_dissipated_{name}"][0, n - 1] - e[f"energy_dissipated_{name}"][0, 0]
    spent -= e["energy_work_gravity"][0, n - 1] - e["energy_work_gravity"][0, 0]
    return abs(work - spent) / work


def test_the_demo_on_ice_arrives_with_traction_control_slowing_down():
    # without it the demo skids wide of its turns into a rack; with the torques clipped alone
    # it lags and skids (collision); slowed to the map's friction it arrives, the wheels below
    # ice's peak slip, the energy balanced
    data = load_scenario("demo").model_dump(mode="json")
    data["terrain"] = {"surface": "ice"}
    data["odometry"]["slip_compensation"] = True
    data["controller"]["traction_control"] = {"friction": "map", "slow_down": True}
    prepared = prepare(copy.deepcopy(data))
    log = prepared.engine.run(prepared.start, seeds=[prepared.scenario.seed])
    metrics = run_metrics(prepared, log, 0)
    assert metrics["status"] == "arrived"
    assert metrics["max_slip"] <= SURFACES["ice"].friction.peak_slip
    assert metrics["final_position_error_true_m"] <= 0.05
    assert metrics["duration_s"] > metrics["trajectory_duration_s"]  # slower than asked
    assert _energy_residual(prepared, log) <= 1e-6
    timing = prepared.engine.controller.timing
    assert timing.clock == pytest.approx(timing.times[-1])


def test_the_demo_on_grass_drives_its_route_with_traction_control_slowing_down():
    # grass grips with μ_p 0.24 and resists with c_rr 0.10: when traction control counted the
    # wheels' rolling moment against the grip the RM100 moved 9 mm and ended stuck; the moment
    # is the torque's, so it drives the whole route, below grass's peak slip, energy balanced
    grass = SURFACES["grass"]
    data = load_scenario("demo").model_dump(mode="json")
    data["terrain"] = {"surface": "grass"}
    data["controller"]["traction_control"] = {"friction": "map", "slow_down": True}
    prepared = prepare(copy.deepcopy(data))
    log = prepared.engine.run(prepared.start, seeds=[prepared.scenario.seed])
    metrics = run_metrics(prepared, log, 0)
    assert metrics["status"] != "collision"
    assert metrics["distance_travelled_m"] >= 0.95 * metrics["path_length_m"]
    assert metrics["max_slip"] <= 0.5 * grass.friction.peak_slip
    assert metrics["final_position_error_estimated_m"] <= 0.1  # grass's odometry drift: the rest
    assert _energy_residual(prepared, log) <= 1e-6
    timing = prepared.engine.controller.timing
    assert timing.clock == pytest.approx(timing.times[-1])  # its slowed clock ran to the end


def test_the_casters_resist_along_their_own_velocity_a_turn_on_the_spot_by_hand():
    # casters of load N_c = (1 − s)·m·g/C resist with c_rr·N_c along their velocity: straight
    # ahead the two drive wheels each push c_rr·(1 − s)·m·g/2; on the spot at r > 0 each caster
    # at distance ρ from B resists with the moment c_rr·N_c·ρ, which the wheels overcome with
    # ∓ c_rr·N_c·Σρ/(2d) (left backward, right forward) and no net push
    from wheelbase.control.traction import TractionControl
    from wheelbase.dynamics import RM100
    from wheelbase.terrain import RM100_CONTACTS

    class Law:
        command_names = ("tau_left", "tau_right")

        def __call__(self, t, state, reference):
            return np.zeros((np.shape(state)[0], 2))

    casters = np.array(RM100_CONTACTS.casters)
    control = TractionControl(
        Law(), RM100, friction=0.2, rolling_resistance=0.1, casters=casters, slow_down=True
    )
    weight = 0.5 * RM100.body.mass * GRAVITY
    rows = np.zeros((2, 9))
    rows[0, 3] = 0.5  # straight ahead
    rows[1, 5] = 1.0  # on the spot, counter-clockwise
    forces = control._caster_forces(rows)
    assert forces[0] == pytest.approx([0.1 * weight / 2] * 2)
    rho = np.hypot(casters[:, 0], casters[:, 1]).sum()
    turn = 0.1 * weight / len(casters) * rho / (2 * RM100.half_track)
    assert forces[1] == pytest.approx([-turn, turn])
    bare = TractionControl(Law(), RM100, friction=0.2, rolling_resistance=0.1)
    assert bare._caster_forces(rows)[0] == pytest.approx(forces[0])  # without casters: the push
