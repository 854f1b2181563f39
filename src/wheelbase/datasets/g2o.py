"""2-D pose graphs in the g2o text format: read and write.

A file holds lines (g2o's ``EDGE_SE2`` / ``VERTEX_SE2`` of Kümmerle et al., "g2o: A general
framework for graph optimization", ICRA 2011)::

    VERTEX_SE2 id x y θ
    EDGE_SE2 i j dx dy dθ I11 I12 I13 I22 I23 I33
    FIX id

An edge measures the pose of vertex j in the frame of vertex i, ``Z_ij ≈ X_i⁻¹ X_j``, with the
upper triangle of its 3×3 information matrix Ω (the inverse covariance, in the order x, y, θ).
Blank lines, ``#`` comments and other tags (``PARAMS_SE2OFFSET``, 3-D types) are counted and
skipped.

Vertices hold the initial guess. Some benchmark files (SE-Sync's CSAIL and manhattan) have no
vertex at all: their initial guess is then the odometry, the composition of the edges along a
breadth-first spanning tree from the lowest id (the chain of edges i → i + 1 where the file has
one), as g2o's and GTSAM's ``initialize`` tools do. A file that has vertices but an edge naming
a vertex it lacks is an error, and so is an information matrix that is not symmetric positive
definite.
"""

from __future__ import annotations

import gzip
from collections import deque
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from wheelbase.errors import DataError
from wheelbase.geometry import compose, wrap_angle

__all__ = ["PoseGraph", "odometry_guess", "read_g2o", "write_g2o"]

_MAX_VERTICES = 10_000_000  # a typo'd id (1e12) must not allocate terabytes


@dataclass(frozen=True)
class PoseGraph:
    """A 2-D pose graph: vertices with an initial guess and relative-pose edges.

    Attributes
    ----------
    ids : numpy.ndarray, shape (V,)
        Vertex ids as in the file (int64), in increasing order.
    poses : numpy.ndarray, shape (V, 3)
        Vertex poses (x [m], y [m], θ [rad]) in the world frame.
    edges : numpy.ndarray, shape (E, 2)
        Row indices ``(i, j)`` into ``ids`` / ``poses`` of each edge (int64).
    measurements : numpy.ndarray, shape (E, 3)
        ``Z_ij``: the pose of j in the frame of i (x [m], y [m], θ [rad]).
    information : numpy.ndarray, shape (E, 3, 3)
        Ω_ij, symmetric positive definite [1/m², 1/(m·rad), 1/rad²].
    fixed : numpy.ndarray, shape (V,)
        Vertices held fixed (``FIX`` lines); the optimiser fixes the first vertex when none is.
    skipped_lines : int
        Lines of other types left out.
    """

    ids: np.ndarray
    poses: np.ndarray
    edges: np.ndarray
    measurements: np.ndarray
    information: np.ndarray
    fixed: np.ndarray = field(default_factory=lambda: np.zeros(0, bool))
    skipped_lines: int = 0

    def __post_init__(self) -> None:
        if self.fixed.size != self.ids.size:
            object.__setattr__(self, "fixed", np.zeros(self.ids.size, bool))

    @property
    def n_vertices(self) -> int:
        """Number of vertices V."""
        return int(self.ids.size)

    @property
    def n_edges(self) -> int:
        """Number of edges E."""
        return int(self.edges.shape[0])

    def with_poses(self, poses: np.ndarray) -> PoseGraph:
        """The same graph with other vertex poses (e.g. the optimised ones).

        Parameters
        ----------
        poses : numpy.ndarray, shape (V, 3)
            New poses.
        """
        poses = np.asarray(poses, dtype=np.float64)
        if poses.shape != self.poses.shape:
            raise DataError(f"poses must have shape {self.poses.shape} (got {poses.shape})")
        return PoseGraph(self.ids, poses, self.edges, self.measurements, self.information,
                         self.fixed, self.skipped_lines)  # fmt: skip


def _open_text(path: Path) -> list[str]:
    if not path.is_file():
        raise DataError(f"g2o file not found: {path}")
    try:
        raw = gzip.decompress(path.read_bytes()) if path.suffix == ".gz" else path.read_bytes()
        return raw.decode("utf-8").splitlines()
    except (OSError, EOFError, gzip.BadGzipFile) as exc:
        raise DataError(f"cannot read g2o file {path}: {exc}") from None
    except UnicodeDecodeError as exc:
        raise DataError(f"{path}: not UTF-8 text (byte offset {exc.start})") from None


def _numbers(path: Path, number: int, tokens: list[str], count: int) -> list[float]:
    if len(tokens) - 1 < count:
        raise DataError(
            f"{path}:{number}: {tokens[0]} needs {count} numbers (got {len(tokens) - 1})"
        )
    try:
        values = [float(t) for t in tokens[1 : count + 1]]
    except ValueError:
        raise DataError(f"{path}:{number}: {tokens[0]} holds a non-number") from None
    if not np.all(np.isfinite(values)):
        raise DataError(f"{path}:{number}: {tokens[0]} holds NaN or inf")
    return values


def _vertex_id(path: Path, number: int, value: float) -> int:
    if value != int(value) or not 0 <= value < _MAX_VERTICES * 100:
        raise DataError(
            f"{path}:{number}: vertex ids must be integers in [0, {_MAX_VERTICES * 100}) "
            f"(got {value:g})"
        )
    return int(value)


def read_g2o(path: str | Path) -> PoseGraph:
    """Read a 2-D g2o pose graph (``VERTEX_SE2``, ``EDGE_SE2``, ``FIX``; ``.gz`` too).

    Parameters
    ----------
    path : str or Path
        The file.

    Returns
    -------
    PoseGraph
        Vertices sorted by id; without any vertex line, the odometry guess
        (:func:`odometry_guess`).

    Raises
    ------
    DataError
        A missing or unreadable file, a malformed line, no edge, an edge that names a vertex
        the file does not define (when it defines any), a duplicate vertex, an edge from a
        vertex to itself, or an information matrix that is not symmetric positive definite
        (the line is named).
    """
    path = Path(path)
    vertices: dict[int, tuple[float, float, float]] = {}
    edge_rows: list[tuple[int, int]] = []
    edge_lines: list[int] = []
    meas: list[list[float]] = []
    info: list[list[float]] = []
    fixed: set[int] = set()
    skipped = 0
    for number, line in enumerate(_open_text(path), start=1):
        tokens = line.split()
        if not tokens or tokens[0].startswith("#"):
            continue
        tag = tokens[0]
        if tag == "VERTEX_SE2":
            values = _numbers(path, number, tokens, 4)
            vid = _vertex_id(path, number, values[0])
            if vid in vertices:
                raise DataError(f"{path}:{number}: vertex {vid} is defined twice")
            vertices[vid] = (values[1], values[2], values[3])
        elif tag == "EDGE_SE2":
            values = _numbers(path, number, tokens, 11)
            i, j = (_vertex_id(path, number, v) for v in values[:2])
            if i == j:
                raise DataError(f"{path}:{number}: edge from vertex {i} to itself")
            edge_rows.append((i, j))
            edge_lines.append(number)
            meas.append(values[2:5])
            info.append(values[5:11])
        elif tag == "FIX":
            for value in _numbers(path, number, tokens, len(tokens) - 1):
                fixed.add(_vertex_id(path, number, value))
        else:
            skipped += 1
    if not edge_rows:
        raise DataError(f"{path}: no EDGE_SE2 line: not a 2-D pose graph")
    pairs = np.array(edge_rows, dtype=np.int64)
    upper = np.array(info, dtype=np.float64)
    omega = np.empty((upper.shape[0], 3, 3))
    for (a, b), k in zip(((0, 0), (0, 1), (0, 2), (1, 1), (1, 2), (2, 2)), range(6), strict=True):
        omega[:, a, b] = omega[:, b, a] = upper[:, k]
    eig = np.linalg.eigvalsh(omega)
    bad = np.flatnonzero(~(eig[:, 0] > 0))
    if bad.size:
        k = int(bad[0])
        raise DataError(
            f"{path}:{edge_lines[k]}: the information matrix of edge {pairs[k, 0]} → "
            f"{pairs[k, 1]} is not positive definite (least eigenvalue {eig[k, 0]:.3g}); "
            f"{bad.size} edge(s) in all"
        )
    measurements = np.array(meas, dtype=np.float64)
    measurements[:, 2] = wrap_angle(measurements[:, 2])
    if vertices:
        missing = sorted({int(v) for v in pairs.ravel()} - set(vertices))
        if missing:
            k = next(n for n, (i, j) in enumerate(edge_rows) if missing[0] in (i, j))
            raise DataError(
                f"{path}:{edge_lines[k]}: edge {pairs[k, 0]} → {pairs[k, 1]} names vertex "
                f"{missing[0]}, which no VERTEX_SE2 line defines ({len(missing)} missing)"
            )
        ids = np.array(sorted(vertices), dtype=np.int64)
        poses = np.array([vertices[int(v)] for v in ids], dtype=np.float64)
        poses[:, 2] = wrap_angle(poses[:, 2])
    else:
        ids = np.unique(pairs)
        if ids.size > _MAX_VERTICES:
            raise DataError(f"{path}: more than {_MAX_VERTICES} vertices")
        poses = np.full((ids.size, 3), np.nan)
    rows = np.searchsorted(ids, pairs)
    graph = PoseGraph(ids, poses, rows, measurements, omega,
                      np.isin(ids, sorted(fixed)), skipped)  # fmt: skip
    if not vertices:
        graph = graph.with_poses(odometry_guess(graph))
    return graph


def odometry_guess(graph: PoseGraph) -> np.ndarray:
    """Poses composed from the edges along a breadth-first spanning tree from vertex 0.

    Edges i → i + 1 (the odometry chain, where a file has one) are taken first, so that the
    guess is dead reckoning; other edges reach vertices the chain does not.

    Parameters
    ----------
    graph : PoseGraph
        The graph (its poses are ignored).

    Returns
    -------
    numpy.ndarray, shape (V, 3)

    Raises
    ------
    DataError
        If the graph is not connected.
    """
    from wheelbase.geometry import inverse_pose

    n = graph.n_vertices
    neighbours: list[list[tuple[int, int, bool, int]]] = [[] for _ in range(n)]
    for k, (i, j) in enumerate(graph.edges.tolist()):
        cost = 0 if j == i + 1 else 1  # the odometry chain costs nothing: it is preferred
        neighbours[i].append((j, k, True, cost))
        neighbours[j].append((i, k, False, cost))
    # 0-1 breadth-first search: the tree of fewest non-chain edges from vertex 0
    hops = np.full(n, np.iinfo(np.int64).max)
    parent = np.full(n, -1, np.int64)
    forward_of = np.zeros(n, bool)
    hops[0] = 0
    queue = deque([0])
    done = np.zeros(n, bool)
    order: list[int] = []
    while queue:
        i = queue.popleft()
        if done[i]:
            continue
        done[i] = True
        order.append(i)
        for j, k, forward, cost in neighbours[i]:
            if hops[i] + cost < hops[j]:
                hops[j] = hops[i] + cost
                parent[j], forward_of[j] = k, forward
                if cost == 0:
                    queue.appendleft(j)
                else:
                    queue.append(j)
    seen = done
    poses = np.full((n, 3), np.nan)
    inverse = inverse_pose(graph.measurements)
    for j in order:
        k = parent[j]
        if k < 0:
            poses[j] = 0.0
            continue
        i = graph.edges[k, 0] if forward_of[j] else graph.edges[k, 1]
        poses[j] = compose(poses[i], graph.measurements[k] if forward_of[j] else inverse[k])
    if not seen.all():
        lost = graph.ids[~seen]
        raise DataError(
            f"the pose graph is not connected: {lost.size} vertices (first {lost[0]}) cannot be "
            f"reached from vertex {graph.ids[0]}"
        )
    return poses


def write_g2o(graph: PoseGraph, path: str | Path, *, overwrite: bool = False) -> Path:
    """Write a pose graph as g2o text (``VERTEX_SE2``, ``EDGE_SE2``, ``FIX``), full precision.

    Parameters
    ----------
    graph : PoseGraph
        The graph.
    path : str or Path
        Output file.
    overwrite : bool
        Replace an existing file (default: refuse with FileExistsError).

    Returns
    -------
    pathlib.Path
    """
    path = Path(path)
    if path.exists() and not overwrite:
        raise FileExistsError(f"{path} exists; pass overwrite=True to replace it")
    lines = [
        f"VERTEX_SE2 {vid} {x!r} {y!r} {t!r}"
        for vid, (x, y, t) in zip(graph.ids.tolist(), graph.poses.tolist(), strict=True)
    ]
    upper = graph.information[:, [0, 0, 0, 1, 1, 2], [0, 1, 2, 1, 2, 2]]
    for (i, j), z, w in zip(graph.edges.tolist(), graph.measurements.tolist(), upper.tolist(),
                            strict=True):  # fmt: skip
        numbers = " ".join(repr(float(v)) for v in (*z, *w))
        lines.append(f"EDGE_SE2 {graph.ids[i]} {graph.ids[j]} {numbers}")
    lines += [f"FIX {vid}" for vid in graph.ids[graph.fixed].tolist()]
    path.write_text("\n".join(lines) + "\n")
    return path
