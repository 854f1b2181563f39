"""The engine's hooks for navigation: controller rate, a controller that gives up, per-robot
references and the perception a controller may read."""

import math

import numpy as np
import pytest

from wheelbase import DiffDrive
from wheelbase.errors import ConfigError
from wheelbase.sim import STATUSES, Arrival, Engine, KinematicPlant, WheelAxle

ROBOT = DiffDrive(wheel_radius=0.05, half_track=0.2)


class Counting:
    """v = 0.1·(number of calls so far): shows when it is called."""

    command_names = ("v", "omega")

    def __init__(self):
        self.calls = []

    def reset(self):
        self.calls = []

    def __call__(self, t, pose, reference):
        self.calls.append(t)
        return np.broadcast_to([0.1 * len(self.calls), 0.0], (*np.shape(pose)[:-1], 2)).copy()


def engine(controller, **options):
    settings = {
        "plant": KinematicPlant(ROBOT, WheelAxle(0.05, 0.2)),
        "controller": controller,
        "reference": None,
        "dt": 0.01,
        "duration": 0.2,
    }
    settings.update(options)
    return Engine(**settings)


def test_the_controller_runs_at_its_own_rate_and_the_command_is_held():
    law = Counting()
    log = engine(law, control_every=5).run([0, 0, 0])
    # steps 0, 5, 10, 15 and the last row's (t = 0.2 s, the time limit, where nothing moves)
    np.testing.assert_allclose(law.calls, [0.0, 0.05, 0.10, 0.15, 0.20])
    v = log.command[0, :20, 0]
    np.testing.assert_allclose(v, np.repeat([0.1, 0.2, 0.3, 0.4], 5))
    # every step still integrates: 5 steps of each held command
    assert log.true_pose[0, -1, 0] == pytest.approx(0.01 * 5 * (0.1 + 0.2 + 0.3 + 0.4), rel=1e-9)


def test_every_step_calls_the_controller_by_default():
    law = Counting()
    engine(law).run([0, 0, 0])
    assert len(law.calls) == 21


class GivesUp:
    """Drives, then reports ``blocked`` from t = 0.1 s on (as a navigator with no way on)."""

    command_names = ("v", "omega")
    per_robot = True

    def reset(self):
        self.status = "ok"

    def __call__(self, t, pose, reference):
        if t >= 0.1 - 1e-12:
            self.status = "blocked"
            return np.zeros(2)
        return np.array([0.5, 0.0])


def test_a_controller_that_gives_up_ends_the_robot_blocked_and_stopped():
    log = engine(GivesUp(), duration=5.0).run([0, 0, 0])
    assert log.statuses == ["blocked"]
    assert STATUSES.index("blocked") == int(log.status[0])
    assert log.t[log.length[0] - 1] == pytest.approx(0.1)
    assert log.true_pose[0, -1, 0] == pytest.approx(0.05)  # 10 steps at 0.5 m/s, then stopped


class FollowsItsReference:
    command_names = ("v", "omega")
    per_robot = True

    def reset(self):
        pass

    def __call__(self, t, pose, reference):
        return np.array([reference, 0.0])


def test_each_robot_of_a_world_follows_its_own_reference():
    log = engine(FollowsItsReference(), references=(0.1, 0.3)).run(np.zeros((4, 3)))
    speeds = log.command[:, 0, 0]
    np.testing.assert_allclose(speeds, [0.1, 0.3, 0.1, 0.3])


def test_references_need_a_per_robot_controller():
    with pytest.raises(ConfigError, match="per-robot"):
        engine(Counting(), references=(0.1, 0.2))


class Sees:
    command_names = ("v", "omega")
    per_robot = True
    uses_perception = True

    def reset(self):
        self.seen = []

    def __call__(self, t, pose, reference, perception=None):
        self.seen.append(perception)
        return np.zeros(2)


class Perceives:
    """A stand-in perception: counts its updates, views name the robot and the time."""

    def start(self, poses):
        return np.zeros(len(poses), dtype=int)

    def update(self, state, t, readings, estimates, index):
        state = state.copy()
        state[index] += 1
        return state

    def view(self, state, i, t):
        return (i, round(t, 6), int(state[i]))


def test_a_perceiving_controller_gets_its_robots_view():
    from wheelbase.planning import OccupancyGrid
    from wheelbase.sensors import Lidar
    from wheelbase.sim import SensorSuite

    room = OccupancyGrid.from_array(np.pad(np.zeros((40, 40), bool), 1, constant_values=True), 0.1)
    sensors = SensorSuite(room, lidar=Lidar(beams=8), lidar_rate_hz=50.0)
    law = Sees()
    engine(law, perception=Perceives(), sensors=sensors, duration=0.05).run([[1.0, 1.0, 0.0]])
    # a scan every 0.02 s, read after the step; the view of t = 0.04 has seen two
    assert law.seen == [(0, 0.0, 0), (0, 0.01, 0), (0, 0.02, 1), (0, 0.03, 1), (0, 0.04, 2),
                        (0, 0.05, 2)]  # fmt: skip


def test_arrival_rule_unchanged_with_the_hooks():
    class Straight(Counting):
        def __call__(self, t, pose, reference):
            return np.broadcast_to([0.2 if pose[..., 0].max() < 0.5 else 0.0, 0.0], (1, 2))

    log = engine(
        Straight(), duration=10.0, arrival=Arrival([0.5, 0, 0], (0.02, math.radians(5)))
    ).run([0, 0, 0])
    assert log.statuses == ["arrived"]
