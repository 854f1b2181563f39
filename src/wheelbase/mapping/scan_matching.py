"""Scan matching: a correlative search (Olson 2009) refined by point-to-line ICP (Censi 2008).

The reference is a set of points in the world (a previous scan, or the points of a submap) and
the scan a set of points in the robot frame; the match is the robot pose that lays the scan on
the reference.

**Correlative matching** (E. Olson, "Real-time correlative scan matching", ICRA 2009). The
reference is rasterised into a lookup table over cells of ``resolution``: per cell the log
likelihood of a scan point there, ln(p_floor + (1 − p_floor)·exp(−d²/2σ²)) with d the distance
from the cell centre to the nearest reference point (a Euclidean distance transform) and
p_floor = 0.1 the weight of an unexplained point (Olson's "uniform" term, which keeps one
outlier from vetoing a pose). The score of a pose is the sum over the scan's points of the
table at each point's cell. The search covers a window of poses around a guess, at translation
steps of one cell and rotation steps of ``resolution / r_max`` (the farthest point then moves by
at most one cell per step). It is exhaustive in effect but not in cost: for each rotation,
branch and bound over translations (W. Hess, D. Kohler, H. Rapp and D. Andor, "Real-time loop
closure in 2D LIDAR SLAM", ICRA 2016, §V: Olson's multi-resolution search generalised to a
stack of levels) scores a block of 2ʰ × 2ʰ translations at once with a table whose cell is the
maximum of the finest table over the 2ʰ × 2ʰ cells beside it (an upper bound on every score
in the block), expands the best blocks first and prunes those whose bound is no better than
the best pose found. The result is the best pose of the window, exactly.

The covariance comes from the score surface (Olson 2009, §IV-C): the likelihood exp(L(x) −
L_max) weighs the poses of a neighbourhood of the best one (±2 steps in x, y and θ), Σ =
Σ_x w x xᵀ / Σ w − μμᵀ, plus the variance of the quantisation (step²/12) of each axis.

**Point-to-line ICP** (A. Censi, "An ICP variant using a point-to-line metric", ICRA 2008)
refines the pose: each scan point is paired with its nearest reference point within
``max_correspondence``, and the error is its distance to the line through the reference
points around it (the line fitted to the nearest reference points, by their principal axis,
rather than Censi's segment between the two nearest of a single scan: a submap merges many
scans). Gauss–Newton on (x, y, θ) with Huber weights, correspondences found again at every
iteration, until the step is below 1e-6 m and rad. Its covariance is σ̂²(JᵀJ)⁻¹, σ̂² the
weighted mean squared residual (the usual first-order estimate; Censi, ICRA 2007, gives one
that accounts for the correspondences changing).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numba
import numpy as np
from numpy.typing import ArrayLike
from scipy import ndimage
from scipy.spatial import cKDTree

from wheelbase._validate import as_float_array, integer, positive
from wheelbase.errors import ConfigError, MapError
from wheelbase.geometry import wrap_angle
from wheelbase.limits import MAX_MAP_CELLS

__all__ = [
    "LikelihoodTable",
    "MatchResult",
    "PointReference",
    "ScanMatcher",
    "scan_points",
    "surface_points",
]


def scan_points(
    ranges: ArrayLike,
    angles: ArrayLike,
    max_range: float,
    *,
    min_range: float = 0.0,
    mount: ArrayLike = (0.0, 0.0, 0.0),
) -> np.ndarray:
    """The returns of a scan as points in the robot frame (no-return and NaN readings dropped).

    Parameters
    ----------
    ranges : array_like, shape (B,)
        Readings [m].
    angles : array_like, shape (B,)
        Beam directions in the sensor frame [rad].
    max_range : float
        Readings at or beyond this are no return [m].
    min_range : float
        Readings below this are dropped [m].
    mount : array_like, shape (3,)
        The sensor's pose in the robot frame.

    Returns
    -------
    numpy.ndarray, shape (M, 2)
    """
    ranges = np.asarray(ranges, dtype=np.float64)
    angles = np.asarray(angles, dtype=np.float64)
    with np.errstate(invalid="ignore"):
        keep = np.isfinite(ranges) & (ranges < max_range) & (ranges >= min_range)
    r, a = ranges[keep], angles[keep]
    mount = np.asarray(mount, dtype=np.float64)
    a = a + mount[2]
    return np.column_stack([mount[0] + r * np.cos(a), mount[1] + r * np.sin(a)])


def surface_points(
    points: ArrayLike,
    *,
    step: float = 0.05,
    max_gap: float = 1.0,
    short: float = 0.15,
    max_turn: float = math.radians(10.0),
) -> np.ndarray:
    """A scan's returns and points filled in along the surfaces between neighbouring beams.

    Consecutive returns (in beam order) are joined by a segment when it is at most ``max_gap``
    long and either shorter than ``short`` or in line (within ``max_turn``) with the segment
    before or after it; each joined segment gets points every ``step``. A wall seen at a
    grazing angle is sampled more sparsely than the matcher's σ (at 1° per beam, a corridor's
    side wall 1 m away has returns 0.6 m apart 6 m ahead); as a reference, such a scan scores
    the next scan best where its own returns fall on the same samples, i.e. where the robot
    has not moved along the corridor (Intel: identical scans 0.95 m apart matched 0 m apart),
    while the filled-in wall scores every position along it alike and leaves the decision to
    what the corridor does show. The depth jump at an occluding edge is a segment that lines up
    with neither neighbour and is left open.

    Parameters
    ----------
    points : array_like, shape (M, 2)
        The returns in beam order [m] (:func:`scan_points`).
    step : float
        Spacing of the added points [m].
    max_gap : float
        Longest segment joined [m].
    short : float
        Segments up to this long are joined whatever their direction [m].
    max_turn : float
        Largest turn between neighbouring segments that counts as in line [rad].

    Returns
    -------
    numpy.ndarray, shape (M + A, 2)
        The returns, then the ``A`` added points.
    """
    points = as_float_array("points", points, 2, min_ndim=2, max_ndim=2)
    step = positive("step", step, "m")
    if points.shape[0] < 3:
        return points
    d = np.diff(points, axis=0)
    length = np.hypot(d[:, 0], d[:, 1])
    heading = np.arctan2(d[:, 1], d[:, 0])
    in_line = np.abs(wrap_angle(np.diff(heading))) <= max_turn  # segment s with s + 1
    with_neighbour = np.concatenate([[False], in_line]) | np.concatenate([in_line, [False]])
    joined = np.flatnonzero((length <= max_gap) & ((length <= short) | with_neighbour))
    count = (length[joined] // step).astype(np.int64)
    if count.sum() == 0:
        return points
    seg = np.repeat(joined, count)
    rank = np.arange(count.sum()) - np.repeat(np.cumsum(count) - count, count) + 1
    fraction = rank / np.repeat(count + 1, count)
    return np.vstack([points, points[seg] + fraction[:, None] * d[seg]])


def _transform(pose: np.ndarray, points: np.ndarray) -> np.ndarray:
    c, s = math.cos(pose[2]), math.sin(pose[2])
    return np.column_stack([pose[0] + c * points[:, 0] - s * points[:, 1],
                            pose[1] + s * points[:, 0] + c * points[:, 1]])  # fmt: skip


@dataclass(frozen=True, eq=False)
class LikelihoodTable:
    """The correlative matcher's lookup tables of a reference (module docstring).

    Attributes
    ----------
    levels : tuple of numpy.ndarray
        ``levels[h][i, j]``: the maximum of the finest table (``levels[0]``) over cells
        ``[i, i + 2ʰ) × [j, j + 2ʰ)``; float32, cells off the finest table score ``floor``
        (the tables have 2^(depth − 1) cells of it below and left of the reference).
    resolution : float
        Cell side [m].
    origin : tuple of float
        World (x, y) [m] of cell (0, 0)'s lower-left corner.
    floor : float
        Log likelihood of a point far from every reference point.
    """

    levels: tuple[np.ndarray, ...]
    resolution: float
    origin: tuple[float, float]
    floor: float

    @classmethod
    def build(
        cls,
        points: ArrayLike,
        resolution: float = 0.05,
        sigma: float = 0.05,
        *,
        p_floor: float = 0.1,
        margin: float = 1.0,
        depth: int = 7,
        max_cells: int = MAX_MAP_CELLS,
    ) -> LikelihoodTable:
        """Rasterise reference points into the tables.

        Parameters
        ----------
        points : array_like, shape (M, 2)
            Reference points in the world [m].
        resolution : float
            Cell side [m].
        sigma : float
            σ of the Gaussian around each point [m].
        p_floor : float
            Likelihood of an unexplained point, in (0, 1).
        margin : float
            Space around the points [m].
        depth : int
            Number of levels (the coarsest scores blocks of 2^(depth − 1) cells), 1..16.
        max_cells : int
            Most cells of the table.

        Returns
        -------
        LikelihoodTable
        """
        points = as_float_array("points", points, 2, min_ndim=2, max_ndim=2)
        if points.shape[0] == 0:
            raise MapError("the reference holds no point: nothing to match against")
        r = positive("resolution", resolution, "m")
        sigma = positive("sigma", sigma, "m")
        depth = integer("depth", depth, 1, 16)
        lo = points.min(0) - margin
        hi = points.max(0) + margin
        cols, rows = (np.floor((hi - lo) / r).astype(int) + 1).tolist()
        if rows * cols > max_cells:
            raise MapError(
                f"the matcher's table would need {rows} × {cols} cells: more than max_cells "
                f"= {max_cells}"
            )
        occupied = np.zeros((rows, cols), bool)
        cells = np.floor((points - lo) / r).astype(int)
        occupied[cells[:, 1], cells[:, 0]] = True
        distance = ndimage.distance_transform_edt(~occupied) * r
        table = np.log(p_floor + (1.0 - p_floor) * np.exp(-0.5 * (distance / sigma) ** 2))
        floor = math.log(p_floor)
        # 2^(depth−1) cells of floor below and left of the table: a block of offsets that
        # starts off the table but reaches into it is then bounded by what it reaches
        pad = 2 ** (depth - 1)
        table = np.pad(table, ((pad, 0), (pad, 0)), constant_values=floor)
        lo = lo - pad * r
        levels = [np.ascontiguousarray(table, np.float32)]
        for h in range(1, depth):
            size = 2**h
            prev = levels[-1]
            half = size // 2
            # max over [i, i + 2ʰ) = max of the previous level at i and at i + 2ʰ⁻¹
            padded = np.pad(prev, ((0, half), (0, half)), constant_values=floor)
            a = np.maximum(padded[: -half or None, :], padded[half:, :])[:, : prev.shape[1] + half]
            b = np.maximum(a[:, : -half or None], a[:, half:])
            levels.append(np.ascontiguousarray(b[: prev.shape[0], : prev.shape[1]], np.float32))
        return cls(tuple(levels), r, (float(lo[0]), float(lo[1])), floor)


@dataclass(frozen=True)
class MatchResult:
    """The outcome of a scan match.

    Attributes
    ----------
    pose : numpy.ndarray, shape (3,)
        Best robot pose (x [m], y [m], θ [rad]).
    covariance : numpy.ndarray, shape (3, 3)
        Its covariance.
    score : float
        Mean per-point likelihood of the correlative match, in [p_floor, 1] (1: every point
        on a reference point).
    inliers : float
        Fraction of scan points ICP paired with the reference.
    rms : float
        RMS point-to-line distance of the paired points [m].
    """

    pose: np.ndarray
    covariance: np.ndarray
    score: float
    inliers: float
    rms: float


@numba.njit(cache=True)
def _score(level, cells_i, cells_j, di, dj, floor):
    rows, cols = level.shape
    total = 0.0
    for k in range(cells_i.shape[0]):
        i = cells_i[k] + di
        j = cells_j[k] + dj
        if 0 <= i < rows and 0 <= j < cols:
            total += level[i, j]
        else:
            total += floor
    return total


@numba.njit(cache=True)
def _block_prior(oi, oj, size, w):
    """The largest prior −w·(di² + dj²) over the offsets of the block [oi, oi + size)²."""
    ni = 0 if oi <= 0 <= oi + size - 1 else min(abs(oi), abs(oi + size - 1))
    nj = 0 if oj <= 0 <= oj + size - 1 else min(abs(oj), abs(oj + size - 1))
    return -w * (ni * ni + nj * nj)


@numba.njit(cache=True)
def _branch_and_bound(levels, cells_i, cells_j, n_angles, half_i, half_j, floor, best_in,
                      w_lin, angle_prior):  # fmt: skip
    """Best (score, angle, di, dj) over angles and integer offsets in [−half, half]².

    ``cells_i/j[a]``: the points' cells at offset 0 for angle a. The score adds the log prior
    −w_lin·(di² + dj²) + angle_prior[a]. Depth-first from the coarsest level, children in order
    of their bound, pruned at the best score so far."""
    top = len(levels) - 1
    size = 1 << top
    best = best_in
    best_a, best_i, best_j = -1, 0, 0
    stack_s = np.empty(4096 * 4)
    stack_a = np.empty(4096 * 4, np.int64)
    stack_i = np.empty(4096 * 4, np.int64)
    stack_j = np.empty(4096 * 4, np.int64)
    stack_h = np.empty(4096 * 4, np.int64)
    for a in range(n_angles):
        ci = cells_i[a]
        cj = cells_j[a]
        # the top-level candidates of this angle, pushed worst first (popped best first)
        n_top_i = (2 * half_i + size) // size
        n_top_j = (2 * half_j + size) // size
        cand_s = np.empty(n_top_i * n_top_j)
        cand_i = np.empty(n_top_i * n_top_j, np.int64)
        cand_j = np.empty(n_top_i * n_top_j, np.int64)
        k = 0
        for u in range(n_top_i):
            for v in range(n_top_j):
                oi = -half_i + u * size
                oj = -half_j + v * size
                cand_s[k] = (
                    _score(levels[top], ci, cj, oi, oj, floor)
                    + _block_prior(oi, oj, size, w_lin)
                    + angle_prior[a]
                )
                cand_i[k] = oi
                cand_j[k] = oj
                k += 1
        order = np.argsort(cand_s)
        sp = 0
        for q in range(k):
            o = order[q]
            if cand_s[o] > best:
                if sp >= stack_s.shape[0]:
                    break
                stack_s[sp] = cand_s[o]
                stack_a[sp] = a
                stack_i[sp] = cand_i[o]
                stack_j[sp] = cand_j[o]
                stack_h[sp] = top
                sp += 1
        while sp > 0:
            sp -= 1
            s = stack_s[sp]
            if s <= best:
                continue
            h = stack_h[sp]
            oi = stack_i[sp]
            oj = stack_j[sp]
            if h == 0:
                best = s
                best_a, best_i, best_j = a, oi, oj
                continue
            # children: the 4 blocks of half the size, inside the window
            half_size = 1 << (h - 1)
            cs = np.empty(4)
            cii = np.empty(4, np.int64)
            cjj = np.empty(4, np.int64)
            m = 0
            for du in range(2):
                for dv in range(2):
                    ni = oi + du * half_size
                    nj = oj + dv * half_size
                    if ni > half_i or nj > half_j:
                        continue
                    cs[m] = (
                        _score(levels[h - 1], ci, cj, ni, nj, floor)
                        + _block_prior(ni, nj, half_size, w_lin)
                        + angle_prior[a]
                    )
                    cii[m] = ni
                    cjj[m] = nj
                    m += 1
            # push in increasing score so that the best child is popped first
            idx = np.argsort(cs[:m])
            for q in range(m):
                c = idx[q]
                if cs[c] > best and sp < stack_s.shape[0]:
                    stack_s[sp] = cs[c]
                    stack_a[sp] = a
                    stack_i[sp] = cii[c]
                    stack_j[sp] = cjj[c]
                    stack_h[sp] = h - 1
                    sp += 1
    return best, best_a, best_i, best_j


@dataclass(frozen=True, eq=False)
class PointReference:
    """Reference points with the lines through them, for point-to-line ICP.

    Attributes
    ----------
    points : numpy.ndarray, shape (M, 2)
        Points in the world [m].
    normals : numpy.ndarray, shape (M, 2)
        Unit normal of the line fitted to each point's neighbours.
    tree : scipy.spatial.cKDTree
        Nearest-neighbour index of ``points``.
    """

    points: np.ndarray
    normals: np.ndarray
    tree: cKDTree

    @classmethod
    def build(cls, points: ArrayLike, neighbours: int = 6, radius: float = 0.25) -> PointReference:
        """Fit a line to the ``neighbours`` nearest points (within ``radius`` [m]) of each point.

        Parameters
        ----------
        points : array_like, shape (M, 2)
            Reference points [m].
        neighbours : int
            Points per line fit (the point itself included), >= 2.
        radius : float
            Only neighbours within this distance count [m].

        Returns
        -------
        PointReference
        """
        points = as_float_array("points", points, 2, min_ndim=2, max_ndim=2)
        if points.shape[0] < 2:
            raise MapError("the reference needs >= 2 points for point-to-line ICP")
        tree = cKDTree(points)
        k = min(integer("neighbours", neighbours, 2), points.shape[0])
        dist, idx = tree.query(points, k=k)
        near = dist <= radius
        weights = near.astype(np.float64)
        counts = weights.sum(1, keepdims=True)
        nb = points[idx]
        mean = (nb * weights[..., None]).sum(1) / counts
        dev = (nb - mean[:, None, :]) * weights[..., None]
        cov = np.einsum("mki,mkj->mij", dev, nb - mean[:, None, :])
        _, vectors = np.linalg.eigh(cov)
        normals = vectors[:, :, 0]  # the smallest principal axis: the line's normal
        return cls(points, normals, tree)

    @classmethod
    def merge(cls, parts: list[PointReference], poses: ArrayLike) -> PointReference:
        """References fitted in their own frames (e.g. one per keyframe), placed at ``poses``
        and joined: points and normals moved, one tree over all; each normal stays that of its
        own part's fit (no line is fitted across parts).

        Parameters
        ----------
        parts : list of PointReference
            The references, each in its own frame.
        poses : array_like, shape (len(parts), 3)
            Pose of each part's frame in the world [m, m, rad].

        Returns
        -------
        PointReference
        """
        poses = as_float_array("poses", poses, 3, min_ndim=2, max_ndim=2)
        if len(parts) == 0 or poses.shape[0] != len(parts):
            raise MapError(f"{len(parts)} references and {poses.shape[0]} poses to merge")
        placed = list(zip(poses, parts, strict=True))
        points = np.vstack([_transform(q, part.points) for q, part in placed])
        normals = np.vstack([_transform((0.0, 0.0, q[2]), part.normals) for q, part in placed])
        return cls(points, normals, cKDTree(points))


@dataclass(frozen=True)
class ScanMatcher:
    """Correlative search then point-to-line ICP (module docstring).

    Parameters
    ----------
    resolution : float
        Cell of the lookup table and translation step of the search [m].
    sigma : float
        σ of the table's Gaussian [m].
    linear_window : float
        Half-width of the translation window [m].
    angular_window : float
        Half-width of the rotation window [rad].
    icp_iterations : int
        Most Gauss–Newton iterations of ICP (0: correlative search only).
    max_correspondence : float
        Largest distance of an ICP pair [m].
    huber : float
        Huber threshold of the ICP residuals [m].
    """

    resolution: float = 0.05
    sigma: float = 0.05
    linear_window: float = 0.3
    angular_window: float = math.radians(20.0)
    icp_iterations: int = 30
    max_correspondence: float = 0.3
    huber: float = 0.05

    def __post_init__(self) -> None:
        for name in ("resolution", "sigma", "max_correspondence", "huber"):
            positive(name, getattr(self, name), "m")
        if not 0.0 <= self.linear_window < 1e3:
            raise ConfigError(f"linear_window must be in [0, 1000) m (got {self.linear_window})")
        if not 0.0 <= self.angular_window <= math.pi:
            raise ConfigError(f"angular_window must be in [0, π] rad (got {self.angular_window})")
        integer("icp_iterations", self.icp_iterations, 0)

    def correlative(
        self,
        table: LikelihoodTable,
        points: np.ndarray,
        guess: ArrayLike,
        *,
        linear_window: float | None = None,
        angular_window: float | None = None,
        min_score: float = -math.inf,
        prior_std: tuple[float, float] | None = None,
    ) -> tuple[np.ndarray, float, np.ndarray] | None:
        """The best pose of the window around ``guess`` (module docstring).

        Parameters
        ----------
        table : LikelihoodTable
            The reference's tables.
        points : numpy.ndarray, shape (M, 2)
            Scan points in the robot frame [m].
        guess : array_like, shape (3,)
            Centre of the window.
        linear_window, angular_window : float or None
            Override the matcher's windows [m], [rad].
        min_score : float
            Mean per-point likelihood below which a pose is not worth finding (branch and
            bound prunes with it: a loop-closure search is then much faster).
        prior_std : tuple of float or None
            Standard deviations (translation [m], rotation [rad]) of a Gaussian prior on the
            pose around ``guess``, added to the log likelihood (Olson's motion term: it breaks
            the ties of a corridor); None for none.

        Returns
        -------
        tuple or None
            ``(pose, score, covariance)`` with ``score`` the mean per-point likelihood, or None
            when no pose of the window reaches ``min_score``.
        """
        guess = as_float_array("guess", guess, 3, max_ndim=1)
        if points.shape[0] == 0:
            return None
        lw = self.linear_window if linear_window is None else linear_window
        aw = self.angular_window if angular_window is None else angular_window
        r = table.resolution
        # the angular step moves the 90th-percentile point by one cell (the farthest few
        # would make it needlessly fine: ICP refines the angle)
        reach = float(np.percentile(np.hypot(points[:, 0], points[:, 1]), 90))
        step = min(r / max(reach, r), math.radians(2.0))
        n_half = math.ceil(aw / step) if aw > 0 else 0
        angles = guess[2] + step * np.arange(-n_half, n_half + 1)
        cells_i, cells_j = self._cells(table, points, guess[:2], angles)
        half = math.ceil(lw / r)
        n = points.shape[0]
        bound = n * math.log(min_score) if min_score > 0 else -math.inf
        levels = numba.typed.List(table.levels)
        if prior_std is None:
            w_lin, angle_prior = 0.0, np.zeros(angles.size)
        else:
            w_lin = 0.5 * (r / prior_std[0]) ** 2
            angle_prior = -0.5 * ((angles - guess[2]) / prior_std[1]) ** 2
        best, a, di, dj = _branch_and_bound(
            levels,
            cells_i,
            cells_j,
            angles.size,
            half,
            half,
            table.floor,
            bound - 1e-9,
            w_lin,
            angle_prior,
        )
        if a >= 0:
            best -= _block_prior(di, dj, 1, w_lin) + angle_prior[a]  # the likelihood alone
        if a < 0:
            return None
        pose = np.array([guess[0] + dj * r, guess[1] + di * r, wrap_angle(angles[a])])
        cov = self._surface_covariance(table, cells_i, cells_j, a, di, dj, best, r, step)
        return pose, math.exp(best / n), cov

    def _cells(self, table, points, xy, angles):
        c, s = np.cos(angles)[:, None], np.sin(angles)[:, None]
        x = xy[0] + c * points[:, 0] - s * points[:, 1]
        y = xy[1] + s * points[:, 0] + c * points[:, 1]
        cj = np.floor((x - table.origin[0]) / table.resolution).astype(np.int64)
        ci = np.floor((y - table.origin[1]) / table.resolution).astype(np.int64)
        return np.ascontiguousarray(ci), np.ascontiguousarray(cj)

    def _surface_covariance(self, table, cells_i, cells_j, a, di, dj, best, r, step):
        """Olson's covariance of the score surface over ±2 steps around the best pose."""
        samples, weights = [], []
        fine = table.levels[0]
        for da in range(-2, 3):
            aa = a + da
            if not 0 <= aa < cells_i.shape[0]:
                continue
            for u in range(-2, 3):
                for v in range(-2, 3):
                    s = _score(fine, cells_i[aa], cells_j[aa], di + u, dj + v, table.floor)
                    samples.append((v * r, u * r, da * step))
                    weights.append(s - best)
        x = np.array(samples)
        w = np.exp(np.array(weights))
        w /= w.sum()
        mean = w @ x
        cov = (x * w[:, None]).T @ x - np.outer(mean, mean)
        return cov + np.diag([r * r / 12.0, r * r / 12.0, step * step / 12.0])

    def icp(
        self, reference: PointReference, points: np.ndarray, guess: ArrayLike
    ) -> tuple[np.ndarray, np.ndarray, float, float]:
        """Point-to-line ICP from ``guess`` (module docstring).

        Parameters
        ----------
        reference : PointReference
            Reference points and lines.
        points : numpy.ndarray, shape (M, 2)
            Scan points in the robot frame [m].
        guess : array_like, shape (3,)
            Start pose.

        Returns
        -------
        tuple
            ``(pose, covariance, inlier_fraction, rms)``.
        """
        pose = as_float_array("guess", guess, 3, max_ndim=1).copy()
        cov = np.diag([1e-2, 1e-2, 1e-3])
        inliers, rms = 0.0, math.inf
        for _ in range(self.icp_iterations):
            world = _transform(pose, points)
            dist, idx = reference.tree.query(world, distance_upper_bound=self.max_correspondence)
            ok = np.isfinite(dist)
            inliers = float(ok.mean()) if ok.size else 0.0
            if ok.sum() < 6:
                break
            p, q, nrm = points[ok], reference.points[idx[ok]], reference.normals[idx[ok]]
            w_pts = world[ok]
            res = np.einsum("mi,mi->m", nrm, w_pts - q)
            c, s = math.cos(pose[2]), math.sin(pose[2])
            dpx = -s * p[:, 0] - c * p[:, 1]  # ∂(R p)/∂θ
            dpy = c * p[:, 0] - s * p[:, 1]
            jac = np.column_stack([nrm[:, 0], nrm[:, 1], nrm[:, 0] * dpx + nrm[:, 1] * dpy])
            absr = np.abs(res)
            w = np.where(absr <= self.huber, 1.0, self.huber / np.maximum(absr, 1e-12))
            h = (jac * w[:, None]).T @ jac
            g = (jac * w[:, None]).T @ res
            try:
                delta = -np.linalg.solve(h + 1e-9 * np.eye(3), g)
            except np.linalg.LinAlgError:
                break
            pose = pose + delta
            pose[2] = wrap_angle(pose[2])
            sigma2 = float((w * res * res).sum() / max(w.sum(), 1e-12))
            rms = math.sqrt(float((res * res).mean()))
            try:
                cov = sigma2 * np.linalg.inv(h / 1.0)
            except np.linalg.LinAlgError:
                cov = np.diag([1e-2, 1e-2, 1e-3])
            if np.abs(delta[:2]).max() < 1e-6 and abs(delta[2]) < 1e-6:
                break
        return pose, cov, inliers, rms

    def likelihood(
        self,
        reference: PointReference,
        points: np.ndarray,
        pose: np.ndarray,
        guess: np.ndarray,
        prior_std: tuple[float, float],
    ) -> float:
        """Log likelihood of a pose: Σ ln(0.1 + 0.9·exp(−d²/2h²)) over the points (d to the
        nearest reference point, h = ``huber``) plus the Gaussian prior around ``guess``.

        Parameters
        ----------
        reference : PointReference
            Reference points.
        points : numpy.ndarray, shape (M, 2)
            Scan points in the robot frame [m].
        pose, guess : numpy.ndarray, shape (3,)
            The pose, and the prior's centre.
        prior_std : tuple of float
            Prior standard deviations (translation [m], rotation [rad]).
        """
        d, _ = reference.tree.query(_transform(pose, points))
        e = np.asarray(pose) - guess
        e[2] = wrap_angle(e[2])
        prior = (e[0] ** 2 + e[1] ** 2) / prior_std[0] ** 2 + (e[2] / prior_std[1]) ** 2
        return float(np.log(0.1 + 0.9 * np.exp(-0.5 * (d / self.huber) ** 2)).sum() - 0.5 * prior)

    def match(
        self,
        table: LikelihoodTable,
        reference: PointReference,
        points: np.ndarray,
        guess: ArrayLike,
        **window: object,
    ) -> MatchResult | None:
        """Correlative search, then ICP from its pose.

        Parameters
        ----------
        table : LikelihoodTable
            The reference's lookup tables.
        reference : PointReference
            The reference's points and lines.
        points : numpy.ndarray, shape (M, 2)
            Scan points in the robot frame [m].
        guess : array_like, shape (3,)
            Centre of the search window.
        **window : float
            ``linear_window``, ``angular_window``, ``min_score``, ``prior_std`` of
            :meth:`correlative`.

        Returns
        -------
        MatchResult or None
            None when the window holds no pose scoring ``min_score``. With a ``prior_std``,
            ICP also runs from ``guess`` and the better of the two refined poses by
            :meth:`likelihood` is kept.
        """
        prior_std = window.get("prior_std")
        found = self.correlative(table, points, guess, **window)
        if found is None:
            return None
        pose, score, cov = found
        inliers, rms = math.nan, math.nan
        if self.icp_iterations:
            refined, icp_cov, inliers, rms = self.icp(reference, points, pose)
            # ICP may not wander off the correlative optimum by more than its search step
            if np.hypot(*(refined[:2] - pose[:2])) <= 2 * table.resolution:
                pose = refined
                cov = icp_cov + np.diag([1e-6, 1e-6, 1e-8])
            if prior_std is not None:
                # a second hypothesis: ICP from the prediction itself. Along a corridor the
                # table's cells (coarser than the scan's accuracy) may rank a pose a door's
                # width away above the true one; the sharper likelihood of both refined poses
                # (σ = huber), with the prior, decides
                alt, alt_cov, alt_in, alt_rms = self.icp(reference, points, guess)
                guess = np.asarray(guess, dtype=np.float64)
                if self.likelihood(reference, points, alt, guess, prior_std) > self.likelihood(
                    reference, points, pose, guess, prior_std
                ):
                    pose, cov, inliers, rms = (
                        alt,
                        alt_cov + np.diag([1e-6, 1e-6, 1e-8]),
                        alt_in,
                        alt_rms,
                    )
        return MatchResult(pose, cov, score, inliers, rms)
