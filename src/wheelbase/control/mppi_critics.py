"""Critics of the MPPI controller: their weights, and the local path window they score against.

Every critic adds a non-negative cost to each sampled rollout; :class:`~wheelbase.control.MPPI`
turns the costs into weights exp(−(S − S_min)/λ). With T the horizon steps, p_t the rollout pose
after step t, u_t the sampled command and dt the step:

==================  ==============================================================  ============
critic (weight)     cost of one rollout                                              weight unit
==================  ==============================================================  ============
``path``            mean over checked steps of d, d = distance from p_t to the       1/m
                    nearest point of the local path window (every ``path_stride``)
``path_align``      mean over the same steps of wrap(θ_t − θ_path)², θ_path the      1/rad²
                    travel heading of the robot at that nearest window point
``follow``          path length left in the window past the window point nearest     1/m
                    p_T (progress along the path, without cutting corners)
``goal``            mean over t of |p_t − goal| once the section end is near         1/m
``goal_heading``    |wrap(θ_T − θ_goal)| once the section end is near                1/rad
``obstacle``        mean over t of (r_infl − c)² for 0 < c < r_infl, c the           1/m²
                    footprint's clearance: the least over its disks of distance
                    field − disk radius − √2·cell; off within ``near_goal_distance``
                    of the goal
(lethal)            ``collision_cost`` once if any c <= 0 or a disk leaves the map    —
``prefer_forward``  Σ_t max(0, −s·v_t)·dt, s = ±1 the direction of the path section   1/m
``effort``          mean over t of Σ_j (u_tj/ū_j)², ū the command limits             —
``rate``            mean over t of Σ_j ((u_tj − u_{t−1,j})/ū_j)², u_{−1} the last     —
                    command sent
``twirl``           mean over t of |ω_t|/ω̄ (velocity commands only)                  —
==================  ==============================================================  ============

While the end of the current path section (the goal, or a cusp) is closer than
``goal_distance``, ``follow`` is off and ``goal``/``goal_heading`` on, as Nav2's critics do
(Macenski et al., Nav2 MPPI controller documentation); unlike Nav2, ``path`` and ``path_align``
stay on, so the robot does not cut straight to a cusp. ``path`` is linear in the distance (as
Nav2's path-align critic): a squared distance gives millimetre errors too little weight against
the sampling noise. ``follow`` counts progress along the path, not the straight distance to a
point ahead, which would pull the rollouts across the inside of bends. Also as in Nav2
(``max_path_occupancy_ratio``), ``path`` and ``path_align`` are off for a call when more than
7 % of the window's poses put the footprint in collision: a path that cuts through obstacles
must not pull the robot onto them (``follow`` still asks for progress). A user critic
(``extra``) is a vectorised function ``extra(poses (N, T + 1, 3), commands (N, T, 2)) -> (N,)``
added to the costs.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, fields

import numpy as np

from wheelbase._validate import finite, positive
from wheelbase.errors import ConfigError
from wheelbase.limits import MAX_PATH_POINTS

__all__ = ["MPPICritics"]


@dataclass(frozen=True)
class MPPICritics:
    """Weights and shape parameters of the MPPI critics (see the module table for units).

    Parameters
    ----------
    path, path_align, follow, goal, goal_heading, obstacle, prefer_forward, effort, rate, twirl
        Critic weights, >= 0 (0 switches a critic off).
    inflation : float
        Clearance r_infl [m] below which the obstacle critic starts to cost, > 0.
    collision_cost : float
        Cost added to a rollout that collides or leaves the map, > 0 (finite: no NaN ever).
    near_goal_distance : float
        Distance [m] to the goal (the end of the last path section) under which the
        ``obstacle`` cost is off — collisions stay lethal — so that a goal close to an obstacle
        (a parking bay) can be reached (Nav2's ``near_goal_distance``), >= 0.
    goal_distance : float
        Distance [m] to the end of the path section under which the goal critics take over.
    path_stride : int
        The path critics check every ``path_stride``-th step (Nav2's trajectory_point_step).
    extra : callable, optional
        User critic ``extra(poses (N, T+1, 3), commands (N, T, 2)) -> costs (N,)``.

    Examples
    --------
    >>> MPPICritics(obstacle=0.0).obstacle
    0.0
    """

    path: float = 20.0
    path_align: float = 2.0
    follow: float = 2.0
    goal: float = 5.0
    goal_heading: float = 3.0
    obstacle: float = 10.0
    prefer_forward: float = 5.0
    effort: float = 0.1
    rate: float = 0.1
    twirl: float = 0.0
    inflation: float = 0.4
    collision_cost: float = 1.0e6
    goal_distance: float = 0.5
    near_goal_distance: float = 1.0
    path_stride: int = 4
    extra: Callable[[np.ndarray, np.ndarray], np.ndarray] | None = None

    WEIGHTS = (
        "path",
        "path_align",
        "follow",
        "goal",
        "goal_heading",
        "obstacle",
        "prefer_forward",
        "effort",
        "rate",
        "twirl",
    )

    def __post_init__(self) -> None:
        for name in self.WEIGHTS:
            value = finite(name, getattr(self, name))
            if value < 0.0:
                raise ConfigError(f"critic weight {name} must be >= 0 (got {value:g})")
            object.__setattr__(self, name, value)
        object.__setattr__(self, "inflation", positive("inflation", self.inflation, "m"))
        object.__setattr__(self, "collision_cost", positive("collision_cost", self.collision_cost))
        object.__setattr__(
            self, "goal_distance", positive("goal_distance", self.goal_distance, "m")
        )
        near = finite("near_goal_distance", self.near_goal_distance)
        if near < 0.0:
            raise ConfigError(f"near_goal_distance must be >= 0 m (got {near:g})")
        object.__setattr__(self, "near_goal_distance", near)
        stride = self.path_stride
        if isinstance(stride, bool) or not isinstance(stride, (int, np.integer)) or stride < 1:
            raise ConfigError(f"path_stride must be an integer >= 1 (got {stride!r})")
        if self.extra is not None and not callable(self.extra):
            raise ConfigError(f"extra critic must be callable (got {type(self.extra).__name__})")

    @classmethod
    def from_mapping(cls, values: dict | MPPICritics | None) -> MPPICritics:
        """Critics from a mapping of plain keyword weights (a scenario file), or as given.

        Parameters
        ----------
        values : dict, MPPICritics or None
            Weights by name; ``None`` gives the defaults.

        Returns
        -------
        MPPICritics
        """
        if values is None:
            return cls()
        if isinstance(values, cls):
            return values
        if not isinstance(values, dict):
            raise ConfigError(f"critics must be a mapping of weights (got {type(values).__name__})")
        known = {f.name for f in fields(cls)}
        unknown = sorted(set(values) - known)
        if unknown:
            raise ConfigError(f"unknown critic {unknown[0]!r}; allowed: {', '.join(sorted(known))}")
        return cls(**values)

    def vector(self) -> np.ndarray:
        """The weights in the order of :attr:`WEIGHTS` plus (inflation, collision_cost), float64."""
        values = [getattr(self, name) for name in self.WEIGHTS]
        return np.array([*values, self.inflation, self.collision_cost], dtype=np.float64)


def _wrap(angle: np.ndarray) -> np.ndarray:
    return np.arctan2(np.sin(angle), np.cos(angle))


class PathTables:
    """A reference path densified every ``spacing`` metres, with its sections (private helper).

    Attributes: ``xy`` (P, 2), ``heading`` (P,) robot heading when travelling the path there
    (the chord's, or ``end_heading`` at the last point),
    ``direction`` (P,), ``arc`` (P,), ``section`` (P,) index of the direction run of each point.
    """

    def __init__(
        self,
        points: np.ndarray,
        directions: np.ndarray,
        spacing: float,
        end_heading: float | None = None,
    ) -> None:
        xy, heading, direction, arc, section = [points[:1]], [], [], [0.0], []
        seg = np.diff(points, axis=0)
        length = np.hypot(seg[:, 0], seg[:, 1])
        needed = float(np.sum(np.maximum(1.0, np.ceil(length / spacing - 1e-9))))
        if not needed <= MAX_PATH_POINTS:
            raise ConfigError(
                f"the reference path ({length.sum():.3g} m) at path_spacing = {spacing:g} m "
                f"needs {needed:.3g} points: more than {MAX_PATH_POINTS:.0e} "
                "(wheelbase.limits.MAX_PATH_POINTS); use a larger path_spacing"
            )
        seg_heading = np.arctan2(seg[:, 1], seg[:, 0])
        run = 0
        for i in range(seg.shape[0]):
            if i > 0 and directions[i] != directions[i - 1]:
                run += 1
            count = max(1, math.ceil(length[i] / spacing - 1e-9))
            frac = np.arange(1, count + 1) / count
            xy.append(points[i] + frac[:, None] * seg[i])
            robot_heading = seg_heading[i] if directions[i] > 0 else seg_heading[i] + math.pi
            heading.extend([robot_heading] * count)
            direction.extend([directions[i]] * count)
            arc.extend(list(arc[-1] + frac * length[i]))
            section.extend([run] * count)
        # The first point takes the values of the first segment.
        self.xy = np.concatenate(xy)
        self.heading = _wrap(np.array([heading[0], *heading]))
        self.direction = np.array([direction[0], *direction], dtype=np.float64)
        self.arc = np.array(arc)
        self.section = np.array([section[0], *section], dtype=np.int64)
        if end_heading is not None:
            # The goal's heading (a planned path knows it): the last chord's direction differs
            # from it by half the turn of the last segment.
            self.heading[-1] = _wrap(np.array([end_heading]))[0]
        # A cusp point belongs to the section that ends there.
        self.n_sections = run + 1
        self.section_end = np.array(
            [np.flatnonzero(self.section == k)[-1] for k in range(self.n_sections)]
        )
