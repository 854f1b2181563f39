"""Encoders and dead reckoning (document 003 §III): closed forms, identities, drift orders."""

import math

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from wheelbase.errors import ConfigError, InputError
from wheelbase.geometry import wrap_angle
from wheelbase.odometry import (
    DEAD_RECKONING_METHODS,
    Encoder,
    WheelOdometry,
    dead_reckon,
    ticks_to_distance,
    ticks_to_rpm,
    unwrap_ticks,
)
from wheelbase.odometry.drift import CurvyDrive, drift_table
from wheelbase.odometry.error_model import OdometryErrors

R, D = 0.05, 0.15


def arc(pose, v, omega, h):
    """Closed-form circular arc (ICC formula), independent of wheelbase.geometry.se2_exp."""
    x, y, th = pose
    if omega == 0.0:
        return np.array([x + v * h * math.cos(th), y + v * h * math.sin(th), th])
    rho = v / omega
    th1 = th + omega * h
    return np.array(
        [x + rho * (math.sin(th1) - math.sin(th)), y - rho * (math.cos(th1) - math.cos(th)), th1]
    )


def test_exact_arc_update_equals_true_pose_on_arcs_to_1e_9():
    rng = np.random.default_rng(3)
    h, n = 0.05, 400
    pose = np.array([0.3, -0.2, 0.4])
    truth = [pose]
    wheel_speeds = np.repeat(rng.uniform(-4.0, 12.0, size=(8, 2)), n // 8, axis=0)  # rad/s
    for left, right in wheel_speeds:
        v, omega = 0.5 * R * (left + right), 0.5 * R * (right - left) / D
        truth.append(arc(truth[-1], v, omega, h))
    truth = np.array(truth)
    angles = np.concatenate([[[0.0, 0.0]], np.cumsum(wheel_speeds * h, axis=0)])
    encoder = Encoder(2**40)  # a perfect encoder at high resolution
    ticks = unwrap_ticks(encoder.measure(angles), None)
    odo = WheelOdometry(R, D, 2**40, method="exact")
    est = odo.integrate(pose, ticks)
    assert np.max(np.abs(est[:, :2] - truth[:, :2])) < 1e-9
    assert np.max(np.abs(wrap_angle(est[:, 2] - truth[:, 2]))) < 1e-9
    # The step-by-step update gives the same poses as the vectorised stream.
    step = pose
    for k in range(20):
        step = odo.update(step, ticks[k])
    np.testing.assert_allclose(step, est[20], atol=1e-12)
    # Euler and midpoint are not exact on the same arcs.
    for method in ("euler", "midpoint"):
        other = WheelOdometry(R, D, 2**40, method=method).integrate(pose, ticks)
        assert np.max(np.abs(other[:, :2] - truth[:, :2])) > 1e-6


def test_euler_is_document_003_equations_1_to_5_as_printed():
    odo = WheelOdometry(R, D, 1000, method="euler")
    pose = np.array([1.0, 2.0, 0.3])
    ticks = np.array([300, 500])
    d_left, d_right = 2 * math.pi * R * 300 / 1000, 2 * math.pi * R * 500 / 1000  # eq. 7
    d_c = (d_left + d_right) / 2  # eq. 1
    phi = (d_right - d_left) / (2 * D)  # eq. 2
    expected = [1.0 + d_c * math.cos(0.3), 2.0 + d_c * math.sin(0.3), 0.3 + phi]  # eqs. 3-5
    np.testing.assert_allclose(odo.update(pose, ticks), expected, atol=1e-15)


def test_methods_agree_on_straight_lines_and_share_the_heading():
    ticks = np.array([[100, 100], [250, 250], [40, 90]])
    results = {
        m: WheelOdometry(R, D, 1024, method=m).integrate([0, 0, 1.0], ticks)
        for m in DEAD_RECKONING_METHODS
    }
    for m in DEAD_RECKONING_METHODS:
        np.testing.assert_allclose(results[m][:3], results["exact"][:3], atol=1e-15)
        np.testing.assert_allclose(results[m][:, 2], results["exact"][:, 2], atol=1e-15)


@settings(max_examples=60, deadline=None)
@given(
    theta=st.floats(-math.pi, math.pi),
    d_left=st.floats(-2.0, 2.0),
    d_right=st.floats(-2.0, 2.0),
)
def test_exact_update_is_the_icc_arc(theta, d_left, d_right):
    ppr = 2**20
    ticks = np.array([d_left, d_right]) / (2 * math.pi * R) * ppr
    odo = WheelOdometry(R, D, ppr, method="exact")
    d_l, d_r = odo.wheel_distances(ticks)
    v, omega = (d_l + d_r) / 2, (d_r - d_l) / (2 * D)
    assume(abs(omega) > 1e-3)  # the ICC formula cancels badly near straight lines (tested apart)
    expected = arc([0.0, 0.0, theta], v, omega, 1.0)
    got = odo.update([0.0, 0.0, theta], ticks)
    np.testing.assert_allclose(got[:2], expected[:2], atol=1e-9)
    assert abs(wrap_angle(got[2] - expected[2])) < 1e-12


def test_dead_reckon_from_v_omega_matches_wheel_odometry():
    rng = np.random.default_rng(0)
    t = np.cumsum(rng.uniform(0.005, 0.02, 300))
    v, omega = rng.uniform(0, 0.5, 300), rng.uniform(-1, 1, 300)
    dt = np.diff(t)
    left = (v[:-1] - D * omega[:-1]) * dt / R  # wheel angles per interval
    right = (v[:-1] + D * omega[:-1]) * dt / R
    ticks = np.stack([left, right], -1) / (2 * math.pi)  # one "tick" per revolution
    for method in DEAD_RECKONING_METHODS:
        from_ticks = WheelOdometry(R, D, 1, method=method).integrate([1, 1, 1], ticks)
        from_v = dead_reckon(t, v, omega, [1, 1, 1], method=method)
        np.testing.assert_allclose(from_v, from_ticks, atol=1e-12)


def test_dead_reckon_batch_axis():
    t = np.linspace(0, 2, 21)
    v = np.stack([np.full(21, 0.3), np.full(21, 0.1)], -1)
    omega = np.stack([np.full(21, 0.5), np.zeros(21)], -1)
    poses = dead_reckon(t, v, omega, [[0, 0, 0], [1, 0, 0]])
    assert poses.shape == (21, 2, 3)
    np.testing.assert_allclose(poses[-1, 1], [1.2, 0.0, 0.0], atol=1e-15)
    single = dead_reckon(t, v[:, 0], omega[:, 0], [0, 0, 0])
    np.testing.assert_allclose(poses[:, 0], single, atol=1e-15)


def test_drift_orders_euler_first_midpoint_and_exact_second():
    table = drift_table(rates_hz=(10.0, 20.0), duration=60.0)
    err = {(r["rate_hz"], r["method"]): r["max_position_error_m"] for r in table}
    assert err[(10.0, "exact")] < err[(10.0, "midpoint")] < err[(10.0, "euler")]
    assert 1.6 < err[(10.0, "euler")] / err[(20.0, "euler")] < 2.5
    assert 3.2 < err[(10.0, "exact")] / err[(20.0, "exact")] < 5.0
    assert 3.2 < err[(10.0, "midpoint")] / err[(20.0, "midpoint")] < 5.0
    # With exact wheel angles the heading is exact for every method.
    assert all(r["final_heading_error_rad"] < 1e-9 for r in table)


def test_curvy_drive_wheel_angles_are_consistent_with_its_heading():
    drive = CurvyDrive()
    t = np.linspace(0, 30, 7)
    angles = drive.wheel_angles(t)
    heading = R * (angles[:, 1] - angles[:, 0]) / (2 * drive.half_track)
    np.testing.assert_allclose(heading, drive.heading(t), atol=1e-12)


# ------------------------------------------------------------------ encoders
def test_eq6_and_eq7_generalised_to_any_period():
    assert ticks_to_rpm(20, 20, 1.0) == pytest.approx(60.0)  # eq. 6 as printed, T = 1 s
    assert ticks_to_rpm(20, 20, 0.1) == pytest.approx(600.0)
    # eq. 7: distance per second = 2π r RPM/60; over T seconds → 2π r Δn/P.
    rpm = ticks_to_rpm(37, 360, 0.25)
    assert ticks_to_distance(37, 360, R) == pytest.approx(2 * math.pi * R * rpm / 60 * 0.25)
    odo = WheelOdometry(R, D, 360)
    v, omega = odo.velocity([36, 72], 0.5)
    assert omega == pytest.approx((0.2 - 0.1) * 2 * math.pi * R / (2 * D) / 0.5)
    assert v == pytest.approx(0.5 * (0.1 + 0.2) * 2 * math.pi * R / 0.5)
    np.testing.assert_allclose(odo.wheel_rpm([36, 72], 0.5), [12.0, 24.0])


@settings(max_examples=50, deadline=None)
@given(
    bits=st.integers(4, 32),
    steps=st.lists(st.integers(-(2**62), 2**62), min_size=1, max_size=40),
    start=st.integers(0, 2**40),
)
def test_counter_wrap_is_undone_by_the_reader(bits, steps, start):
    half = 2 ** (bits - 1)
    deltas = np.array([s % (2 * half - 1) - half + 1 for s in steps], dtype=np.int64)
    counts = start + np.concatenate([[0], np.cumsum(deltas)])
    raw = counts % (2**bits)
    np.testing.assert_array_equal(unwrap_ticks(raw, bits), deltas)


def test_encoder_quantisation_and_wrap():
    encoder = Encoder(100, counter_bits=8)
    angles = 2 * math.pi * np.array([0.0, 0.004, 0.011, 1.0, 2.0, 3.555])
    raw = encoder.measure(angles)
    np.testing.assert_array_equal(raw, np.array([0, 0, 1, 100, 200, 355]) % 256)
    # 155 ticks between two reads exceed 2^(8-1): the documented limit, it aliases to -101.
    np.testing.assert_array_equal(unwrap_ticks(raw, 8), [0, 1, 99, 100, -101])


def test_encoder_random_errors_are_seeded_and_have_the_right_rates():
    angles = np.linspace(0.0, 2 * math.pi * 1000, 101)  # 1000 revolutions, 100 reads
    missing = Encoder(1000, miss_probability=0.1, seed=4)
    a, b = missing.measure(angles), missing.measure(angles)
    np.testing.assert_array_equal(a, b)
    assert a[-1] / 1e6 == pytest.approx(0.9, abs=0.005)
    extra = Encoder(1000, extra_probability=0.02, seed=5).measure(angles)
    assert extra[-1] / 1e6 == pytest.approx(1.02, abs=0.002)
    noisy = Encoder(1000, noise_std=3.0, seed=6)
    deltas = np.diff(noisy.measure(angles)) - 10000
    assert 2.0 < deltas.std() < 4.0
    backwards = Encoder(1000, miss_probability=0.5, seed=1).measure(-angles)
    assert -1e6 < backwards[-1] < -0.4e6


def test_systematic_error_model():
    errors = OdometryErrors(diameter_ratio=1.01, track_ratio=1.05)
    left, right = errors.wheel_radii(R)
    assert right / left == pytest.approx(1.01)
    assert (left + right) / 2 == pytest.approx(R)
    dc, phi = errors.ground_increments(R, D, [[1.0, 1.0]])
    assert phi[0] == pytest.approx((right - left) / (2 * 1.05 * D))
    slipping = OdometryErrors(slip_std=0.1)
    dc, phi = slipping.ground_increments(R, D, np.ones((4000, 2)), np.random.default_rng(0))
    assert dc.mean() == pytest.approx(R, rel=0.01)
    assert 0.04 < phi.std() * 2 * D / R < 0.2


# ------------------------------------------------------------------ bad input
@pytest.mark.parametrize("ppr", [0, -5, 2.5, float("nan")])
def test_bad_pulses_per_revolution(ppr):
    with pytest.raises(ConfigError, match="pulses_per_revolution"):
        Encoder(ppr)
    with pytest.raises(ConfigError, match="pulses_per_revolution"):
        WheelOdometry(R, D, ppr)


def test_bad_inputs():
    with pytest.raises(ConfigError, match="period"):
        ticks_to_rpm(10, 100, 0.0)
    with pytest.raises(ConfigError, match="period"):
        WheelOdometry(R, D, 100).velocity([1, 2], 0.0)
    with pytest.raises(InputError, match="sampling period"):
        dead_reckon([0.0, 0.1, 0.1], [1, 1, 1], [0, 0, 0], [0, 0, 0])
    with pytest.raises(ConfigError, match="method"):
        WheelOdometry(R, D, 100, method="rk4")
    with pytest.raises(ConfigError, match="half_track"):
        WheelOdometry(R, -0.1, 100)
    with pytest.raises(ConfigError, match="counter_bits"):
        Encoder(100, counter_bits=1)
    with pytest.raises(ConfigError, match="miss_probability"):
        Encoder(100, miss_probability=1.0)
    with pytest.raises(InputError, match="ticks"):
        WheelOdometry(R, D, 100).update([0, 0, 0], [1, 2, 3])
    with pytest.raises(ConfigError, match="diameter_ratio"):
        OdometryErrors(diameter_ratio=0.0)
