"""Point-to-polyline distance: the pruned kernel equals brute force."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from wheelbase.errors import InputError
from wheelbase.polyline import distance_to_polyline


def brute_force(points, polyline):
    a, b = polyline[:-1], polyline[1:]
    ab = b - a
    length2 = np.maximum(np.sum(ab * ab, axis=1), 1e-300)
    p = points[:, None, :]
    u = np.clip(np.sum((p - a) * ab, axis=2) / length2, 0.0, 1.0)
    gap = p - (a + u[..., None] * ab)
    return np.min(np.hypot(gap[..., 0], gap[..., 1]), axis=1)


coordinates = st.floats(-50, 50, allow_nan=False, allow_infinity=False)


@settings(max_examples=200, deadline=None)
@given(
    arrays(np.float64, st.tuples(st.integers(2, 80), st.just(2)), elements=coordinates),
    arrays(np.float64, st.tuples(st.integers(1, 60), st.just(2)), elements=coordinates),
)
def test_equals_brute_force(polyline, points):
    np.testing.assert_allclose(
        distance_to_polyline(points, polyline), brute_force(points, polyline), rtol=1e-12,
        atol=1e-12,
    )  # fmt: skip


def test_a_driven_path_against_a_long_plan():
    rng = np.random.default_rng(1)
    s = np.linspace(0, 20, 900)
    plan = np.column_stack([s, np.sin(s)])
    driven = plan[::3] + rng.normal(0, 0.05, (300, 2))
    np.testing.assert_allclose(
        distance_to_polyline(driven, plan), brute_force(driven, plan), atol=1e-12
    )


def test_one_vertex_and_shapes():
    assert distance_to_polyline([3.0, 4.0], [[0.0, 0.0]]) == pytest.approx(5.0)
    assert distance_to_polyline(np.zeros((2, 5, 2)), [[0, 1], [1, 1]]).shape == (2, 5)
    with pytest.raises(InputError):
        distance_to_polyline([[0.0, 0.0]], np.zeros((0, 2)))
