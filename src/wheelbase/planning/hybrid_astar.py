"""Hybrid A*: smooth, kinematically feasible paths for car-like and differential-drive robots.

Document 002 (last part: "smooth path planning in a given 2-D space for vehicles with
nonholonomic constraints using Hybrid A*"), after Dolgov, Thrun, Montemerlo & Diebel (2010) and
ROS 2 Nav2's Smac Hybrid-A* planner:

* continuous states ``(x, y, θ)`` binned into cells of ``xy_resolution`` × ``2π/headings``; the
  first (cheapest) state to close a bin prunes later ones;
* motion primitives: arcs of curvature in ``linspace(−1/R, 1/R, curvatures)`` driven forward and
  (optionally) in reverse, of length ``max(R·2π/headings, √2·xy_resolution)``; with
  ``turning_radius=0`` (differential drive) straight moves plus turns in place; with
  ``moves_to_contact`` (on by default; only where the lattice of whole primitives found
  nothing), near obstacles a primitive that collides is kept up to its last free sample (the
  short back-and-forth moves of tight parking: a 1.15-car-length parallel slot takes 13), and
  where the lattice still fails, the tight end is left by moves to contact on continuous poses
  (:mod:`~wheelbase.planning.escape`: a 1.10 slot, about 30 moves);
* cost: distance × ``non_straight_penalty`` on arcs × ``reverse_penalty`` in reverse, plus
  ``change_penalty`` × distance when the curvature changes and ``switch_penalty`` [m] at each
  change of driving direction (defaults are Nav2's: 1.2, 2.0, 0.0; Nav2 has no separate cusp
  penalty, here 2 m);
* heuristic (admissible: see ``HybridAStar._holonomic_heuristic``): max(Reeds–Shepp
  length — Dubins without reverse, Euclidean distance for turning in place — ignoring
  obstacles, a lower bound on the distance around the obstacles for the reference point)
  plus the least cost of turning to the goal's heading (``turn_in_place_cost`` per radian, or
  for a car ``(non_straight_penalty − 1)·R`` per radian: it drives at least R metres of arc
  per radian turned). The curve length costs microseconds, so a child is queued on the cheap
  part alone and gets the curve length when it first reaches the top of the queue; it is
  skipped altogether where the obstacle distance exceeds the straight-line distance by πR,
  which no Reeds–Shepp curve does;
* analytic expansion: a Reeds–Shepp (Dubins, rotate–straight–rotate) shot to the goal tried
  every ``⌊h / (analytic_expansion_ratio · xy_resolution)⌋`` expansions (every expansion near
  the goal) and accepted when collision-free.

Motions are checked by conservative advancement: at a checked sample, the distance field
bounds how far every covering circle may move and stay clear, and the samples within that
reach are skipped (they are clear); only samples near an obstacle reach the exact test.

Collision checking is continuous, not only at samples: every motion is sampled at spacing
``collision_step`` and checked with the footprint grown by the largest distance any footprint
point can travel between samples, ``collision_step/2 · (1 + ρ_max/R)`` (ρ_max = farthest
footprint vertex from the reference point), so returned paths are collision-free at every
intermediate pose under the exact check of :meth:`OccupancyGrid.in_collision` — every sample
exactly, and continuously in between. (One caveat: the start pose is checked exactly, without
the margin, so that a robot parked closer than the margin to an obstacle can still leave; the
first half sample interval is then covered only by the samples around it.)

Poses are those of the footprint's reference point: the **rear-axle centre** for car-like
robots (use ``rear_axle_to_center``), the wheel-axle centre for differential drive.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from typing import NamedTuple

import numba
import numpy as np
from numpy.typing import ArrayLike

from wheelbase._validate import (
    as_float_array,
    check_choice,
    count_text,
    flag,
    integer,
    nonnegative,
    positive,
)
from wheelbase.errors import ConfigError, PlanningError
from wheelbase.geometry import wrap_angle
from wheelbase.limits import MAX_PRIMITIVE_SAMPLES, MAX_STATE_BINS
from wheelbase.planning._heap import _heap_pop, _heap_push
from wheelbase.planning.astar import _dijkstra_kernel
from wheelbase.planning.collision import _circles_clearance, _collides_one, _scratch
from wheelbase.planning.dubins import _WORDS as _DUBINS_WORDS
from wheelbase.planning.dubins import _dubins_all
from wheelbase.planning.escape import escape
from wheelbase.planning.footprint import Footprint
from wheelbase.planning.occupancy import OccupancyGrid
from wheelbase.planning.path import PlannedPath, PlanningStats
from wheelbase.planning.reeds_shepp import _FAMILIES, _best, _min_length, _normalise
from wheelbase.planning.smoothing import smooth_path
from wheelbase.planning.world import PolygonWorld

__all__ = ["HybridAStar"]

_NO_LIMIT = 2**62  # an iteration limit above this is none (the kernel counts in int64)
_FINITE = 1.0e300  # below this a cost is finite: the kernels compare with it, never with inf
_DEEPER = 1.0e-6
"""The queue key is ``(1 − _DEEPER)·g + w·h``: of two states whose f = g + w·h differ by less
than 1e-6 of the cost, the deeper (larger g) comes first. The search meets many such near-ties
(equal-cost detours on the lattice); breaking them towards depth cut the PythonRobotics maze's
expansions from 77k to 61k. It is A* with the heuristic weighted by 1/(1 − 1e-6): a path at
most 1e-6 of its cost dearer than the best on the lattice."""
_OCTILE_RATIO = math.sqrt(4.0 - 2.0 * math.sqrt(2.0))
"""Largest ratio of the 8-connected (octile) distance to the straight-line one (at 22.5°)."""
_HEURISTIC_NORMS = (
    (1.0 / _OCTILE_RATIO, math.sqrt(2.0) / _OCTILE_RATIO),  # octile / worst ratio
    (1.0, 1.0),  # Chebyshev
    (1.0 / math.sqrt(2.0), math.sqrt(2.0)),  # (|x| + |y|) / √2
)
"""(axis, diagonal) move costs of three grid norms that never exceed the Euclidean length."""
_ROTATE = 2  # segment type code for a turn in place (length = signed angle [rad])
_MODE_RS, _MODE_DUBINS, _MODE_POINT = 0, 1, 2
_ESCAPE_EXITS = 3
"""Ways out of a tight end (:func:`~wheelbase.planning.escape.escape`) the lattice is tried from
before the plan fails."""
_ESCAPE_STEPS = 4
"""The escape samples its moves this many times finer than ``collision_step``."""
_STATUS = {
    0: "goal reached",
    1: "search space exhausted",
    2: "iteration limit reached",
    3: "time limit reached",
}


class _Search(NamedTuple):
    """What the search kernel returns: its status (a key of ``_STATUS``), the goal's node and
    the node arrays (pose, parent, primitive, samples of it driven), and the curve shot."""

    status: int
    goal_node: int
    xs: np.ndarray
    ys: np.ndarray
    ths: np.ndarray
    parents: np.ndarray
    prim_of: np.ndarray
    used_of: np.ndarray
    expanded: int
    shot_types: np.ndarray
    shot_lengths: np.ndarray


@dataclass(frozen=True)
class _Primitives:
    offsets: np.ndarray  # (P, S, 3) poses relative to the node, padded
    nsamples: np.ndarray  # (P,)
    direction: np.ndarray  # (P,) +1/-1, 0 for turns in place
    kappa: np.ndarray  # (P,) steering curvature, ±inf for turns in place
    length: np.ndarray  # (P,) distance travelled [m]
    cost: np.ndarray  # (P,) base cost [m]
    sweep: np.ndarray  # (P,) farthest any covering-circle centre moves [m]


class HybridAStar:
    """Hybrid A* planner on an occupancy grid.

    Parameters
    ----------
    grid : OccupancyGrid
        The static map.
    footprint : Footprint or tuple of float
        Robot outline, or ``(length, width)`` [m] of a rectangle placed with
        ``rear_axle_to_center``.
    turning_radius : float
        Minimum turning radius R [m] of the reference point, >= 0; 0 means a differential
        drive that turns in place.
    reverse : bool
        Allow driving backwards (Reeds–Shepp) or not (Dubins).
    rear_axle_to_center : float
        Distance [m] from the reference point (rear-axle centre) forward to the centre of the
        rectangular footprint; ignored when ``footprint`` is a :class:`Footprint`.
    headings : int
        Number of heading bins (72 = 5°, Nav2's default).
    xy_resolution : float or None
        Position bin size [m]; default ``max(grid.resolution, min(length, width)/4)``.
    curvatures : int
        Number of arc curvatures per direction (odd, >= 3; Nav2 uses 3).
    reverse_penalty : float
        Multiplier (>= 1) on the cost of reverse motion.
    switch_penalty : float
        Cost [m] added at each change of driving direction (cusp).
    non_straight_penalty : float
        Multiplier (>= 1) on the cost of arcs.
    change_penalty : float
        Extra multiplier on an arc's length when its curvature differs from the previous one.
    turn_in_place_cost : float
        Cost [m/rad] of turning in place (differential drive only).
    analytic_expansion_ratio : float
        Controls how often a curve shot to the goal is tried (Nav2's parameter).
    heuristic_weight : float or None
        Weight (>= 1) on the admissible heuristic; above 1 trades optimality (a path at most
        that factor dearer) for speed. Default 1 for car-like robots and 1.5 for turning in
        place, whose rotations the heuristic ignores (a plateau of equal-cost states in every
        heading otherwise makes the search ~20× slower, 390 000 instead of 20 000 expansions,
        for a path 0.5–3 % shorter on the bundled maze).
    collision_step : float or None
        Sample spacing [m] of collision checks along motions; default ``grid.resolution/2``.
    xy_goal_tolerance : float
        Accept a search state within this distance [m] of the goal (0: only exact shots).
    yaw_goal_tolerance : float
        ... and within this heading error [rad].
    max_iterations : int
        Expansion limit.
    time_limit : float
        Time limit [s] of the whole search (the escape from a tight end and the lattice
        search after it included).
    smooth : bool
        Smooth the found path with :func:`~wheelbase.planning.smoothing.smooth_path`
        (curvature profile low-pass; keeps cusps, clearance and the curvature limit).
    max_state_bins : int
        Most state bins (x × y × heading) the search may allocate (default
        :data:`wheelbase.limits.MAX_STATE_BINS` = 5e7, about 0.5 GB); raise it on purpose.
    search_from : {"auto", "start", "goal"}
        Which end the search grows from. ``"goal"`` searches from the goal to the start with
        the forward and reverse costs swapped and returns that path driven backwards: the same
        cost, but the search starts where the space is tight, e.g. inside a parking slot,
        where a few short moves decide everything and the curve shots to the open end succeed
        early. ``"auto"`` (default) starts from the end whose footprint has less clearance
        (for a car-like robot; a robot that turns in place starts from the start: on the
        bundled maze, searching from the goal expanded 5× more states) and, where that search
        exhausts its space, searches from the other end, so that it never does worse than
        either end alone (a slot the lattice cannot leave may still be entered by a curve
        shot from outside). Only the start is searched from without reverse or with a goal
        tolerance.
    moves_to_contact : bool
        Where the lattice of whole primitives from the first end found no path, plan with
        moves to contact: the lattice from that end with each primitive that collides near
        obstacles cut at its last free sample and kept as a shorter move (as a driver edges
        forward and back in a tight slot: a 1.15-car-length slot takes 13 moves); then, after
        the other end's lattice (``search_from="auto"``), for a car that may reverse, from each
        tight end the escape by moves to contact on continuous poses
        (:func:`~wheelbase.planning.escape.escape`: a slot 1.10 car lengths long, about 30
        moves) and the lattice from outside. Every cut move is collision-checked like any
        motion. Default on, decided on ``benchmarks/parking.py`` (54 parking cases by a rule,
        and the 26 bundled scenarios): off, the default lattice solves 39 of the 54, on 54;
        where the first end's lattice finds a path (56 of the 80 cases) the path and the
        expansions are the same on or off; in the 5 cases only the other end's lattice solves,
        the cut moves from the first end find a better path first (1–2 cusps instead of 3–4,
        8.0–17.2 m instead of 9.1–25.7 m). Off, the plan fails where the lattice does.
        All these searches share the one time limit: the first may take all of it, each
        later one shares what is left equally with those after it.

    Notes
    -----
    A motion primitive is never longer than the map's diagonal (no longer one could stay in
    the map): with a huge turning radius (1e9 m) the primitives are cut there instead of
    asking for billions of collision samples each.

    Examples
    --------
    >>> grid = OccupancyGrid.from_array(np.zeros((100, 100), bool), 0.1)
    >>> planner = HybridAStar(grid, footprint=(0.8, 0.5), turning_radius=1.0,
    ...                       rear_axle_to_center=0.2)
    >>> path = planner.plan((2.0, 2.0, 0.0), (8.0, 6.0, np.pi / 2))
    >>> path.success, bool(np.allclose(path.poses[-1], (8.0, 6.0, np.pi / 2)))
    (True, True)
    """

    def __init__(
        self,
        grid: OccupancyGrid,
        footprint: Footprint | tuple[float, float],
        turning_radius: float,
        *,
        reverse: bool = True,
        rear_axle_to_center: float = 0.0,
        headings: int = 72,
        xy_resolution: float | None = None,
        curvatures: int = 3,
        reverse_penalty: float = 2.0,
        switch_penalty: float = 2.0,
        non_straight_penalty: float = 1.2,
        change_penalty: float = 0.0,
        turn_in_place_cost: float = 0.5,
        analytic_expansion_ratio: float = 3.5,
        heuristic_weight: float | None = None,
        collision_step: float | None = None,
        xy_goal_tolerance: float = 0.0,
        yaw_goal_tolerance: float = 0.0,
        max_iterations: int = 1_000_000,
        time_limit: float = 5.0,
        smooth: bool = True,
        max_state_bins: int = MAX_STATE_BINS,
        search_from: str = "auto",
        moves_to_contact: bool = True,
    ) -> None:
        if not isinstance(grid, OccupancyGrid | PolygonWorld):
            raise ConfigError(
                f"grid must be an OccupancyGrid or a PolygonWorld (got {type(grid).__name__})"
            )
        if isinstance(footprint, Footprint):
            fp = footprint
        else:
            try:
                dims = np.asarray(footprint, dtype=float).ravel()
            except (TypeError, ValueError):
                dims = np.zeros(0)
            if dims.shape != (2,):
                raise ConfigError(f"footprint must be (length, width) [m] (got {footprint!r})")
            fp = Footprint.rectangle(dims[0], dims[1], rear_axle_to_center)
        diagonal = math.hypot(grid.width_m, grid.height_m)
        if fp.max_radius > diagonal:
            raise ConfigError(
                f"footprint reaches {fp.max_radius:.3g} m from its reference point, farther "
                f"than the map's diagonal ({diagonal:.3g} m): it fits nowhere in the map"
            )
        self.grid = grid
        self.footprint = fp
        self.turning_radius = nonnegative("turning_radius", turning_radius, "m")
        self.reverse = flag("reverse", reverse)
        self.headings = integer("headings", headings, minimum=8)
        try:
            self.curvatures = integer("curvatures", curvatures, minimum=3)
        except ConfigError:
            self.curvatures = 0
        if self.curvatures % 2 == 0:
            raise ConfigError(f"curvatures must be an odd integer >= 3 (got {curvatures!r})")
        poly = fp.polygon
        short = float(min(np.ptp(poly[:, 0]), np.ptp(poly[:, 1])))
        if xy_resolution is None:
            xy_resolution = max(grid.resolution, short / 4.0)
        self.xy_resolution = positive("xy_resolution", xy_resolution, "m")
        if collision_step is None:
            collision_step = grid.resolution / 2.0
        self.collision_step = positive("collision_step", collision_step, "m")
        if heuristic_weight is None:
            heuristic_weight = 1.0 if self.turning_radius > 0 else 1.5
        for name, value in (
            ("reverse_penalty", reverse_penalty),
            ("non_straight_penalty", non_straight_penalty),
            ("heuristic_weight", heuristic_weight),
        ):
            if positive(name, value) < 1.0:
                raise ConfigError(f"{name} must be >= 1 (got {value:g})")
        self.reverse_penalty = float(reverse_penalty)
        self.non_straight_penalty = float(non_straight_penalty)
        self.heuristic_weight = float(heuristic_weight)
        self.switch_penalty = nonnegative("switch_penalty", switch_penalty, "m")
        self.change_penalty = nonnegative("change_penalty", change_penalty)
        self.turn_in_place_cost = nonnegative("turn_in_place_cost", turn_in_place_cost, "m/rad")
        self.analytic_expansion_ratio = positive(
            "analytic_expansion_ratio", analytic_expansion_ratio
        )
        self.xy_goal_tolerance = nonnegative("xy_goal_tolerance", xy_goal_tolerance, "m")
        self.yaw_goal_tolerance = nonnegative("yaw_goal_tolerance", yaw_goal_tolerance, "rad")
        self.max_iterations = integer("max_iterations", max_iterations, minimum=1)
        self.time_limit = positive("time_limit", time_limit, "s")
        self.smooth = flag("smooth", smooth)
        self.max_state_bins = integer("max_state_bins", max_state_bins, minimum=1)
        self.search_from = check_choice("search_from", search_from, ("auto", "start", "goal"))
        if self.search_from == "goal" and not self.reverse:
            raise ConfigError("search_from='goal' needs reverse=True (a path driven backwards)")
        self.moves_to_contact = flag("moves_to_contact", moves_to_contact)

        spans = (grid.width_m / self.xy_resolution, grid.height_m / self.xy_resolution)
        if math.isfinite(spans[0]) and math.isfinite(spans[1]):
            nx, ny = math.ceil(spans[0]), math.ceil(spans[1])
            bins: float = nx * ny * self.headings
        else:  # a subnormal xy_resolution: the quotient is inf, which ceil refuses
            nx = ny = 0
            bins = math.inf
        if bins > self.max_state_bins:
            raise ConfigError(
                f"xy_resolution {self.xy_resolution:g} m and {count_text(self.headings)} "
                f"headings give {count_text(bins)} state bins: more than max_state_bins = "
                f"{self.max_state_bins}; use a coarser xy_resolution or fewer headings, or "
                "raise max_state_bins"
            )
        self._nx, self._ny = nx, ny
        self.primitive_length = min(
            max(
                self.turning_radius * 2.0 * math.pi / self.headings,
                math.sqrt(2.0) * self.xy_resolution,
            ),
            diagonal,
        )
        # the footprint grown by the largest motion of any of its points between samples
        rho = fp.max_radius
        kappa = 1.0 / self.turning_radius if self.turning_radius > 0 else 0.0
        self.collision_margin = 0.5 * self.collision_step * (1.0 + rho * kappa)
        if self.turning_radius == 0.0:
            self.collision_margin = 0.5 * self.collision_step * 1.0
        self._checked = fp.inflated(self.collision_margin)
        # least cost [m/rad] of changing the heading, for the heuristic: a turn in place costs
        # turn_in_place_cost per radian; a car turns along arcs of |κ| <= 1/R, so it drives at
        # least R metres of arc per radian, each dearer by (non_straight_penalty − 1)
        self._turn_cost = (
            self.turn_in_place_cost
            if self.turning_radius == 0.0
            else (self.non_straight_penalty - 1.0) * self.turning_radius
        )
        self._prims = self._build_primitives()
        self._prims_swapped = self._build_primitives(swap_directions=True) if self.reverse else None
        # The search works in the grid's own frame (origin (0, 0)): 4.5e9 m from the world
        # origin, absolute float64 keeps only micrometres (see ``plan``).
        self._local = grid.with_origin((0.0, 0.0))
        self._heuristic_blocked = self._local.reference_blocked(fp.inscribed_radius)

    # ------------------------------------------------------------------ setup
    def _build_primitives(self, swap_directions: bool = False) -> _Primitives:
        step = self.collision_step
        ds = self.primitive_length
        rows: list[tuple[np.ndarray, int, float, float, float]] = []
        dirs = (1, -1) if self.reverse else (1,)
        # Every primitive is sampled every collision_step and tried at every expansion: refuse
        # a table that would not fit (curvatures=3e7 hung, collision_step=1e-9 m alike).
        arcs = len(dirs) * (self.curvatures if self.turning_radius > 0 else 1)
        samples = arcs * max(1, math.ceil(min(ds / step, 1e15)))
        if samples > MAX_PRIMITIVE_SAMPLES:
            raise ConfigError(
                f"{arcs} motion primitives of {ds:.3g} m sampled every {step:.3g} m need "
                f"{samples:.3g} samples: more than {MAX_PRIMITIVE_SAMPLES:g}; use fewer "
                "curvatures or a larger collision_step"
            )
        if self.turning_radius > 0:
            kmax = 1.0 / self.turning_radius
            kappas = np.linspace(-kmax, kmax, self.curvatures)
        else:
            kappas = np.array([0.0])
        for d in dirs:
            for k in kappas:
                n = max(1, math.ceil(ds / step))
                s = d * ds * np.arange(1, n + 1) / n
                offs = _arc_offsets(float(k), s)
                cost = ds * (self.non_straight_penalty if k != 0 else 1.0)
                cost *= self.reverse_penalty if (d > 0 if swap_directions else d < 0) else 1.0
                rows.append((offs, d, float(k), ds, cost))
        if self.turning_radius == 0:
            bin_angle = 2.0 * math.pi / self.headings
            rho = self.footprint.max_radius
            for nb in sorted({1, max(1, self.headings // 8), max(1, self.headings // 4)}):
                for sign in (1.0, -1.0):
                    angle = sign * nb * bin_angle
                    n = max(1, math.ceil(abs(angle) * rho / step))
                    offs = np.zeros((n, 3))
                    offs[:, 2] = angle * np.arange(1, n + 1) / n
                    rows.append(
                        (offs, 0, sign * math.inf, 0.0, self.turn_in_place_cost * nb * bin_angle)
                    )
        rho_c = float(np.max(np.hypot(*self._checked.circles.T)))
        sweep = [
            r[3] * (1.0 + (abs(r[2]) if np.isfinite(r[2]) else 0.0) * rho_c)
            + abs(r[0][-1, 2] if not np.isfinite(r[2]) else 0.0) * rho_c
            for r in rows
        ]
        nmax = max(r[0].shape[0] for r in rows)
        offsets = np.zeros((len(rows), nmax, 3))
        for i, r in enumerate(rows):
            offsets[i, : len(r[0])] = r[0]
        return _Primitives(
            offsets,
            np.array([len(r[0]) for r in rows], dtype=np.int64),
            np.array([r[1] for r in rows], dtype=np.int64),
            np.array([r[2] for r in rows]),
            np.array([r[3] for r in rows]),
            np.array([r[4] for r in rows]),
            np.array(sweep),
        )

    def _check_pose(self, name: str, pose: ArrayLike) -> np.ndarray:
        pose = as_float_array(name, pose, 3, min_ndim=1, max_ndim=1).copy()
        pose[2] = float(wrap_angle(pose[2]))
        text = f"({pose[0]:.3f} m, {pose[1]:.3f} m, {math.degrees(pose[2]):.1f} deg)"
        if not bool(self.grid.contains(pose[:2])):
            raise PlanningError(f"{name} {text} is outside the map {self.grid.extent}")
        if bool(self.grid.in_collision(self.footprint, pose)):
            raise PlanningError(f"{name} {text} is in collision (footprint hits an obstacle)")
        return pose

    # ------------------------------------------------------------------ planning
    def plan(self, start: ArrayLike, goal: ArrayLike) -> PlannedPath:
        """Plan from ``start`` to ``goal``.

        Parameters
        ----------
        start : array_like
            Start pose ``(x, y, θ)`` [m, m, rad] of the reference point.
        goal : array_like
            Goal pose.

        Returns
        -------
        PlannedPath
            Poses sampled every ``collision_step`` metres (and along turns in place), driving
            directions, steering curvatures and statistics; ``success=False`` (empty arrays,
            with the statistics) when the search space is exhausted or a limit is hit.

        Raises
        ------
        PlanningError
            If the start or goal is outside the map or in collision.
        """
        start = self._check_pose("start", start)
        goal = self._check_pose("goal", goal)
        # Plan in the grid's frame and move the result back: the same path, to rounding, at
        # any distance from the world origin (coordinates up to 1e10 m).
        origin = np.array([*self.grid.origin, 0.0])
        ends = (start, goal)
        start, goal = start - origin, goal - origin
        t_compile = time.perf_counter()
        _ensure_compiled()
        compile_time = time.perf_counter() - t_compile

        t0 = time.perf_counter()
        found, status, expanded = self._staged(start, goal, t0)
        if found is None:
            stats = PlanningStats(expanded, time.perf_counter() - t0, compile_time, _STATUS[status])
            return PlannedPath.failure(stats)
        backwards, out, way_out, prims = found
        root = way_out.poses[-1] if way_out is not None else (goal if backwards else start)
        path = self._reconstruct(out, root, prims)
        if way_out is not None:
            path = _joined(way_out, path)
        if backwards:
            path = _driven_backwards(path)
        if self.smooth:
            path = smooth_path(
                path,
                self._local,
                self.footprint,
                self.turning_radius,
                collision_margin=self.collision_margin,
            )
        stats = PlanningStats(expanded, time.perf_counter() - t0, compile_time, _STATUS[0])
        poses = path.poses + origin
        poses[0], poses[-1] = ends  # exactly as given (headings wrapped)
        return PlannedPath(poses, path.directions, path.curvatures, path.arc_length, True, stats)

    def _staged(self, start: np.ndarray, goal: np.ndarray, t0: float) -> tuple:
        """The searches of :meth:`plan` (see ``moves_to_contact``), each begun only when those
        before it found nothing, all within the one time limit and expansion limit:

        1. the lattice of whole primitives from the first end (the tighter one for
           ``search_from="auto"``);
        2. with ``moves_to_contact``: the lattice with moves cut at contact from that end;
        3. for ``search_from="auto"``: the lattice of whole primitives from the other end;
        4. with ``moves_to_contact``, for a car that may reverse: from each tight end (one no
           straight or full-lock move leaves by half the car's length), the escape by moves
           to contact on continuous poses and the lattice, with cut moves, from each of its
           ways out.

        The first search may take the whole time limit; each later one shares the time left
        equally with those after it (time it does not use passes on): a search from an open
        end towards a slot it cannot enter explores the whole map before it exhausts, 2.5 s
        on the bundled 0.1 m, 2.5° lattices, and would starve the escape.

        Returns ``(found, status, expanded)``: ``found`` is ``(backwards, search, way_out,
        primitives)`` or None, ``status`` a key of ``_STATUS``.
        """
        mode = (
            _MODE_POINT
            if self.turning_radius == 0
            else (_MODE_RS if self.reverse else _MODE_DUBINS)
        )
        heuristics: dict[bool, tuple[np.ndarray, float]] = {}
        expanded = 0

        def left() -> float:
            return self.time_limit - (time.perf_counter() - t0)

        def heuristic(backwards: bool) -> tuple[np.ndarray, float]:
            if backwards not in heuristics:
                heuristics[backwards] = self._holonomic_heuristic(start if backwards else goal)
            return heuristics[backwards]

        def lattice(root, backwards, cut, seconds) -> tuple[_Search, _Primitives]:
            """One lattice search from ``root`` to the far end."""
            nonlocal expanded
            hgrid, hres = heuristic(backwards)
            prims = self._prims_swapped if backwards else self._prims
            budget = min(self.max_iterations, _NO_LIMIT) - expanded
            target = start if backwards else goal
            out = self._lattice(root, target, hgrid, hres, prims, mode, seconds, budget, cut)
            expanded += int(out.expanded)
            return out, prims

        def escaped(backwards, seconds) -> tuple:
            """The escape from one end and the lattice from its ways out: ``(found, status)``
            as :meth:`_staged`'s, ``status`` None when nothing ended the search early."""
            nonlocal expanded
            root, target = (goal, start) if backwards else (start, goal)
            until = time.perf_counter() + seconds
            exits, escape_expanded = self._escape(
                root, target, time_limit=max(seconds, 1e-9), exits=_ESCAPE_EXITS
            )
            expanded += escape_expanded
            clocked = not exits and time.perf_counter() >= until
            for candidate in exits:
                seconds = until - time.perf_counter()
                if seconds <= 0.0:
                    return None, 3
                out, prims = lattice(candidate.poses[-1], backwards, True, seconds)
                if out.status == 0:
                    return (backwards, out, candidate, prims), 0
                if out.status != 1:
                    return None, int(out.status)
            return None, (3 if clocked else None)

        # no path at all, even for the reference point alone (the holonomic bound is infinite:
        # it keeps the inscribed radius from every obstacle, see _holonomic_heuristic)
        hgrid, hres = heuristic(False)
        i, j = int(start[1] // hres), int(start[0] // hres)  # the grid's frame: origin (0, 0)
        if not (0 <= i < hgrid.shape[0] and 0 <= j < hgrid.shape[1] and hgrid[i, j] < _FINITE):
            return None, 1, expanded
        ends = self._search_ends(start, goal)
        stages: list[tuple[str, bool]] = [("lattice", ends[0])]
        if self.moves_to_contact:
            stages.append(("cut", ends[0]))
        stages += [("lattice", backwards) for backwards in ends[1:]]
        if self.moves_to_contact and self.turning_radius > 0 and self.reverse:
            stages += [
                ("escape", backwards) for backwards in ends if self._tight(start, goal, backwards)
            ]
        clocked = False  # whether the clock (a share of the time) ended a search
        for n, (kind, backwards) in enumerate(stages):
            if left() <= 0.0:
                clocked = True
                break
            share = left() / (len(stages) - n) if n > 0 else left()
            if kind == "escape":
                found, status = escaped(backwards, share)
                if found is not None or status in (0, 2):
                    return found, status, expanded
                clocked |= status == 3
                continue
            out, prims = lattice(goal if backwards else start, backwards, kind == "cut", share)
            if out.status == 0:
                return (backwards, out, None, prims), 0, expanded
            if out.status == 2:
                return None, 2, expanded
            clocked |= out.status == 3
        return None, (3 if clocked else 1), expanded

    def _tight(self, start: np.ndarray, goal: np.ndarray, backwards: bool) -> bool:
        """Whether an end is tight: no straight or full-lock move from it, forwards or in
        reverse, runs the escape's probe length (half the car's length) without contact."""
        root, target = (goal, start) if backwards else (start, goal)
        exits, _ = self._escape(root, target, max_expansions=1)
        return not (exits and len(exits[0].poses) == 1)

    def _escape(self, root: np.ndarray, target: np.ndarray, **options) -> tuple:
        """:func:`~wheelbase.planning.escape.escape` from ``root``, sampled
        ``_ESCAPE_STEPS`` times finer than the lattice and so with that much less margin (a
        slot 1.10 car lengths long leaves 0.235 m at either end of the car: at the lattice's
        own 2.9 cm margin of its default 2.5 cm step, the way out of it behind a curb took 153
        moves instead of 32), keeping only the ways out whose last pose the lattice's own check
        (the footprint grown by its margin) finds free."""
        step = self.collision_step / _ESCAPE_STEPS
        kappa = 1.0 / self.turning_radius
        exits, expanded = escape(
            self._local, self.footprint, self.turning_radius, root, target, step=step,
            margin=0.5 * step * (1.0 + self.footprint.max_radius * kappa),
            spacing=self.collision_step, **options,
        )  # fmt: skip
        ends = np.array([e.poses[-1] for e in exits]).reshape(-1, 3)
        free = ~self._local.in_collision(self._checked, ends) if len(exits) else []
        return [e for e, ok in zip(exits, free, strict=True) if ok or len(e.poses) == 1], expanded

    def _lattice(
        self, start, goal, hgrid, hres, prims, mode, time_limit, max_iterations, cut_moves
    ) -> _Search:
        """The lattice search (compiled) from ``start`` to ``goal`` in the grid's frame."""
        return _Search(
            *_search(
                self._local._kernel_world,
                self._checked.polygon,
                self._checked.circles,
                self._checked.circle_radius,
                hgrid,
                hres,
                start,
                goal,
                prims.offsets,
                prims.nsamples,
                prims.direction,
                prims.kappa,
                prims.cost,
                prims.sweep,
                self._nx,
                self._ny,
                self.headings,
                self.xy_resolution,
                self.turning_radius,
                mode,
                _FAMILIES,
                self.footprint.max_radius,
                self.switch_penalty,
                self.change_penalty,
                self.heuristic_weight,
                self.analytic_expansion_ratio,
                self.collision_step,
                self.xy_goal_tolerance,
                self.yaw_goal_tolerance,
                max(max_iterations, 0),
                max(time_limit, 0.0),
                self._turn_cost,
                cut_moves,
            )
        )

    def _holonomic_heuristic(self, goal: np.ndarray) -> tuple[np.ndarray, float]:
        """Admissible cost-to-go [m] around the obstacles on cells of ``xy_resolution``.

        Why it never overestimates:

        1. The reference point keeps at least the footprint's inscribed radius from every
           obstacle, so it never lies in a cell of ``reference_blocked``; a coarse cell is free
           when any of its fine cells is, so every feasible path stays in free coarse cells.
        2. The shortest curve in that free region is a taut polyline bending at cell corners.
           A straight piece spanning ``a >= b`` cells in x and y crosses cells that an
           8-connected walk of ``a − b`` axis and ``b`` diagonal moves follows (diagonal moves
           may cut corners here, as the piece may). With move costs ``α`` (axis) and ``β``
           (diagonal) the walk costs ``N(a, b) = (a − b)·α + b·β``, a norm of the piece.
        3. Three such norms never exceed the Euclidean length: the octile norm divided by its
           worst ratio ``√(4 − 2√2) ≈ 1.0824`` (exact at 22.5°), the Chebyshev norm (α = β =
           1, exact along the axes) and ``(|x| + |y|)/√2`` (α = 1/√2, β = √2, exact at 45°).
           Their maximum is within 2 % of the straight-line distance in every direction (the
           octile distance alone overestimates it by up to 8.2 %).
        4. A corner-to-corner piece saves one move at its ends, which pays for the step
           between the cells around a bend; the two ends of the path may cost one diagonal
           ``√2·hres`` each, which is subtracted.

        So each Dijkstra distance ``D`` obeys ``D − 2√2·hres <= L`` for every feasible path of
        length ``L``, and every motion costs at least its length: the maximum of the three is
        admissible. The search adds a heading term that stays admissible: a path that turns
        the heading by ``Δθ`` (wrapped) turns at least ``|Δθ|`` in all; a car does so on arcs
        of curvature at most 1/R, at least ``R·|Δθ|`` metres of them, each costing
        ``non_straight_penalty − 1`` more than its length; a differential drive pays
        ``turn_in_place_cost`` per radian. So A* with ``heuristic_weight=1`` returns
        least-cost paths on its lattice; a weight above 1 gives this up on purpose, for speed.
        """
        blocked = self._heuristic_blocked
        rows, cols = blocked.shape
        # a coarse cell wider than the map is the map (and keeps the padding finite)
        f = max(1, min(round(self.xy_resolution / self.grid.resolution), max(rows, cols)))
        pr, pc = (-rows) % f, (-cols) % f
        free = np.pad(~blocked, ((0, pr), (0, pc)), constant_values=False)
        coarse_free = free.reshape(free.shape[0] // f, f, free.shape[1] // f, f).any(axis=(1, 3))
        hres = self.grid.resolution * f
        gr = int((goal[1] - self._local.origin[1]) // hres)
        gc = int((goal[0] - self._local.origin[0]) // hres)
        coarse_free[gr, gc] = True
        occ = (~coarse_free).astype(np.uint8)
        dist = np.zeros(occ.size)
        for axis, diagonal in _HEURISTIC_NORMS:
            d = _dijkstra_kernel(occ, gr, gc, 8, True, axis, diagonal)
            np.maximum(dist, d, out=dist)
        bound = dist.reshape(occ.shape) * hres - 2.0 * math.sqrt(2.0) * hres
        return np.maximum(bound, 0.0), hres

    def _search_ends(self, start: np.ndarray, goal: np.ndarray) -> list[bool]:
        """The ends the search grows from, in turn (True: from the goal): ``search_from``'s
        one end, or for ``"auto"`` the tighter end first and the other after it (the search
        from the goal needs reverse and exact goals)."""
        if self.search_from != "auto":
            return [self.search_from == "goal"]
        if not self.reverse or self.xy_goal_tolerance > 0 or self.yaw_goal_tolerance > 0:
            return [False]
        if self.turning_radius == 0.0:  # turns in place: no end is tighter to leave
            return [False, True]
        clear = self._local.footprint_clearance(self.footprint, np.stack([start, goal]))
        first = bool(clear[1] < clear[0])
        return [first, not first]

    def _reconstruct(self, out: _Search, start: np.ndarray, prims: _Primitives) -> PlannedPath:
        """The path of a successful search ``out`` from its root ``start``."""
        xs, ys, ths, parents, prim_of, used_of = out[2:8]
        chain = [int(out.goal_node)]
        while parents[chain[-1]] >= 0:
            chain.append(int(parents[chain[-1]]))
        chain.reverse()
        poses = [start[None, :]]
        dirs: list[np.ndarray] = []
        curv: list[np.ndarray] = []
        dist: list[np.ndarray] = []
        for node in chain[1:]:
            p = int(prim_of[node])
            parent = int(parents[node])
            base = np.array([xs[parent], ys[parent], ths[parent]])
            used = int(used_of[node])  # all of the primitive's samples, or a move cut at contact
            offs = prims.offsets[p, :used]
            poses.append(_compose(base, offs))
            n = len(offs)
            dirs.append(np.full(n, prims.direction[p]))
            curv.append(np.full(n, prims.kappa[p]))
            dist.append(np.full(n, prims.length[p] / prims.nsamples[p]))
        last = np.array([xs[chain[-1]], ys[chain[-1]], ths[chain[-1]]])
        for kind, length in zip(out.shot_types, out.shot_lengths, strict=True):
            if length == 0.0:
                continue
            seg, d, k, ds = _sample_segment(
                last,
                int(kind),
                float(length),
                self.turning_radius,
                self.collision_step,
                self.footprint.max_radius,
            )
            poses.append(seg)
            dirs.append(d)
            curv.append(k)
            dist.append(ds)
            last = seg[-1]
        poses_arr = np.concatenate(poses)
        poses_arr[:, 2] = wrap_angle(poses_arr[:, 2])
        if dirs:
            d_all = np.concatenate(dirs)
            k_all = np.concatenate(curv)
            s_all = np.concatenate(dist)
        else:
            d_all, k_all, s_all = np.zeros(0, np.int64), np.zeros(0), np.zeros(0)
        # turns in place have direction 0 internally: give them the surrounding direction
        d_all = _fill_direction(d_all)
        d_all = np.concatenate([[d_all[0] if len(d_all) else 1], d_all])
        k_all = np.concatenate([[k_all[0] if len(k_all) else 0.0], k_all])
        arc = np.concatenate([[0.0], np.cumsum(s_all)])
        return PlannedPath(poses_arr, d_all, k_all, arc)


# ---------------------------------------------------------------------- helpers
def _joined(first: PlannedPath, second: PlannedPath) -> PlannedPath:
    """``first`` then ``second``, which starts where ``first`` ends."""
    return PlannedPath(
        np.concatenate([first.poses, second.poses[1:]]),
        np.concatenate([first.directions, second.directions[1:]]),
        np.concatenate([first.curvatures, second.curvatures[1:]]),
        np.concatenate([first.arc_length, first.arc_length[-1] + second.arc_length[1:]]),
    )


def _driven_backwards(path: PlannedPath) -> PlannedPath:
    """The same curve traversed from its end to its start: every motion in the other gear,
    the curvature (dθ per signed metre) unchanged."""
    n = len(path.poses)
    directions = np.empty_like(path.directions)
    curvatures = np.empty_like(path.curvatures)
    directions[1:] = -path.directions[1:][::-1]
    curvatures[1:] = path.curvatures[1:][::-1]
    directions[0] = directions[1] if n > 1 else path.directions[0]
    curvatures[0] = curvatures[1] if n > 1 else path.curvatures[0]
    arc = path.arc_length[-1] - path.arc_length[::-1]
    return PlannedPath(
        path.poses[::-1].copy(), directions, curvatures, arc, path.success, path.stats
    )


def _arc_offsets(kappa: float, s: np.ndarray) -> np.ndarray:
    """Poses after signed distances ``s`` along an arc of curvature ``kappa`` from the origin."""
    if kappa == 0.0:
        return np.stack([s, np.zeros_like(s), np.zeros_like(s)], -1)
    th = kappa * s
    return np.stack([np.sin(th) / kappa, (1.0 - np.cos(th)) / kappa, th], -1)


def _compose(base: np.ndarray, offs: np.ndarray) -> np.ndarray:
    c, s = math.cos(base[2]), math.sin(base[2])
    out = np.empty_like(offs)
    out[:, 0] = base[0] + c * offs[:, 0] - s * offs[:, 1]
    out[:, 1] = base[1] + s * offs[:, 0] + c * offs[:, 1]
    out[:, 2] = base[2] + offs[:, 2]
    return out


def _sample_segment(
    pose: np.ndarray, kind: int, length: float, radius: float, step: float, rho: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    if kind == _ROTATE:
        n = max(1, math.ceil(abs(length) * rho / step))
        offs = np.zeros((n, 3))
        offs[:, 2] = length * np.arange(1, n + 1) / n
        kappa = math.copysign(math.inf, length)
        return _compose(pose, offs), np.zeros(n, np.int64), np.full(n, kappa), np.zeros(n)
    n = max(1, math.ceil(abs(length) / step))
    s = length * np.arange(1, n + 1) / n
    kappa = kind / radius if kind != 0 else 0.0
    seg = _compose(pose, _arc_offsets(kappa, s))
    d = 1 if length > 0 else -1
    return seg, np.full(n, d), np.full(n, kappa), np.full(n, abs(length) / n)


def _fill_direction(d: np.ndarray) -> np.ndarray:
    d = d.copy()
    nonzero = np.nonzero(d)[0]
    if len(nonzero) == 0:
        return np.ones_like(d)
    # forward fill, then back fill the leading zeros
    idx = np.where(d != 0, np.arange(len(d)), 0)
    np.maximum.accumulate(idx, out=idx)
    filled = d[idx]
    filled[: nonzero[0]] = d[nonzero[0]]
    return filled


_COMPILED: list[bool] = []


def _ensure_compiled() -> None:
    """Compile (or load from cache) the search kernel on a tiny problem, once per process."""
    if _COMPILED:
        return
    grid = OccupancyGrid.from_array(np.zeros((12, 12), bool), 0.5)
    planner = HybridAStar(grid, (1.0, 0.5), 1.0, time_limit=1.0)
    _COMPILED.append(True)
    planner.plan((1.5, 1.5, 0.0), (4.0, 4.0, 1.0))


# ---------------------------------------------------------------------- Numba kernels
@numba.njit(cache=True)
def _now():
    with numba.objmode(t="float64"):
        t = time.perf_counter()
    return t


@numba.njit(cache=True, inline="always")
def _wrap(a):
    """``a`` wrapped to (−π, π] [rad], by arithmetic (no trigonometric calls)."""
    if -math.pi < a <= math.pi:
        return a
    return a - 2.0 * math.pi * math.ceil((a - math.pi) / (2.0 * math.pi))


@numba.njit(cache=True)
def _advance(x, y, th, kind, s, radius):
    if kind == _ROTATE:
        return x, y, th + s
    if kind == 0:
        return x + s * math.cos(th), y + s * math.sin(th), th
    k = kind / radius
    th1 = th + k * s
    return x + (math.sin(th1) - math.sin(th)) / k, y + (math.cos(th) - math.cos(th1)) / k, th1


@numba.njit(cache=True)
def _shot_word(x, y, th, gx, gy, gth, mode, radius, families, reverse_ok):
    """Segment types and signed lengths (m, or rad for turns in place) of the curve shot."""
    types = np.zeros(5, dtype=np.int64)
    lengths = np.zeros(5)
    if mode == _MODE_RS:
        nx, ny, nphi = _normalise(x, y, th, gx, gy, gth, radius)
        t, ell, total = _best(nx, ny, nphi, families)
        if not np.isfinite(total):
            return False, types, lengths
        for i in range(5):
            types[i] = t[i]
            lengths[i] = ell[i] * radius
        return True, types, lengths
    if mode == _MODE_DUBINS:
        segs = _dubins_all(x, y, th, gx, gy, gth, radius)
        best = -1
        best_len = np.inf
        for w in range(6):
            if not np.isnan(segs[w, 0]):
                total = segs[w, 0] + segs[w, 1] + segs[w, 2]
                if total < best_len:
                    best_len = total
                    best = w
        if best < 0:
            return False, types, lengths
        for i in range(3):
            types[i] = _DUBINS_WORDS[best, i]
            lengths[i] = segs[best, i] * radius
        return True, types, lengths
    # rotate - straight - rotate
    dx = gx - x
    dy = gy - y
    d = math.hypot(dx, dy)
    heading = math.atan2(dy, dx) if d > 1e-12 else th
    sign = 1.0
    a1 = _wrap(heading - th)
    if reverse_ok:
        a1b = _wrap(heading + math.pi - th)
        a2b = _wrap(gth - heading - math.pi)
        a2 = _wrap(gth - heading)
        if abs(a1b) + abs(a2b) < abs(a1) + abs(a2):
            a1 = a1b
            sign = -1.0
    a2 = _wrap(gth - (th + a1))
    types[0] = _ROTATE
    lengths[0] = a1
    types[1] = 0
    lengths[1] = sign * d
    types[2] = _ROTATE
    lengths[2] = a2
    return True, types, lengths


@numba.njit(cache=True, inline="always")
def _next_sample(k, clear, per):
    """The first sample after ``k`` that the clearance ``clear`` [m] at sample ``k`` does not
    vouch for, when no covering circle moves more than ``per`` [m] from one sample to the
    next (conservative advancement: the samples in between are clear)."""
    if clear <= 0.0:
        return k + 1
    if per <= 0.0:
        return 1 << 62
    return k + max(1, math.ceil(min(clear / per, 1.0e15)))


@numba.njit(cache=True, _nrt=False)
def _shot_free(
    x,
    y,
    th,
    types,
    lengths,
    radius,
    step,
    rho,
    world,
    poly,
    circles,
    cradius,
    wp,
    near,
):
    for i in range(5):
        ell = lengths[i]
        if ell == 0.0:
            continue
        kind = types[i]
        span = abs(ell) * rho if kind == _ROTATE else abs(ell)
        n = max(1, math.ceil(span / step))
        # the most any covering circle (within rho of the reference point) moves per sample
        per = (
            span / n
            if kind == _ROTATE
            else abs(ell) / n * (1.0 + (rho / radius if kind != 0 else 0.0))
        )
        dist, res, x0, y0 = world[2], world[3], world[4], world[5]
        k = _next_sample(0, _circles_clearance(dist, res, x0, y0, circles, cradius, x, y, th), per)
        while k <= n:
            px, py, pth = _advance(x, y, th, kind, ell * k / n, radius)
            clear = _circles_clearance(dist, res, x0, y0, circles, cradius, px, py, pth)
            if clear <= 0.0 and _collides_one(world, poly, circles, cradius, px, py, pth, wp, near):
                return False
            k = _next_sample(k, clear, per)
        x, y, th = _advance(x, y, th, kind, ell, radius)
    return True


@numba.njit(cache=True, _nrt=False)
def _free_prefix(
    world, dist, res, x0, y0, poly, circles, cradius, x, y, th, offsets, p, ns, sweep, clear0,
    wp, near,
):  # fmt: skip
    """How many leading samples ``offsets[p, :ns]`` of primitive ``p`` from pose ``(x, y, th)``
    are free (``ns``: all). Not inlined and without reference counting, as the collision
    kernels (see :mod:`wheelbase.planning.collision`): inlined, it took and released a
    reference to each of its 15 array arguments at every call. ``sweep`` bounds how far a
    covering circle moves along the whole primitive and ``clear0`` is the clearance of the
    circles at the pose (see ``_circles_clearance``; ``dist``, ``res``, ``x0``, ``y0``
    are the world's distance field and raster geometry; ``wp``, ``near``: scratch)."""
    c = math.cos(th)
    s = math.sin(th)
    per = sweep / ns
    k = _next_sample(-1, clear0, per)
    while k < ns:
        px = x + c * offsets[p, k, 0] - s * offsets[p, k, 1]
        py = y + s * offsets[p, k, 0] + c * offsets[p, k, 1]
        pth = th + offsets[p, k, 2]
        clear = _circles_clearance(dist, res, x0, y0, circles, cradius, px, py, pth)
        if clear <= 0.0 and _collides_one(world, poly, circles, cradius, px, py, pth, wp, near):
            return k
        k = _next_sample(k, clear, per)
    return ns


@numba.njit(cache=True, inline="always")
def _bin(x, y, th, x0, y0, xy_res, nx, ny, nh):
    ix = math.floor((x - x0) / xy_res)
    iy = math.floor((y - y0) / xy_res)
    if ix < 0 or ix >= nx or iy < 0 or iy >= ny:
        return -1
    ih = math.floor(_wrap(th) / (2.0 * math.pi / nh) + 0.5) % nh
    return (iy * nx + ix) * nh + ih


@numba.njit(cache=True, inline="always")
def _cheap_heuristic(x, y, th, gx, gy, gth, mode, hgrid, hres, x0, y0, turn_cost):
    """A lower bound on :func:`_heuristic` without the curve length (a table look-up): the
    holonomic cost-to-go or the straight-line distance, plus the least cost of turning to the
    goal's heading (for turning in place, this is the whole heuristic)."""
    j = math.floor((x - x0) / hres)
    i = math.floor((y - y0) / hres)
    if i < 0 or i >= hgrid.shape[0] or j < 0 or j >= hgrid.shape[1]:
        return np.inf
    return max(math.hypot(gx - x, gy - y), hgrid[i, j]) + turn_cost * abs(_wrap(gth - th))


@numba.njit(cache=True)
def _heuristic(x, y, th, gx, gy, gth, mode, radius, families, hgrid, hres, x0, y0, turn_cost):
    """Admissible cost-to-go: max(curve length without obstacles, holonomic cost-to-go with
    them) + ``turn_cost`` × |heading change| (see ``HybridAStar._holonomic_heuristic``)."""
    j = math.floor((x - x0) / hres)
    i = math.floor((y - y0) / hres)
    if i < 0 or i >= hgrid.shape[0] or j < 0 or j >= hgrid.shape[1]:
        return np.inf
    h2 = hgrid[i, j]
    turn = turn_cost * abs(_wrap(gth - th))
    d = math.hypot(gx - x, gy - y)
    if mode == _MODE_POINT or (mode == _MODE_RS and h2 >= d + math.pi * radius):
        # turning in place: the Euclidean distance is the curve length. Reeds–Shepp: turning
        # to face the goal (or away), a straight line and turning to the goal's heading is a
        # path of at most d + πR (each turn in place costs |angle|·R, e.g. by L+R−L+, and
        # the two turns add up to at most π for one of the two driving directions): the
        # curve length cannot exceed h2, and its microseconds are saved
        return max(d, h2) + turn
    if mode == _MODE_RS:
        nx, ny, nphi = _normalise(x, y, th, gx, gy, gth, radius)
        h1 = _min_length(nx, ny, nphi, families) * radius
    else:
        segs = _dubins_all(x, y, th, gx, gy, gth, radius)
        h1 = np.inf
        for w in range(6):
            if not np.isnan(segs[w, 0]):
                h1 = min(h1, (segs[w, 0] + segs[w, 1] + segs[w, 2]) * radius)
    return max(h1, h2) + turn


@numba.njit(cache=True)
def _grown(a, n, capacity):
    """A copy of ``a[:n]`` in a new array of ``capacity`` entries."""
    out = np.empty(capacity, dtype=a.dtype)
    out[:n] = a[:n]
    return out


@numba.njit(cache=True)
def _search(
    world,
    poly,
    circles,
    cradius,
    hgrid,
    hres,
    start,
    goal,
    offsets,
    nsamples,
    pdir,
    pkappa,
    pcost,
    psweep,
    nx,
    ny,
    nh,
    xy_res,
    radius,
    mode,
    families,
    rho,
    switch_penalty,
    change_penalty,
    hweight,
    ratio,
    step,
    xy_tol,
    yaw_tol,
    max_iter,
    time_limit,
    turn_cost,
    cut_moves,
):
    t_start = _now()
    dist = world[2]
    res = world[3]
    x0 = world[4]
    y0 = world[5]
    capacity = 4096
    xs = np.empty(capacity)
    ys = np.empty(capacity)
    ths = np.empty(capacity)
    gs = np.empty(capacity)
    parents = np.empty(capacity, dtype=np.int64)
    prim_of = np.empty(capacity, dtype=np.int64)
    used_of = np.empty(capacity, dtype=np.int64)  # samples of the primitive driven (a cut move)
    last_dir = np.empty(capacity, dtype=np.int64)
    # whether a node's queue key holds the full heuristic or only the cheap bound: the curve
    # length (microseconds) is computed when a node first reaches the top of the queue, so
    # children that are never expanded never pay for it (the key only grows: still A*)
    exact_h = np.empty(capacity, dtype=np.bool_)
    nbins = nx * ny * nh
    best_g = np.full(nbins, np.inf)
    gx, gy, gth = goal[0], goal[1], goal[2]
    reverse_ok = False
    for p in range(pdir.shape[0]):
        if pdir[p] < 0:
            reverse_ok = True

    xs[0], ys[0], ths[0], gs[0] = start[0], start[1], start[2], 0.0
    parents[0] = -1
    prim_of[0] = -1
    used_of[0] = 0
    last_dir[0] = 0
    exact_h[0] = True
    n_nodes = 1
    b0 = _bin(start[0], start[1], start[2], x0, y0, xy_res, nx, ny, nh)
    best_g[b0] = 0.0
    h0 = _heuristic(
        start[0],
        start[1],
        start[2],
        gx,
        gy,
        gth,
        mode,
        radius,
        families,
        hgrid,
        hres,
        x0,
        y0,
        turn_cost,
    )
    # the open list: a binary heap of (key, node) in two arrays (numba's heapq on a list costs
    # atomic reference counts at every push and pop, a quarter of the search's time); the
    # order is that of the tuples, so the search is the same
    hcap = 2 * capacity
    hkeys = np.empty(hcap)
    hids = np.empty(hcap, dtype=np.int64)
    hsize = _heap_push(hkeys, hids, 0, hweight * h0, 0)
    expanded = 0
    since_shot = 1 << 30
    status = 1
    goal_node = -1
    shot_types = np.zeros(5, dtype=np.int64)
    shot_lengths = np.zeros(5)
    n_prims = pdir.shape[0]
    placed, listed = _scratch(world, poly)  # scratch buffers of the exact collision check

    # The node arrays grow in the outer loop only: reassigning them inside the search loop
    # makes Numba reference-count all eight at every accepted child (a third of the time).
    while True:
        grow = False
        if n_nodes + n_prims > capacity:
            capacity *= 2
            xs = _grown(xs, n_nodes, capacity)
            ys = _grown(ys, n_nodes, capacity)
            ths = _grown(ths, n_nodes, capacity)
            gs = _grown(gs, n_nodes, capacity)
            parents = _grown(parents, n_nodes, capacity)
            prim_of = _grown(prim_of, n_nodes, capacity)
            used_of = _grown(used_of, n_nodes, capacity)
            last_dir = _grown(last_dir, n_nodes, capacity)
            exact_h = _grown(exact_h, n_nodes, capacity)
        if hsize + n_prims + 1 > hcap:
            hcap *= 2
            hkeys = _grown(hkeys, hsize, hcap)
            hids = _grown(hids, hsize, hcap)
        while hsize > 0:
            if n_nodes + n_prims > capacity or hsize + n_prims + 1 > hcap:
                grow = True  # room for every child of the next node: grow outside this loop
                break
            f, node, hsize = _heap_pop(hkeys, hids, hsize)
            x, y, th, g = xs[node], ys[node], ths[node], gs[node]
            b = _bin(x, y, th, x0, y0, xy_res, nx, ny, nh)
            if g > best_g[b] + 1e-9:  # closed (-inf) or reached more cheaply since
                continue
            if not exact_h[node]:
                exact_h[node] = True
                hfull = _heuristic(
                    x, y, th, gx, gy, gth, mode, radius, families, hgrid, hres, x0, y0, turn_cost
                )
                if not hfull < _FINITE:
                    continue
                if (1.0 - _DEEPER) * g + hweight * hfull > f:
                    key = (1.0 - _DEEPER) * g + hweight * hfull
                    hsize = _heap_push(hkeys, hids, hsize, key, node)
                    continue
            best_g[b] = -np.inf  # closed
            expanded += 1
            if expanded > max_iter:
                status = 2
                break
            if (expanded & 255) == 0 and _now() - t_start > time_limit:
                status = 3
                break
            # goal tolerance
            if (
                xy_tol > 0.0
                and math.hypot(x - gx, y - gy) <= xy_tol
                and abs(_wrap(th - gth)) <= yaw_tol
            ):
                status = 0
                goal_node = node
                break
            # analytic expansion
            h = (f - (1.0 - _DEEPER) * g) / hweight
            since_shot += 1
            # An infinite heuristic (no free way to the goal even for a point) means no shot can
            # succeed either: none is tried, and int() never sees inf (undefined when compiled).
            shots = h < _FINITE
            interval = int(min(max(h, 0.0) / (ratio * xy_res), 1.0e18)) if shots else 0
            if shots and since_shot >= interval:
                since_shot = 0
                ok, types, lengths = _shot_word(
                    x, y, th, gx, gy, gth, mode, radius, families, reverse_ok
                )
                if ok and _shot_free(
                    x,
                    y,
                    th,
                    types,
                    lengths,
                    radius,
                    step,
                    rho,
                    world,
                    poly,
                    circles,
                    cradius,
                    placed,
                    listed,
                ):
                    status = 0
                    goal_node = node
                    shot_types = types
                    shot_lengths = lengths
                    break
            c = math.cos(th)
            s = math.sin(th)
            parent_prim = prim_of[node]
            # lower bound on how far every covering circle may move and stay clear
            free_sweep = _circles_clearance(dist, res, x0, y0, circles, cradius, x, y, th)
            for p in range(n_prims):
                ns = nsamples[p]
                d = pdir[p]
                ld = last_dir[node]
                extra = switch_penalty if (d != 0 and ld != 0 and d != ld) else 0.0
                pc = pcost[p]
                if (
                    parent_prim >= 0
                    and pdir[p] != 0
                    and pdir[parent_prim] != 0
                    and pkappa[p] != pkappa[parent_prim]
                ):
                    extra += change_penalty * pcost[p]  # the whole primitive's, cut or not
                nxp = x + c * offsets[p, ns - 1, 0] - s * offsets[p, ns - 1, 1]
                nyp = y + s * offsets[p, ns - 1, 0] + c * offsets[p, ns - 1, 1]
                nth = _wrap(th + offsets[p, ns - 1, 2])
                nb = _bin(nxp, nyp, nth, x0, y0, xy_res, nx, ny, nh)
                full_open = nb >= 0 and g + (pc + extra) < best_g[nb]
                near = psweep[p] >= free_sweep
                if not full_open and not (cut_moves and near):
                    continue
                use = ns
                if near:
                    use = _free_prefix(
                        world, dist, res, x0, y0, poly, circles, cradius, x, y, th,
                        offsets, p, ns, psweep[p], free_sweep, placed, listed,
                    )  # fmt: skip
                    if use == 0 or (use < ns and not cut_moves) or (use == ns and not full_open):
                        continue
                    if use < ns:  # the move until contact: up to the last free sample
                        nxp = x + c * offsets[p, use - 1, 0] - s * offsets[p, use - 1, 1]
                        nyp = y + s * offsets[p, use - 1, 0] + c * offsets[p, use - 1, 1]
                        nth = _wrap(th + offsets[p, use - 1, 2])
                        nb = _bin(nxp, nyp, nth, x0, y0, xy_res, nx, ny, nh)
                        if nb < 0 or best_g[nb] == -np.inf:
                            continue
                ng = g + ((pc if use == ns else pc * use / ns) + extra)
                if ng >= best_g[nb]:
                    continue
                hn = _cheap_heuristic(
                    nxp, nyp, nth, gx, gy, gth, mode, hgrid, hres, x0, y0, turn_cost
                )
                if not hn < _FINITE:
                    continue
                best_g[nb] = ng
                xs[n_nodes] = nxp
                ys[n_nodes] = nyp
                ths[n_nodes] = nth
                gs[n_nodes] = ng
                parents[n_nodes] = node
                prim_of[n_nodes] = p
                used_of[n_nodes] = use
                last_dir[n_nodes] = d if d != 0 else ld
                exact_h[n_nodes] = mode == _MODE_POINT  # there the cheap bound is the heuristic
                hsize = _heap_push(hkeys, hids, hsize, (1.0 - _DEEPER) * ng + hweight * hn, n_nodes)
                n_nodes += 1
        if not grow:
            break
    return (
        status,
        goal_node,
        xs[:n_nodes],
        ys[:n_nodes],
        ths[:n_nodes],
        parents[:n_nodes],
        prim_of[:n_nodes],
        used_of[:n_nodes],
        expanded,
        shot_types,
        shot_lengths,
    )
