"""Scenarios with sensors and localisation: the keys, the runner, metrics, CSV and drawing."""

import json
import math

import numpy as np
import pytest

from wheelbase.errors import ScenarioError
from wheelbase.report import animate_run, sensing_overlay, write_report
from wheelbase.runner import run, run_seeds
from wheelbase.scenario import load_scenario
from wheelbase.sim import KalmanLocalizer, ParticleLocalizer

AISLE = {
    "name": "aisle",
    "map": "warehouse",
    "robot": {"model": "diffdrive", "preset": "rm100"},
    "controller": {"law": "kanayama"},
    "odometry": {"tick_noise_std": 0.3, "wheel_radius_scale": [1.0, 1.01]},
    "start": [3.0, 2.0, 0.0],
    "goal": [8.0, 2.5, 0.0],
    "trajectory": {"max_speed": 0.8, "max_acceleration": 0.8},
    "goal_tolerance": [0.03, 5.0],
    "dt": 0.02,
}
LIDAR = {"lidar": {"beams": 60, "max_range": 8.0, "range_std": 0.02, "rate_hz": 10}}
LANDMARKS = {
    "landmarks": {
        "positions": [[3.0, 0.5], [6.0, 0.5], [9.0, 0.5], [5.0, 3.5], [8.0, 3.8], [11.0, 3.5]],
        "max_range": 6.0,
        "range_std": 0.05,
        "bearing_std_deg": 2.0,
        "rate_hz": 5,
    }
}


def scenario(method, sensors, **localization):
    return {**AISLE, "sensors": sensors, "localization": {"method": method, **localization}}


@pytest.fixture(scope="module")
def amcl_result():
    return run(scenario("amcl", LIDAR, min_particles=200, max_particles=600))


def test_odometry_alone_misses_where_amcl_arrives(amcl_result):
    alone = run(scenario("odometry", {}))
    assert alone.metrics["status"] == "missed_goal"  # 1 % one-wheel error over 5 m
    assert alone.metrics["localization_max_error_m"] > 0.05
    m = amcl_result.metrics
    assert m["status"] == "arrived" and m["localization"] == "amcl"
    # a filter's final error is its own, not an odometry drift
    assert "odometry_drift_m" not in m and m["localization_final_error_m"] < 0.04
    assert "odometry_drift_m" in alone.metrics and "localization_final_error_m" not in alone.metrics
    assert m["localization_rms_error_m"] < 0.02 and m["localization_max_error_m"] < 0.04
    assert m["localization_updates"] > 10 and m["localization_beams_used"] > 40 * 10
    # of the 60 beams each update chooses, those not used are skipped (max-range readings)
    assert (
        m["localization_beams_used"] + m["localization_beams_skipped"]
        == 60 * m["localization_updates"]
    )
    assert isinstance(amcl_result.sensors.lidar.beams, int)


@pytest.mark.parametrize("method", ["ekf", "ukf"])
def test_kalman_filters_on_landmarks_arrive(method):
    result = run(scenario(method, LANDMARKS))
    m = result.metrics
    assert m["status"] == "arrived" and m["localization_max_error_m"] < 0.03
    assert m["localization_landmarks_used"] > 20
    # the filter keeps its covariance: the 3σ bound covers the error most of the time
    log = result.log
    error = np.hypot(*(log.true_pose[0, :, :2] - log.estimated_pose[0, :, :2]).T)
    sigma = np.sqrt(log.extras["est_cov_xx"][0] + log.extras["est_cov_yy"][0])
    assert np.mean(error <= 3 * sigma) > 0.95


def test_report_has_the_estimate_covariance_and_draws_what_the_robot_senses(amcl_result, tmp_path):
    write_report(amcl_result, tmp_path, gif=False)
    metrics = json.loads((tmp_path / "metrics.json").read_text())
    assert {"localization_rms_error_m", "localization_max_error_m"} <= set(metrics)
    header = (tmp_path / "log.csv").read_text().splitlines()[0].split(",")
    for column in ("est_x", "est_cov_xx", "est_cov_xy", "est_cov_thetatheta", "loc_particles"):
        assert column in header
    assert load_scenario(tmp_path / "scenario.yaml") == amcl_result.scenario  # round trip
    log, lidar = amcl_result.log, amcl_result.sensors.lidar
    overlay = sensing_overlay(log, lidar)
    row = min(row for _, row in log.scans)
    drawn = overlay(row)
    beams = drawn["tab:red"]
    assert len(beams) == lidar.beams
    ends = np.array([beam[1] for beam in beams])
    expected = lidar.endpoints(log.true_pose[0, row], log.scans[(0, row)])
    np.testing.assert_allclose(ends, expected)
    particle_row = min(row for _, row in log.particles)
    assert len(overlay(particle_row)["tab:green"]) <= 300
    short = log.robot(0)
    path = animate_run(amcl_result.grid, None, short, (0.66, 0.455, 0.0), tmp_path / "a.gif",
                       frames=4, lidar=lidar)  # fmt: skip
    assert path.stat().st_size > 0


def test_kalman_overlay_is_the_three_sigma_ellipse():
    result = run(scenario("ekf", LANDMARKS))
    log = result.log
    k = len(log.t) // 2
    (ellipse,) = sensing_overlay(log)(k)["tab:blue"]
    cov = np.array([[log.extras["est_cov_xx"][0, k], log.extras["est_cov_xy"][0, k]],
                    [log.extras["est_cov_xy"][0, k], log.extras["est_cov_yy"][0, k]]])  # fmt: skip
    offset = ellipse - log.estimated_pose[0, k, :2]
    mahalanobis = np.einsum("ni,ij,nj->n", offset, np.linalg.inv(cov), offset)
    np.testing.assert_allclose(mahalanobis, 9.0, rtol=1e-9)


def test_a_seed_batch_with_amcl_equals_its_single_runs():
    data = scenario("amcl", LIDAR, min_particles=100, max_particles=300)
    rows = run_seeds(data, [3, 4])
    for row in rows:
        alone = run({**data, "seed": row["seed"]}).metrics
        assert row["localization_rms_error_m"] == pytest.approx(alone["localization_rms_error_m"])
        assert row["status"] == alone["status"]


def test_the_runner_builds_the_filters_the_scenario_names():
    from wheelbase.runner import prepare

    ekf = prepare(scenario("ekf", LANDMARKS, gate_probability=0.95, initial_std=[0.1, 0.2, 3]))
    estimator = ekf.engine.estimator
    assert isinstance(estimator, KalmanLocalizer)
    assert estimator.filter.gate_probability == 0.95
    assert estimator.filter.bearing_std == pytest.approx(math.radians(2.0))
    assert estimator.initial_std == pytest.approx((0.1, 0.2, math.radians(3)))
    amcl = prepare(scenario("amcl", {**LIDAR, **LANDMARKS}, update_min_a_deg=10, alpha3=0.01))
    particles = amcl.engine.estimator
    assert isinstance(particles, ParticleLocalizer)
    assert particles.amcl.update_min_a == pytest.approx(math.radians(10))
    assert particles.amcl.motion.alpha3 == 0.01 and particles.amcl.sigma_hit == 0.05
    assert particles.amcl.landmarks.shape == (6, 2) and particles.amcl.lidar.beams == 60
    assert prepare(AISLE).engine.sensors is None  # defaults keep today's behaviour


def test_the_bundled_amcl_warehouse_scenario_loads():
    bundled = load_scenario("amcl_warehouse")
    assert bundled.localization.method == "amcl" and bundled.sensors.lidar.beams == 60
    assert bundled.odometry.wheel_radius_scale == (1.005, 1.005)


@pytest.mark.parametrize(
    ("change", "match"),
    [
        ({"localization": {"method": "ekf"}}, "ekf corrects with landmarks: give sensors"),
        ({"localization": {"method": "amcl"}}, "amcl needs sensors.lidar or sensors.landmarks"),
        ({"localization": {"method": "kalman"}}, "localization.method"),
        (
            {"sensors": LIDAR, "localization": {"method": "amcl", "gate_probability": 0.9}},
            "gate_probability is an option of ekf and ukf, not of method 'amcl'",
        ),
        (
            {"sensors": LIDAR, "localization": {"method": "amcl", "min_particles": 0}},
            "localization.min_particles: Input should be greater than 0",
        ),
        (
            {"sensors": LIDAR, "localization": {"method": "amcl", "sigma_hit": -0.1}},
            "localization.sigma_hit: Input should be greater than 0",
        ),
        (
            {
                "sensors": LIDAR,
                "localization": {"method": "amcl", "max_particles": 10, "min_particles": 50},
            },
            "localization: .*min_particles must be <= max_particles = 10",
        ),
        ({"sensors": {"lidar": {"rate_hz": 0}}}, "sensors.lidar.rate_hz: Input should be greater"),
        ({"sensors": {"lidar": {"range_std": 0}}}, "sensors.lidar.range_std: Input should be"),
        ({"sensors": {"lidar": {"min_range": 9.0}}}, "min_range must be < max_range = 8 m"),
        (
            {"sensors": {"lidar": {"beam_model": {"z_bogus": 1.0}}}},
            "beam_model: unknown key 'z_bogus'",
        ),
        (
            {"sensors": {"landmarks": {**LANDMARKS["landmarks"], "bearing_std_deg": -2}}},
            "sensors.landmarks.bearing_std_deg: Input should be greater than 0",
        ),
        ({"sensors": {"landmarks": {"positions": []}}}, "sensors.landmarks.positions"),
        (
            {"sensors": {"landmarks": {"positions": [[1.0, float("nan")]]}}},
            "positions must be finite",
        ),
        (
            {"odometry": {"mode": "perfect"}, "sensors": LIDAR, "localization": {"method": "amcl"}},
            "fuses wheel-encoder odometry with the sensors: set odometry.mode: encoders",
        ),
        (
            {"sensors": LIDAR, "localization": {"method": "amcl", "initial_std": [0, -1, 0]}},
            "localization.initial_std: must be three finite values >= 0",
        ),
    ],
)
def test_bad_sensor_and_localization_keys_are_clear_errors(change, match):
    from wheelbase.runner import prepare

    with pytest.raises(ScenarioError, match=match):
        prepare({**AISLE, **change})


@pytest.mark.parametrize("beta", [0.0, 0.5])
def test_a_ukf_beta_of_zero_stays_zero(beta):
    from wheelbase.runner import prepare

    prepared = prepare(scenario("ukf", LANDMARKS, beta=beta, kappa=0.0, alpha=0.5))
    ukf = prepared.engine.estimator.filter
    assert (ukf.beta, ukf.kappa, ukf.alpha) == (beta, 0.0, 0.5)
