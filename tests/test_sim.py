import math

import numpy as np
import pytest

from wheelbase import DiffDrive, Unicycle
from wheelbase.odometry import Encoder, WheelOdometry
from wheelbase.sim import OdometrySetup, run_loop
from wheelbase.timing import SpeedLimits, time_parametrize

ROBOT = DiffDrive(wheel_radius=0.05, half_track=0.2)


def straight_reference():
    poses = np.column_stack([np.linspace(0, 2, 21), np.zeros(21), np.zeros(21)])
    return time_parametrize(poses, limits=SpeedLimits(max_speed=0.5), dt=0.01)


def feedforward(t, pose, reference):
    index = min(round(t / 0.01), len(reference.t) - 1)
    return np.array([reference.v[index], reference.omega[index]])


def to_wheels(command):
    return np.array(ROBOT.wheel_speeds(command[0], command[1]))


def reference_pose(reference):
    return lambda t: reference.poses[min(round(t / 0.01), len(reference.t) - 1)]


def test_feedforward_arrives_and_logs_consistently():
    reference = straight_reference()
    log = run_loop(
        ROBOT,
        feedforward,
        reference,
        [0, 0, 0],
        dt=0.01,
        duration=20.0,
        command_to_inputs=to_wheels,
        odometry=OdometrySetup(0.05, 0.2),
        reference_pose=reference_pose(reference),
        goal=[2, 0, 0],
        tolerance=(0.02, math.radians(1)),
    )
    assert log.status == "arrived"
    assert log.true_pose[-1, 0] == pytest.approx(2.0, abs=0.02)
    np.testing.assert_array_equal(log.true_pose, log.estimated_pose)  # perfect state
    # Wheel rates are the commanded wheel speeds on the nominal robot.
    np.testing.assert_allclose(log.wheel_rates[:, 0], log.command[:, 0] / 0.05, atol=1e-12)


def test_encoders_and_systematic_error_make_odometry_drift():
    reference = straight_reference()
    setup = OdometrySetup(
        0.05,
        0.2,
        encoder=Encoder(4096),
        odometry=WheelOdometry(0.05, 0.2, 4096),
        radius_scale=(1.0, 1.01),
    )
    log = run_loop(
        ROBOT,
        feedforward,
        reference,
        [0, 0, 0],
        dt=0.01,
        duration=6.0,
        command_to_inputs=to_wheels,
        odometry=setup,
        reference_pose=reference_pose(reference),
        goal=[2, 0, 0],
    )
    # A larger right wheel turns the robot left; odometry (nominal radii) does not see it.
    assert log.true_pose[-1, 2] > 0.04
    assert abs(log.estimated_pose[-1, 2]) < 1e-3
    # Ticks count the true wheel rotation: right wheel rotation ≈ left (same commanded rates).
    assert abs(log.ticks[-1, 0] - 2.0 / 0.05 / (2 * np.pi) * 4096) < 5


def test_collision_ends_the_run_with_a_status():
    reference = straight_reference()
    log = run_loop(
        Unicycle(),
        feedforward,
        reference,
        [0, 0, 0],
        dt=0.01,
        duration=20.0,
        command_to_inputs=lambda c: c,
        odometry=OdometrySetup(0.05, 0.2),
        reference_pose=reference_pose(reference),
        goal=[2, 0, 0],
        in_collision=lambda pose: pose[0] > 1.0,
    )
    assert log.status == "collision"
    assert 1.0 < log.true_pose[-1, 0] < 1.01


def test_non_finite_command_is_diverged_not_a_crash(tmp_path):
    reference = straight_reference()
    log = run_loop(
        Unicycle(),
        lambda t, pose, ref: np.array([np.nan, 0.0]),
        reference,
        [0, 0, 0],
        dt=0.01,
        duration=1.0,
        command_to_inputs=lambda c: c,
        odometry=OdometrySetup(0.05, 0.2),
        reference_pose=reference_pose(reference),
        goal=[2, 0, 0],
    )
    assert log.status == "diverged" and len(log.t) == 1
    path = log.to_csv(tmp_path / "log.csv")
    assert path.read_text().splitlines()[0].startswith("t,true_x,true_y,true_theta,est_x")
    with pytest.raises(FileExistsError):
        log.to_csv(path)
