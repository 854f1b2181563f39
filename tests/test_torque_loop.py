"""A kinematic law on the dynamic plant: TwistTorqueLoop, alone and in scenarios."""

import math

import numpy as np
import pytest

from wheelbase.control import PurePursuit, RearWheelFeedback, TwistTorqueLoop
from wheelbase.dynamics import RM100
from wheelbase.errors import ConfigError, ScenarioError
from wheelbase.runner import run


class Constant:
    """A law that always asks for the same (v, ω)."""

    command_names = ("v", "omega")

    def __init__(self, v, omega):
        self.command = np.array([v, omega])

    def __call__(self, t, pose, reference):
        return self.command


def test_the_twist_follows_the_command_as_a_first_order_lag():
    bandwidth, dt = 4.0, 1e-3
    loop = TwistTorqueLoop(Constant(0.3, 0.4), RM100, bandwidth=bandwidth)
    state = np.zeros(6)
    for step in range(1, 1001):
        torques = loop(step * dt, state, None)
        state = RM100.step(state, torques, dt)
        if step in (100, 250, 1000):
            lag = 1.0 - math.exp(-bandwidth * step * dt)
            # zero-order hold of the torque over each step: O(k·dt) off the continuous lag
            assert state[3] == pytest.approx(0.3 * lag, abs=2e-3)
            assert state[5] == pytest.approx(0.4 * lag, abs=3e-3)
    assert abs(state[4]) < 1e-12  # no lateral slip


def test_torques_saturate_and_bad_laws_are_refused():
    loop = TwistTorqueLoop(Constant(5.0, 0.0), RM100, bandwidth=50.0, max_torque=2.0)
    np.testing.assert_allclose(loop(0.0, np.zeros(6), None), [2.0, 2.0])
    steering = RearWheelFeedback(speed=0.3, output="steering", wheel_base=0.5)
    with pytest.raises(ConfigError, match="tracks \\(v, omega\\)"):
        TwistTorqueLoop(steering, RM100)
    with pytest.raises(ConfigError, match="bandwidth"):
        TwistTorqueLoop(PurePursuit(speed=0.3), RM100, bandwidth=0.0)


SCENARIO = {
    "name": "aisle-dynamic",
    "map": "warehouse",
    "robot": {"model": "diffdrive", "preset": "rm100"},
    "plant": "dynamic",
    "start": [3.0, 2.0, 0.0],
    "goal": [8.0, 2.5, 0.0],
    "trajectory": {"max_speed": 0.8, "max_acceleration": 0.8},
    "dt": 0.01,
}


@pytest.mark.parametrize(
    "controller",
    [
        {"law": "kanayama", "torque_loop": {"bandwidth": 8.0}},
        {"law": "linear"},  # holds the reference at rest too (min_natural_frequency)
        {"law": "mppi", "gains": {"samples": 300}},
    ],
    ids=["kanayama", "linear", "mppi"],
)
def test_kinematic_laws_drive_the_dynamic_plant(controller):
    result = run({**SCENARIO, "controller": controller})
    metrics = result.metrics
    assert metrics["status"] == "arrived" and not metrics["collision"]
    assert metrics["final_position_error_true_m"] < 0.05
    assert result.log.torques is not None and metrics["max_wheel_torque_nm"] <= 5.0 + 1e-12
    if controller["law"] == "mppi":  # the loop passes MPPI's status and rollouts through
        assert sum(metrics["controller_statuses"].values()) == len(result.log.t)
        assert len(result.log.rollout_fans) >= 5


def test_computed_torque_still_needs_the_dynamic_plant():
    scenario = {**SCENARIO, "plant": "kinematic", "controller": {"law": "computed_torque"}}
    with pytest.raises(ScenarioError, match="computed_torque gives wheel torques"):
        run(scenario)
    bad = {**SCENARIO, "controller": {"law": "pure_pursuit", "torque_loop": {"bandwidth": -1}}}
    with pytest.raises(ScenarioError, match="bandwidth"):
        run(bad)


@pytest.mark.parametrize("plant", ["kinematic", "dynamic"])
@pytest.mark.parametrize(
    "law",
    ["pure_pursuit", "stanley", "rear_wheel_feedback", "segment", "linear", "kanayama", "mppi"],
)
def test_every_velocity_law_parks_the_demo_robot(law, plant):
    # The bundled demo: the RM100 reverse-parks into a bay (a cusp, turns, encoder odometry).
    from wheelbase.scenario import load_scenario

    controller = {"law": law, "gains": {"samples": 300}} if law == "mppi" else {"law": law}
    scenario = load_scenario("demo").model_dump() | {"plant": plant, "controller": controller}
    metrics = run(scenario).metrics
    assert metrics["status"] == "arrived" and not metrics["collision"]
    assert metrics["final_position_error_true_m"] < 0.05
