import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from wheelbase import ConfigError, InputError, Unicycle
from wheelbase.control import SteeringLimits, VelocityLimits
from wheelbase.control.path import (
    PurePursuit,
    RearWheelFeedback,
    SegmentFollower,
    Stanley,
)
from wheelbase.geometry import wrap_angle
from wheelbase.models import RearWheelBicycle
from wheelbase.planning import PlannedPath
from wheelbase.sim import closed_loop

LAWS = (SegmentFollower, PurePursuit, Stanley, RearWheelFeedback)
LIMITS = VelocityLimits(0.5, 1.5)


def circle(radius, n=200, turns=1.0):
    angle = np.linspace(-0.5 * np.pi, -0.5 * np.pi + 2 * np.pi * turns, n)
    return np.stack([radius * np.cos(angle), radius + radius * np.sin(angle)], -1)


def three_point_turn():
    r = 1.5
    a = np.linspace(-np.pi / 2, 0, 40)
    forward = np.stack([r * np.cos(a), r + r * np.sin(a)], -1)
    b = np.linspace(np.pi, 1.5 * np.pi, 40)[1:]
    reverse = np.stack([3 + r * np.cos(b), r + r * np.sin(b)], -1)
    last = np.stack([np.linspace(3, 1, 41)[1:], np.zeros(40)], -1)
    directions = np.r_[np.ones(39), -np.ones(39), np.ones(40)]
    return PlannedPath.from_points(np.concatenate([forward, reverse, last]), directions)


def test_path_from_points_geometry():
    path = PlannedPath.from_points([[0, 0], [1, 0], [1, 0], [1, 2]], directions=[1, 1, -1])
    assert len(path) == 3  # the repeated point is dropped with its segment
    assert path.length == 3.0 and path.cusps == 1
    np.testing.assert_array_equal(path.directions, [1, 1, -1])
    # reversing up +y: the robot faces -y
    np.testing.assert_allclose(path.poses[:, 2], [0.0, 0.0, -math.pi / 2])
    np.testing.assert_allclose(path.distance([[0.5, 1.0], [2.0, 3.0]]), [0.5, math.sqrt(2)])
    ring = PlannedPath.from_points(circle(2.0, 400))
    np.testing.assert_allclose(ring.curvatures[1:-1], 0.5, rtol=1e-3)
    backwards = PlannedPath.from_points(circle(2.0, 400), -np.ones(399))
    # the same left-turning geometry driven in reverse: steering curvature of the other sign
    np.testing.assert_allclose(backwards.curvatures[1:-1], -0.5, rtol=1e-3)


def test_path_from_points_bad_input():
    with pytest.raises(InputError, match="two distinct points"):
        PlannedPath.from_points([[1.0, 1.0], [1.0, 1.0]])
    with pytest.raises(InputError, match="two distinct points"):
        PlannedPath.from_points([[1.0, 1.0]])
    with pytest.raises(InputError, match="directions"):
        PlannedPath.from_points([[0, 0], [1, 0]], directions=[0.5])
    with pytest.raises(InputError, match="one entry per segment"):
        PlannedPath.from_points([[0, 0], [1, 0]], directions=[1, 1])
    with pytest.raises(InputError, match="path points"):
        PlannedPath.from_points([[0, 0, 0], [1, 0, 0]])


@pytest.mark.parametrize("law", LAWS)
def test_straight_line_offset_decays(law):
    path = PlannedPath.from_points([[0.0, 0.0], [8.0, 0.0]])
    controller = law(speed=0.4, wheel_base=0.2, limits=LIMITS)
    result = closed_loop(controller, Unicycle(), [0.0, 0.3, 0.3], path, 28.0, 0.01)
    y = np.abs(result.true_pose[0, :, 1])
    assert y[result.t >= 10.0].max() < 2e-3
    # it stops at the end of the path
    assert result.true_pose[0, -1, 0] == pytest.approx(8.0, abs=0.02)
    # (a planned path has a final heading: the follower holds it, so ω is ~1e-22, not 0)
    assert np.all(np.abs(result.command[0, -50:]) <= 1e-12)


@pytest.mark.parametrize("law", [PurePursuit, RearWheelFeedback])
def test_circle_is_followed_closely(law):
    path = PlannedPath.from_points(circle(1.0, 300, turns=0.9))
    result = closed_loop(law(speed=0.3, limits=LIMITS), Unicycle(), [0, 0, 0], path, 25, 0.01)
    error = path.distance(result.true_pose[0, :, :2])
    assert error.max() < 0.01


def test_segment_follower_steady_offset_on_a_circle_is_the_closed_form():
    # without curvature feed-forward the law needs a heading error e = ω/K_φ = v/(R·K_φ), which
    # it gets from the offset atan(K_r·d/ℓ) = e: d = ℓ·tan(v/(R·K_φ))/K_r (outside the circle)
    path = PlannedPath.from_points(circle(1.0, 600, turns=0.9))
    law = SegmentFollower(speed=0.3, k_r=1.0, k_heading=4.0, length_scale=0.25, limits=LIMITS)
    result = closed_loop(law, Unicycle(), [0, 0, 0], path, 12, 0.01)
    late = result.true_pose[0, result.t > 8, :2]
    offset = np.hypot(late[:, 0], late[:, 1] - 1.0) - 1.0
    np.testing.assert_allclose(offset, 0.25 * math.tan(0.3 / 4.0), atol=1e-3)


def test_stanley_rear_axle_offtracking_matches_the_closed_form():
    # Stanley holds the front axle on the circle, so the rear axle runs on the circle of
    # radius √(R² − L²) that keeps the wheel base as a chord-free tangent: offset R − √(R² − L²)
    radius, base = 1.0, 0.3
    path = PlannedPath.from_points(circle(radius, 400, turns=0.95))
    law = Stanley(speed=0.3, wheel_base=base, k=3.0, limits=LIMITS)
    result = closed_loop(law, Unicycle(), [0, 0, 0], path, 16, 0.01)
    late = result.true_pose[0, (result.t > 8) & (result.t < 16), :2]
    rear_radius = np.hypot(late[:, 0], late[:, 1] - radius)
    np.testing.assert_allclose(rear_radius, math.sqrt(radius**2 - base**2), atol=2e-3)


@pytest.mark.parametrize("law", LAWS)
@pytest.mark.parametrize("plant", ["unicycle", "bicycle"])
def test_cusp_path_with_reverse_section(law, plant):
    path = three_point_turn()
    if plant == "unicycle":
        model, controller = Unicycle(), law(speed=0.3, wheel_base=0.1, limits=LIMITS)
    else:
        model = RearWheelBicycle(wheel_base=0.5, max_steering=math.radians(35))
        limits = SteeringLimits(math.radians(35), max_steering_rate=3.0)
        controller = law(speed=0.3, output="steering", wheel_base=0.5, limits=limits)
    result = closed_loop(controller, model, [0.0, 0.05, 0.0], path, 40.0, 0.01)
    assert result.metrics()[0]["reversals"] == 2
    end = result.true_pose[0, -1]
    assert np.hypot(end[0] - 1.0, end[1]) < 0.03
    assert abs(abs(end[2]) - math.pi) < 0.1
    error = path.distance(result.true_pose[0, result.t >= 5, :2])
    assert error.max() < (0.1 if law is Stanley else 0.02)  # Stanley: rear-axle offtracking
    if plant == "bicycle":
        assert np.all(np.abs(result.command[..., 1]) <= math.radians(35) + 1e-12)


@given(
    st.floats(-0.5, 0.5),
    st.floats(-0.5, 0.5),
    st.floats(-1.0, 1.0),
    st.sampled_from(LAWS),
)
@settings(max_examples=40, deadline=None)
def test_reversing_negates_speed_and_steering(x, y, heading, law):
    # the same geometry driven forwards from θ and backwards from θ + π: (v, ω) → (−v, ω) and
    # (v, δ) → (−v, −δ)
    points = np.array([[-1.0, 0.0], [0.0, 0.2], [2.0, 0.5]])
    forward, backward = (
        PlannedPath.from_points(points, [1, 1]),
        PlannedPath.from_points(points, [-1, -1]),
    )
    pose = np.array([x, y, heading])
    flipped = np.array([x, y, heading + math.pi])
    for output in ("velocity", "steering"):
        a = law(output=output)(0.0, pose, forward)
        b = law(output=output)(0.0, flipped, backward)
        sign = 1.0 if output == "velocity" else -1.0
        np.testing.assert_allclose(b, [-a[0], sign * a[1]], atol=1e-9)


def test_follower_parameters():
    with pytest.raises(ConfigError, match="output"):
        PurePursuit(output="torque")
    with pytest.raises(ConfigError, match="SteeringLimits"):
        PurePursuit(output="steering", limits=LIMITS)
    with pytest.raises(ConfigError, match="k_e"):
        RearWheelFeedback(k_e=0.0)
    with pytest.raises(ConfigError, match="max_steering"):
        Stanley(max_steering=2.0)
    with pytest.raises(ConfigError, match="lookahead_gain"):
        PurePursuit(lookahead_gain=-1.0)
    for bad in (None, [[1.0]], "abc"):  # were TypeError/ValueError from float()
        with pytest.raises(ConfigError, match="lookahead_gain must be a real number"):
            PurePursuit(lookahead_gain=bad)
    assert PurePursuit(output="steering").command_names == ("speed", "steering")


def test_planned_path_with_per_sample_directions_is_accepted():
    planned = three_point_turn()  # a PlannedPath: one direction per sample
    assert planned.directions.shape == (len(planned.poses),)
    law = PurePursuit(speed=0.3, limits=LIMITS)
    result = closed_loop(law, Unicycle(), [0.0, 0.05, 0.0], planned, 40.0, 0.01)
    assert result.metrics()[0]["reversals"] == 2
    assert np.hypot(*(result.true_pose[0, -1, :2] - [1.0, 0.0])) < 0.03


@pytest.mark.parametrize("law", [PurePursuit, Stanley, RearWheelFeedback])
def test_velocity_followers_turn_in_place_to_a_planned_final_heading(law):
    # A planned path ending with a turn in place: its polyline cannot show it, its poses do.
    class Planned:
        poses = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 0.0, math.pi]])

    follower = law(speed=0.3, limits=VelocityLimits(max_speed=0.5, max_yaw_rate=1.5))
    result = closed_loop(follower, Unicycle(), (0.0, 0.0, 0.0), Planned(), 12.0, 0.02)
    final = result.true_pose[0, -1]
    assert np.hypot(final[0] - 1.0, final[1]) < 0.02
    assert abs(wrap_angle(final[2] - math.pi)) < 0.01
    # without the poses (a bare polyline) it stops facing the way it came
    plain = law(speed=0.3, limits=VelocityLimits(max_speed=0.5, max_yaw_rate=1.5))
    result = closed_loop(plain, Unicycle(), (0.0, 0.0, 0.0), Planned.poses[:, :2], 12.0, 0.02)
    assert abs(wrap_angle(result.true_pose[0, -1, 2])) < 0.05
