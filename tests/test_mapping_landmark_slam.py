"""Landmark SLAM: the camera model's Jacobians, and EKF-SLAM + smoothing on MRCLAM robot 1."""

# ruff: noqa: B023 (the lambdas are called at once, inside their loop iteration)

import numpy as np
import pytest

from shared_data import DATA, absent
from wheelbase.errors import ConfigError
from wheelbase.mapping.landmark_slam import _inverse_observe, _observe, landmark_slam

MRCLAM = DATA / "mrclam"
needs_data = pytest.mark.skipif(
    not (MRCLAM / "Dataset6_Robot1_Measurement.dat").is_file(), reason=absent(MRCLAM)
)


def _numeric(f, x, eps=1e-6):
    cols = []
    for k in range(x.size):
        d = np.zeros_like(x)
        d[k] = eps
        cols.append((f(x + d) - f(x - d)) / (2 * eps))
    return np.column_stack(cols)


def test_observation_jacobians_match_finite_differences():
    rng = np.random.default_rng(0)
    for _ in range(20):
        pose, c = rng.normal(size=3), rng.normal(size=3) * 0.05
        kappa, m = 1.0 + 0.05 * rng.normal(), pose[:2] + rng.uniform(1, 4, 2)
        z, hp, hk, hm = _observe(pose, c, kappa, m)
        np.testing.assert_allclose(hp, _numeric(lambda p: _observe(p, c, kappa, m)[0], pose),
                                   atol=1e-6)  # fmt: skip
        np.testing.assert_allclose(hm, _numeric(lambda q: _observe(pose, c, kappa, q)[0], m),
                                   atol=1e-6)  # fmt: skip
        np.testing.assert_allclose(hk, _numeric(lambda k: _observe(pose, c, k[0], m)[0],
                                                np.array([kappa]))[:, 0], atol=1e-6)  # fmt: skip
        # the inverse observation puts the landmark back, with consistent Jacobians
        back, jp, _, jz = _inverse_observe(pose, c, kappa, z)
        np.testing.assert_allclose(back, m, atol=1e-9)
        np.testing.assert_allclose(jz, _numeric(lambda q: _inverse_observe(pose, c, kappa, q)[0],
                                                z), atol=1e-5)  # fmt: skip
        np.testing.assert_allclose(jp, _numeric(lambda p: _inverse_observe(p, c, kappa, z)[0],
                                                pose), atol=1e-5)  # fmt: skip


@needs_data
def test_smoothing_on_mrclam_robot_1_with_unknown_landmarks():
    result = landmark_slam(MRCLAM, 1, "smoothing")
    m = result.metrics()
    assert m["landmarks_seen"] == 15
    assert m["position_rmse_m"] < 0.15  # localisation with the landmarks known: 0.09-0.11 m
    assert m["landmark_rmse_m"] < 0.2
    assert m["dead_reckoning_rmse_m"] > 2.0
    assert 1.0 < m["camera_range_scale"] < 1.05
    with pytest.raises(ConfigError, match="method"):
        landmark_slam(MRCLAM, 1, "fastslam")
