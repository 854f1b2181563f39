"""The range–bearing landmark sensor: geometry, field of view, noise, detections and clutter."""

import math

import numpy as np
import pytest

from wheelbase.errors import ConfigError, InputError
from wheelbase.geometry import transform_points
from wheelbase.sensors import LandmarkSensor, range_bearing


def test_noise_free_measurements_invert_to_the_landmark_positions():
    rng = np.random.default_rng(0)
    landmarks = rng.uniform(-5, 5, (30, 2))
    poses = np.column_stack([rng.uniform(-5, 5, (4, 2)), rng.uniform(-np.pi, np.pi, 4)])
    seen = LandmarkSensor(max_range=100.0).observe(landmarks, poses, rng=1)
    assert len(seen) == 4 * 30 and not seen.false.any()
    # r·(cos φ, sin φ) in the body frame, mapped to the world, is the landmark.
    body = np.column_stack([seen.range * np.cos(seen.bearing), seen.range * np.sin(seen.bearing)])
    world = transform_points(poses[seen.robot], body[:, None, :])[:, 0]
    np.testing.assert_allclose(world, landmarks[seen.landmark], atol=1e-12)
    np.testing.assert_array_equal(np.diff(seen.robot) >= 0, True)


def test_only_landmarks_in_range_and_field_of_view_are_seen():
    landmarks = np.array([[1.0, 0.0], [0.0, 1.0], [-1.0, 0.0], [3.0, 0.1], [0.5, -0.5]])
    sensor = LandmarkSensor(max_range=2.0, fov=math.radians(180))
    seen = sensor.observe(landmarks, [0.0, 0.0, 0.0], rng=0)
    assert sorted(seen.landmark.tolist()) == [0, 1, 4]  # behind (2) and too far (3) unseen
    expected = range_bearing([0.0, 0.0, 0.0], landmarks[[0, 1, 4]])
    np.testing.assert_allclose(np.column_stack([seen.range, seen.bearing]), expected)


def test_noise_detection_probability_and_clutter_have_their_stated_statistics():
    sensor = LandmarkSensor(
        max_range=50.0,
        range_std=0.1,
        bearing_std=0.02,
        detection_probability=0.7,
        false_rate=0.5,
    )
    landmarks = np.array([[3.0, 4.0], [-2.0, 1.0]])
    poses = np.zeros((20000, 3))
    seen = sensor.observe(landmarks, poses, rng=np.random.default_rng(2))
    true = ~seen.false
    n_true = true.sum()
    expected = 0.7 * 2 * 20000
    assert abs(n_true - expected) < 4 * math.sqrt(expected * 0.3)
    n_false = seen.false.sum()
    assert abs(n_false - 0.5 * 20000) < 4 * math.sqrt(0.5 * 20000)  # Poisson
    truth = range_bearing(poses[seen.robot[true]], landmarks[seen.landmark[true]])
    dr = seen.range[true] - truth[:, 0]
    db = seen.bearing[true] - truth[:, 1]
    assert abs(dr.mean()) < 4 * 0.1 / math.sqrt(n_true)
    assert dr.std() == pytest.approx(0.1, rel=0.03)
    assert db.std() == pytest.approx(0.02, rel=0.03)
    assert np.all((seen.range[seen.false] >= 0) & (seen.range[seen.false] <= 50.0))
    assert set(np.unique(seen.landmark[seen.false])) == {0, 1}


def test_padded_layout_for_the_estimators():
    landmarks = np.array([[1.0, 0.0], [2.0, 0.0], [3.0, 0.0]])
    poses = np.array([[0.0, 0.0, 0.0], [10.0, 0.0, 0.0], [2.5, 0.0, 0.0]])
    seen = LandmarkSensor(max_range=1.2).observe(landmarks, poses, rng=0)
    ids, z = seen.padded(3)
    assert ids.shape == (3, 2) and z.shape == (3, 2, 2)
    assert ids.tolist() == [[0, -1], [-1, -1], [1, 2]]
    np.testing.assert_allclose(z[2], [[0.5, math.pi], [0.5, 0.0]])
    assert np.isnan(z[1]).all()


def test_bad_parameters_raise_clear_errors():
    with pytest.raises(ConfigError, match="detection_probability"):
        LandmarkSensor(detection_probability=1.5)
    with pytest.raises(ConfigError, match="bearing_std"):
        LandmarkSensor(bearing_std=-1.0)
    with pytest.raises(ConfigError, match="max_range"):
        LandmarkSensor(max_range=0.0)
    with pytest.raises(InputError, match="landmarks"):
        LandmarkSensor().observe([1.0, 2.0], [0.0, 0.0, 0.0])
    with pytest.raises(InputError, match="false detections"):
        LandmarkSensor(false_rate=1.0).observe(np.zeros((0, 2)), [0.0, 0.0, 0.0])
