import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from wheelbase.errors import InputError
from wheelbase.geometry import (
    compose,
    inverse_pose,
    relative_pose,
    rotation_jacobian,
    se2_exp,
    to_body_frame,
    to_world_frame,
    transform_points,
    wrap_angle,
)

angles = st.floats(-1e3, 1e3, allow_nan=False)
coords = st.floats(-100, 100, allow_nan=False)
poses = st.tuples(coords, coords, st.floats(-np.pi, np.pi))


@given(angles)
def test_wrap_angle_interval_and_equivalence(angle):
    wrapped = float(wrap_angle(angle))
    assert -np.pi < wrapped <= np.pi
    assert np.isclose(np.cos(wrapped), np.cos(angle), atol=1e-9)
    assert np.isclose(np.sin(wrapped), np.sin(angle), atol=1e-9)


def test_wrap_angle_maps_minus_pi_to_pi_and_keeps_shape():
    assert wrap_angle(-np.pi) == np.pi
    assert wrap_angle(np.pi) == np.pi
    assert wrap_angle(np.zeros((4, 2))).shape == (4, 2)


@given(poses, poses)
def test_compose_inverse_identity(a, b):
    a, b = np.array(a), np.array(b)
    identity = compose(a, inverse_pose(a))
    np.testing.assert_allclose(identity[:2], 0.0, atol=1e-9)
    assert abs(wrap_angle(identity[2])) < 1e-9
    back = compose(a, relative_pose(a, b))
    np.testing.assert_allclose(back[:2], b[:2], atol=1e-9)
    assert abs(wrap_angle(back[2] - b[2])) < 1e-9


@given(st.floats(-np.pi, np.pi), st.tuples(coords, coords, coords))
def test_jacobian_matches_world_and_body_frame(theta, twist):
    twist = np.array(twist)
    world = to_world_frame(theta, twist)
    np.testing.assert_allclose(world, rotation_jacobian(theta) @ twist, atol=1e-9)
    np.testing.assert_allclose(to_body_frame(theta, world), twist, atol=1e-9)


def test_transform_points_batch():
    pose = np.array([[1.0, 2.0, np.pi / 2], [0.0, 0.0, 0.0]])
    points = np.array([[1.0, 0.0], [0.0, 1.0]])
    out = transform_points(pose, points)
    assert out.shape == (2, 2, 2)
    np.testing.assert_allclose(out[0], [[1.0, 3.0], [0.0, 2.0]], atol=1e-12)
    np.testing.assert_allclose(out[1], points)


@pytest.mark.parametrize("yaw_rate", [0.0, 1e-12, 1e-6, 0.3, -2.0, 40.0])
def test_se2_exp_is_the_circular_arc(yaw_rate):
    speed, lateral, duration, theta0 = 0.7, 0.2, 1.3, 0.4
    end = se2_exp([1.0, -1.0, theta0], [speed, lateral, yaw_rate], duration)
    # Closed form of a body moving with constant twist: integrate the world velocity exactly.
    if abs(yaw_rate) < 1e-5:  # the arc differs from the line by ~r·h²·u/2 < 1e-5 m here
        expected_xy = (
            np.array([1.0, -1.0]) + duration * to_world_frame(theta0, [speed, lateral, 0.0])[:2]
        )
    else:
        theta1 = theta0 + yaw_rate * duration
        d_sin, d_cos = np.sin(theta1) - np.sin(theta0), np.cos(theta1) - np.cos(theta0)
        dx = speed * d_sin + lateral * d_cos
        dy = -speed * d_cos + lateral * d_sin
        expected_xy = np.array([1.0, -1.0]) + np.array([dx, dy]) / yaw_rate
    tolerance = 1e-12 if abs(yaw_rate) >= 1e-5 else 10 * abs(yaw_rate) + 1e-15
    np.testing.assert_allclose(end[:2], expected_xy, atol=tolerance)
    assert abs(wrap_angle(end[2] - theta0 - yaw_rate * duration)) < 1e-12


def test_bad_pose_shape_is_a_clear_error():
    with pytest.raises(InputError, match=r"shape \(\.\.\., 3\)"):
        compose([1.0, 2.0], [0.0, 0.0, 0.0])
    with pytest.raises(InputError, match="finite"):
        inverse_pose([np.nan, 0.0, 0.0])
