"""Pose-graph optimisation on SE(2): the Lie-group pieces, Jacobians, optimum, and GTSAM."""

import math

import numpy as np
import pytest
from typer.testing import CliRunner

from shared_data import DATA, absent
from wheelbase.datasets import PoseGraph, read_g2o
from wheelbase.errors import ConfigError, DataError, EstimationError
from wheelbase.geometry import compose, relative_pose
from wheelbase.mapping import chordal_initialization, graph_chi2, optimize_pose_graph
from wheelbase.mapping import posegraph as pg
from wheelbase.mapping.se2 import (
    se2_adjoint,
    se2_exp_map,
    se2_log,
    se2_right_jacobian,
    se2_right_jacobian_inv,
)

GRAPHS = DATA / "posegraph"
needs_graphs = pytest.mark.skipif(not (GRAPHS / "intel.g2o").is_file(), reason=absent(GRAPHS))


def _tangents(rng, n=200):
    xi = rng.normal(size=(n, 3))
    xi[:, 2] = rng.uniform(-3.1, 3.1, n)
    xi[:10, 2] = rng.normal(size=10) * 1e-7  # the series branch
    return xi


def test_exp_and_log_are_inverse():
    xi = _tangents(np.random.default_rng(0))
    np.testing.assert_allclose(se2_log(se2_exp_map(xi)), xi, atol=1e-12)
    # and Exp of a pure rotation / translation is what it should be
    np.testing.assert_allclose(se2_exp_map([1.0, 2.0, 0.0]), [1.0, 2.0, 0.0])


def test_right_jacobian_matches_finite_differences_and_its_inverse():
    rng = np.random.default_rng(1)
    for xi in _tangents(rng, 30):
        jr = se2_right_jacobian(xi)
        numeric = np.empty((3, 3))
        for k in range(3):
            d = np.zeros(3)
            d[k] = 1e-6
            # Exp(ξ + δ) = Exp(ξ)·Exp(J_r δ)  ⇒  J_r δ = Log(Exp(ξ)⁻¹ Exp(ξ + δ))
            plus = se2_log(relative_pose(se2_exp_map(xi), se2_exp_map(xi + d)))
            minus = se2_log(relative_pose(se2_exp_map(xi), se2_exp_map(xi - d)))
            numeric[:, k] = (plus - minus) / 2e-6
        np.testing.assert_allclose(jr, numeric, atol=1e-7)
        np.testing.assert_allclose(se2_right_jacobian_inv(xi) @ jr, np.eye(3), atol=1e-12)


def test_adjoint_moves_a_tangent_through_the_pose():
    rng = np.random.default_rng(2)
    x, xi = rng.normal(size=3), rng.normal(size=3) * 0.3
    lhs = compose(compose(x, se2_exp_map(xi)), relative_pose(x, np.zeros(3)))
    np.testing.assert_allclose(lhs, se2_exp_map(se2_adjoint(x) @ xi), atol=1e-12)


def _ring(rng, n=30, noise=0.0):
    """A loop of n poses with odometry and a few loop edges, measured with noise."""
    angle = np.linspace(0, 2 * math.pi, n, endpoint=False)
    truth = np.column_stack([5 * np.cos(angle), 5 * np.sin(angle), angle + math.pi / 2])
    edges = np.array([[i, (i + 1) % n] for i in range(n)] + [[0, n // 2], [3, n - 4]])
    z = (
        relative_pose(truth[edges[:, 0]], truth[edges[:, 1]])
        + rng.normal(size=(len(edges), 3)) * noise
    )
    info = np.broadcast_to(np.diag([100.0, 100.0, 400.0]), (len(edges), 3, 3)).copy()
    return truth, PoseGraph(np.arange(n), truth.copy(), edges, z, info)


def _assembled(graph, poses, weights, fixed):
    """The Numba kernel's normal equations, as a dense H and g in vertex order (free ones)."""
    from wheelbase.mapping._posegraph_kernels import assemble_kernel

    s = pg._GraphSystem(graph, fixed)
    n = s.free.size
    diag, off, g = np.empty((n, 3, 3)), np.empty((s.chol.n_off, 3, 3)), np.empty((n, 3))
    poses = np.ascontiguousarray(poses)
    z, zcs, info = s.measurements, s.measured_cos_sin, s.information
    assemble_kernel(poses, s.edges, z, zcs, info, weights, s.free_index, s.slot, s.upper,
                    diag, off, g)  # fmt: skip
    return s, s.chol.to_dense(diag, off), g


def test_gradient_and_gauss_newton_matrix_match_finite_differences():
    rng = np.random.default_rng(3)
    _, graph = _ring(rng, 8, noise=0.1)
    poses = graph.poses + rng.normal(size=graph.poses.shape) * 0.2
    fixed = np.zeros(graph.n_vertices, bool)
    fixed[0] = True
    s, _, g = _assembled(graph, poses, np.ones(graph.n_edges), fixed)
    numeric = np.zeros_like(g)
    for row, v in enumerate(s.free):
        for k in range(3):
            d = np.zeros(3)
            d[k] = 1e-6
            up, down = poses.copy(), poses.copy()
            up[v] = compose(poses[v], se2_exp_map(d))
            down[v] = compose(poses[v], se2_exp_map(-d))
            numeric[row, k] = (graph_chi2(graph, up) - graph_chi2(graph, down)) / 2e-6 / 2
    np.testing.assert_allclose(g, numeric, rtol=1e-5, atol=1e-5)


def test_numba_assembly_equals_the_numpy_linearisation():
    # random weights, two fixed vertices, a repeated edge in both directions and a self-edge
    rng = np.random.default_rng(9)
    _, ring = _ring(rng, 12, noise=0.1)
    edges = np.vstack([ring.edges, [[4, 3], [3, 4], [6, 6], [0, 11]]])
    z = np.vstack([ring.measurements, rng.normal(size=(4, 3)) * 0.5])
    info = np.concatenate([ring.information, ring.information[:4]])
    graph = PoseGraph(ring.ids, ring.poses, edges, z, info)
    poses = graph.poses + rng.normal(size=graph.poses.shape) * 0.3
    poses[:, 2] = np.where(np.arange(len(poses)) % 3 == 0, poses[:, 2] + 3.0, poses[:, 2])
    weights = rng.uniform(0.1, 2.0, graph.n_edges)
    fixed = np.zeros(graph.n_vertices, bool)
    fixed[[0, 7]] = True
    s, h, g = _assembled(graph, poses, weights, fixed)
    _, blocks, gi, gj = pg._linearise(graph, poses, weights)
    n = graph.n_vertices
    dense_h, dense_g = np.zeros((3 * n, 3 * n)), np.zeros((n, 3))
    for e, (i, j) in enumerate(graph.edges):
        for (a, b), block in zip([(i, i), (i, j), (j, i), (j, j)], blocks[e], strict=True):
            dense_h[3 * a : 3 * a + 3, 3 * b : 3 * b + 3] += block
        dense_g[i] += gi[e]
        dense_g[j] += gj[e]
    keep = (3 * s.free[:, None] + np.arange(3)).ravel()
    np.testing.assert_allclose(h, dense_h[np.ix_(keep, keep)], rtol=1e-12, atol=1e-9)
    np.testing.assert_allclose(g, dense_g[s.free], rtol=1e-12, atol=1e-9)
    # the retraction X·Exp(δ) of the free vertices, angles across ±π included
    from wheelbase.mapping._posegraph_kernels import retract_kernel

    step = rng.normal(size=(s.free.size, 3))
    step[:3, 2] = [0.0, 1e-9, 3.1]
    moved = retract_kernel(poses, s.free, step)
    np.testing.assert_allclose(moved[s.free], pg._retract(poses[s.free], step), atol=1e-12)
    np.testing.assert_array_equal(moved[fixed], poses[fixed])
    np.testing.assert_allclose(
        pg.edge_chi2(graph, poses),
        np.einsum("ei,eij,ej->e", r := pg.edge_residuals(graph, poses), graph.information, r),
        rtol=1e-12,
    )


def test_exact_measurements_are_recovered_from_a_perturbed_start():
    rng = np.random.default_rng(4)
    truth, graph = _ring(rng)
    start = graph.poses.copy()
    start[1:] += rng.normal(size=(len(start) - 1, 3)) * [0.3, 0.3, 0.1]
    for initial in ("graph", "chordal"):
        result = optimize_pose_graph(graph.with_poses(start), initial=initial)
        assert result.converged and result.chi2 < 1e-16
        np.testing.assert_allclose(result.poses[:, :2], truth[:, :2], atol=1e-8)


def test_robust_kernel_discounts_a_false_loop_closure():
    rng = np.random.default_rng(5)
    _, graph = _ring(rng, noise=0.01)
    bad = PoseGraph(graph.ids, graph.poses,
                    np.vstack([graph.edges, [[5, 20]]]),
                    np.vstack([graph.measurements, [[0.5, 0.0, 0.0]]]),
                    np.concatenate([graph.information, graph.information[:1]]))  # fmt: skip
    loops = np.zeros(bad.n_edges, bool)
    loops[graph.n_edges - 2 :] = True
    plain = optimize_pose_graph(bad)
    robust = optimize_pose_graph(bad, robust="dcs", robust_scale=1.0, robust_edges=loops)
    clean = optimize_pose_graph(graph).poses
    err = lambda r: np.abs(r.poses[:, :2] - clean[:, :2]).max()  # noqa: E731
    assert err(robust) < 1e-3 and err(plain) > 0.1
    assert robust.edge_weights[-1] < 1e-3 and np.all(robust.edge_weights[:-3] == 1.0)


def test_options_are_checked():
    _, graph = _ring(np.random.default_rng(6))
    with pytest.raises(ConfigError, match="robust"):
        optimize_pose_graph(graph, robust="tukey")
    with pytest.raises(ConfigError, match="robust_edges"):
        optimize_pose_graph(graph, robust="huber", robust_edges=np.ones(3, bool))


def test_a_graph_the_kernels_cannot_index_is_refused():
    _, graph = _ring(np.random.default_rng(10), 6)
    bad = PoseGraph(graph.ids, graph.poses, np.vstack([graph.edges, [[2, 6]]]),
                    np.vstack([graph.measurements, [[1.0, 0.0, 0.0]]]),
                    np.concatenate([graph.information, graph.information[:1]]))  # fmt: skip
    with pytest.raises(DataError, match="edges must index the 6 vertices"):
        optimize_pose_graph(bad)
    with pytest.raises(DataError, match="edges must index"):
        graph_chi2(bad)
    with pytest.raises(DataError, match="poses must have shape"):
        graph_chi2(graph, graph.poses[:, :2])


def test_an_unconstrained_vertex_is_a_clear_error():
    # vertex 3 has no edge: H is singular there (the Cholesky pivot vanishes), and the
    # chordal problems have a second component
    info = np.broadcast_to(np.eye(3) * 10.0, (2, 3, 3)).copy()
    graph = PoseGraph(np.arange(4), np.zeros((4, 3)), np.array([[0, 1], [1, 2]]),
                      np.array([[1.0, 0.0, 0.1], [1.0, 0.0, 0.1]]), info)  # fmt: skip
    with pytest.raises(EstimationError, match="not fully constrained"):
        optimize_pose_graph(graph)
    with pytest.raises(EstimationError, match="not connected"):
        optimize_pose_graph(graph, initial="chordal")


@needs_graphs
def test_intel_reaches_the_gtsam_optimum():
    # GTSAM 4.3's Levenberg-Marquardt from the file's guess reaches chi2 45.004 (notes)
    result = optimize_pose_graph(read_g2o(GRAPHS / "intel.g2o"), initial="graph")
    assert result.converged
    assert result.chi2 == pytest.approx(45.00423308, rel=1e-8)


@needs_graphs
def test_chordal_start_escapes_the_local_minimum_of_mit():
    graph = read_g2o(GRAPHS / "MIT.g2o")
    result = optimize_pose_graph(graph, initial="chordal")
    assert result.converged and result.chi2 < 45.0  # GTSAM's LM from the odometry: 770.24
    start = chordal_initialization(graph)
    np.testing.assert_allclose(start[0], graph.poses[0], atol=1e-12)


def test_chi2_is_twice_gtsams_error():
    gtsam = pytest.importorskip("gtsam")
    rng = np.random.default_rng(7)
    _, graph = _ring(rng, noise=0.2)
    poses = graph.poses + rng.normal(size=graph.poses.shape)
    factors, values = gtsam.NonlinearFactorGraph(), gtsam.Values()
    for k, (i, j) in enumerate(graph.edges):
        factors.add(gtsam.BetweenFactorPose2(int(i), int(j), gtsam.Pose2(*graph.measurements[k]),
                    gtsam.noiseModel.Gaussian.Information(graph.information[k])))  # fmt: skip
    for v, pose in enumerate(poses):
        values.insert(v, gtsam.Pose2(*pose))
    assert graph_chi2(graph, poses) == pytest.approx(2 * factors.error(values), rel=1e-12)


def test_posegraph_command(tmp_path):
    from wheelbase.cli import app
    from wheelbase.datasets import write_g2o

    _, graph = _ring(np.random.default_rng(8), noise=0.02)
    path = write_g2o(graph, tmp_path / "ring.g2o")
    runner = CliRunner()
    result = runner.invoke(app, ["posegraph", str(path), "--out", str(tmp_path / "out")])
    assert result.exit_code == 0, result.output
    import json

    metrics = json.loads((tmp_path / "out" / "metrics.json").read_text())
    assert set(metrics) >= {"chi2_initial", "chi2", "iterations", "solve_time_s"}
    assert metrics["chi2"] <= metrics["chi2_initial"]
    assert read_g2o(tmp_path / "out" / "optimized.g2o").n_edges == graph.n_edges
    again = runner.invoke(app, ["posegraph", str(path), "--out", str(tmp_path / "out")])
    assert again.exit_code == 2 and "exists" in again.output
    bad = runner.invoke(app, ["posegraph", str(tmp_path / "no.g2o"), "--out", str(tmp_path)])
    assert bad.exit_code == 2 and "not found" in bad.output
