"""Pose-graph optimisation on SE(2): sparse Gauss–Newton / Levenberg–Marquardt, robust kernels,
and a chordal initialisation.

The graph's objective is the g2o / GTSAM one (Grisetti, Kümmerle, Stachniss and Burgard, "A
tutorial on graph-based SLAM", IEEE ITS Magazine 2010, eq. 4):

    χ²(X) = Σ_ij r_ijᵀ Ω_ij r_ij,      r_ij = Log(Z_ij⁻¹ X_i⁻¹ X_j),

the residual of edge (i, j) being the SE(2) logarithm (:mod:`wheelbase.mapping.se2`) of the
mismatch between the measured relative pose Z_ij and the estimated one, exactly as GTSAM's
``BetweenFactor<Pose2>`` (2 × its ``error()`` is this χ²; a test checks it to 1e-9). Poses are
perturbed on the right, X ← X·Exp(δ), so that

    ∂r/∂δ_j = J_r⁻¹(r),      ∂r/∂δ_i = −J_r⁻¹(r)·Ad(X_j⁻¹ X_i).

Each iteration assembles the normal equations H δ = −g (H = Σ JᵀWΩJ, one 3×3 block per vertex
pair), holding the fixed vertices (the first one when the graph fixes none: the gauge), in one
Numba loop over the edges, straight into the storage of a sparse block Cholesky factorisation
(:mod:`wheelbase.mapping.block_cholesky`) whose ordering and symbolic part are computed once
per graph; only the numeric factorisation and the two substitutions are repeated. Steps are
Gauss–Newton while they lower the cost; where one does not, Levenberg–Marquardt damping
H + λ·diag(H) grows tenfold until a step does, and shrinks tenfold after each success. It stops
when the relative decrease of the cost falls below ``tolerance`` (1e-10; GTSAM's default is
1e-5) or the largest step component below 1e-10.

Robust kernels (Huber, Cauchy, and dynamic covariance scaling, Agarwal et al. ICRA 2013) reweight
the edges a mask names (the loop closures) by iteratively reweighted least squares on their
squared Mahalanobis distance s = rᵀΩr: Huber ρ(s) = s for √s ≤ k, 2k√s − k² beyond; Cauchy ρ(s)
= k² ln(1 + s/k²); DCS scales the residual by min(1, 2Φ/(Φ + s)).

Odometry initial guesses leave long loops far from their optimum, where Gauss–Newton may stop in
a local minimum. :func:`chordal_initialization` first solves for the rotations alone, relaxed to
unit-free 2-vectors (a linear least-squares problem, Carlone, Tron, Daniilidis and Dellaert,
"Initialization techniques for 3D SLAM: a survey on rotation estimation and its use in pose
graph optimization", ICRA 2015, §IV-B, "chordal relaxation"), normalises them, then the
translations given the rotations (linear too), and Gauss–Newton starts from there. Both
linear problems live on the vertex graph too (2×2 blocks) and reuse the optimiser's symbolic
factorisation when it holds vertex 0 only.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np

from wheelbase._validate import check_choice, integer, positive
from wheelbase.datasets.g2o import PoseGraph
from wheelbase.errors import ConfigError, DataError, EstimationError
from wheelbase.geometry import compose, inverse_pose, wrap_angle
from wheelbase.mapping._posegraph_kernels import (
    accumulate_linear,
    assemble_kernel,
    edge_chi2_kernel,
    retract_kernel,
)
from wheelbase.mapping.block_cholesky import BlockCholesky
from wheelbase.mapping.se2 import se2_adjoint, se2_exp_map, se2_log, se2_right_jacobian_inv

__all__ = [
    "INITIALIZATIONS",
    "ROBUST_KERNELS",
    "PoseGraphResult",
    "chordal_initialization",
    "edge_chi2",
    "edge_residuals",
    "graph_chi2",
    "optimize_pose_graph",
]

ROBUST_KERNELS: tuple[str, ...] = ("none", "huber", "cauchy", "dcs")
"""Robust kernels :func:`optimize_pose_graph` takes (module docstring)."""

INITIALIZATIONS: tuple[str, ...] = ("graph", "chordal")
"""``graph``: the graph's own poses; ``chordal``: :func:`chordal_initialization`."""


@dataclass(frozen=True)
class PoseGraphResult:
    """An optimised pose graph.

    Attributes
    ----------
    poses : numpy.ndarray, shape (V, 3)
        Optimised poses; fixed vertices (or the first) where they were.
    chi2_initial : float
        χ² at the initial guess of the graph's file (before any initialisation).
    chi2 : float
        χ² at ``poses`` (all edges at full weight).
    iterations : int
        Linear solves taken (rejected damped steps included).
    solve_time_s : float
        Wall time of the optimisation, initialisation included [s].
    converged : bool
        The cost stopped decreasing (rather than ``max_iterations`` being reached).
    edge_weights : numpy.ndarray, shape (E,)
        Final robust weights (1 for edges outside the robust mask).
    history : numpy.ndarray
        Cost after each accepted step, the initial one first.
    """

    poses: np.ndarray
    chi2_initial: float
    chi2: float
    iterations: int
    solve_time_s: float
    converged: bool
    edge_weights: np.ndarray = field(repr=False, default_factory=lambda: np.zeros(0))
    history: np.ndarray = field(repr=False, default_factory=lambda: np.zeros(0))

    def metrics(self) -> dict[str, float | int | bool]:
        """``chi2_initial``, ``chi2``, ``iterations``, ``solve_time_s``, ``converged``."""
        return {
            "chi2_initial": self.chi2_initial,
            "chi2": self.chi2,
            "iterations": self.iterations,
            "solve_time_s": self.solve_time_s,
            "converged": self.converged,
        }


def edge_residuals(graph: PoseGraph, poses: np.ndarray | None = None) -> np.ndarray:
    """Residuals r_ij = Log(Z_ij⁻¹ X_i⁻¹ X_j) of every edge, shape ``(E, 3)``.

    Parameters
    ----------
    graph : PoseGraph
        The graph.
    poses : numpy.ndarray or None, shape (V, 3)
        Vertex poses (default: the graph's).
    """
    poses = graph.poses if poses is None else np.asarray(poses, dtype=np.float64)
    xi, xj = poses[graph.edges[:, 0]], poses[graph.edges[:, 1]]
    return se2_log(_between(_between(xi, xj), graph.measurements, inverse_first=True))


def edge_chi2(graph: PoseGraph, poses: np.ndarray | None = None) -> np.ndarray:
    """Squared Mahalanobis distances rᵀΩr of every edge, shape ``(E,)``.

    Parameters
    ----------
    graph : PoseGraph
        The graph.
    poses : numpy.ndarray or None
        Vertex poses (default: the graph's).
    """
    poses, edges, z, info = _kernel_arrays(graph, graph.poses if poses is None else poses)
    return edge_chi2_kernel(poses, edges, z, np.column_stack([np.cos(z[:, 2]), np.sin(z[:, 2])]),
                            info)  # fmt: skip


def _kernel_arrays(graph: PoseGraph, poses: np.ndarray):
    """Contiguous float64 / int64 poses, edges, measurements and information of a graph,
    their shapes and the edges' vertex indices checked: the Numba kernels do not check
    bounds."""
    poses = np.ascontiguousarray(poses, dtype=np.float64)
    edges = np.ascontiguousarray(graph.edges, dtype=np.int64)
    z = np.ascontiguousarray(graph.measurements, dtype=np.float64)
    info = np.ascontiguousarray(graph.information, dtype=np.float64)
    v, e = graph.n_vertices, edges.shape[0] if edges.ndim == 2 else -1
    if poses.shape != (v, 3):
        raise DataError(f"poses must have shape ({v}, 3) (got {poses.shape})")
    if edges.shape != (e, 2) or z.shape != (e, 3) or info.shape != (e, 3, 3):
        raise DataError(
            f"a graph needs edges (E, 2), measurements (E, 3) and information (E, 3, 3) "
            f"(got {edges.shape}, {z.shape}, {info.shape})"
        )
    if e and (edges.min() < 0 or edges.max() >= v):
        raise DataError(f"edges must index the {v} vertices (got {edges.min()}..{edges.max()})")
    return poses, edges, z, info


def graph_chi2(graph: PoseGraph, poses: np.ndarray | None = None) -> float:
    """χ² = Σ rᵀΩr over all edges (g2o's ``chi2``; 2 × GTSAM's ``error``).

    Parameters
    ----------
    graph : PoseGraph
        The graph.
    poses : numpy.ndarray or None
        Vertex poses (default: the graph's).
    """
    return float(edge_chi2(graph, poses).sum())


def _between(a: np.ndarray, b: np.ndarray, *, inverse_first: bool = False) -> np.ndarray:
    """a⁻¹·b for pose arrays (rows), or b⁻¹·a with ``inverse_first`` (Z⁻¹·T for a = T, b = Z)."""
    if inverse_first:
        a, b = b, a
    c, s = np.cos(a[:, 2]), np.sin(a[:, 2])
    dx, dy = b[:, 0] - a[:, 0], b[:, 1] - a[:, 1]
    return np.stack([c * dx + s * dy, -s * dx + c * dy, wrap_angle(b[:, 2] - a[:, 2])], -1)


def _weights(s: np.ndarray, kernel: str, k: float) -> np.ndarray:
    """IRLS weights ρ'(s) of the kernels on squared distances s."""
    if kernel == "huber":
        root = np.sqrt(s)
        return np.where(root <= k, 1.0, k / np.maximum(root, 1e-300))
    if kernel == "cauchy":
        return 1.0 / (1.0 + s / (k * k))
    if kernel == "dcs":
        return np.minimum(1.0, 2.0 * k / (k + s)) ** 2
    return np.ones_like(s)


def _robust_cost(s: np.ndarray, kernel: str, k: float) -> np.ndarray:
    if kernel == "huber":
        root = np.sqrt(s)
        return np.where(root <= k, s, 2.0 * k * root - k * k)
    if kernel == "cauchy":
        return k * k * np.log1p(s / (k * k))
    if kernel == "dcs":  # the cost whose IRLS weight is DCS's scale squared (Agarwal, eq. 12)
        return np.where(s <= k, s, k * (3.0 * s - k) / (s + k))
    return s


class _GraphSystem:
    """The block pattern of a graph's normal equations with some vertices held, its symbolic
    Cholesky factorisation (:class:`~wheelbase.mapping.block_cholesky.BlockCholesky`, built
    once) and the kernels' contiguous copies of the edges."""

    def __init__(self, graph: PoseGraph, held: np.ndarray) -> None:
        self.free = np.flatnonzero(~held)
        self.free_index = np.full(graph.n_vertices, -1, np.int64)
        self.free_index[self.free] = np.arange(self.free.size)
        _, self.edges, self.measurements, self.information = _kernel_arrays(graph, graph.poses)
        angle = self.measurements[:, 2]
        self.measured_cos_sin = np.column_stack([np.cos(angle), np.sin(angle)])
        fi, fj = self.free_index[self.edges[:, 0]], self.free_index[self.edges[:, 1]]
        both = (fi >= 0) & (fj >= 0)
        self.chol = BlockCholesky(self.free.size, np.column_stack([fi[both], fj[both]]))
        self.slot = np.full(graph.n_edges, -1, np.int64)
        self.slot[both] = self.chol.pair_slot
        self.upper = np.ones(graph.n_edges, np.bool_)
        self.upper[both] = self.chol.pair_upper


def _linearise(graph: PoseGraph, poses: np.ndarray, weights: np.ndarray):
    """Residuals, and the blocks JᵀWΩJ and gradients JᵀWΩr of every edge: the NumPy
    reference of the Numba assembly (a test holds them equal), used by landmark SLAM."""
    xi, xj = poses[graph.edges[:, 0]], poses[graph.edges[:, 1]]
    r = se2_log(_between(_between(xi, xj), graph.measurements, inverse_first=True))
    jinv = se2_right_jacobian_inv(r)
    jj = jinv
    ji = -jinv @ se2_adjoint(_between(xj, xi))
    omega = graph.information * weights[:, None, None]
    oji, ojj = omega @ ji, omega @ jj
    jit, jjt = np.swapaxes(ji, 1, 2), np.swapaxes(jj, 1, 2)
    blocks = np.stack([jit @ oji, jit @ ojj, jjt @ oji, jjt @ ojj], 1)
    wr = np.einsum("eij,ej->ei", omega, r)
    gi = np.einsum("eji,ej->ei", ji, wr)
    gj = np.einsum("eji,ej->ei", jj, wr)
    return r, blocks, gi, gj


def optimize_pose_graph(
    graph: PoseGraph,
    *,
    initial: str = "graph",
    robust: str = "none",
    robust_scale: float = 1.0,
    robust_edges: np.ndarray | None = None,
    max_iterations: int = 100,
    tolerance: float = 1e-10,
) -> PoseGraphResult:
    """Minimise χ² over the vertex poses (module docstring).

    Parameters
    ----------
    graph : PoseGraph
        The graph; its poses are the initial guess (``initial="graph"``).
    initial : {"graph", "chordal"}
        Start from the graph's poses or from :func:`chordal_initialization`.
    robust : {"none", "huber", "cauchy", "dcs"}
        Kernel on the edges of ``robust_edges``.
    robust_scale : float
        The kernel's k (Huber, Cauchy: on the Mahalanobis distance √s; DCS: Φ on s), > 0.
    robust_edges : numpy.ndarray or None, shape (E,)
        Boolean mask of the edges the kernel applies to (default: all).
    max_iterations : int
        Most linear solves, >= 1.
    tolerance : float
        Stop when the cost decreases by less than this fraction in a step, > 0.

    Returns
    -------
    PoseGraphResult

    Raises
    ------
    EstimationError
        If the normal equations are singular (a vertex no edge constrains fully).
    """
    check_choice("initial", initial, INITIALIZATIONS)
    check_choice("robust", robust, ROBUST_KERNELS)
    k = positive("robust_scale", robust_scale)
    max_iterations = integer("max_iterations", max_iterations, 1)
    tolerance = positive("tolerance", tolerance)
    mask = np.ones(graph.n_edges, bool) if robust_edges is None else np.asarray(robust_edges, bool)
    if mask.shape != (graph.n_edges,):
        raise ConfigError(f"robust_edges must have shape ({graph.n_edges},) (got {mask.shape})")
    start = time.perf_counter()
    chi2_initial = graph_chi2(graph)
    fixed = graph.fixed.copy()
    if not fixed.any():
        fixed[0] = True
    system = _GraphSystem(graph, fixed)
    if initial == "graph":
        poses = graph.poses.copy()
    else:  # the chordal problems hold vertex 0: the same pattern when it is the one fixed
        anchored = np.zeros(graph.n_vertices, bool)
        anchored[0] = True
        same = np.array_equal(fixed, anchored)
        poses = _chordal(graph, system if same else _GraphSystem(graph, anchored))
    free = system.free
    edges, z, info = system.edges, system.measurements, system.information
    zcs = system.measured_cos_sin

    def cost_of(p: np.ndarray) -> tuple[float, np.ndarray]:
        s = edge_chi2_kernel(p, edges, z, zcs, info)
        if robust != "none":
            s = np.where(mask, _robust_cost(s, robust, k), s)
        return float(s.sum()), s

    def weights_of(p: np.ndarray) -> np.ndarray:
        if robust == "none":
            return np.ones(graph.n_edges)
        return np.where(mask, _weights(edge_chi2_kernel(p, edges, z, zcs, info), robust, k), 1.0)

    poses = np.ascontiguousarray(poses, dtype=np.float64)
    cost, _ = cost_of(poses)
    history = [cost]
    lam, nu = 0.0, 2.0
    iterations = 0
    converged = False
    weights = weights_of(poses)
    n_free = free.size
    diag, off = np.empty((n_free, 3, 3)), np.empty((system.chol.n_off, 3, 3))
    g = np.empty((n_free, 3))
    while iterations < max_iterations and not converged:
        assemble_kernel(poses, edges, z, zcs, info, weights, system.free_index, system.slot,
                        system.upper, diag, off, g)  # fmt: skip
        scale = np.maximum(np.diagonal(diag, axis1=1, axis2=2), 1e-12)
        while iterations < max_iterations:
            iterations += 1
            if system.chol.factor(diag, off, lam * scale if lam > 0.0 else None):
                step = -system.chol.solve(g)
            elif lam == 0.0:
                raise EstimationError(
                    "pose graph: singular normal equations; a vertex is not fully "
                    "constrained by its edges"
                )
            else:
                step = np.full(g.shape, np.nan)
            if np.all(np.isfinite(step)):
                trial = retract_kernel(poses, free, step)
                new_cost = cost_of(trial)[0]
            else:
                trial, new_cost = poses, math.inf
            # the decrease the quadratic model predicts, L(0) − L(δ) = −(gᵀδ + ½δᵀHδ), times
            # 2; with (H + λD)δ = −g, δᵀHδ = −gᵀδ − λδᵀDδ. Sums, not np.vdot: OpenBLAS's dot
            # of 10⁴ numbers wakes its threads, which wait for a busy core on a loaded machine
            predicted = float(((lam * scale * step - g) * step).sum())
            if new_cost <= cost:
                decrease = (cost - new_cost) / max(cost, 1e-300)
                gain = (cost - new_cost) / predicted if predicted > 0 else 1.0
                poses, cost = trial, new_cost
                history.append(cost)
                # Nielsen's update (Madsen, Nielsen and Tingleff, "Methods for non-linear least
                # squares problems", 2004, eq. 3.16): near-Gauss-Newton while the model is good
                lam *= max(1.0 / 3.0, 1.0 - (2.0 * gain - 1.0) ** 3)
                nu = 2.0
                if lam < 1e-12:
                    lam = 0.0
                if decrease < tolerance or np.abs(step).max() < 1e-10:
                    converged = True
                break
            lam = max(lam * nu, 1e-6)
            nu *= 2.0
            if lam > 1e12:
                converged = True  # no step lowers the cost: a (local) minimum to rounding
                break
        weights = weights_of(poses)
    chi2 = graph_chi2(graph, poses)
    return PoseGraphResult(
        poses=poses,
        chi2_initial=chi2_initial,
        chi2=chi2,
        iterations=iterations,
        solve_time_s=time.perf_counter() - start,
        converged=converged,
        edge_weights=weights,
        history=np.array(history),
    )


def _retract(poses: np.ndarray, delta: np.ndarray) -> np.ndarray:
    """X·Exp(δ) for each row."""
    return compose(poses, se2_exp_map(delta))


def chordal_initialization(graph: PoseGraph) -> np.ndarray:
    """Rotations first by the chordal relaxation, then translations; both linear.

    Each rotation is a 2-vector q_i = (cos θ_i, sin θ_i) left free of its unit norm; an edge
    asks q_j = R(Z_θ) q_i (weight: its information in θ). With q of the first vertex held, the
    weighted least-squares solution is normalised to unit length. Then, the rotations fixed, an
    edge asks t_j − t_i = R_i Z_t (weight R_i Ω_tt R_iᵀ), a second linear problem. The result
    is moved so that the first vertex keeps its pose in the graph.

    Parameters
    ----------
    graph : PoseGraph
        The graph (its poses serve only to place the first vertex).

    Returns
    -------
    numpy.ndarray, shape (V, 3)
    """
    anchored = np.zeros(graph.n_vertices, bool)
    anchored[0] = True
    return _chordal(graph, _GraphSystem(graph, anchored))


def _chordal(graph: PoseGraph, system: _GraphSystem) -> np.ndarray:
    """:func:`chordal_initialization` on the pattern of a system that holds vertex 0 only."""
    n, e = graph.n_vertices, graph.n_edges
    edges = system.edges
    i = edges[:, 0]
    n_free, n_off = system.free.size, system.chol.n_off
    diag, off, rhs = np.empty((n_free, 2, 2)), np.empty((n_off, 2, 2)), np.empty((n_free, 2))
    held = np.zeros((n, 2))

    def solve(ji, jj, weight, target):
        accumulate_linear(ji, jj, weight, target, edges, held, system.free_index, system.slot,
                          system.upper, diag, off, rhs)  # fmt: skip
        if not system.chol.factor(diag, off):
            raise EstimationError(
                "chordal initialisation: singular system; the graph is not connected"
            )
        x = held.copy()
        x[system.free] = system.chol.solve(rhs)
        return x

    # rotations: q_j = R(z) q_i, weight Ω_θθ; unknowns q = (cos θ, sin θ) relaxed, q_0 = (1, 0)
    c, s = np.cos(graph.measurements[:, 2]), np.sin(graph.measurements[:, 2])
    rot_z = np.stack([np.stack([c, -s], -1), np.stack([s, c], -1)], -2)
    eye = np.ascontiguousarray(np.broadcast_to(np.eye(2), (e, 2, 2)))
    weight = np.maximum(graph.information[:, 2, 2], 1e-12)[:, None, None] * eye
    held[0] = [math.cos(0.0), math.sin(0.0)]
    q = solve(-rot_z, eye, weight, np.zeros((e, 2)))
    norm = np.hypot(q[:, 0], q[:, 1])
    theta = np.arctan2(q[:, 1], q[:, 0])
    if np.any(norm < 1e-9):
        theta = np.where(norm < 1e-9, 0.0, theta)
    # translations: t_j − t_i = R_i z_t, weight R_i Ω_tt R_iᵀ (Ω_tt positive definite where Ω
    # is; an identity weight where a graph built by hand has one that is not)
    ci, si = np.cos(theta[i]), np.sin(theta[i])
    zt = graph.measurements[:, :2]
    rhs_t = np.stack([ci * zt[:, 0] - si * zt[:, 1], si * zt[:, 0] + ci * zt[:, 1]], -1)
    rot = np.stack([np.stack([ci, -si], -1), np.stack([si, ci], -1)], -2)
    omega_t = graph.information[:, :2, :2]
    det = omega_t[:, 0, 0] * omega_t[:, 1, 1] - omega_t[:, 0, 1] * omega_t[:, 1, 0]
    if np.all((det > 0.0) & (omega_t[:, 0, 0] > 0.0)):
        weight = np.ascontiguousarray(rot @ omega_t @ np.swapaxes(rot, 1, 2))
    else:
        weight = eye
    held[0] = 0.0
    t = solve(-eye, eye, weight, np.ascontiguousarray(rhs_t))
    poses = np.column_stack([t, wrap_angle(theta)])
    # place the first vertex where the graph has it
    anchor = graph.poses[0] if np.all(np.isfinite(graph.poses[0])) else np.zeros(3)
    return compose(compose(anchor, inverse_pose(poses[0])), poses)
