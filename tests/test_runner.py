import json
import math

import numpy as np
import pytest

from wheelbase.errors import PlanningError, ScenarioError
from wheelbase.report import REPORT_FILES, write_report
from wheelbase.runner import run

BASE = {
    "name": "aisle",
    "map": "warehouse",
    "robot": {"model": "diffdrive", "preset": "rm100"},
    "controller": {"law": "kanayama"},
    "start": [3.0, 2.0, 0.0],
    "goal": [8.0, 2.5, 0.0],
    "trajectory": {"max_speed": 0.8, "max_acceleration": 0.8},
    "dt": 0.02,
}


@pytest.fixture(scope="module")
def result():
    return run(BASE)


def test_closed_loop_arrives_with_encoder_odometry(result):
    m = result.metrics
    assert m["status"] == "arrived" and m["planning_success"] and not m["collision"]
    assert "success" not in m  # the run's outcome is "status"; planning has its own key
    assert m["final_position_error_true_m"] < 0.05
    assert m["tracking_max_position_error_m"] < 0.02
    # Odometry (2048-tick encoders, exact-arc update) stays within a few mm on 5 m.
    assert m["odometry_drift_m"] < 0.005
    log = result.log
    assert log.true_pose.shape == log.estimated_pose.shape == (1, len(log.t), 3)
    # The encoders count the wheel rotation that the commands asked for.
    rotation = np.sum(log.wheel_rates[0, :-1, 0]) * 0.02
    assert abs(log.ticks[0, -1, 0] - rotation * 2048 / (2 * math.pi)) <= 2


def test_report_files_and_no_overwrite(result, tmp_path):
    written = write_report(result, tmp_path, gif=False)
    names = {path.name for path in written}
    assert names == set(REPORT_FILES) - {"animation.gif"}
    metrics = json.loads((tmp_path / "metrics.json").read_text())
    assert metrics["status"] == "arrived"
    header = (tmp_path / "log.csv").read_text().splitlines()[0].split(",")
    assert header[:5] == ["robot", "t", "true_x", "true_y", "true_theta"]
    assert "ticks_left" in header and "cmd_omega" in header
    with pytest.raises(FileExistsError, match="--force"):
        write_report(result, tmp_path, gif=False)
    write_report(result, tmp_path, gif=False, force=True)


def test_resolved_scenario_round_trips(result, tmp_path):
    from wheelbase.scenario import load_scenario

    path = tmp_path / "resolved.yaml"
    path.write_text(result.scenario.to_yaml())
    assert load_scenario(path) == result.scenario


@pytest.mark.parametrize(
    ("change", "error", "match"),
    [
        ({"start": [4.6, 8.0, 0.0]}, PlanningError, r"start \(4.6, 8, 0 deg\).*obstacle"),
        ({"goal": [100.0, 2.0, 0.0]}, PlanningError, r"goals\[0\].*outside the map"),
        ({"controller": {"law": "magic"}}, ScenarioError, "unknown law 'magic'; allowed: "),
        (
            {"controller": {"law": "kanayama", "gains": {"k_x": -1.0}}},
            ScenarioError,
            "controller.gains: .*k_x",
        ),
        ({"map": "atlantis"}, ScenarioError, "map: "),
        ({"robot": {"model": "tank"}}, ScenarioError, "robot.model"),
        ({"dt": -0.1}, ScenarioError, "dt: Input should be greater than 0"),
        ({"extra": 1}, ScenarioError, "extra: unknown key"),
    ],
)
def test_bad_scenarios_are_clear_errors(change, error, match):
    with pytest.raises(error, match=match):
        run({**BASE, **change})


def test_unknown_gain_lists_the_allowed_ones():
    bad = {**BASE, "controller": {"law": "kanayama", "gains": {"k_z": 1.0}}}
    with pytest.raises(ScenarioError, match=r"controller.gains: .*k_z.*takes: k_x, k_y, k_theta"):
        run(bad)


def test_mppi_scenario_runs_from_plain_gains():
    scenario = {
        **BASE,
        "map": "cluttered",
        "robot": {"model": "unicycle", "footprint": [0.4, 0.4]},
        "controller": {"law": "mppi", "gains": {"samples": 200, "backend": "numpy"}},
        "odometry": {"mode": "perfect"},
        "start": [1.0, 4.0, 0.0],
        "goal": [5.0, 4.0, 0.0],
        "goal_tolerance": [0.1, 180.0],
        "dt": 0.05,
        "duration": 30.0,
    }
    result = run(scenario)
    metrics = result.metrics
    assert metrics["status"] == "arrived" and not metrics["collision"]
    # Fans of sampled rollouts are kept once a second for the animation.
    fans = result.log.rollout_fans
    assert len(fans) >= int(metrics["duration_s"]) - 1
    robot, row = min(fans)
    first = fans[(robot, row)]
    assert robot == 0 and first.shape[0] == 20 and first.shape[2] == 2
    start = np.broadcast_to(result.log.true_pose[0, row, :2], first[:, 0].shape)
    np.testing.assert_allclose(first[:, 0], start, atol=1e-9)  # rollouts start at the robot
    # The loop records what MPPI reported at each step; no step saw every rollout collide.
    assert metrics["controller_statuses"].get("ok", 0) > 0
    assert "all_collide" not in metrics["controller_statuses"]
    assert metrics["min_clearance_m"] > 0.05


def test_segment_follower_gains_scale_with_the_speed():
    # At 1.5 m/s the default 0.25 m length scale breaks the heading-before-offset condition
    # (k_heading 4 < 6 1/s); the scenario default scales it with the speed instead of failing.
    from wheelbase.scenario import load_scenario

    scenario = load_scenario("parking").model_dump() | {"controller": {"law": "segment"}}
    assert run(scenario).metrics["status"] == "arrived"
    bad = scenario | {"controller": {"law": "segment", "gains": {"length_scale": 0.25}}}
    with pytest.raises(ScenarioError, match="k_heading must be >"):
        run(bad)


def test_scenario_limits_reach_the_engine_and_gains_are_checked():
    from wheelbase.errors import ScenarioError

    tight = {**BASE, "resources": {"max_steps": 10}}
    with pytest.raises(ScenarioError, match="max_steps"):
        run(tight)
    gains = {"model_error": "abc"}
    torque = {**BASE, "plant": "dynamic", "robot": {"model": "diffdrive", "preset": "rm100"},
              "controller": {"law": "computed_torque", "gains": gains}}  # fmt: skip
    with pytest.raises(ScenarioError, match="model_error"):
        run(torque)


def test_least_clearance_is_the_brute_force_minimum():
    from wheelbase.runner import _min_clearance, prepare

    prepared = prepare("demo")
    rng = np.random.default_rng(3)
    grid, footprint = prepared.grid, prepared.footprint
    x0, x1, y0, y1 = grid.extent
    for _ in range(5):
        poses = np.column_stack([rng.uniform(x0, x1, 300), rng.uniform(y0, y1, 300),
                                 rng.uniform(-np.pi, np.pi, 300)])  # fmt: skip
        expected = float(np.min(grid.footprint_clearance(footprint, poses)))
        assert _min_clearance(grid, footprint, poses) == expected


SLOW_FOLLOWER = {
    "name": "slow",
    "map": "empty",
    "robot": {"model": "unicycle"},
    "controller": {"law": "pure_pursuit", "gains": {"speed": 0.2}},
    "odometry": {"mode": "perfect"},
    "start": [0.0, 0.0, 0.0],
    "goal": [6.0, 0.0, 0.0],
    "trajectory": {"max_speed": 1.0, "max_acceleration": 1.0},
    "dt": 0.05,
    "duration": 60.0,
}


def test_duration_governs_a_robot_slower_than_its_reference():
    # The reference reaches the goal in about 7 s; the follower, at 0.2 m/s, in about 30 s:
    # more than 15 s late (the old settle time), well within the duration.
    m = run(SLOW_FOLLOWER).metrics
    assert m["status"] == "arrived"
    assert m["trajectory_duration_s"] < 8.0 and 25.0 < m["duration_s"] < 60.0
    assert m["arrival_delay_s"] == pytest.approx(m["duration_s"] - m["trajectory_duration_s"])
    assert m["arrival_delay_s"] > 15.0
    # a settle time, when given, ends the run that long after the reference instead
    cut = run({**SLOW_FOLLOWER, "settle_time": 5.0}).metrics
    assert cut["status"] == "timeout" and "arrival_delay_s" not in cut
    assert cut["duration_s"] == pytest.approx(cut["trajectory_duration_s"] + 5.0, abs=0.051)
    with pytest.raises(ScenarioError, match="settle_time"):
        run({**SLOW_FOLLOWER, "settle_time": -1.0})


def test_a_path_follower_is_scored_by_its_distance_to_the_path():
    # At 0.2 m/s behind a 1 m/s reference the follower is metres from where the timed
    # trajectory is, yet on the path all along: that is its tracking error.
    m = run(SLOW_FOLLOWER).metrics
    assert m["tracking_error_of"] == "path"
    assert m["tracking_rms_position_error_m"] == m["path_deviation_rms_m"] < 0.01
    assert m["tracking_max_position_error_m"] == m["path_deviation_max_m"] < 0.02
    assert m["timed_rms_position_error_m"] > 1.0 and m["timed_max_position_error_m"] > 4.0
    assert "tracking_rms_heading_error_deg" not in m and "timed_rms_heading_error_deg" in m
    # a trajectory law keeps the timed error as its tracking error
    timed = run(BASE).metrics
    assert timed["tracking_error_of"] == "trajectory" and "timed_rms_position_error_m" not in timed
    # with perfect state there is no estimate to score: no drift, no localisation error
    for key in ("odometry_drift_m", "localization_rms_error_m", "final_position_error_estimated_m"):
        assert key not in m
    assert "odometry_drift_m" in timed and "localization_final_error_m" not in timed


def test_min_clearance_is_the_least_over_every_pose():
    scenario = {**BASE, "dt": 0.005}  # 1,600 rows
    result = run(scenario)
    from wheelbase.runner import prepare

    prepared = prepare(scenario)
    poses = result.log.true_pose[0]
    every = prepared.grid.footprint_clearance(prepared.footprint, poses)
    assert result.metrics["min_clearance_m"] == float(np.min(every))


def test_reversals_ignore_the_flicker_of_a_turn_in_place():
    from wheelbase.sim.log import _reversals

    turning = np.array([0.5] * 20 + [1e-5, -1e-5, 2e-5, -3e-5] * 10 + [0.5] * 20)
    assert _reversals(turning) == 0  # a forward-only run: no reversal
    parking = np.array([0.5] * 20 + [0.01, -0.01] * 3 + [-0.3] * 20 + [0.4] * 5)
    assert _reversals(parking) == 2  # backwards and forwards again
    assert _reversals(np.zeros(5)) == 0 and _reversals(np.array([])) == 0


def test_torque_tracking_acceleration_gains_must_be_numbers():
    # found by benchmarks/fuzz.py: a raw ValueError from float('empty')
    scenario = {"name": "gain", "map": "empty", "robot": {"model": "diffdrive", "preset": "rm100"},
                "plant": "dynamic", "controller": {"law": "adaptive_computed_torque",
                                                   "gains": {"max_acceleration": "empty"}},
                "start": [0.0, 0.0, 0.0], "goal": [1.5, 0.0, 0.0], "dt": 0.02}  # fmt: skip
    with pytest.raises(ScenarioError, match="max_acceleration must be a real number"):
        run(scenario)
    scenario["controller"]["gains"]["max_acceleration"] = -1.0
    with pytest.raises(ScenarioError, match="max_acceleration must be > 0"):
        run(scenario)
