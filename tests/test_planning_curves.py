"""Reeds–Shepp and Dubins curves: end poses, lengths, sampling, symmetry, RS <= Dubins."""

import math

import numpy as np
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st

from wheelbase.errors import ConfigError, InputError
from wheelbase.geometry import wrap_angle
from wheelbase.planning import (
    dubins_candidates,
    dubins_length,
    dubins_path,
    reeds_shepp_candidates,
    reeds_shepp_length,
    reeds_shepp_path,
)

coord = st.floats(-8, 8, allow_nan=False)
angle = st.floats(-math.pi, math.pi, allow_nan=False)
pose = st.tuples(coord, coord, angle)
radius = st.floats(0.3, 4.0)


def _pose_error(a, b):
    return max(abs(a[0] - b[0]), abs(a[1] - b[1]), abs(float(wrap_angle(a[2] - b[2]))))


def test_all_48_reeds_shepp_words_occur_and_end_at_the_goal():
    rng = np.random.default_rng(7)
    words = set()
    for _ in range(1500):
        start, goal = rng.uniform(-5, 5, 3), rng.uniform(-5, 5, 3)
        for path in reeds_shepp_candidates(start, goal, 1.3):
            assert _pose_error(path.end, goal) < 1e-9, path.word
            words.add(path.word)
    assert len(words) == 48


@settings(max_examples=150, deadline=None)
@given(pose, pose, radius)
@example((0.0, 0.0, 0.0), (0.0, 1e-12, 0.0), 1.0)
@example((0.0, 0.0, 0.0), (0.0, 3.424362380703804e-07, 0.0), 3.0)
def test_dubins_candidates_end_at_goal_and_rs_is_never_longer(start, goal, r):
    candidates = dubins_candidates(start, goal, r)
    assert candidates  # Dubins paths always exist
    for path in candidates:
        # rounding grows along the path: 2e-9 m at the end of a 19 m loop
        assert _pose_error(path.end, goal) < 1e-9 * max(1.0, path.length), path.word
        assert np.all(path.segment_lengths >= 0)
    dub = dubins_length(start, goal, r)
    assert dub == pytest.approx(min(p.length for p in candidates), rel=1e-12)
    rs = reeds_shepp_length(start, goal, r)
    # Both solvers end within 1e-9 of the goal; a sideways offset ε that one of them rounds
    # away costs the other arcs of length ~ 2√(ε·r) (a goal 1e-12 m aside: RS 2.8e-6 m, Dubins 0).
    assert rs <= dub + 1e-9 + 4.0 * math.sqrt(1e-9 * r)
    assert rs >= math.dist(start[:2], goal[:2]) - 1e-9


@settings(max_examples=150, deadline=None)
@given(pose, pose, radius)
def test_reeds_shepp_symmetry_and_scaling(start, goal, r):
    forward = reeds_shepp_length(start, goal, r)
    assert reeds_shepp_length(goal, start, r) == pytest.approx(forward, rel=1e-9, abs=1e-9)
    scaled = reeds_shepp_length(np.multiply(start, [2, 2, 1]), np.multiply(goal, [2, 2, 1]), 2 * r)
    assert scaled == pytest.approx(2 * forward, rel=1e-9, abs=1e-9)
    # Dubins: driving the reversed path backwards in time = swapping and turning both poses
    flip = np.array([0, 0, math.pi])
    assert dubins_length(np.add(goal, flip), np.add(start, flip), r) == pytest.approx(
        dubins_length(start, goal, r), rel=1e-9, abs=1e-9
    )


@settings(max_examples=60, deadline=None)
@given(pose, pose, radius, st.floats(0.05, 0.5), st.booleans())
def test_sampling_hits_both_ends_and_preserves_length(start, goal, r, step, use_dubins):
    curve = dubins_path(start, goal, r) if use_dubins else reeds_shepp_path(start, goal, r)
    path = curve.sample(step)
    assert _pose_error(path.poses[0], start) < 1e-9
    assert _pose_error(path.poses[-1], goal) < 1e-9
    assert path.length == pytest.approx(curve.length, rel=1e-12, abs=1e-12)
    ds = np.diff(path.arc_length)
    assert np.all(ds <= step + 1e-9)
    chords = np.hypot(*np.diff(path.poses[:, :2], axis=0).T)
    assert np.all(chords <= ds + 1e-9)
    # heading change = steering curvature x direction x distance, sample by sample
    dtheta = wrap_angle(np.diff(path.poses[:, 2]))
    expected = path.curvatures[1:] * path.directions[1:] * ds
    np.testing.assert_allclose(dtheta, wrap_angle(expected), atol=1e-9)
    assert set(np.round(np.abs(path.curvatures) * r, 9)) <= {0.0, 1.0}
    assert path.cusps == curve.cusps <= 2
    if use_dubins:
        assert np.all(path.directions == 1)


def test_closed_forms():
    r = 2.0
    assert reeds_shepp_length((0, 0, 0), (-3, 0, 0), r) == pytest.approx(3.0)
    assert reeds_shepp_path((0, 0, 0), (-3, 0, 0), r).word == "S-"
    assert dubins_length((0, 0, 0), (5, 0, 0), r) == pytest.approx(5.0)
    for phi in (0.3, 1.0, 2.5):
        arc_end = (r * math.sin(phi), r * (1 - math.cos(phi)), phi)
        assert dubins_length((0, 0, 0), arc_end, r) == pytest.approx(r * phi)
        assert reeds_shepp_length((0, 0, 0), arc_end, r) == pytest.approx(r * phi)
    # a U-turn to the point beside the start: Dubins needs a full half circle (πR) and more
    assert dubins_length((0, 0, 0), (0, 2 * r, math.pi), r) == pytest.approx(math.pi * r)


def test_curve_errors():
    with pytest.raises(ConfigError, match="turning_radius"):
        reeds_shepp_length((0, 0, 0), (1, 1, 0), 0.0)
    with pytest.raises(ConfigError, match="turning_radius"):
        dubins_path((0, 0, 0), (1, 1, 0), -1.0)
    with pytest.raises(InputError, match="start"):
        reeds_shepp_path((0, 0), (1, 1, 0), 1.0)
    with pytest.raises(InputError, match="goal"):
        dubins_length((0, 0, 0), (1, np.nan, 0), 1.0)
    with pytest.raises(ConfigError, match="step"):
        reeds_shepp_path((0, 0, 0), (1, 1, 0), 1.0).sample(0.0)
