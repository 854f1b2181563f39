"""Ground models (issue 24): friction curves, soils (Bekker, Wong, Janosi–Hanamoto), surfaces,
terrain maps, payloads and the regressor of the dynamics in the inertial parameters."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.integrate import quad

from wheelbase.dynamics import RM100, RigidBody
from wheelbase.errors import ConfigError
from wheelbase.inertial import (
    Payload,
    body_from_parameters,
    inertial_parameters,
    regressor,
    with_payload,
)
from wheelbase.terrain.contact import RM100_CONTACTS, WheelContacts, normal_loads
from wheelbase.terrain.friction import FrictionCurve
from wheelbase.terrain.map import Region, TerrainMap, grade_slope
from wheelbase.terrain.soil import (
    SOILS,
    Soil,
    compaction_resistance,
    contact_length,
    drawbar_pull,
    sinkage,
    thrust,
    wong_reece,
)
from wheelbase.terrain.surfaces import SURFACES, Surface


# --------------------------------------------------------------------------- friction
@pytest.mark.parametrize("name", ["dry_concrete", "wet_concrete", "ice", "grass"])
def test_friction_curve_peaks_at_the_table_values(name):
    curve = SURFACES[name].friction
    s = np.linspace(0.0, 1.0, 200_001)
    mu = curve.mu(s)
    assert mu.max() == pytest.approx(curve.peak, rel=1e-9)
    assert s[np.argmax(mu)] == pytest.approx(curve.peak_slip, abs=1e-5)
    assert curve.mu(1.0) == pytest.approx(curve.sliding, rel=1e-12)
    # odd in the slip, slope B·C·D at zero
    assert curve.mu(-0.3) == pytest.approx(-curve.mu(0.3))
    assert (curve.mu(1e-8) / 1e-8) == pytest.approx(curve.slip_stiffness, rel=1e-6)


def test_friction_table_values_are_the_sources():
    # Wong's table of road adhesion (peak, sliding); Burckhardt's peak slips
    assert (SURFACES["dry_concrete"].friction.peak, SURFACES["dry_concrete"].friction.sliding) == (
        0.85,
        0.75,
    )
    assert (SURFACES["ice"].friction.peak, SURFACES["ice"].friction.sliding) == (0.1, 0.07)
    assert SURFACES["dry_concrete"].friction.peak_slip == pytest.approx(
        math.log(1.1973 * 25.168 / 0.5373) / 25.168
    )


@pytest.mark.parametrize(
    ("peak", "sliding", "slip", "match"),
    [(0.0, 0.1, 0.1, "peak"), (-0.5, 0.1, 0.1, "peak"), (0.8, 0.9, 0.1, "sliding"),
     (0.8, 0.0, 0.1, "sliding"), (0.8, 0.7, 1.2, "peak_slip"), (0.8, 0.2, 0.3, "too low"),
     (math.nan, 0.2, 0.3, "peak")],
)  # fmt: skip
def test_friction_curve_refuses_bad_coefficients(peak, sliding, slip, match):
    with pytest.raises(ConfigError, match=match):
        FrictionCurve(peak, sliding, slip)


# --------------------------------------------------------------------------- soil
def test_soils_are_wongs_table_2_3():
    sand, loam = SOILS["dry_sand"], SOILS["sandy_loam"]
    assert (sand.n, sand.k_c, sand.k_phi, sand.cohesion) == (1.1, 990.0, 1528430.0, 1040.0)
    assert sand.friction_angle == pytest.approx(math.radians(28.0))
    assert (loam.n, loam.k_c, loam.k_phi, loam.cohesion) == (0.7, 5270.0, 1515040.0, 1720.0)


@pytest.mark.parametrize("name", ["dry_sand", "sandy_loam", "clay"])
def test_compaction_resistance_equals_wongs_closed_form_in_the_load(name):
    soil, w, a, b = SOILS[name], 120.0, 0.1, 0.06
    n, d = soil.n, 2 * a
    e = (2 * n + 2) / (2 * n + 1)
    closed = (3 * w / math.sqrt(d)) ** e / (
        (3 - n) ** e * (n + 1) * (soil.k_c + b * soil.k_phi) ** (1 / (2 * n + 1))
    )
    assert float(compaction_resistance(w, a, b, soil)) == pytest.approx(closed, rel=1e-12)


def test_sinkage_carries_the_load_on_a_parabolic_rim_for_n_1():
    # Bekker's ∫(1 − t²)ⁿdt ≈ (3 − n)/3 is exact for n = 1: W = b·k·∫(z₀ − x²/D)dx exactly
    soil = Soil(1.0, 2e3, 8e5, 1e3, 0.5, 0.02)
    w, a, b = 200.0, 0.15, 0.08
    z0 = float(sinkage(w, a, b, soil))
    d = 2 * a
    carried = b * soil.modulus(b) * quad(lambda x: z0 - x * x / d, 0, math.sqrt(d * z0))[0]
    assert carried == pytest.approx(w, rel=1e-12)


def test_thrust_is_the_janosi_shear_integrated_over_the_contact():
    soil, w, a, b, i = SOILS["sandy_loam"], 90.0, 0.1, 0.05, 0.23
    length = float(contact_length(sinkage(w, a, b, soil), a))
    p = w / (b * length)

    def tau(x):
        strength = soil.cohesion + p * math.tan(soil.friction_angle)
        return strength * (1 - math.exp(-i * x / soil.shear_modulus))

    assert float(thrust(w, i, a, b, soil)) == pytest.approx(b * quad(tau, 0, length)[0], rel=1e-10)
    # and it rises from 0 at zero slip to the Mohr–Coulomb strength A·c + W·tan φ
    strength = b * length * soil.cohesion + w * math.tan(soil.friction_angle)
    assert float(thrust(w, 0.0, a, b, soil)) == 0.0
    assert float(thrust(w, 1e6, a, b, soil)) == pytest.approx(strength, rel=1e-5)


@pytest.mark.parametrize("slip", [0.1, 0.2, 0.3, 0.5])
def test_closed_form_drawbar_pull_is_near_wong_reece_stress_integrals(slip):
    # a 1 m wheel, where Bekker's equations hold (D > 0.5 m): within 0.1 of the load
    soil, w, a, b = SOILS["sandy_loam"], 5000.0, 0.5, 0.3
    closed = float(drawbar_pull(w, slip, a, b, soil))
    full = wong_reece(w, slip, a, b, soil).drawbar_pull
    assert abs(closed - full) / w < 0.1
    assert full > 0 and closed > 0


@pytest.mark.parametrize(
    ("field", "value", "match"),
    [("n", -1.0, "soil n"), ("n", 2.5, "soil n"), ("k_phi", 0.0, "k_phi"),
     ("cohesion", -5.0, "cohesion"), ("friction_angle", 1.2, "friction_angle"),
     ("shear_modulus", 0.0, "shear_modulus"), ("k_c", math.inf, "k_c")],
)  # fmt: skip
def test_soil_refuses_values_outside_physical_ranges(field, value, match):
    values = dict(n=1.0, k_c=1e3, k_phi=1e6, cohesion=1e3, friction_angle=0.5, shear_modulus=0.01)
    values[field] = value
    with pytest.raises(ConfigError, match=match):
        Soil(**values)


def test_surface_needs_friction_or_soil_and_a_sane_rolling_resistance():
    with pytest.raises(ConfigError, match="either"):
        Surface("nothing")
    with pytest.raises(ConfigError, match="rolling_resistance"):
        SURFACES["ice"].with_values(rolling_resistance=-0.1)
    with pytest.raises(ConfigError, match="no friction curve"):
        SURFACES["dry_sand"].with_values(peak=0.5)
    assert SURFACES["ice"].with_values(peak=0.2).friction.peak == 0.2


# --------------------------------------------------------------------------- contacts
def test_normal_loads_balance_the_weight_and_the_tipping_moments():
    layout = RM100_CONTACTS.layout(0.2275)
    weight, cg, h, t = 500.0, (0.03, -0.02), 0.12, (40.0, -25.0)
    loads = normal_loads(RM100_CONTACTS, 0.2275, weight, cg, h, t)
    assert loads.sum() == pytest.approx(weight)
    assert loads @ layout[:, 0] == pytest.approx(weight * cg[0] - h * t[0])
    assert loads @ layout[:, 1] == pytest.approx(weight * cg[1] - h * t[1])
    # accelerating unloads the front casters, turning left (T_y > 0) the left wheel
    rest = normal_loads(RM100_CONTACTS, 0.2275, weight)
    forward = normal_loads(RM100_CONTACTS, 0.2275, weight, tangential=(50.0, 0.0))
    left = normal_loads(RM100_CONTACTS, 0.2275, weight, tangential=(0.0, 50.0))
    assert forward[2] < rest[2] and forward[4] > rest[4]
    assert left[0] < rest[0] < left[1]
    assert rest[:2].sum() == pytest.approx(RM100_CONTACTS.drive_load_share * weight)


def test_contacts_refuse_a_robot_that_would_tip():
    with pytest.raises(ConfigError, match="off the drive axle"):
        WheelContacts(casters=((0.0, 0.2),))
    with pytest.raises(ConfigError, match="drive_load_share"):
        WheelContacts(drive_load_share=1.0)


# --------------------------------------------------------------------------- maps
def _square(x0, y0, size):
    return [[x0, y0], [x0 + size, y0], [x0 + size, y0 + size], [x0, y0 + size]]


def test_terrain_map_from_regions_paints_surfaces_and_slopes():
    ice = Region(_square(1.0, 1.0, 2.0), SURFACES["ice"])
    ramp = Region(_square(4.0, 0.0, 2.0), SURFACES["dry_concrete"], grade=0.1, uphill=0.5)
    terrain = TerrainMap.from_regions(
        SURFACES["dry_concrete"], [ice, ramp], bounds=(0, 0, 8, 4), resolution=0.1
    )
    names = terrain.names
    assert names[int(terrain.index([2.0, 2.0]))] == "ice"
    assert names[int(terrain.index([0.5, 0.5]))] == "dry_concrete"
    assert int(terrain.index([100.0, 100.0])) == 0  # outside the raster: the default
    slope = terrain.slope_at([5.0, 1.0])
    assert np.hypot(*slope) == pytest.approx(0.1 / math.sqrt(1.01))
    assert math.atan2(slope[1], slope[0]) == pytest.approx(0.5)
    assert np.all(terrain.slope_at([2.0, 2.0]) == 0.0)


def test_overlapping_regions_must_agree():
    a = Region(_square(0.0, 0.0, 2.0), SURFACES["ice"])
    b = Region(_square(1.0, 1.0, 2.0), SURFACES["grass"])
    same = Region(_square(1.0, 1.0, 2.0), SURFACES["ice"])
    with pytest.raises(ConfigError, match="regions 0 and 1 overlap"):
        TerrainMap.from_regions(SURFACES["dry_concrete"], [a, b], resolution=0.1)
    TerrainMap.from_regions(SURFACES["dry_concrete"], [a, same], resolution=0.1)


def test_grade_beyond_100_percent_is_refused():
    with pytest.raises(ConfigError, match="grade"):
        grade_slope(1.5, 0.0)
    with pytest.raises(ConfigError, match="grade"):
        Region(_square(0, 0, 1), SURFACES["ice"], grade=-0.1)


# --------------------------------------------------------------------------- payload
def test_payload_combines_by_the_parallel_axis_theorem():
    body = RM100.body
    payload = Payload(13.1, (0.10, -0.05), inertia=0.2)
    both = with_payload(body, payload)
    assert both.mass == pytest.approx(39.3)
    cg = (np.array(body.cg_offset) * body.mass + np.array(payload.position) * 13.1) / 39.3
    assert both.cg_offset == pytest.approx(tuple(cg))
    # about B the inertias simply add: I_B' = I_B + I_p + m_p|p|²
    assert both.inertia_centroid == pytest.approx(
        body.inertia_centroid + 0.2 + 13.1 * (0.10**2 + 0.05**2)
    )
    assert with_payload(body, None) is body


@settings(max_examples=40, deadline=None)
@given(
    st.floats(0.1, 80.0), st.floats(-0.3, 0.3), st.floats(-0.2, 0.2), st.floats(0.0, 2.0),
    st.lists(st.floats(-2, 2), min_size=6, max_size=6),
)  # fmt: skip
def test_dynamics_are_linear_in_the_inertial_parameters(mass, x, y, inertia, motion):
    body = RM100.body
    payload = Payload(mass, (x, y), inertia)
    both = with_payload(body, payload)
    alone = RigidBody(mass, max(inertia, 1e-9), (x, y))
    theta = inertial_parameters(both)
    # θ adds: the payload's θ is what an estimator must learn
    assert theta == pytest.approx(inertial_parameters(body) + inertial_parameters(alone), abs=1e-8)
    velocity, acceleration = np.array(motion[:3]), np.array(motion[3:])
    y_matrix = regressor(velocity, acceleration)
    assert y_matrix @ theta == pytest.approx(both.inverse(velocity, acceleration), abs=1e-8)
    assert body_from_parameters(theta).inertia == pytest.approx(both.inertia, abs=1e-9)


def test_payload_refuses_negative_values_and_positions_off_the_robot():
    with pytest.raises(ConfigError, match="payload mass"):
        Payload(-1.0)
    with pytest.raises(ConfigError, match="payload inertia"):
        Payload(1.0, inertia=-0.1)
    with pytest.raises(ConfigError, match="outside the robot's footprint"):
        Payload(5.0, (0.5, 0.0)).check_footprint(0.66, 0.455)
    Payload(5.0, (0.3, 0.2)).check_footprint(0.66, 0.455)


@pytest.mark.parametrize("name", ["dry_sand", "sandy_loam"])
def test_drawbar_pull_against_slip_is_wongs_closed_form(name):
    # DP/W against slip for the benchmark's 1 m, 0.3 m wide wheel under 5 kN, written out from
    # Wong ch. 2 with Table 2.3's values in the table's units (kN/m^(n+1), kN/m^(n+2), kPa)
    table = {"dry_sand": (1.1, 0.99, 1528.43, 1.04, 28.0), "sandy_loam": (0.7, 5.27, 1515.04,
                                                                          1.72, 29.0)}  # fmt: skip
    n, k_c, k_phi, c, phi = table[name]
    k_c, k_phi, c = 1e3 * k_c, 1e3 * k_phi, 1e3 * c
    big_k = SOILS[name].shear_modulus
    w, a, b = 5000.0, 0.5, 0.3
    z0 = (3 * w / ((3 - n) * (k_c + b * k_phi) * math.sqrt(2 * a))) ** (2 / (2 * n + 1))
    r_c = b * (k_c / b + k_phi) * z0 ** (n + 1) / (n + 1)
    length = a * math.acos(1 - z0 / a)
    strength = b * length * c + w * math.tan(math.radians(phi))
    slips = np.array([0.05, 0.1, 0.2, 0.3, 0.5, 0.8])
    expected = (strength * (1 - big_k / (slips * length) * (1 - np.exp(-slips * length / big_k)))
                - r_c) / w  # fmt: skip
    ours = drawbar_pull(w, slips, a, b, SOILS[name]) / w
    assert np.allclose(ours, expected, rtol=1e-12, atol=0)
    assert np.all(np.diff(ours) > 0)  # pull grows with slip towards (A·c + W·tan φ − R_c)/W
    assert ours[-1] < (strength - r_c) / w
