"""EKF and UKF: Jacobians, agreement with each other, NEES consistency, gating, bad input."""

import math

import numpy as np
import pytest
from scipy import stats

from wheelbase.errors import ConfigError, EstimationError, InputError
from wheelbase.geometry import wrap_angle
from wheelbase.localization import (
    EKF,
    UKF,
    VelocityMotion,
    arc_move,
    chi2_gate,
    odometry_delta,
)
from wheelbase.sensors import LandmarkSensor, range_bearing

LANDMARKS = np.array([[6.0 * math.cos(a), 6.0 * math.sin(a)] for a in np.linspace(0, 6, 8)])
MOTION = VelocityMotion(
    distance_per_m=1e-3, distance_per_rad=1e-4, heading_per_m=1e-4, heading_per_rad=1e-3
)


def numeric_jacobian(f, x, eps=1e-6):
    x = np.asarray(x, float)
    cols = []
    for i in range(x.size):
        dx = np.zeros_like(x)
        dx[i] = eps
        diff = np.asarray(f(x + dx)) - np.asarray(f(x - dx))
        cols.append(diff / (2 * eps))
    return np.stack(cols, -1)


@pytest.mark.parametrize("increments", [(0.3, 0.4), (0.2, 0.0), (0.0, -0.7), (-0.5, 1e-6)])
def test_motion_jacobians_match_finite_differences(increments):
    pose = np.array([1.0, -2.0, 2.9])
    g, v = MOTION.jacobians(pose, increments)

    def wrap_theta(p):
        p = np.array(p)
        p[..., 2] = wrap_angle(p[..., 2] - 2.9) + 2.9
        return p

    g_num = numeric_jacobian(lambda p: wrap_theta(arc_move(p, increments)), pose)
    v_num = numeric_jacobian(lambda u: wrap_theta(arc_move(pose, u)), np.array(increments))
    np.testing.assert_allclose(g, g_num, atol=1e-8)
    np.testing.assert_allclose(v, v_num, atol=1e-8)


def test_range_bearing_jacobian_of_the_ekf_matches_finite_differences():
    ekf = EKF(LANDMARKS)
    mean = np.array([[0.5, 1.0, 0.3]])
    _, h, s = ekf._moments(mean, np.eye(3)[None] * 0.01, LANDMARKS[2:3], np.eye(2))
    h_num = numeric_jacobian(lambda p: range_bearing(p, LANDMARKS[2]), mean[0])
    np.testing.assert_allclose(h[0], h_num, atol=1e-8)
    np.testing.assert_allclose(s[0], h[0] @ (0.01 * np.eye(3)) @ h[0].T + np.eye(2))


def test_ekf_and_ukf_agree_when_the_belief_is_tight():
    ekf, ukf = EKF(LANDMARKS, MOTION), UKF(LANDMARKS, MOTION)
    mean = np.array([[0.5, 1.0, 3.1], [-1.0, 0.2, -3.1]])  # headings near the ±π cut
    cov = np.tile(np.diag([1e-4, 2e-4, 1e-5]), (2, 1, 1))
    control = np.array([[1.0, 0.4], [0.5, -0.8]])
    m_e, p_e = ekf.predict(mean, cov, control, 0.1)
    m_u, p_u = ukf.predict(mean, cov, control, 0.1)
    np.testing.assert_allclose(m_e, m_u, atol=1e-5)
    np.testing.assert_allclose(p_u, p_e, rtol=0.02, atol=1e-8)
    # zero noise and zero covariance: the prediction is the exact arc
    quiet = EKF(LANDMARKS, VelocityMotion(0, 0, 0, 0))
    m0, p0 = quiet.predict(mean, np.zeros((2, 3, 3)), control, 0.1)
    np.testing.assert_allclose(m0, arc_move(mean, control * 0.1))
    np.testing.assert_array_equal(p0, 0.0)
    ids = np.array([[1, 3], [0, 5]])
    z = range_bearing(m_e[:, None, :], LANDMARKS[ids]) + np.array([0.05, -0.01])
    m_e2, p_e2, info_e = ekf.update(m_e, p_e, ids, z)
    m_u2, p_u2, info_u = ukf.update(m_u, p_u, ids, z)
    assert info_e.accepted.all() and info_u.accepted.all()
    np.testing.assert_allclose(m_e2, m_u2, atol=1e-5)
    np.testing.assert_allclose(p_u2, p_e2, rtol=0.02, atol=1e-9)
    # the correction shrinks the covariance
    assert np.all(np.linalg.eigvalsh(p_e - p_e2) >= -1e-15)


def run_filters(n_runs=50, steps=120, dt=0.1, seed=0):
    """Simulate n_runs robots with the filters' own noise; NEES per step for both filters."""
    rng = np.random.default_rng(seed)
    sensor = LandmarkSensor(max_range=8.0, range_std=0.1, bearing_std=0.02)
    filters = {"ekf": EKF(LANDMARKS, MOTION, 0.1, 0.02), "ukf": UKF(LANDMARKS, MOTION, 0.1, 0.02)}
    p0 = np.diag([0.1, 0.1, 0.05]) ** 2
    truth = np.zeros((n_runs, 3))
    start = rng.multivariate_normal(np.zeros(3), p0, n_runs)
    beliefs = {name: (start.copy(), np.tile(p0, (n_runs, 1, 1))) for name in filters}
    nees = {name: np.empty((steps, n_runs)) for name in filters}
    for k in range(steps):
        control = np.array([1.0, 0.5 * math.sin(0.05 * k)])
        truth = MOTION.sample(truth, control, dt, rng)
        ids, z = sensor.observe(LANDMARKS, truth, rng).padded(n_runs)
        for name, f in filters.items():
            mean, cov = f.predict(*beliefs[name], control, dt)
            if k % 5 == 4:
                mean, cov, _ = f.update(mean, cov, ids, z)
            beliefs[name] = (mean, cov)
            e = truth - mean
            e[:, 2] = wrap_angle(e[:, 2])
            nees[name][k] = np.einsum("ni,nij,nj->n", e, np.linalg.inv(cov), e)
    return nees


def test_average_nees_over_50_runs_lies_in_the_95_percent_chi2_interval():
    nees = run_filters()
    runs = 50
    lo, hi = stats.chi2.ppf([0.025, 0.975], 3 * runs) / runs  # 2.36, 3.72
    for name, values in nees.items():
        average = values.mean(axis=1)  # over the runs, at each step
        inside = np.mean((average >= lo) & (average <= hi))
        assert inside >= 0.9, (name, inside)  # 95 % expected; steps are correlated
        assert lo < average.mean() < hi, (name, average.mean())


def test_gate_rejects_outliers_and_invalid_measurements_are_counted():
    ekf = EKF(LANDMARKS, MOTION, 0.1, 0.02, gate_probability=0.99)
    mean = np.array([0.0, 0.0, 0.0])
    cov = np.diag([0.01, 0.01, 0.001])
    good = range_bearing(mean, LANDMARKS[0])
    ids = np.array([0, 0, 1, 99, 2, -1])
    z = np.array(
        [good, good + np.array([3.0, 0.0]), [np.nan, 0.1], [4.0, 0.2], [-1.0, 0.0], [0.0, 0.0]]
    )
    new_mean, new_cov, info = ekf.update(mean, cov, ids, z)
    assert info.accepted.tolist() == [True, False, False, False, False, False]
    assert info.gated.tolist() == [False, True, False, False, False, False]
    assert info.invalid.tolist() == [False, False, True, True, True, False]
    assert info.nis[1] > chi2_gate(0.99) > info.nis[0]
    assert np.isfinite(new_mean).all() and np.isfinite(new_cov).all()
    # without a gate the outlier is applied
    _, _, open_info = EKF(LANDMARKS, MOTION, 0.1, 0.02, gate_probability=1.0).update(
        mean, cov, ids, z
    )
    assert open_info.accepted.tolist() == [True, True, False, False, False, False]
    # gated fraction of correct measurements is about 1 %
    rng = np.random.default_rng(3)
    z_true = good + rng.standard_normal((4000, 2)) * [0.1, 0.02]
    s = np.diag([0.01, 0.01 / 36.0 + 0.02**2 + 0.001]) + np.diag([0.01, 0.0])
    nis = np.einsum("ni,ij,nj->n", z_true - good, np.linalg.inv(s), z_true - good)
    assert np.mean(nis > chi2_gate(0.99)) < 0.03


@pytest.mark.parametrize("cls", [EKF, UKF])
def test_range_noise_grows_with_the_predicted_range(cls):
    # with a known pose (P = 0) the innovation covariance is R itself: σ_r = 0.01 + 0.02·r̂
    f = cls([[4.0, 0.0], [0.0, -1.0]], MOTION, 0.01, 0.05, 1.0, range_std_per_m=0.02)
    mean, cov = np.zeros(3), np.zeros((3, 3))
    z = [[4.1, 0.05], [1.1, -math.pi / 2]]
    _, _, info = f.update(mean, cov, [0, 1], z)
    assert info.nis[0] == pytest.approx(0.1**2 / 0.09**2 + 1.0, rel=1e-9)
    assert info.nis[1] == pytest.approx(0.1**2 / 0.03**2, rel=1e-9)
    # without the growth, σ_r is range_std at any range
    _, _, flat = cls([[4.0, 0.0]], MOTION, 0.01, 0.05, 1.0).update(mean, cov, [0], z[:1])
    assert flat.nis[0] == pytest.approx(0.1**2 / 0.01**2 + 1.0, rel=1e-9)
    with pytest.raises(ConfigError, match="range_std_per_m"):
        cls([[4.0, 0.0]], MOTION, 0.01, 0.05, range_std_per_m=-0.1)


@pytest.mark.parametrize("cls", [EKF, UKF])
def test_huber_weighting_equals_an_inflated_measurement_noise(cls):
    mean, cov = np.zeros(3), np.diag([0.04, 0.04, 0.01])
    z = [[4.3, 0.12]]
    robust = cls([[4.0, 0.0]], MOTION, 0.1, 0.05, 1.0, huber_k=1.5)
    m1, p1, info = robust.update(mean, cov, [0], z)
    w = 1.5 / math.sqrt(info.nis[0])
    assert w < 1.0  # the measurement lies beyond k standard deviations
    # the same as a filter whose R is divided by the weight
    plain = cls([[4.0, 0.0]], MOTION, 0.1 / math.sqrt(w), 0.05 / math.sqrt(w), 1.0)
    m2, p2, _ = plain.update(mean, cov, [0], z)
    np.testing.assert_allclose(m1, m2, atol=1e-12)
    np.testing.assert_allclose(p1, p2, atol=1e-12)
    # within k standard deviations nothing changes
    near = [[4.02, 0.01]]
    np.testing.assert_allclose(
        robust.update(mean, cov, [0], near)[0],
        cls([[4.0, 0.0]], MOTION, 0.1, 0.05, 1.0).update(mean, cov, [0], near)[0],
    )
    with pytest.raises(ConfigError, match="huber_k"):
        cls([[4.0, 0.0]], MOTION, huber_k=0.0)


def test_odometry_delta_reverses_and_composes():
    old = np.array([1.0, 2.0, 0.5])
    ahead = np.array([1.0 + math.cos(0.5), 2.0 + math.sin(0.5), 0.9])
    np.testing.assert_allclose(odometry_delta(old, ahead), [0.0, 1.0, 0.4], atol=1e-12)
    behind = np.array([1.0 - math.cos(0.5), 2.0 - math.sin(0.5), 0.5])
    np.testing.assert_allclose(odometry_delta(old, behind), [0.0, -1.0, 0.0], atol=1e-12)


def test_bad_input_and_broken_beliefs_raise_clear_errors():
    with pytest.raises(ConfigError, match="range_std"):
        EKF(LANDMARKS, range_std=0.0)
    with pytest.raises(ConfigError, match="gate_probability"):
        EKF(LANDMARKS, gate_probability=1.5)
    with pytest.raises(ConfigError, match="distance_per_m"):
        VelocityMotion(distance_per_m=-1.0)
    with pytest.raises(ConfigError, match="alpha"):
        UKF(LANDMARKS, alpha=0.0)
    with pytest.raises(InputError, match="landmarks"):
        EKF(np.zeros(3))
    ekf = EKF(LANDMARKS)
    with pytest.raises(InputError, match="mean"):
        ekf.predict([0.0, np.nan, 0.0], np.eye(3), [1.0, 0.0], 0.1)
    with pytest.raises(ConfigError, match="dt"):
        ekf.predict([0.0, 0.0, 0.0], np.eye(3), [1.0, 0.0], 0.0)
    with pytest.raises(InputError, match="ids"):
        ekf.update([0.0, 0.0, 0.0], np.eye(3), [0.5], [[1.0, 0.0]])
    with pytest.raises(InputError, match="cov of robot 0 is not positive semi-definite"):
        ekf.predict([0.0, 0.0, 0.0], -np.eye(3), [1.0, 0.0], 0.1)
    with pytest.raises(InputError, match="robot 1"):
        UKF(LANDMARKS).predict(np.zeros((2, 3)), np.stack([np.eye(3), -np.eye(3)]), [1, 0], 0.1)
    # A belief that breaks inside the filter is an EstimationError naming the filter
    broken = EKF(LANDMARKS, VelocityMotion(distance_per_m=np.finfo(float).max))
    with pytest.raises(EstimationError, match="EKF: the covariance of robot 0"):
        broken.predict([0.0, 0.0, 0.0], np.eye(3), [1e10, 0.0], 1.0)


@pytest.mark.parametrize("cls", [EKF, UKF])
def test_predict_sequence_equals_repeated_predictions(cls):
    f = cls(LANDMARKS, MOTION)
    rng = np.random.default_rng(5)
    mean = np.array([[0.5, 1.0, 3.0], [-1.0, 0.2, -2.0]])
    cov = np.tile(np.diag([1e-3, 2e-3, 1e-4]), (2, 1, 1))
    controls = np.column_stack([rng.uniform(-0.5, 1.0, 40), rng.uniform(-1, 1, 40)])
    dts = rng.uniform(0.005, 0.05, 40)
    means, covs = f.predict_sequence(mean, cov, controls, dts)
    m, p = mean, cov
    for k in range(40):
        m, p = f.predict(m, p, controls[k], dts[k])
        np.testing.assert_allclose(means[k], m, atol=1e-12)
        np.testing.assert_allclose(covs[k], p, atol=1e-15, rtol=1e-10)
    single_m, single_p = f.predict_sequence(mean[0], cov[0], controls, dts)
    np.testing.assert_allclose(single_m, means[:, 0], atol=1e-12)
    np.testing.assert_allclose(single_p, covs[:, 0], atol=1e-15)


def test_relative_motion_sampling_is_exact_without_noise_and_has_the_arc_variance():
    from wheelbase.geometry import compose

    rng = np.random.default_rng(6)
    poses = np.column_stack([rng.uniform(-3, 3, (5, 2)), rng.uniform(-3, 3, 5)])
    relative = np.array([0.4, 0.05, 0.3])
    quiet = VelocityMotion(0, 0, 0, 0).sample_relative(poses, relative, 0.5, rng)
    np.testing.assert_allclose(quiet, compose(poses, relative), atol=1e-12)
    model = VelocityMotion(0.0, 0.0, 0.0, 0.0, 0.0, heading_per_s=0.01)
    moved = model.sample_relative(np.zeros((20000, 3)), [0.0, 0.0, 0.0], 2.0, rng)
    assert moved[:, 2].std() == pytest.approx(math.sqrt(0.02), rel=0.03)


@pytest.mark.parametrize("cls", [EKF, UKF])
def test_a_noise_scale_is_a_measurement_covariance_that_many_times_larger(cls):
    marks = np.array([[2.0, 1.0], [-1.0, 3.0]])
    mean, cov = np.array([0.1, -0.2, 0.3]), np.diag([0.04, 0.03, 0.01])
    z = np.array([[2.1, 0.2], [3.0, 1.7]])
    ids = np.array([0, 1])
    base = cls(marks, range_std=0.1, bearing_std=0.02, gate_probability=1.0)
    wide = cls(marks, range_std=0.1 * 2.0, bearing_std=0.02 * 2.0, gate_probability=1.0)
    scaled = base.update(mean, cov, ids, z, noise_scale=[4.0, 4.0])
    expected = wide.update(mean, cov, ids, z)
    np.testing.assert_allclose(scaled[0], expected[0], rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(scaled[1], expected[1], rtol=1e-12, atol=1e-15)
    # a factor on one measurement only: the same as applying the two in turn
    one = base.update(mean, cov, ids[:1], z[:1], noise_scale=[1.0])
    two = wide.update(*one[:2], ids[1:], z[1:])
    mixed = base.update(mean, cov, ids, z, noise_scale=[1.0, 4.0])
    np.testing.assert_allclose(mixed[1], two[1], rtol=1e-12, atol=1e-15)
    with pytest.raises(InputError, match="noise_scale"):
        base.update(mean, cov, ids, z, noise_scale=[1.0, 0.0])
