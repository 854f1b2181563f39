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
* heuristic (admissible: see :mod:`~wheelbase.planning.hybrid_heuristic`): max(Reeds–Shepp
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

The planner is split by job: :mod:`~wheelbase.planning.lattice` (the motion primitives and the
sampling of segments), :mod:`~wheelbase.planning.hybrid_heuristic` (the admissible
cost-to-go), :mod:`~wheelbase.planning.hybrid_search` (the compiled search) and this module
(the planner's parameters and checks, the stages of a plan and the path it returns).
"""

from __future__ import annotations

import math
import time

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
from wheelbase.limits import MAX_STATE_BINS
from wheelbase.planning.escape import escape
from wheelbase.planning.footprint import Footprint
from wheelbase.planning.hybrid_heuristic import (
    _MODE_DUBINS,
    _MODE_POINT,
    _MODE_RS,
    _holonomic_heuristic,
)
from wheelbase.planning.hybrid_search import _FINITE, _NO_LIMIT, _STATUS, _Search, _search
from wheelbase.planning.lattice import _build_primitives, _compose, _Primitives, _sample_segment
from wheelbase.planning.occupancy import OccupancyGrid
from wheelbase.planning.path import PlannedPath, PlanningStats
from wheelbase.planning.reeds_shepp import _FAMILIES
from wheelbase.planning.smoothing import smooth_path
from wheelbase.planning.world import PolygonWorld

__all__ = ["HybridAStar"]

_ESCAPE_EXITS = 3
"""Ways out of a tight end (:func:`~wheelbase.planning.escape.escape`) the lattice is tried from
before the plan fails."""
_ESCAPE_STEPS = 4
"""The escape samples its moves this many times finer than ``collision_step``."""


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
        table = {
            "turning_radius": self.turning_radius,
            "reverse": self.reverse,
            "curvatures": self.curvatures,
            "headings": self.headings,
            "length": self.primitive_length,
            "step": self.collision_step,
            "non_straight_penalty": self.non_straight_penalty,
            "reverse_penalty": self.reverse_penalty,
            "turn_in_place_cost": self.turn_in_place_cost,
            "footprint": fp,
            "checked": self._checked,
        }
        self._prims = _build_primitives(**table)
        self._prims_swapped = (
            _build_primitives(**table, swap_directions=True) if self.reverse else None
        )
        # The search works in the grid's own frame (origin (0, 0)): 4.5e9 m from the world
        # origin, absolute float64 keeps only micrometres (see ``plan``).
        self._local = grid.with_origin((0.0, 0.0))
        self._heuristic_blocked = self._local.reference_blocked(fp.inscribed_radius)

    # ------------------------------------------------------------------ setup
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
        """The admissible obstacle bound to ``goal`` (grid frame) for this planner's footprint
        and bins (``hybrid_heuristic._holonomic_heuristic``)."""
        return _holonomic_heuristic(
            self._heuristic_blocked, self.grid.resolution, self.xy_resolution, goal
        )

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
