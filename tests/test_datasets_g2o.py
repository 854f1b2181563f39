"""g2o pose graphs: reading the benchmark files, writing them back, and refusing bad ones."""

import numpy as np
import pytest

from shared_data import DATA, absent
from wheelbase.datasets import PoseGraph, odometry_guess, read_g2o, write_g2o
from wheelbase.errors import DataError
from wheelbase.geometry import compose

GRAPHS = DATA / "posegraph"
needs_graphs = pytest.mark.skipif(not (GRAPHS / "intel.g2o").is_file(), reason=absent(GRAPHS))

EDGE = "EDGE_SE2 {} {} 1 0 0.1 100 0 0 100 0 400\n"


@needs_graphs
@pytest.mark.parametrize(
    ("name", "vertices", "edges"),
    [("intel", 1728, 2512), ("MIT", 808, 827), ("CSAIL", 1045, 1172), ("manhattan", 3500, 5453)],
)
def test_benchmark_files_have_their_published_size(name, vertices, edges):
    graph = read_g2o(GRAPHS / f"{name}.g2o")
    assert (graph.n_vertices, graph.n_edges) == (vertices, edges)
    assert np.all(np.isfinite(graph.poses))
    assert np.all(np.linalg.eigvalsh(graph.information)[:, 0] > 0)
    np.testing.assert_array_equal(graph.information, np.swapaxes(graph.information, 1, 2))


@needs_graphs
def test_files_without_vertices_start_from_the_odometry_chain():
    graph = read_g2o(GRAPHS / "CSAIL.g2o")  # no VERTEX_SE2 line at all
    chain = np.flatnonzero(graph.edges[:, 1] == graph.edges[:, 0] + 1)
    for k in chain[:50]:
        i, j = graph.edges[k]
        np.testing.assert_allclose(compose(graph.poses[i], graph.measurements[k]),
                                   graph.poses[j], atol=1e-9)  # fmt: skip


def _graph(rng, n=12):
    poses = np.column_stack([rng.normal(size=(n, 2)) * 3, rng.uniform(-np.pi, np.pi, n)])
    edges = np.array([[i, i + 1] for i in range(n - 1)] + [[0, n - 1], [2, 7]])
    from wheelbase.geometry import relative_pose

    z = relative_pose(poses[edges[:, 0]], poses[edges[:, 1]])
    a = rng.normal(size=(edges.shape[0], 3, 3))
    info = a @ np.swapaxes(a, 1, 2) + 0.5 * np.eye(3)
    return PoseGraph(np.arange(n) * 2 + 5, poses, edges, z, info)


def test_write_then_read_is_the_identity(tmp_path):
    graph = _graph(np.random.default_rng(0))
    path = write_g2o(graph, tmp_path / "g.g2o")
    back = read_g2o(path)
    np.testing.assert_array_equal(back.ids, graph.ids)
    np.testing.assert_array_equal(back.edges, graph.edges)
    np.testing.assert_array_equal(back.poses, graph.poses)
    np.testing.assert_array_equal(back.measurements, graph.measurements)
    np.testing.assert_array_equal(back.information, graph.information)
    with pytest.raises(FileExistsError):
        write_g2o(graph, path)


def test_odometry_guess_recovers_the_poses_of_exact_edges():
    graph = _graph(np.random.default_rng(1))
    guess = odometry_guess(graph)
    moved = compose(compose(graph.poses[0], guess[0] * 0), guess)  # vertex 0 at the origin
    from wheelbase.geometry import relative_pose

    np.testing.assert_allclose(relative_pose(moved[0], moved), relative_pose(graph.poses[0],
                               graph.poses), atol=1e-9)  # fmt: skip


@pytest.mark.parametrize(
    ("text", "match"),
    [
        (
            "VERTEX_SE2 0 0 0 0\nVERTEX_SE2 1 1 0 0\n" + EDGE.format(0, 1) + EDGE.format(1, 2),
            "names vertex 2, which no VERTEX_SE2",
        ),
        (
            "VERTEX_SE2 0 0 0 0\nVERTEX_SE2 1 1 0 0\nEDGE_SE2 0 1 1 0 0 100 0 0 -1 0 400\n",
            "not positive definite",
        ),
        ("EDGE_SE2 0 1 1 0 0 100 0 0 100 0 nan\n", "NaN or inf"),
        ("EDGE_SE2 0 1 1 0 0 100\n", "needs 11 numbers"),
        ("VERTEX_SE2 0 0 0 0\n", "no EDGE_SE2"),
        ("", "no EDGE_SE2"),
        (EDGE.format(0, 1) + EDGE.format(2, 3), "not connected"),
        (EDGE.format(0, 0), "to itself"),
        (EDGE.format(0, 1.5), "integers"),
        ("VERTEX_SE2 0 0 0 0\nVERTEX_SE2 0 1 0 0\n" + EDGE.format(0, 1), "defined twice"),
    ],
)
def test_bad_files_are_refused_with_the_line(tmp_path, text, match):
    path = tmp_path / "bad.g2o"
    path.write_text(text)
    with pytest.raises(DataError, match=match):
        read_g2o(path)


def test_missing_and_binary_files(tmp_path):
    with pytest.raises(DataError, match="not found"):
        read_g2o(tmp_path / "none.g2o")
    (tmp_path / "b.g2o").write_bytes(b"\xff\xfe\x00")
    with pytest.raises(DataError, match="UTF-8"):
        read_g2o(tmp_path / "b.g2o")
