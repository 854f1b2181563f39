import math

import numpy as np

from control_cases import pose_benchmark_starts
from wheelbase.control import TwistTorqueLoop, VelocityLimits
from wheelbase.control.pose import ViaDirection
from wheelbase.control.torque import velocity_torques
from wheelbase.dynamics import RM100
from wheelbase.sim import closed_loop


class Constant:
    command_names = ("v", "omega")

    def __init__(self, v, omega):
        self.command = np.array([v, omega])

    def reset(self):
        pass

    def __call__(self, t, pose, reference):
        return np.broadcast_to(self.command, (*np.shape(pose)[:-1], 2))


def test_velocity_loop_is_first_order_with_the_exact_model():
    # a = k(ω_cmd − r) through the inverse dynamics, held over each step h: the sampled loop
    # r_{n+1} = r_n + h·k(ω − r_n), θ_{n+1} = θ_n + h·r_n + h²·k(ω − r_n)/2, which tends to
    # the continuous r(t) = ω(1 − e^(−kt)) as h → 0
    k, h, omega = 10.0, 0.001, 0.8
    loop = TwistTorqueLoop(Constant(0.4, omega), RM100, bandwidth=k)
    result = closed_loop(loop, RM100, [0.0, 0.0, 0.0], None, 1.0, h)
    rate, angle, expected = 0.0, 0.0, [0.0]
    for _ in range(result.t.size - 1):
        angle += h * rate + 0.5 * h * h * k * (omega - rate)
        rate += h * k * (omega - rate)
        expected.append(angle)
    # (the CG offset couples u and r within a step: agreement to 1e-4 relative)
    np.testing.assert_allclose(result.true_pose[0, :, 2], expected, rtol=1e-4, atol=1e-7)
    continuous = omega * (result.t - (1.0 - np.exp(-k * result.t)) / k)
    np.testing.assert_allclose(result.true_pose[0, :, 2], continuous, atol=5 * k * h * omega / k)


def test_torques_are_zero_at_the_commanded_velocity_on_a_straight_line():
    state = np.array([[0.0, 0.0, 0.0, 0.3, 0.0, 0.0]])
    np.testing.assert_allclose(velocity_torques(RM100, state, np.array([[0.3, 0.0]])), 0.0)


def test_pose_law_drives_the_rm100_to_the_goal():
    starts = pose_benchmark_starts()[::16]
    law = TwistTorqueLoop(ViaDirection(limits=VelocityLimits(0.5, 1.5)), RM100, bandwidth=30.0)
    result = closed_loop(law, RM100, starts, np.zeros(3), 40.0, 0.01, goal=np.zeros(3),
                         tolerance=(0.01, math.radians(1.0)))  # fmt: skip
    assert result.statuses == ["arrived"] * len(starts)
