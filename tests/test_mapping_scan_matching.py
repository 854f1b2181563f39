"""Scan matching: branch and bound equals brute force, the pose is recovered, evaluation."""

import math

import numba
import numpy as np
import pytest

from wheelbase.errors import MapError
from wheelbase.geometry import compose, relative_pose
from wheelbase.mapping.evaluation import (
    absolute_trajectory_error,
    align_trajectory,
    map_agreement,
    relation_pairs,
    relative_errors,
)
from wheelbase.mapping.scan_matching import (
    LikelihoodTable,
    PointReference,
    ScanMatcher,
    _branch_and_bound,
    _score,
    _transform,
    scan_points,
    surface_points,
)
from wheelbase.planning import load_map
from wheelbase.sensors import Lidar

WAREHOUSE = load_map("warehouse")
LIDAR = Lidar(beams=360, max_range=8.0)


def _points(pose):
    return scan_points(LIDAR.scan(WAREHOUSE, pose, noise=False), LIDAR.beam_angles, 8.0)


@pytest.mark.parametrize("seed", range(3))
def test_branch_and_bound_finds_the_brute_force_optimum(seed):
    rng = np.random.default_rng(seed)
    world = rng.uniform(0, 6, size=(300, 2))
    table = LikelihoodTable.build(world, 0.1, 0.1, depth=4)
    points = rng.uniform(-2, 2, size=(40, 2))
    angles = rng.uniform(-0.2, 0.2, 5)
    c, s = np.cos(angles)[:, None], np.sin(angles)[:, None]
    x, y = 3 + c * points[:, 0] - s * points[:, 1], 3 + s * points[:, 0] + c * points[:, 1]
    ci = np.floor((y - table.origin[1]) / 0.1).astype(np.int64)
    cj = np.floor((x - table.origin[0]) / 0.1).astype(np.int64)
    prior = -0.3 * angles**2
    best, a, di, dj = _branch_and_bound(numba.typed.List(table.levels), ci, cj, 5, 9, 9,
                                        table.floor, -np.inf, 0.01, prior)  # fmt: skip
    brute = max(
        (_score(table.levels[0], ci[k], cj[k], u, v, table.floor) - 0.01 * (u * u + v * v)
         + prior[k], k, u, v)
        for k in range(5) for u in range(-9, 10) for v in range(-9, 10)
    )  # fmt: skip
    assert best == pytest.approx(brute[0], abs=1e-9) and (a, di, dj) == brute[1:]


def test_surface_points_fill_a_grazing_wall_and_leave_a_depth_jump_open():
    # a corridor's side wall y = 1 seen from the origin at 1° per beam (returns up to 0.6 m
    # apart), then the beams jump to a far wall x = 9 behind an opening
    angles = np.radians(np.arange(10.0, 60.0))
    wall = np.column_stack([1.0 / np.tan(angles), np.ones(angles.size)])[::-1]
    far = np.column_stack([np.full(5, 9.0), np.linspace(2.0, 2.6, 5)])
    points = np.vstack([wall, far])
    dense = surface_points(points, step=0.05)
    assert np.array_equal(dense[: len(points)], points)  # the returns first, unchanged
    added = dense[len(points) :]
    on_wall = np.abs(added[:, 1] - 1.0) < 1e-12
    on_far = np.abs(added[:, 0] - 9.0) < 1e-12
    assert (on_wall | on_far).all()  # nothing in the opening between the two walls
    # the wall is sampled every 5 cm or closer from its first return to its last
    xs = np.sort(np.concatenate([wall[:, 0], added[on_wall, 0]]))
    assert np.diff(xs).max() <= 0.05 + 1e-12 and xs[0] == wall[:, 0].min()
    gaps = np.hypot(*np.diff(wall, axis=0).T)
    assert gaps.max() > 0.5  # the test's premise: returns sparser than the matcher's σ
    # a lone segment across a depth jump (not in line with its neighbours) stays open
    jump = np.array([[1.0, 0.0], [1.0, 0.1], [1.6, 0.5], [1.6, 0.6]])
    filled = surface_points(jump)[4:]
    assert filled.size and np.isin(filled[:, 0], [1.0, 1.6]).all()
    assert surface_points(points[:2]).shape == (2, 2)


@pytest.mark.parametrize("offset", [(0.4, -0.2, 0.15), (-0.5, 0.3, -0.5), (0.05, 0.02, 0.01)])
def test_scan_to_scan_recovers_the_motion(offset):
    a = np.array([6.0, 5.0, 0.3])
    b = compose(a, offset)
    reference = _transform(a, _points(a))
    table = LikelihoodTable.build(reference, 0.05, 0.05)
    matcher = ScanMatcher(linear_window=1.2, angular_window=math.radians(45))
    found = matcher.match(table, PointReference.build(reference), _points(b), a)
    error = relative_pose(b, found.pose)
    assert np.hypot(*error[:2]) < 0.01 and abs(error[2]) < math.radians(0.3)
    assert np.all(np.linalg.eigvalsh(found.covariance) > 0)
    assert found.inliers > 0.8 and found.rms < 0.01


def test_references_merged_from_their_own_frames_keep_their_own_lines():
    # two walls seen from two poses, each fitted in its own frame, then placed in the world
    wall = np.column_stack([np.linspace(-1.0, 1.0, 41), np.full(41, 2.0)])  # y = 2 m, local
    poses = np.array([[1.0, 0.5, 0.3], [-2.0, 1.0, -1.2]])
    other = wall + np.array([0.0, 1.0])
    parts = [PointReference.build(wall), PointReference.build(other)]
    merged = PointReference.merge(parts, poses)
    world = np.vstack([_transform(poses[0], wall), _transform(poses[1], other)])
    np.testing.assert_allclose(merged.points, world, atol=1e-12)
    # each normal is its own wall's (local ±y) turned by its pose, not a fit across the walls
    for k, q in enumerate(poses):
        rows = merged.normals[41 * k : 41 * (k + 1)]
        across = np.abs(rows @ np.array([-math.sin(q[2]), math.cos(q[2])]))
        np.testing.assert_allclose(across, 1.0, atol=1e-9)
    d, i = merged.tree.query(world[50])
    assert d == 0.0 and i == 50
    with pytest.raises(MapError):
        PointReference.merge(parts, poses[:1])


def test_window_and_min_score_reject_what_is_not_there():
    a = np.array([6.0, 5.0, 0.3])
    reference = _transform(a, _points(a))
    table = LikelihoodTable.build(reference, 0.05, 0.05)
    far = compose(a, [3.0, 0.0, 0.0])  # outside the ±0.3 m window
    matcher = ScanMatcher()
    assert matcher.correlative(table, _points(a), far, min_score=0.9) is None


def test_relative_errors_and_alignment():
    rng = np.random.default_rng(1)
    truth = np.column_stack([np.cumsum(rng.normal(size=(50, 2)), 0), rng.uniform(-3, 3, 50)])
    moved = compose([2.0, -1.0, 0.7], truth)  # a rigid motion changes no relative pose
    pairs = np.column_stack([np.arange(49), np.arange(1, 50)])
    et, er = relative_errors(moved, truth, pairs)
    assert et.max() < 1e-12 and er.max() < 1e-12
    assert absolute_trajectory_error(moved, truth) < 1e-9
    np.testing.assert_allclose(align_trajectory(moved, truth)[:, :2], truth[:, :2], atol=1e-9)
    local, loops = relation_pairs(truth, np.arange(50.0) * 10, min_distance=1.0, loop_gap_s=30,
                                  loop_distance=3.0, loop_angle=math.pi)  # fmt: skip
    assert len(local) > 0 and np.all(local[:, 1] > local[:, 0])
    assert np.all(loops[:, 1] - loops[:, 0] >= 3)


def test_map_agreement_of_a_map_with_itself_and_its_negative():
    assert map_agreement(WAREHOUSE, WAREHOUSE)[0] == 1.0
    from wheelbase.planning import OccupancyGrid

    flipped = OccupancyGrid(~WAREHOUSE.occupied, WAREHOUSE.resolution, WAREHOUSE.origin)
    assert map_agreement(flipped, WAREHOUSE)[0] == 0.0
