"""Go-to-goal of document 003 §IV and its closed loop through motors, encoders and odometry."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from wheelbase.control.goal import (
    FIGURE8_GOALS,
    DriveTrain,
    GoToGoal,
    saturate_keep_turn_rate,
)
from wheelbase.errors import ConfigError, InputError
from wheelbase.models import DiffDrive
from wheelbase.odometry import OdometryErrors
from wheelbase.sim import run_go_to_goal

LAW = GoToGoal(kp=2.0, max_speed=0.2, slow_radius=0.3, tolerance=0.01)


def test_heading_error_is_atan2_and_wrapped():
    # Heading 3.0 rad, goal in direction -3.0 rad: the error is +0.283 rad, not -6 rad.
    pose = [0.0, 0.0, 3.0]
    goal = [10 * math.cos(-3.0), 10 * math.sin(-3.0)]
    v, omega = LAW(0.0, pose, goal)
    assert v == pytest.approx(0.2)
    assert omega == pytest.approx(2.0 * (2 * math.pi - 6.0))
    # Goal straight behind (third quadrant from the origin facing +x): atan2, not atan.
    _, omega = LAW(0.0, [0, 0, 0], [-1.0, -1.0])
    assert omega == pytest.approx(2.0 * (-3 * math.pi / 4))


def test_corrected_wheel_setpoints_are_the_inverse_kinematics():
    robot = DiffDrive(wheel_radius=LAW.wheel_radius, half_track=LAW.half_track)
    poses = np.array([[0.0, 0.0, 0.0], [0.3, -0.2, 2.0], [1.0, 1.0, -1.0]])
    goal = np.array([0.5, 1.5])
    wheels = LAW.wheel_setpoints(poses, goal)
    v, omega = robot.body_velocity(wheels[:, 0], wheels[:, 1])
    command = LAW(0.0, poses, goal)
    np.testing.assert_allclose(np.stack([v, omega], -1), command, atol=1e-12)
    # Eqs. 9–10 corrected: V_R,L = v ± W·L/2 [m/s], then ω = V/r, RPM = ω·60/2π.
    w = command[0, 1]
    v_right = command[0, 0] + w * 2 * LAW.half_track / 2
    assert wheels[0, 1] == pytest.approx(v_right / LAW.wheel_radius)
    rpm = LAW.rpm_setpoints(poses, goal)
    np.testing.assert_allclose(rpm, wheels * 60 / (2 * math.pi))


def test_speed_slows_near_the_goal_and_stops_within_tolerance():
    far, near, there = (LAW(0, [0, 0, 0], [d, 0.0]) for d in (2.0, 0.15, 0.005))
    assert far[0] == pytest.approx(0.2)
    assert near[0] == pytest.approx(0.2 * 0.15 / 0.3)
    assert there.tolist() == [0.0, 0.0]


@settings(max_examples=80, deadline=None)
@given(
    v=st.floats(-3, 3),
    omega=st.floats(-30, 30),
    limit=st.floats(1.0, 50.0),
)
def test_saturation_keeps_the_turning_rate(v, omega, limit):
    r, d = 0.035, 0.075
    v2, w2 = saturate_keep_turn_rate(v, omega, r, d, limit)
    fastest = (abs(v2) + d * abs(w2)) / r
    assert fastest <= limit * (1 + 1e-12)
    assert abs(v2) <= abs(v) and abs(w2) <= abs(omega)
    assert v2 * v >= 0 and w2 * omega >= 0
    if d * abs(omega) <= r * limit:
        assert w2 == omega  # the turning rate is kept; only the speed is given up
    if (abs(v) + d * abs(omega)) / r <= limit:
        assert (v2, w2) == (v, omega)


def test_figure8_goals_are_reached_through_the_full_loop():
    log = run_go_to_goal(FIGURE8_GOALS)  # the four goals: four robots in one batch
    metrics = log.metrics()
    np.testing.assert_array_equal(log.goal[:, :2], FIGURE8_GOALS)
    assert log.statuses == ["arrived"] * 4
    for i, m in enumerate(metrics):
        assert m["final_position_error_estimated_m"] < 0.015  # the law stops within 1 cm
        assert m["final_position_error_true_m"] < 0.02
        assert m["odometry_drift_m"] < 1e-3  # ideal geometry: only encoder quantisation
        assert log.end_time[i] < 20.0
        # at rest: the motors have stopped
        assert np.all(np.abs(log.wheel_rates[i, log.length[i] - 1]) * 0.035 <= 0.01)
    assert np.all(np.abs(log.extras["duty"]) <= 1.0)
    assert log.extras["setpoint_rpm"].shape == (4, log.t.size, 2)
    # Fig. 8: the robot starts facing +x and arcs; goals in the left half plane need more turn.
    first_heading_rate = log.true_pose[:, 5, 2]
    assert first_heading_rate[0] > 0 and first_heading_rate[3] < 0
    # Mirror symmetry y → −y (up to encoder quantisation).
    np.testing.assert_allclose(log.final_pose[3, :2], log.final_pose[0, :2] * [1, -1], atol=2e-3)


def test_a_batch_of_goals_equals_the_single_runs():
    batch = run_go_to_goal(FIGURE8_GOALS[:2], seed=5)
    for i in range(2):
        alone = run_go_to_goal(FIGURE8_GOALS[i], seed=5 + i)
        np.testing.assert_allclose(batch.robot(i).true_pose, alone.true_pose, atol=1e-12)


def test_systematic_errors_make_odometry_lie():
    drive = DriveTrain(errors=OdometryErrors(diameter_ratio=1.03, track_ratio=1.05))
    log = run_go_to_goal((1.0, 1.0), drive=drive)
    m = log.metrics()[0]
    assert log.statuses == ["missed_goal"]  # the estimate says "there", the robot is not
    assert m["final_position_error_estimated_m"] < 0.015
    assert m["odometry_drift_m"] > 0.02
    assert m["final_position_error_true_m"] > m["final_position_error_estimated_m"]


def test_bad_input():
    with pytest.raises(ConfigError, match="kp"):
        GoToGoal(kp=-1.0)
    with pytest.raises(ConfigError, match="orbits"):
        GoToGoal(kp=0.1, max_speed=0.5, slow_radius=0.3)
    with pytest.warns(UserWarning, match="spirals"):
        GoToGoal(kp=1.0, max_speed=0.5, slow_radius=0.4)
    with pytest.raises(InputError, match="goal"):
        run_go_to_goal((float("nan"), 1.0))
    with pytest.raises(InputError, match="goal"):
        LAW(0.0, [0, 0, 0], [1.0, float("inf")])
    with pytest.raises(ConfigError, match="control_period"):
        run_go_to_goal((1.0, 1.0), control_period=0.025)
    with pytest.raises(ConfigError, match="max_wheel_speed"):
        saturate_keep_turn_rate(1.0, 1.0, 0.035, 0.075, 0.0)


def test_a_drive_train_step_with_slip_is_a_function_of_its_state():
    from wheelbase.sim import DriveTrainPlant

    plant = DriveTrainPlant(DriveTrain(errors=OdometryErrors(slip_std=0.05)))
    state = plant.start(3, np.array([0, 1, 2]))
    pose, twist = np.zeros((3, 3)), np.zeros((3, 3))
    command, index = np.tile([0.3, 0.2], (3, 1)), np.arange(3)
    for _ in range(5):
        pose, twist, _, state = plant.step(pose, twist, command, None, None, 0.05, state, index)
    first = plant.step(pose, twist, command, None, None, 0.05, state, index)
    second = plant.step(pose, twist, command, None, None, 0.05, state, index)
    np.testing.assert_array_equal(first[0], second[0])  # the same slip both times
    np.testing.assert_array_equal(first[3].motors, second[3].motors)
    assert not np.allclose(first[0][0], first[0][1])  # each robot slips its own way
    # robot 1 alone (seed 1) slips as robot 1 of the batch
    one = plant.start(1, np.array([1]))
    p1, t1 = np.zeros((1, 3)), np.zeros((1, 3))
    for _ in range(6):
        p1, t1, _, one = plant.step(p1, t1, command[:1], None, None, 0.05, one, np.arange(1))
    np.testing.assert_allclose(p1[0], first[0][1], atol=1e-12)
