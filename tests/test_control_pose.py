import math
import warnings

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from control_cases import evaluate_pose_law, pose_benchmark_starts
from wheelbase import ConfigError, DiffDrive, InputError, Unicycle
from wheelbase.control import VelocityLimits, saturate_velocity
from wheelbase.control.point import GoToPoint
from wheelbase.control.pose import Aicardi, LineArc, PolarPose, ViaDirection, ViaPoint
from wheelbase.geometry import compose
from wheelbase.sim import closed_loop

LIMITS = VelocityLimits(max_speed=0.5, max_yaw_rate=1.5)
STARTS = pose_benchmark_starts()
GUARANTEED = {
    "polar": PolarPose,
    "aicardi": Aicardi,
    "via_point": ViaPoint,
    "via_direction": ViaDirection,
    "line_arc": LineArc,
}
ALL_LAWS = {"point": GoToPoint, **GUARANTEED}


def test_benchmark_starts_are_the_issue_grid():
    assert STARTS.shape == (128, 3)
    np.testing.assert_allclose(np.hypot(STARTS[:, 0], STARTS[:, 1]), 2.0)
    assert len({round(math.atan2(y, x), 6) for x, y, _ in STARTS}) == 16
    assert len(set(np.round(STARTS[:, 2], 6))) == 8


@pytest.mark.parametrize("name", sorted(GUARANTEED))
def test_laws_2_to_6_reach_every_pose_of_the_benchmark(name):
    metrics, result = evaluate_pose_law(GUARANTEED[name](limits=LIMITS), Unicycle(), STARTS)
    assert metrics["success_rate"] == 1.0, metrics
    assert metrics["mean_time_s"] < 30.0
    # a path from a circle of 2 m is at least 2 m long
    assert metrics["mean_path_length_m"] >= 2.0
    # every command respected the limits
    commands = result.command
    assert np.all(np.abs(commands[..., 0]) <= 0.5 + 1e-9)
    assert np.all(np.abs(commands[..., 1]) <= 1.5 + 1e-9)


def test_go_to_point_reaches_the_position_not_the_heading():
    metrics, _ = evaluate_pose_law(GoToPoint(limits=LIMITS), Unicycle(), STARTS)
    assert metrics["position_success_rate"] == 1.0
    assert metrics["success_rate"] < 0.1  # the final heading is the approach direction
    assert metrics["reversals"] == 0.0


@given(
    st.tuples(st.floats(-3, 3), st.floats(-3, 3), st.floats(-3.1, 3.1)),
    st.tuples(st.floats(-3, 3), st.floats(-3, 3), st.floats(-3.1, 3.1)),
    st.sampled_from(sorted(ALL_LAWS)),
)
@settings(max_examples=60, deadline=None)
def test_commands_do_not_depend_on_the_world_frame(pose, frame, name):
    goal = np.array([0.3, -0.2, 0.4])
    pose = np.asarray(pose)
    if np.hypot(*(pose[:2] - goal[:2])) < 1e-3:
        return
    law = ALL_LAWS[name](limits=LIMITS)
    here = law(0.0, pose, goal)
    law.reset()
    moved = law(0.0, compose(frame, pose), compose(frame, goal))
    np.testing.assert_allclose(moved, here, atol=1e-7)


def test_polar_law_closed_form():
    # robot at (−1, 1) heading 0, goal at the origin facing +x: ρ = √2,
    # α = atan2(−1, 1) − 0 = −π/4, β = −0 − α = π/4.
    law = PolarPose(k_rho=3.0, k_alpha=8.0, k_beta=-1.5)
    v, omega = law(0.0, [-1.0, 1.0, 0.0], [0.0, 0.0, 0.0])
    assert math.isclose(v, 3.0 * math.sqrt(2.0))
    assert math.isclose(omega, 8.0 * -math.pi / 4 - 1.5 * math.pi / 4)


def test_polar_law_reverses_for_the_whole_episode_when_the_goal_is_behind():
    start = np.array([[2.0, 0.0, 0.0], [-2.0, 0.5, 0.0]])  # goal behind / ahead
    result = closed_loop(
        PolarPose(limits=LIMITS), Unicycle(), start, [0, 0, 0], 30.0, 0.01,
        goal=[0, 0, 0], tolerance=(0.01, math.radians(1)),
    )  # fmt: skip
    assert result.statuses == ["arrived", "arrived"]
    moving = np.abs(result.command[:, :-1, 0]) > 1e-6
    assert np.all(result.command[0, :-1, 0][moving[0]] < 0)
    assert np.all(result.command[1, :-1, 0][moving[1]] > 0)
    assert [row["reversals"] for row in result.metrics()] == [0, 0]


def test_polar_gains_stability_conditions():
    with pytest.raises(ConfigError, match="k_beta < 0"):
        PolarPose(k_beta=0.5)
    with pytest.raises(ConfigError, match="k_alpha - k_rho > 0"):
        PolarPose(k_rho=3.0, k_alpha=2.0)
    with pytest.raises(ConfigError, match="k_rho"):
        PolarPose(k_rho=float("nan"))
    with pytest.warns(UserWarning, match="5/3"):
        PolarPose(k_rho=3.0, k_alpha=8.0, k_beta=-4.0)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        PolarPose()  # Siegwart's gains are strongly stable


def test_go_to_point_gain_conditions():
    with pytest.raises(ConfigError, match="circles the goal"):
        GoToPoint(k_heading=0.5, k_speed=1.0)
    with pytest.warns(UserWarning, match="spirals"):
        GoToPoint(k_heading=0.9, k_speed=1.0)
    with pytest.raises(ConfigError, match="k_speed"):
        GoToPoint(k_speed=-1.0)


def test_bidirectional_go_to_point_backs_up_to_a_goal_behind():
    law = GoToPoint(bidirectional=True)
    v, omega = law(0.0, [1.0, 0.1, 0.0], [0.0, 0.0, 0.0])
    assert v < 0
    # folded error e' = atan(tan(atan2(−0.1, −1))) = atan(0.1): the rear (heading π) has to
    # turn to π + atan(0.1) to point at the goal, so ω > 0
    assert omega == pytest.approx(3.0 * math.atan(0.1))
    forward = GoToPoint()
    assert forward(0.0, [1.0, 0.1, 0.0], [0.0, 0.0, 0.0])[0] > 0


def test_aicardi_lyapunov_function_never_increases():
    law = Aicardi(gamma=1.0, k=3.0, h=1.0, limits=LIMITS)
    result = closed_loop(law, Unicycle(), STARTS[::5], [0, 0, 0], 20.0, 0.001)
    x, y, theta = np.moveaxis(np.swapaxes(result.true_pose, 0, 1), -1, 0)  # (T, N) each
    psi = np.arctan2(-y, -x)
    alpha = np.angle(np.exp(1j * (psi - theta)))
    lyapunov = 0.5 * (x**2 + y**2 + alpha**2 + psi**2)
    # away from the ψ = ±π cut (the robot ahead of the goal), V decreases step by step
    jumps = np.abs(np.diff(psi, axis=0)) > 1.0
    steps = np.diff(lyapunov, axis=0)
    assert np.all(steps[~jumps] <= 1e-6)
    assert np.all(lyapunov[-1] < 1e-3)


def test_gains_must_be_positive():
    with pytest.raises(ConfigError, match="gamma"):
        Aicardi(gamma=0.0)
    with pytest.raises(ConfigError, match="distance"):
        ViaPoint(distance=-0.1)
    with pytest.raises(ConfigError, match="radius"):
        ViaDirection(radius=0.0)
    with pytest.raises(ConfigError, match="radius"):
        LineArc(radius=-1.0)
    with pytest.raises(ConfigError, match="align_distance"):
        LineArc(align_distance=0.0)


@pytest.mark.parametrize("name", sorted(ALL_LAWS))
def test_goal_equal_to_start_is_an_error(name):
    law = ALL_LAWS[name]()
    with pytest.raises(InputError, match="goal equals the start"):
        law(0.0, [1.0, 2.0, 0.5], [1.0, 2.0, 0.0])


def test_bad_pose_shapes():
    with pytest.raises(InputError, match="pose"):
        PolarPose()(0.0, [1.0, 2.0], [0.0, 0.0, 0.0])
    with pytest.raises(InputError, match="goal"):
        PolarPose()(0.0, [1.0, 2.0, 0.0], [0.0, np.nan, 0.0])


def test_line_arc_plan_is_tangent_and_follows_the_circle():
    law = LineArc(radius=0.5)
    plan = law.plan(STARTS[:, 0], STARTS[:, 1])
    sigma, tangent = plan["sigma"], plan["tangent"]
    centre = np.stack([np.zeros(128), sigma * 0.5], -1)
    radial = tangent - centre
    np.testing.assert_allclose(np.hypot(*radial.T), 0.5)
    line = tangent - STARTS[:, :2]
    # the line is perpendicular to the radius at T and runs along the circulation σ
    np.testing.assert_allclose(np.sum(line * radial, -1), 0.0, atol=1e-12)
    circulation = sigma[:, None] * np.stack([-radial[:, 1], radial[:, 0]], -1)
    assert np.all(np.sum(line * circulation, -1) > 0)
    # a start straight behind the goal: the line is the whole path
    behind = law.plan(np.array([-2.0]), np.array([0.0]))
    assert behind["length"][0] == pytest.approx(2.0)
    assert behind["arc_angle"][0] == 0.0
    # the length is never shorter than the distance
    assert np.all(plan["length"] >= 2.0 - 1e-12)


def test_via_point_passes_near_its_intermediate_point():
    law = ViaPoint(distance=0.4, switch_distance=0.05, limits=LIMITS)
    result = closed_loop(
        law, Unicycle(), STARTS[::9], [0, 0, 0], 60.0, 0.01, goal=[0, 0, 0],
        tolerance=(0.01, 0.0175),
    )  # fmt: skip
    gap = np.hypot(result.true_pose[..., 0] + 0.4, result.true_pose[..., 1]).min(axis=1)
    assert np.all(gap < 0.05)


def test_differential_drive_plant_with_wheel_speed_limits():
    robot = DiffDrive(wheel_radius=0.05, half_track=0.2)
    limits = VelocityLimits(max_speed=0.5, max_wheel_speed=12.0, wheel_radius=0.05, half_track=0.2)
    result = closed_loop(
        ViaDirection(limits=limits), robot, STARTS[::7], [0, 0, 0], 60.0, 0.01,
        goal=[0, 0, 0], tolerance=(0.01, math.radians(1)),
    )  # fmt: skip
    assert set(result.statuses) == {"arrived"}
    v, omega = result.command[..., 0], result.command[..., 1]
    wheels = np.maximum(np.abs(v - 0.2 * omega), np.abs(v + 0.2 * omega)) / 0.05
    assert wheels.max() <= 12.0 + 1e-9
    np.testing.assert_allclose(saturate_velocity(result.command, limits), result.command)
