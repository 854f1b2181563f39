"""The one closed-loop engine: statuses, arrival rule, batches, plants and bad input."""

import math

import numpy as np
import pytest

from wheelbase import DiffDrive, Unicycle
from wheelbase.control import GoToGoal, Kanayama, VelocityLimits
from wheelbase.errors import ConfigError, InputError
from wheelbase.models import Bicycle, mecanum4
from wheelbase.odometry import Encoder, WheelOdometry
from wheelbase.sim import (
    STATUSES,
    Arrival,
    EncoderOdometry,
    Engine,
    KinematicPlant,
    WheelAxle,
)
from wheelbase.timing import SpeedLimits, time_parametrize

ROBOT = DiffDrive(wheel_radius=0.05, half_track=0.2)


def straight_reference():
    poses = np.column_stack([np.linspace(0, 2, 21), np.zeros(21), np.zeros(21)])
    return time_parametrize(poses, limits=SpeedLimits(max_speed=0.5), dt=0.01)


class Feedforward:
    """The reference's (v, ω) at t for every robot: open loop."""

    command_names = ("v", "omega")

    def reset(self):
        pass

    def __call__(self, t, pose, reference):
        index = min(round(t / 0.01), len(reference.t) - 1)
        command = np.array([reference.v[index], reference.omega[index]])
        return np.broadcast_to(command, (*np.shape(pose)[:-1], 2)).copy()


def engine(reference, **options):
    settings = {
        "plant": KinematicPlant(ROBOT, WheelAxle(0.05, 0.2)),
        "controller": Feedforward(),
        "reference": reference,
        "dt": 0.01,
        "duration": 20.0,
        "arrival": Arrival([2, 0, 0], (0.02, math.radians(1)), end_time=float(reference.t[-1])),
        "reference_pose": lambda t: reference.poses[min(round(t / 0.01), len(reference.t) - 1)],
    }
    settings.update(options)
    return Engine(**settings)


def test_feedforward_arrives_and_logs_consistently():
    reference = straight_reference()
    log = engine(reference).run([0, 0, 0])
    assert log.statuses == ["arrived"] and log.n_robots == 1
    assert log.final_pose[0, 0] == pytest.approx(2.0, abs=0.02)
    np.testing.assert_array_equal(log.true_pose, log.estimated_pose)  # perfect state
    # Wheel rates are the commanded wheel speeds on the nominal robot.
    np.testing.assert_allclose(log.wheel_rates[0, :, 0], log.command[0, :, 0] / 0.05, atol=1e-12)
    # arrival is judged after the reference has ended, at rest
    assert log.end_time[0] >= reference.t[-1]
    assert np.hypot(*log.twist[0, -1, :2]) <= 0.01


def test_encoders_and_systematic_error_make_odometry_drift():
    reference = straight_reference()
    run = engine(
        reference,
        plant=KinematicPlant(ROBOT, WheelAxle(0.05, 0.2, radius_scale=(1.0, 1.01))),
        estimator=EncoderOdometry(Encoder(4096), WheelOdometry(0.05, 0.2, 4096)),
        duration=6.0,
    ).run([0, 0, 0])
    # A larger right wheel turns the robot left; odometry (nominal radii) does not see it.
    assert run.final_pose[0, 2] > 0.04
    assert abs(run.final_estimate[0, 2]) < 1e-3
    # Ticks count the true wheel rotation: right wheel rotation ≈ left (same commanded rates).
    assert abs(run.ticks[0, -1, 0] - 2.0 / 0.05 / (2 * np.pi) * 4096) < 5
    # the estimate says "arrived" but the truth is off: drift, not arrival
    assert run.statuses == ["missed_goal"]


def test_car_follows_its_own_kinematics_under_odometry_errors():
    """Seam: a car with a wrong track must turn as v·tan(δ)/L, not as a differential drive."""
    car = Bicycle(wheel_base=0.5, max_steering=math.radians(35))
    steer = 0.3

    class Constant:
        command_names = ("speed", "steering")

        def reset(self):
            pass

        def __call__(self, t, pose, reference):
            return np.broadcast_to([0.4, steer], (*np.shape(pose)[:-1], 2)).copy()

    for track_scale, radius_scale in ((1.1, (1.0, 1.0)), (1.0, (1.02, 1.02))):
        axle = WheelAxle(0.1, 0.2, radius_scale=radius_scale, track_scale=track_scale)
        log = Engine(
            KinematicPlant(car, axle, integrator="exact"),
            Constant(),
            None,
            dt=0.01,
            duration=2.0,
            estimator=EncoderOdometry(Encoder(4096), WheelOdometry(0.1, 0.2, 4096)),
        ).run([0, 0, 0])
        twist = log.twist[0, :-1]
        np.testing.assert_allclose(twist[:, 2] / twist[:, 0], math.tan(steer) / 0.5, rtol=1e-12)
        # the speed scales with the true radius of the driven wheels
        nominal = car.twist(np.array([0.4, steer]))
        np.testing.assert_allclose(
            twist, np.tile(nominal * np.mean(radius_scale), (200, 1)), rtol=1e-12
        )
        # odometry with the nominal track sees the wrong yaw rate
        yaw = log.final_estimate[0, 2]
        assert abs(yaw - log.final_pose[0, 2]) > 1e-3


def test_holonomic_commands_run_through_the_engine():
    """Seam: a (vx, vy, ω) command drives a holonomic base; nothing ends 'diverged'."""
    base = mecanum4(wheel_radius=0.05, half_length=0.2, half_width=0.2)

    class Sideways:
        command_names = ("vx", "vy", "omega")

        def reset(self):
            pass

        def __call__(self, t, pose, reference):
            return np.broadcast_to([0.0, 0.3, 0.0], (*np.shape(pose)[:-1], 3)).copy()

    log = Engine(
        KinematicPlant(base, integrator="exact"),
        Sideways(),
        None,
        dt=0.01,
        duration=2.0,
        arrival=Arrival([0.0, 0.6, 0.0], (0.01, 0.01)),
    ).run([[0, 0, 0], [1, 0, 0]])
    assert log.statuses == ["timeout", "timeout"]  # never at rest: it keeps moving sideways
    np.testing.assert_allclose(log.final_pose[:, 1], 0.6, atol=1e-9)
    np.testing.assert_allclose(log.final_pose[:, 0], [0, 1], atol=1e-9)


def test_collision_ends_the_run_with_a_status():
    reference = straight_reference()
    log = engine(reference, plant=KinematicPlant(Unicycle()),
                 collides=lambda poses: poses[:, 0] > 1.0).run([0, 0, 0])  # fmt: skip
    assert log.statuses == ["collision"]
    assert 1.0 < log.final_pose[0, 0] < 1.01


def test_nan_for_one_robot_leaves_the_others_running(tmp_path):
    reference = straight_reference()

    class NanForSecond(Feedforward):
        def __call__(self, t, pose, reference):
            command = super().__call__(t, pose, reference)
            command[1] = np.nan
            return command

    starts = np.array([[0, 0, 0], [0, 0.5, 0], [0, 1, 0]])
    goals = starts + np.array([2.0, 0.0, 0.0])
    arrival = Arrival(goals, (0.02, 0.02), end_time=float(reference.t[-1]))
    log = engine(reference, controller=NanForSecond(), arrival=arrival).run(starts)
    assert log.statuses == ["arrived", "diverged", "arrived"]
    assert log.length[1] == 1
    assert log.robot(1).t.shape == (1,)
    path = log.to_csv(tmp_path / "log.csv")
    header = path.read_text().splitlines()[0]
    assert header.startswith("robot,t,true_x,true_y,true_theta,est_x")
    rows = path.read_text().splitlines()[1:]
    assert len(rows) == int(np.sum(log.length))
    with pytest.raises(FileExistsError):
        log.to_csv(path)


def test_a_batch_equals_its_single_runs():
    """Robot i of a batch is the single run with seed i: poses equal to 1e-9 m."""
    reference = straight_reference()
    noisy = EncoderOdometry(Encoder(1024, noise_std=0.7), WheelOdometry(0.05, 0.2, 1024))
    controller = Kanayama(limits=VelocityLimits(1.0, 2.0))
    run = engine(reference, estimator=noisy, controller=controller)
    starts = np.array([[0, 0, 0], [0.1, 0.05, 0.1], [0, -0.1, 0], [0, 0, 0.2], [0, 0.02, 0]])
    batch = run.run(starts, seeds=[7, 8, 9, 10, 11])
    for i in range(5):
        alone = run.run(starts[i], seeds=[7 + i])
        picked = batch.robot(i)
        assert picked.statuses == alone.statuses
        np.testing.assert_allclose(picked.true_pose, alone.true_pose, atol=1e-9, rtol=0)
        np.testing.assert_array_equal(picked.ticks, alone.ticks)


def test_per_robot_goals_and_metrics():
    law = GoToGoal(kp=3.0, max_speed=0.3, slow_radius=0.3, tolerance=0.005)
    goals = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
    log = Engine(
        KinematicPlant(Unicycle(), integrator="exact"),
        law,
        goals,
        dt=0.01,
        duration=20.0,
        arrival=Arrival(goals, (0.01, math.pi)),
    ).run([0, 0, 0] * np.ones((2, 1)))
    assert log.statuses == ["arrived", "arrived"]
    metrics = log.metrics()
    assert [m["final_position_error_true_m"] < 0.01 for m in metrics] == [True, True]
    assert metrics[0]["distance_travelled_m"] == pytest.approx(1.0, abs=0.01)


def test_statuses_table_is_shared():
    assert STATUSES == (
        "running", "arrived", "missed_goal", "collision", "timeout", "diverged", "blocked", "stuck"
    )  # fmt: skip


def test_bad_input_is_a_clear_error():
    reference = straight_reference()
    run = engine(reference)
    with pytest.raises(InputError, match="at least one robot"):
        run.run(np.zeros((0, 3)))
    with pytest.raises(InputError, match="seeds"):
        run.run(np.zeros((2, 3)), seeds=[1, 2, 3])
    with pytest.raises(InputError, match=r"arrival\.goal has 3 rows for 2 robots"):
        engine(reference, arrival=Arrival(np.zeros((3, 3)))).run(np.zeros((2, 3)))

    class Wide(Feedforward):
        def __call__(self, t, pose, reference):
            return np.zeros((*np.shape(pose)[:-1], 3))

    with pytest.raises(ConfigError, match=r"expects \(2, 2\)"):
        engine(reference, controller=Wide()).run(np.zeros((2, 3)))
    with pytest.raises(ConfigError, match="steered model"):

        class Steering(Feedforward):
            command_names = ("speed", "steering")

        engine(reference, controller=Steering())
    with pytest.raises(ConfigError, match="tolerance"):
        Arrival([0, 0, 0], (-0.1, 0.1))
    with pytest.raises(InputError, match="robot index"):
        run.run([0, 0, 0]).robot(3)


def test_limits_and_seeds_are_clear_errors():
    reference = straight_reference()
    with pytest.raises(ConfigError, match="max_steps"):
        engine(reference, dt=1e-300)  # would loop for 2e301 steps
    assert engine(reference, duration=2.0, dt=1e-5, max_steps=200_000).steps == 200_000
    run = engine(reference, duration=0.05)
    for bad in (-1, 2**63, [2**64, 0]):
        with pytest.raises(InputError, match="seeds"):
            run.run(np.zeros((2, 3)), seeds=bad)
