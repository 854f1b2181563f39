"""Replanning and recovery: the job of Nav2's behaviour tree, as one controller of the engine.

A :class:`Navigator` wraps a local controller (MPPI, DWA, a path follower) for one robot. At
each call it sees only what the robot perceives (a :class:`~wheelbase.perception.LocalView`:
its costmap and its tracks of moving obstacles), never the world's truth, and:

1. *follows* the current global plan with the local controller;
2. *replans* (Hybrid A* on what the robot believes: the map and the obstacles its lidar marked)
   when a cell of the plan within ``lookahead`` ahead has become blocked, and at ``rate_hz``.
   A periodic replan is skipped when the believed obstacles are the ones of the last plan (the
   deterministic planner would give the remainder of the same plan). The old plan is kept until
   a new one is found;
3. *yields* (a robot of a fleet other than the first, whose order is its right of way) when
   the plan is blocked and no new one exists: it drives to the nearest refuge off its plan,
   far enough aside for a robot of its own width to pass along the plan, waits there until a
   plan to its goal is free of obstacles and of every track *along its whole length* (the
   robot with the right of way has gone by, not merely moved on), and goes on (at most
   ``yield_time`` in all, then the recoveries);
4. *recovers* when the plan is blocked and no new one exists: the recoveries (``wait``,
   ``back_up``, ``spin``) run in turn, each followed by a replan, at most ``max_retries``
   times; then the robot stops and its status is ``blocked`` (the engine ends it so).

What the global plan believes: the lethal cells of the costmap (the map's obstacles and the
lidar's marks), less the cells within a track's radius (+ one cell) of every track moving
faster than ``moving_speed``, plus those of every confirmed track slower than that: a walker
crossing the aisle is the local controller's business, not a reason to plan the route around
it; a box, a stopped robot or a person standing still is planned around, from as far as it is
tracked. Blocked cells are checked with the robot's own footprint (without the
planner's margin) at the plan's poses.

Decisions where Nav2 leaves a choice: the expansion budget of a replan is counted in states
(``max_expansions``), not seconds, so that a run repeats exactly on any machine; ``spin`` is
skipped for a car-like robot (it cannot turn in place) and ``back_up`` is skipped when the
costmap behind the robot is lethal; a recovery ends early when its motion would enter a lethal
cell.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, replace
from typing import Any

import numba
import numpy as np

from wheelbase._validate import nonnegative, positive
from wheelbase.errors import ConfigError
from wheelbase.geometry import wrap_angle

__all__ = [
    "ARRIVED_ASIDE",
    "NAVIGATOR_STATUSES",
    "REFUGE_ASIDE",
    "Navigator",
    "NavigatorOptions",
    "Route",
    "believed_grid",
]

NAVIGATOR_STATUSES: tuple[str, ...] = ("yielding", "recovering", "blocked")

REFUGE_ASIDE = 0.25
"""Margin [m] of a refuge beyond the sum of the yielding robot's circumscribed radius and half
the passing robot's width, from the route. The robot with the right of way sees the yielding one
as a tracked disc of about the circumscribed radius, painted one cell wider: with 0.05 m, a
robot 0.7 m square that stopped turned 45° into the bay left 6 cm to the passer's footprint,
which its belief filled (corridor_swap seed 2: both ended blocked)."""
ARRIVED_ASIDE = 0.15
"""Margin [m] (as :data:`REFUGE_ASIDE`) at which a yielding robot has arrived aside: the
refuge's, less the 0.1 m within which a robot has reached the refuge itself."""
"""The navigator's own statuses, beside the local controller's (``ok``, ``all_collide``, …)."""

YIELD_PROGRESS_RADIUS = 0.5
"""Headway [m] a yielding robot must make on its way aside within :data:`YIELD_PROGRESS_TIME`
(Nav2's progress checker: ``required_movement_radius``)."""

YIELD_PROGRESS_TIME = 10.0
"""[s] (Nav2's ``movement_time_allowance``): past it without headway the way aside is planned
again from where the robot stands."""

LETHAL = 254
"""Nav2's lethal cost: an obstacle cell."""


@dataclass(frozen=True)
class NavigatorOptions:
    """Replanning and recovery parameters (the scenario's ``replanning`` and ``recovery``).

    Parameters
    ----------
    replan : bool
        Replan at all.
    rate_hz : float
        Periodic replans per second [Hz] (0: only when blocked).
    lookahead : float
        Distance ahead along the plan [m] in which a blocked pose forces a replan.
    moving_speed : float
        Tracks faster than this [m/s] are left to the local controller.
    behaviours : tuple of str
        Recoveries in turn (``wait``, ``back_up``, ``spin``).
    max_retries : int
        Recoveries before ``blocked``.
    wait_time : float
        [s]
    back_up_distance, back_up_speed : float
        [m], [m/s]
    spin_angle, spin_rate : float
        [rad], [rad/s]
    yield_time : float
        Longest a lower-priority robot of a fleet waits aside [s] (0: it never yields).
    local_window : float or None
        Side [m] of the rolling window of the costmap the local controller sees (Nav2's local
        costmap); None: the whole costmap. Outside the window is lethal to it, so the window
        must reach past the controller's horizon.
    """

    replan: bool = True
    rate_hz: float = 1.0
    lookahead: float = 3.0
    moving_speed: float = 0.2
    behaviours: tuple[str, ...] = ("wait", "back_up", "spin")
    max_retries: int = 6
    wait_time: float = 2.0
    back_up_distance: float = 0.3
    back_up_speed: float = 0.1
    spin_angle: float = math.pi / 2
    spin_rate: float = math.radians(60.0)
    yield_time: float = 60.0
    local_window: float | None = None

    def __post_init__(self) -> None:
        nonnegative("rate_hz", self.rate_hz, "Hz")
        positive("lookahead", self.lookahead, "m")
        nonnegative("moving_speed", self.moving_speed, "m/s")
        for name in self.behaviours:
            if name not in ("wait", "back_up", "spin"):
                raise ConfigError(
                    f"recovery behaviours: unknown {name!r}; allowed: wait, back_up, spin"
                )
        if not self.behaviours:
            raise ConfigError("recovery behaviours: give at least one of wait, back_up, spin")
        for name in ("wait_time", "back_up_distance", "back_up_speed", "spin_angle", "spin_rate"):
            positive(name, getattr(self, name))
        nonnegative("yield_time", self.yield_time, "s")
        if self.local_window is not None:
            positive("local_window", self.local_window, "m")


def believed_grid(view: Any, moving_speed: float) -> Any:
    """What the global planner believes from a robot's perception: an OccupancyGrid.

    The costmap's lethal cells, less the discs of the tracks faster than ``moving_speed`` (a
    walker crossing is the local controller's business) and of the tentative tracks, plus the
    discs of the confirmed tracks slower than that: a box or a person standing still is planned
    around as soon as it is tracked, before it comes within the costmap's marking range. A
    tentative track is not yet evidence of an obstacle that stays: in ``crowd_crossing`` the
    tracker lost a walker passing 0.4 m away and started a new track on its returns (speed 0,
    tentative); its marks blocked the plan, the replan failed, and the robot stopped for a
    recovery where the walker struck it. The local controller still sees those marks in its
    costmap.

    Parameters
    ----------
    view : LocalView
        The robot's costmap (``cost`` uint8 (rows, cols), ``resolution`` [m], ``origin``) and
        tracks (``position`` (K, 2), ``velocity`` (K, 2), ``radius`` (K,), ``confirmed``).
    moving_speed : float
        Tracks faster than this [m/s] are not obstacles to the plan (module docstring).

    Returns
    -------
    OccupancyGrid
        Lethal cells as occupied, on the costmap's geometry.
    """
    from wheelbase.planning import OccupancyGrid

    costmap = view.costmap
    lethal = np.asarray(costmap.cost) >= LETHAL
    tracks = getattr(view, "tracks", None)
    if tracks is not None and len(tracks.position):
        speed = np.hypot(tracks.velocity[:, 0], tracks.velocity[:, 1])
        moving = speed > moving_speed
        confirmed = np.asarray(getattr(tracks, "confirmed", np.ones(len(speed), bool)), bool)
        standing = ~moving & confirmed
        passing = moving | ~confirmed
        if passing.any() or standing.any():
            lethal = lethal.copy()
            # the passing discs are cleared first, then the standing ones marked
            which = np.concatenate([np.flatnonzero(passing), np.flatnonzero(standing)])
            centres = np.ascontiguousarray(tracks.position[which], dtype=np.float64)
            reaches = np.asarray(tracks.radius, dtype=np.float64)[which] + costmap.resolution
            values = np.arange(len(which)) >= np.count_nonzero(passing)
            x0, y0 = costmap.origin
            _paint_discs(lethal, float(x0), float(y0), float(costmap.resolution), centres,
                         reaches, values)  # fmt: skip
    return OccupancyGrid(lethal, costmap.resolution, costmap.origin)


def _select(tracks: Any, keep: np.ndarray) -> Any:
    """The tracks ``keep`` selects (every array field of the tracks dataclass, row-wise)."""
    from dataclasses import fields

    return replace(
        tracks, **{f.name: np.asarray(getattr(tracks, f.name))[keep] for f in fields(tracks)}
    )


@numba.njit(cache=True)
def _paint_discs(cells, x0, y0, res, centres, reaches, values):
    """Set, disc after disc, the cells whose centres lie within ``reaches[k]`` [m] of
    ``centres[k]`` to ``values[k]`` (``cells`` boolean (rows, cols), lower-left corner of cell
    (0, 0) at (x0, y0) [m], cells ``res`` [m])."""
    rows, cols = cells.shape
    for k in range(centres.shape[0]):
        x, y, reach = centres[k, 0], centres[k, 1], reaches[k]
        c0, c1 = max(int((x - reach - x0) / res), 0), min(int((x + reach - x0) / res) + 1, cols)
        r0, r1 = max(int((y - reach - y0) / res), 0), min(int((y + reach - y0) / res) + 1, rows)
        for row in range(r0, r1):
            cy = y0 + (row + 0.5) * res
            for col in range(c0, c1):
                if math.hypot(x0 + (col + 0.5) * res - x, cy - y) <= reach:
                    cells[row, col] = values[k]


@dataclass(frozen=True)
class Route:
    """Where one robot goes: its first plan and the goals the plan visits.

    Attributes
    ----------
    plan : PlannedPath
        The plan made on the map before the run (its legs end at the goals).
    goals : tuple of numpy.ndarray
        The goals (x [m], y [m], θ [rad]) in order.
    priority : int
        The robot's rank in its fleet (0: the right of way; the others yield to it).
    """

    plan: Any
    goals: tuple
    priority: int = 0

    @property
    def poses(self) -> np.ndarray:
        """The first plan's poses (what a law that follows the route blindly follows)."""
        return self.plan.poses


@dataclass
class _Yield:
    """Waiting aside: since when, where, the way there, and the last headway on it (where the
    robot was when it last moved :data:`YIELD_PROGRESS_RADIUS`, and when)."""

    started: float
    refuge: np.ndarray
    path: Any
    last_try: float
    anchor: np.ndarray
    anchor_time: float
    reached: bool = False


@dataclass
class _Recovery:
    """The recovery running now: which, since when, from where."""

    name: str
    started: float
    pose: np.ndarray


class Navigator:
    """Follow, replan, recover, give up: one robot's navigation (module docstring).

    Parameters
    ----------
    local : callable
        The local controller, ``local(t, pose, path[, perception=view])`` (a path law).
    plan_route : callable
        ``plan_route(grid, start (3,), goals list of (3,)) -> PlannedPath or None``: the global
        planner on a believed grid (the scenario's Hybrid A* through every remaining goal).
    footprint : Footprint
        The robot's outline (blocked-path checks).
    options : NavigatorOptions
        Replanning and recovery parameters.
    kind : {"diff", "car"}
        A car-like robot cannot spin on the spot.
    goal_reach : float
        Distance [m] at which a goal other than the last counts as passed.
    plan_margin : float
        The global planner's margin [m] around the footprint. What the lidar marked within the
        planner's footprint of the robot is cleared before a replan: the robot stands there
        already, and Hybrid A* refuses a start inside an obstacle (``unexpected_boxes`` seed 5:
        the robot stopped 0.48 m from a box's disc, inside the margin, and every replan
        failed until it ended ``blocked`` with the way round the box open).
    """

    per_robot = True
    uses_perception = True

    def __init__(
        self,
        local: Any,
        plan_route: Callable[..., Any],
        footprint: Any,
        options: NavigatorOptions | None = None,
        *,
        kind: str = "diff",
        goal_reach: float = 0.5,
        plan_margin: float = 0.0,
    ) -> None:
        if not callable(local):
            raise ConfigError(f"local must be a control law (got {type(local).__name__})")
        self.local = local
        self.plan_route = plan_route
        self.footprint = footprint
        self.options = NavigatorOptions() if options is None else options
        self.kind = kind
        self.goal_reach = positive("goal_reach", goal_reach, "m")
        self.plan_margin = nonnegative("plan_margin", plan_margin, "m")
        self.command_names = tuple(getattr(local, "command_names", ("v", "omega")))
        self._samples: dict[float, np.ndarray] = {}  # the footprint sampled, per resolution
        self._plan_grids: tuple[Any, bytes, Any] | None = None  # see _plan_grid
        self.reset()

    # ------------------------------------------------------------------ engine protocol
    def reset(self) -> None:
        """Forget the current plan, the recoveries and the counters."""
        reset = getattr(self.local, "reset", None)
        if reset is not None:
            reset()
        self.plan: Any = None  # None: the route's first plan, at the first call
        self.goals: list[np.ndarray] = []
        self.route = np.zeros((0, 2))
        self.next_goal = 0
        self.last_replan = -math.inf
        self.last_belief: bytes | None = None
        self.recovery: _Recovery | None = None
        self.yielding: _Yield | None = None
        self.priority = 0
        self.yields = 0
        self.retries = 0
        self.replans = 0
        self.recoveries = 0
        self.plans: list[tuple[float, np.ndarray]] = []  # (time, poses) of every new plan
        self._mode = "following"

    @property
    def status(self) -> str | None:
        """``recovering`` or ``blocked`` while so, else the local controller's own status."""
        if self._mode != "following":
            return self._mode
        return getattr(self.local, "status", None)

    def summary(self) -> dict:
        """The run's account: ``replans``, ``recoveries``, ``blocked`` and every new plan
        ``plans`` = [(time [s], poses (M, 3))]."""
        return {
            "replans": self.replans,
            "recoveries": self.recoveries,
            "yields": self.yields,
            "blocked": self._mode == "blocked",
            "plans": list(self.plans),
        }

    @property
    def last_plan(self) -> Any:
        """The local controller's last plan (MPPI's rollouts for the animation)."""
        return getattr(self.local, "last_plan", None)

    def predict(self, *args: Any, **kwargs: Any) -> np.ndarray:
        """The local controller's rollouts (MPPI's :meth:`~wheelbase.control.MPPI.predict`)."""
        return self.local.predict(*args, **kwargs)

    def __call__(self, t: float, measured: Any, reference: Any, perception: Any = None):
        """The command for one robot at time ``t``.

        Parameters
        ----------
        t : float
            Time [s].
        measured : array_like, shape (3,) or (6,)
            The estimate (x, y, θ[, u, v, r]).
        reference : Route
            The robot's route: its first plan (used until the navigator makes its own) and
            its goals.
        perception : LocalView or None
            What the robot perceives; None: follow the plan blindly.
        """
        measured = np.asarray(measured, dtype=np.float64)
        pose = measured[:3]
        if self.plan is None:
            self.plan = reference.plan
            self.goals = [np.asarray(goal, dtype=np.float64).reshape(3) for goal in reference.goals]
            self.priority = int(getattr(reference, "priority", 0))
            self.route = np.asarray(reference.plan.poses)[:, :2]
        if self._mode == "blocked":
            return np.zeros(len(self.command_names))
        self._pass_goals(pose)
        if perception is not None and self.options.replan:
            grid = believed_grid(perception, self.options.moving_speed)
            if self.recovery is not None:
                command = self._recover(t, pose, grid)
                if command is not None:
                    return command
            if self.yielding is not None:
                command = self._yield(t, measured, pose, grid, perception)
                if command is not None:
                    return command
            blocked = self._blocked(pose, grid)
            due = self.options.rate_hz > 0 and t - self.last_replan >= 1.0 / self.options.rate_hz
            if blocked or due:
                if blocked or _belief(grid) != self.last_belief:
                    self._replan(t, pose, grid)
                    if blocked and self._blocked(pose, grid):
                        if self._start_yield(t, pose, grid):
                            return self._yield(t, measured, pose, grid, perception)
                        return self._start_recovery(t, pose, grid)
                self.last_replan = t
        self._mode = "following"
        return self._follow(t, measured, pose, self.plan, perception)

    def _follow(
        self, t: float, measured: np.ndarray, pose: np.ndarray, path: Any, perception: Any
    ) -> np.ndarray:
        """The local controller's command along ``path``, seeing its rolling window."""
        if not getattr(self.local, "uses_perception", False):
            return self.local(t, measured, path)
        if perception is None:
            return self.local(t, measured, path, perception=None)
        changes: dict[str, Any] = {}
        if self.options.local_window is not None:
            costmap = perception.costmap
            cells = max(1, round(self.options.local_window / costmap.resolution))
            changes["costmap"] = costmap.window(pose, cells)
        tracks = getattr(perception, "tracks", None)
        if tracks is not None and len(tracks.position):
            # what stands still is in the costmap and the plan; the tracks the local controller
            # predicts are the ones that move
            moving = (
                np.hypot(tracks.velocity[:, 0], tracks.velocity[:, 1]) > self.options.moving_speed
            )
            if not moving.all():
                changes["tracks"] = _select(tracks, moving)
        return self.local(t, measured, path, perception=replace(perception, **changes))

    # ------------------------------------------------------------------ pieces
    def _pass_goals(self, pose: np.ndarray) -> None:
        while self.next_goal < len(self.goals) - 1:
            goal = self.goals[self.next_goal]
            if math.hypot(pose[0] - goal[0], pose[1] - goal[1]) > self.goal_reach:
                break
            self.next_goal += 1

    def _ahead(self, pose: np.ndarray, plan: Any = None) -> np.ndarray:
        """The plan's poses from the nearest one to ``lookahead`` metres further."""
        poses = np.asarray((self.plan if plan is None else plan).poses)
        nearest = int(np.argmin(np.hypot(poses[:, 0] - pose[0], poses[:, 1] - pose[1])))
        steps = np.hypot(*np.diff(poses[nearest:, :2], axis=0).T)
        arc = np.concatenate([[0.0], np.cumsum(steps)])
        return poses[nearest : nearest + int(np.searchsorted(arc, self.options.lookahead)) + 1]

    def _blocked(self, pose: np.ndarray, grid: Any, plan: Any = None) -> bool:
        ahead = self._ahead(pose, plan)
        if len(ahead) == 0:
            return False
        inside = grid.contains(ahead[:, :2])
        if not inside.any():
            return False
        # on the grid the plans are made on: the marks around the robot are its own
        # neighbourhood (_replan), and a new plan may slide past them. Judged on the grid
        # as marked, a robot that stopped 9 cm from a box found every plan blocked where it
        # starts and spent its recoveries (unexpected_boxes seed 27: 14 of 63 poses ahead
        # on the box's marks, a 1.5 m gap beside it)
        hit = self._hits(self._plan_grid(grid, pose), ahead[inside])
        # the robot's own cell: an obstacle the robot already overlaps is not ahead of it
        return bool(np.any(hit[1:]) if len(hit) > 1 else False)

    def _plan_grid(self, grid: Any, pose: np.ndarray) -> Any:
        """The grid plans are made and checked on: ``grid`` with the robot's neighbourhood
        cleared (:func:`_cleared`), made once per believed grid and pose: the blocked check,
        the replan and the check of the new plan in one step share it, and with it the
        distance field a fresh grid computes on first use."""
        key = pose.tobytes()
        last = self._plan_grids
        if last is None or last[0] is not grid or last[1] != key:
            self._plan_grids = (grid, key, _cleared(grid, pose, self.footprint, self.plan_margin))
        return self._plan_grids[2]

    def _hits(self, grid: Any, poses: np.ndarray) -> np.ndarray:
        """Which poses put the footprint on an obstacle cell of ``grid`` (or off it)."""
        key = grid.resolution
        if key not in self._samples:
            self._samples[key] = _footprint_samples(self.footprint, key)
        return _footprint_hits(grid, self._samples[key], poses)

    def _replan(self, t: float, pose: np.ndarray, grid: Any) -> bool:
        # what the lidar marked where the robot stands is the robot's own neighbourhood (an
        # agent brushing past, a mark of noise): the plan may start there
        path = self.plan_route(
            self._plan_grid(grid, pose),
            pose,
            self.goals[self.next_goal :],
        )
        self.last_belief = _belief(grid)
        self.last_replan = t
        if path is None:
            return False
        self.plan = path
        self.replans += 1
        self.plans.append((t, np.asarray(path.poses)))
        return True

    # ------------------------------------------------------------------ yielding
    def _start_yield(self, t: float, pose: np.ndarray, grid: Any) -> bool:
        """Go aside for a robot of higher priority: True when a refuge and a way there exist."""
        if self.priority <= 0 or self.options.yield_time <= 0:
            return False
        cleared = self._plan_grid(grid, pose)
        # the nearest refuges first, each facing as the robot does or the other way: a refuge
        # whose only way in the planner cannot find (a turn into a tight bay) is not the end
        for refuge in self._refuges(pose, grid):
            for heading in (pose[2], wrap_angle(pose[2] + math.pi)):
                target = np.array([refuge[0], refuge[1], heading])
                path = self.plan_route(cleared, pose, [target])
                if path is not None:
                    self.yields += 1
                    self.yielding = _Yield(t, target, path, t, pose[:2].copy(), t)
                    self.plans.append((t, np.asarray(path.poses)))
                    return True
        return False

    def _yield(
        self, t: float, measured: np.ndarray, pose: np.ndarray, grid: Any, perception: Any
    ) -> np.ndarray | None:
        """The yielding command, or None once the way to the goal is free (follow it)."""
        waiting = self.yielding
        self._mode = "yielding"
        if t - waiting.started > self.options.yield_time:
            self.yielding = None
            return self._start_recovery(t, pose, grid)
        # there, or anywhere far enough aside: stop and let the others by
        near = math.hypot(*(pose[:2] - waiting.refuge[:2])) <= 0.1
        waiting.reached = (
            waiting.reached or near or bool(self._aside(pose[None, :2], ARRIVED_ASIDE)[0])
        )
        if not waiting.reached:
            # Nav2's progress checker: no headway of YIELD_PROGRESS_RADIUS within
            # YIELD_PROGRESS_TIME, and the way aside is planned again from where the robot is
            # (in corridor_swap a robot stalled at the bay's mouth, fled from the other robot
            # backwards down the corridor and stopped in its way at the far end)
            if math.dist(pose[:2], waiting.anchor) >= YIELD_PROGRESS_RADIUS:
                waiting.anchor, waiting.anchor_time = pose[:2].copy(), t
            elif t - waiting.anchor_time > YIELD_PROGRESS_TIME:
                self.yielding = None
                if not self._start_yield(t, pose, grid):
                    return self._start_recovery(t, pose, grid)
                self.yielding.started = waiting.started  # yield_time counts from the first
                waiting = self.yielding
        if waiting.reached and t - waiting.last_try >= 1.0:
            waiting.last_try = t
            goals = self.goals[self.next_goal :]
            path = self.plan_route(self._plan_grid(grid, pose), pose, goals)
            if path is not None and self._way_clear(pose, grid, path, perception):
                self.yielding = None
                self.plan = path
                self.replans += 1
                self.plans.append((t, np.asarray(path.poses)))
                self.last_replan = t
                self.last_belief = _belief(grid)
                return None
        if waiting.reached:
            return np.zeros(len(self.command_names))
        return self._follow(t, measured, pose, waiting.path, perception)

    def _way_clear(self, pose: np.ndarray, grid: Any, path: Any, perception: Any) -> bool:
        """No obstacle cell under the footprint along the whole path (but where the robot
        stands) and no track, moving or not, near it."""
        from wheelbase.polyline import distance_to_polyline

        poses = np.asarray(path.poses)
        away = np.hypot(poses[:, 0] - pose[0], poses[:, 1] - pose[1]) > self.footprint.max_radius
        inside = grid.contains(poses[:, :2]) & away
        if inside.any() and self._hits(grid, poses[inside]).any():
            return False
        tracks = getattr(perception, "tracks", None)
        if tracks is None or len(tracks.position) == 0 or len(poses) < 2:
            return True
        reach = np.asarray(tracks.radius) + self.footprint.max_radius + 0.2
        return bool(np.all(distance_to_polyline(tracks.position, poses[:, :2]) > reach))

    def _aside(self, points: np.ndarray, margin: float) -> np.ndarray:
        """Which points are far enough from the way others take (the whole route, behind the
        robot too, and the plan now) for a robot as wide as this one to pass, ``margin`` [m]
        apart (a refuge is chosen :data:`REFUGE_ASIDE` aside; a robot :data:`ARRIVED_ASIDE` aside
        has arrived there)."""
        from wheelbase.polyline import distance_to_polyline

        width = float(np.ptp(self.footprint.polygon[:, 1]))
        away = np.minimum(
            distance_to_polyline(points, self.route),
            distance_to_polyline(points, np.asarray(self.plan.poses)[:, :2]),
        )
        return away >= self.footprint.max_radius + 0.5 * width + margin

    def _refuges(self, pose: np.ndarray, grid: Any, count: int = 3) -> list[np.ndarray]:
        """Up to ``count`` points (x, y) [m] reachable from ``pose`` whose footprint stands
        aside of the plan by at least a robot's width (module docstring), nearest (by the
        way there) first, each at least a robot's diameter from the ones before it."""
        from wheelbase.planning.astar import dijkstra

        footprint = self.footprint
        free = _cleared(grid, pose, footprint).inflate(
            max(footprint.max_radius - grid.resolution, 0)
        )
        cell = free.world_to_cell(pose[:2]).astype(int)
        occupied = free.occupied.copy()
        occupied[cell[0], cell[1]] = False
        from wheelbase.planning import OccupancyGrid

        reach = dijkstra(OccupancyGrid(occupied, grid.resolution, grid.origin), cell)
        rows, cols = np.nonzero(np.isfinite(reach))
        if not len(rows):
            return []
        centres = grid.cell_to_world(np.column_stack([rows, cols]))
        ok = self._aside(centres, REFUGE_ASIDE)
        centres, way = centres[ok], reach[rows[ok], cols[ok]]
        chosen: list[np.ndarray] = []
        for index in np.argsort(way, kind="stable"):
            point = centres[index]
            if all(math.hypot(*(point - other)) >= 2 * footprint.max_radius for other in chosen):
                chosen.append(point)
                if len(chosen) == count:
                    break
        return chosen

    def _start_recovery(self, t: float, pose: np.ndarray, grid: Any) -> np.ndarray:
        if self.retries >= self.options.max_retries:
            self._mode = "blocked"
            return np.zeros(len(self.command_names))
        behaviours = self.options.behaviours
        name = behaviours[self.retries % len(behaviours)]
        self.retries += 1
        self.recoveries += 1
        self.recovery = _Recovery(name, t, pose.copy())
        command = self._recover(t, pose, grid)
        return np.zeros(len(self.command_names)) if command is None else command

    def _recover(self, t: float, pose: np.ndarray, grid: Any) -> np.ndarray | None:
        """The recovery's command, or None once it has ended (the caller then replans)."""
        recovery = self.recovery
        options = self.options
        self._mode = "recovering"
        stop = np.zeros(len(self.command_names))
        elapsed = t - recovery.started
        if recovery.name == "wait":
            if elapsed < options.wait_time:
                return stop
        elif recovery.name == "back_up":
            travelled = math.hypot(*(pose[:2] - recovery.pose[:2]))
            limit = 2.0 * options.back_up_distance / options.back_up_speed + 1.0
            behind = pose.copy()
            behind[:2] -= 0.1 * np.array([math.cos(pose[2]), math.sin(pose[2])])
            if (
                travelled < options.back_up_distance
                and elapsed < limit
                and not self._hits(grid, behind[None])[0]
            ):
                command = stop.copy()
                command[0] = -options.back_up_speed
                return command
        elif recovery.name == "spin" and self.kind == "diff":
            turned = abs(wrap_angle(pose[2] - recovery.pose[2]))
            limit = 2.0 * options.spin_angle / options.spin_rate + 1.0
            # as the back-up looks 0.1 m behind: the footprint turned on by a tenth of a
            # second's spin (a corner swung into a box the robot stopped beside:
            # unexpected_boxes seed 27)
            ahead = pose.copy()
            ahead[2] += 0.1 * options.spin_rate
            if (
                turned < min(options.spin_angle, math.pi - 0.05)
                and elapsed < limit
                and not self._hits(grid, ahead[None])[0]
            ):
                command = stop.copy()
                command[1] = options.spin_rate
                return command
        self.recovery = None
        if self._replan(t, pose, grid) and not self._blocked(pose, grid):
            return None  # back to following; the retries count on until the goal (as Nav2)
        if self._start_yield(t, pose, grid):
            return None  # the caller drives aside (a refuge the last try could not reach)
        return self._start_recovery(t, pose, grid)


def _cleared(grid: Any, pose: np.ndarray, footprint: Any, margin: float = 0.0) -> Any:
    """The grid with the cells within the footprint's reach + ``margin`` [m] (+ one cell) of
    ``pose`` free."""
    from wheelbase.planning import OccupancyGrid

    res = grid.resolution
    reach = footprint.max_radius + margin + res
    x0, y0 = grid.origin
    rows, cols = grid.shape
    c0, c1 = (
        max(int((pose[0] - reach - x0) / res), 0),
        min(int((pose[0] + reach - x0) / res) + 1, cols),
    )
    r0, r1 = (
        max(int((pose[1] - reach - y0) / res), 0),
        min(int((pose[1] + reach - y0) / res) + 1, rows),
    )
    if c0 >= c1 or r0 >= r1 or not grid.occupied[r0:r1, c0:c1].any():
        return grid
    occupied = grid.occupied.copy()
    cx = x0 + (np.arange(c0, c1) + 0.5) * res
    cy = y0 + (np.arange(r0, r1) + 0.5) * res
    near = np.hypot(cx[None, :] - pose[0], cy[:, None] - pose[1]) <= reach
    occupied[r0:r1, c0:c1] &= ~near
    return OccupancyGrid(occupied, res, grid.origin)


def _belief(grid: Any) -> bytes:
    """A compact copy of a believed grid's obstacles, to tell whether anything changed."""
    return np.packbits(grid.occupied).tobytes()


def _footprint_hits(grid: Any, samples: np.ndarray, poses: np.ndarray) -> np.ndarray:
    """Which poses put the footprint (its ``samples`` (K, 2), body frame) on an occupied cell
    or off the grid. A believed grid changes with every scan: a lookup per sample, not a
    distance transform per grid. Only the poses within reach of an occupied cell (or of the
    grid's edge) are sampled: a pose's samples lie within their largest radius r of it, so a
    cell whose centre is farther than r + one cell can hold none of them."""
    poses = np.asarray(poses, dtype=np.float64)
    hit = np.zeros(len(poses), dtype=bool)
    if not len(poses):
        return hit
    res, (x0, y0) = grid.resolution, grid.origin
    rows, cols = grid.shape
    reach = float(np.max(np.hypot(samples[:, 0], samples[:, 1]))) + res
    lo, hi = poses[:, :2].min(axis=0) - reach, poses[:, :2].max(axis=0) + reach
    c0, r0 = math.floor((lo[0] - x0) / res), math.floor((lo[1] - y0) / res)
    c1, r1 = math.floor((hi[0] - x0) / res) + 1, math.floor((hi[1] - y0) / res) + 1
    if c0 < 0 or r0 < 0 or c1 > cols or r1 > rows:  # near the edge: every pose sampled
        return _sampled_hits(grid, samples, poses)
    occupied_rows, occupied_cols = np.nonzero(grid.occupied[r0:r1, c0:c1])
    if not len(occupied_rows):
        return hit
    cx = x0 + (occupied_cols + c0 + 0.5) * res
    cy = y0 + (occupied_rows + r0 + 0.5) * res
    if len(cx) * len(poses) > 4_000_000:  # a box full of obstacles: sampling is cheaper
        return _sampled_hits(grid, samples, poses)
    near = np.min(np.hypot(poses[:, :1] - cx, poses[:, 1:2] - cy), axis=1) <= reach
    if near.any():
        hit[near] = _sampled_hits(grid, samples, poses[near])
    return hit


def _sampled_hits(grid: Any, samples: np.ndarray, poses: np.ndarray) -> np.ndarray:
    """:func:`_footprint_hits` by looking up every sample of every pose."""
    c, s = np.cos(poses[:, 2])[:, None], np.sin(poses[:, 2])[:, None]
    x = poses[:, :1] + c * samples[:, 0] - s * samples[:, 1]
    y = poses[:, 1:2] + s * samples[:, 0] + c * samples[:, 1]
    col = np.floor((x - grid.origin[0]) / grid.resolution).astype(np.int64)
    row = np.floor((y - grid.origin[1]) / grid.resolution).astype(np.int64)
    rows, cols = grid.shape
    outside = (row < 0) | (row >= rows) | (col < 0) | (col >= cols)
    hit = grid.occupied[np.clip(row, 0, rows - 1), np.clip(col, 0, cols - 1)]
    return np.any(hit | outside, axis=1)


def _footprint_samples(footprint: Any, resolution: float) -> np.ndarray:
    """Body-frame points (K, 2) [m] covering a convex footprint at half-cell spacing."""
    poly = np.asarray(footprint.polygon, dtype=np.float64)
    step = 0.5 * resolution
    lo, hi = poly.min(0), poly.max(0)
    gx = np.arange(lo[0], hi[0] + step, step)
    gy = np.arange(lo[1], hi[1] + step, step)
    grid = np.stack(np.meshgrid(np.minimum(gx, hi[0]), np.minimum(gy, hi[1])), -1).reshape(-1, 2)
    edges = np.roll(poly, -1, axis=0) - poly
    cross = edges[None, :, 0] * (grid[:, None, 1] - poly[None, :, 1]) - edges[None, :, 1] * (
        grid[:, None, 0] - poly[None, :, 0]
    )
    inside = np.all(cross >= -1e-12, axis=1) | np.all(cross <= 1e-12, axis=1)
    outline = [
        poly[k]
        + np.linspace(0, 1, max(2, int(np.ceil(np.hypot(*edges[k]) / step)) + 1))[:, None]
        * edges[k]
        for k in range(len(poly))
    ]
    return np.concatenate([grid[inside], *outline])
