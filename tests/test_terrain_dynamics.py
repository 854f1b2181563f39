"""The robot on terrain (issue 24): the rigid limit is the existing model, energy balances,
gravity is conservative, slopes need m·g·sin α, low friction spins the wheels."""

import math

import numpy as np
import pytest

from wheelbase.dynamics import RM100, DiffDriveDynamics
from wheelbase.errors import ConfigError
from wheelbase.terrain.contact import WheelContacts
from wheelbase.terrain.dynamics import TerrainDynamics
from wheelbase.terrain.friction import FrictionCurve
from wheelbase.terrain.map import Region, TerrainMap
from wheelbase.terrain.surfaces import SURFACES, Surface

FREE_CONCRETE = SURFACES["dry_concrete"].with_values(rolling_resistance=0.0)


def _run(model, torques, steps, dt=0.01, state=None):
    s = np.zeros((1, 6)) if state is None else np.array(state, dtype=float).reshape(1, 6)
    aux = model.start(1)
    s0, aux0 = s.copy(), aux.copy()
    signals = None
    for k in range(steps):
        tau = torques(k * dt) if callable(torques) else torques
        s, aux, signals = model.step(s, aux, np.reshape(tau, (1, 2)), dt)
    return s0, aux0, s, aux, signals


def _wiggle(t):
    return np.array([1.2 + 0.8 * math.sin(1.3 * t), 1.0 + 0.9 * math.cos(0.7 * t)])


def test_rigid_contact_without_resistance_is_the_existing_step_to_the_bit():
    model = TerrainDynamics(RM100, TerrainMap.uniform(FREE_CONCRETE), slip=False)
    rng = np.random.default_rng(5)
    s_old = np.array([[1.0, -2.0, 0.3, 0.2, 0.0, -0.1]] * 3)
    s_new, aux = s_old.copy(), model.start(3)
    for _ in range(200):
        tau = rng.uniform(-2, 2, (3, 2))
        s_old = RM100.step(s_old, tau, 0.02)
        s_new, aux, _ = model.step(s_new, aux, tau, 0.02)
    assert np.array_equal(s_old, s_new)


def test_rigid_rolling_resistance_on_a_straight_line_is_the_existing_one():
    c_rr = SURFACES["dry_concrete"].rolling_resistance
    old = DiffDriveDynamics(RM100.body, RM100.wheel_radius, RM100.half_track,
                            rolling_resistance=c_rr)  # fmt: skip
    model = TerrainDynamics(
        RM100, TerrainMap.uniform(SURFACES["dry_concrete"]), slip=False, step_factor=0.05
    )
    # the smoothed resistance is stiff at rest: both integrate it finely (the new model's
    # substeps, the old one at dt/50); per contact, c_rr·N_k sum to c_rr·m·g
    s_old, s_new, aux = np.zeros((1, 6)), np.zeros((1, 6)), model.start(1)
    for k in range(300):
        tau = np.full((1, 2), 0.4 if k < 200 else -0.1)  # speed up, then brake to rest
        for _ in range(50):
            s_old = old.step(s_old, tau, 0.0002)
        s_new, aux, _ = model.step(s_new, aux, tau, 0.01)
    assert s_new == pytest.approx(s_old, abs=1e-9)


@pytest.mark.parametrize("slip", [False, True])
@pytest.mark.parametrize("name", sorted(SURFACES))
def test_energy_balance_on_every_surface(name, slip):
    # a 10 % ramp across the route, turning torques: work = ΔT + against gravity + losses
    ramp = Region([[0.3, -5], [3, -5], [3, 5], [0.3, 5]], SURFACES[name], grade=0.1, uphill=0.3)
    terrain = TerrainMap.from_regions(SURFACES[name], [ramp], bounds=(-5, -5, 8, 5),
                                      resolution=0.05)  # fmt: skip
    model = TerrainDynamics(RM100, terrain, slip=slip, step_factor=0.25)
    s0, aux0, s, aux, _ = _run(model, lambda t: 3.0 * _wiggle(t), 400)  # up to 6 N·m
    terms = model.energy_balance(s0[0], aux0[0], s[0], aux[0])
    assert terms["work"] > 1.0
    assert abs(terms["residual"]) <= 1e-6 * terms["work"]
    for loss in ("slip", "rolling", "soil", "damping"):
        assert terms[loss] >= 0.0
    if not slip:
        assert terms["slip"] == 0.0


def test_gravity_is_conservative_on_one_plane():
    slope = 0.1 / math.sqrt(1.01)
    plane = Region([[-50, -50], [50, -50], [50, 50], [-50, 50]], FREE_CONCRETE, 0.1, 0.8)
    terrain = TerrainMap.from_regions(FREE_CONCRETE, [plane], resolution=1.0)
    for slip in (False, True):
        model = TerrainDynamics(RM100, terrain, slip=slip)
        _, aux0, s, aux, _ = _run(model, _wiggle, 500)
        xc, yc = RM100.body.cg_offset  # the CG rises, not B
        cg = [s[0, 0] + math.cos(s[0, 2]) * xc - math.sin(s[0, 2]) * yc - xc,
              s[0, 1] + math.sin(s[0, 2]) * xc + math.cos(s[0, 2]) * yc - yc]  # fmt: skip
        rise = slope * (math.cos(0.8) * cg[0] + math.sin(0.8) * cg[1])
        work_against = -(aux[0, 9] - aux0[0, 9])
        assert work_against == pytest.approx(RM100.body.mass * 9.80665 * rise, rel=1e-7)


def test_holding_on_a_ramp_takes_m_g_sin_alpha_a_over_two_per_wheel():
    ramp = Region([[-50, -50], [50, -50], [50, 50], [-50, 50]], FREE_CONCRETE, 0.1, 0.0)
    terrain = TerrainMap.from_regions(FREE_CONCRETE, [ramp], resolution=1.0)
    hold = RM100.body.mass * 9.80665 * math.sin(math.atan(0.1)) * RM100.wheel_radius / 2
    rigid = TerrainDynamics(RM100, terrain, slip=False)
    _, _, s, _, _ = _run(rigid, [hold, hold], 300)
    assert np.abs(s[0, 3:]).max() < 1e-12 and np.abs(s[0, :2]).max() < 1e-12
    _, _, s_less, _, _ = _run(rigid, [0.9 * hold, 0.9 * hold], 100)
    assert s_less[0, 3] < -0.01  # less rolls back down
    # with slip it creeps (the regularised slip at standstill) by less than 1 mm/s
    slipping = TerrainDynamics(RM100, terrain, slip=True)
    _, _, s_slip, _, signals = _run(slipping, [hold, hold], 300)
    assert abs(s_slip[0, 3]) < 1e-3
    assert signals[0, 2] + signals[0, 3] == pytest.approx(2 * hold / RM100.wheel_radius, rel=1e-3)


def test_on_ice_the_wheels_spin_and_on_concrete_they_grip():
    for name, spinning in (("ice", True), ("dry_concrete", False)):
        model = TerrainDynamics(RM100, TerrainMap.uniform(SURFACES[name]))
        _, _, s, _, signals = _run(model, [1.5, 1.5], 100)
        slip = signals[0, :2]
        if spinning:
            assert np.all(slip > 1.0)
            # traction is the load times the friction curve at that slip, past its peak
            mu = signals[0, 2:4] / signals[0, 4:6]
            assert mu == pytest.approx(SURFACES["ice"].friction.mu(slip), rel=1e-9)
            assert np.all(mu < 0.071)
        else:
            assert np.all(slip < 0.05)
            # u = (F − c_rr·m·g)·t / (m + 2 J_w(1 + κ)/a²): the spinning wheels add inertia
            a, m, jw = RM100.wheel_radius, RM100.body.mass, 0.01
            expected = (3.0 / a - 0.013 * m * 9.80665) * 1.0 / (m + 2 * jw / a**2)
            assert s[0, 3] == pytest.approx(expected, rel=5e-3)  # κ ≈ 0.02 left out


def test_split_friction_yaws_towards_the_slippery_side():
    # left wheel on ice (y > 0 side), right on concrete: the right wheel pushes, it turns left
    ice = Region([[-5, 0.0], [5, 0.0], [5, 5], [-5, 5]], SURFACES["ice"])
    terrain = TerrainMap.from_regions(SURFACES["dry_concrete"], [ice], bounds=(-5, -5, 5, 5),
                                      resolution=0.02)  # fmt: skip
    model = TerrainDynamics(RM100, terrain)
    _, _, s, _, signals = _run(model, [1.5, 1.5], 50)
    assert s[0, 5] > 0.1
    assert terrain.names[int(signals[0, 8])] == "ice"
    assert terrain.names[int(signals[0, 9])] == "dry_concrete"


def test_pure_rolling_is_the_limit_of_high_grip_and_light_wheels():
    # open-loop torques for 1.5 s: the gap to rolling contact shrinks with the wheels' spin
    # inertia (≈ ∝ J_w) and with the grip
    rigid = TerrainDynamics(RM100, TerrainMap.uniform(FREE_CONCRETE), slip=False)
    _, _, s_rigid, _, _ = _run(rigid, _wiggle, 150)

    def gap(peak, peak_slip, inertia):
        grip = Surface("grip", FrictionCurve(peak, peak, peak_slip))
        model = TerrainDynamics(RM100, TerrainMap.uniform(grip),
                                WheelContacts(wheel_inertia=inertia))  # fmt: skip
        _, _, s, _, _ = _run(model, _wiggle, 150)
        return np.hypot(*(s[0, :2] - s_rigid[0, :2]))

    errors = [gap(1.5, 0.05, inertia) for inertia in (1e-2, 3e-3, 1e-3)]
    assert errors[0] > errors[1] > errors[2]
    assert errors[2] < 0.15 * errors[0]
    assert gap(3.0, 0.02, 1e-3) < gap(0.85, 0.16, 1e-3) < 1.5 * errors[2]


def test_soft_sand_holds_the_rm100_and_loam_lets_a_field_robot_go():
    sand = TerrainDynamics(RM100, TerrainMap.uniform(SURFACES["dry_sand"]))
    _, _, s, _, signals = _run(sand, [5.0, 5.0], 300)
    assert s[0, 0] < 0.05  # 3 s at the torque limit: dug in
    assert np.all(signals[0, 6:8] > 0.02)  # centimetres of sinkage


def test_terrain_dynamics_refuses_what_it_cannot_model():
    with pytest.raises(ConfigError, match="constrained"):
        TerrainDynamics(DiffDriveDynamics(RM100.body, 0.065, 0.2, constrained=False),
                        TerrainMap.uniform(FREE_CONCRETE))  # fmt: skip
    with pytest.raises(ConfigError, match="rolling_resistance"):
        TerrainDynamics(DiffDriveDynamics(RM100.body, 0.065, 0.2, rolling_resistance=0.01),
                        TerrainMap.uniform(FREE_CONCRETE))  # fmt: skip
    with pytest.raises(ConfigError, match="step_factor"):
        TerrainDynamics(RM100, TerrainMap.uniform(FREE_CONCRETE), step_factor=3.0)


@pytest.mark.parametrize("name", ["dry_sand", "sandy_loam"])
def test_each_drive_wheel_pulls_with_janosi_thrust_at_wongs_slip(name):
    # the plant's soil traction at Wong's slip i = 1 − v/(a·ω), against Bekker's sinkage and
    # Janosi–Hanamoto's thrust written out here from Wong (eqs. 2.36, 2.56, 2.62), and the
    # body's drag against the compaction resistance b·k·z₀^(n+1)/(n+1)
    soil = SURFACES[name].soil
    model = TerrainDynamics(RM100, TerrainMap.uniform(SURFACES[name]), slip_speed=1e-4)
    a, b = RM100.wheel_radius, model.contacts.wheel_width
    speed = 0.5
    n, k_c, k_phi = soil.n, soil.k_c, soil.k_phi
    for i in (0.05, 0.2, 0.5, 0.8):
        omega = speed / (a * (1.0 - i))
        aux = model.start(1)
        aux[0, :2] = omega
        aux[0, 12] = 1.0  # the wheel rates are set: no start from the twist
        state = np.array([[0.0, 0.0, 0.0, speed, 0.0, 0.0]])
        _s, _aux, signals = model.step(state, aux, np.zeros((1, 2)), 1e-9)
        load = signals[0, 4]
        z0 = (3 * load / ((3 - n) * (k_c + b * k_phi) * math.sqrt(2 * a))) ** (2 / (2 * n + 1))
        length = a * math.acos(1 - z0 / a)
        strength = b * length * soil.cohesion + load * math.tan(soil.friction_angle)
        x = i * length / soil.shear_modulus
        janosi = strength * (1 - (1 - math.exp(-x)) / x)
        assert signals[0, 6] == pytest.approx(z0, rel=1e-9)
        assert signals[0, 2] == pytest.approx(janosi, rel=1e-6)
