"""Critics of the MPPI controller: their weights, and the local path window they score against.

Every critic adds a non-negative cost to each sampled rollout; :class:`~wheelbase.control.MPPI`
turns the costs into weights exp(−(S − S_min)/λ). With T the horizon steps, p_t the rollout pose
after step t, u_t the sampled command and dt the step:

====================  ==============================================================  ===========
critic (weight)       cost of one rollout                                             weight unit
====================  ==============================================================  ===========
``path``              mean over checked steps of d, d = distance from p_t to the      1/m
                      nearest point of the local path window (every ``path_stride``)
``path_align``        mean over the same steps of wrap(θ_t − θ_path)², θ_path the     1/rad²
                      travel heading of the robot at that nearest window point
``follow``            path length left in the window past the window point nearest    1/m
                      p_T (progress along the path, without cutting corners)
``goal``              mean over t of |p_t − goal| once the section end is near        1/m
``goal_heading``      |wrap(θ_T − θ_goal)| once the section end is near               1/rad
``obstacle``          mean over t of (r_infl − c)² for 0 < c < r_infl, c the          1/m²
                      footprint's clearance: the least over its disks of distance
                      field − disk radius − √2·cell; off within
                      ``near_goal_distance`` of the goal
(lethal)              ``collision_cost`` once if any c <= 0 or a disk leaves the      —
                      map, or the costmap or a track is hit (below)
``costmap``           mean over t of c_t/252, c_t the costmap cost under the robot    —
                      (Nav2's CostCritic; off within ``near_goal_distance``)
``dynamic_obstacle``  Σ over t (and the held final pose) of Σ_tracks g² / T, g the      1/m²
                      scaled gap (obstacle_critics) to the track predicted at step t
``prefer_forward``    Σ_t max(0, −s·v_t)·dt, s = ±1 the direction of the path         1/m
                      section
``effort``            mean over t of Σ_j (u_tj/ū_j)², ū the command limits            —
``rate``              mean over t of Σ_j ((u_tj − u_{t−1,j})/ū_j)², u_{−1} the last   —
                      command sent
``twirl``             mean over t of |ω_t|/ω̄ (velocity commands only)                 —
====================  ==============================================================  ===========

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

The ``costmap`` and ``dynamic_obstacle`` critics score what the robot perceives (a
``perception=`` view: a costmap and tracks of moving obstacles); they are defined, with the
collision rules and the tracks' prediction, in :mod:`wheelbase.control.obstacle_critics`, which
DWA shares.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, fields
from typing import Any

import numpy as np

from wheelbase._validate import finite, nonnegative, positive
from wheelbase.control.obstacle_critics import ACCELERATION_NOISE, HOLD_TIME
from wheelbase.errors import ConfigError
from wheelbase.limits import MAX_SAMPLE_STEPS

__all__ = ["MPPICritics", "critics_from_mapping", "split_critic_gains"]


@dataclass(frozen=True)
class MPPICritics:
    """Weights and shape parameters of the MPPI critics (see the module table for units).

    Parameters
    ----------
    path, path_align, follow, goal, goal_heading, obstacle, prefer_forward, effort, rate, twirl
        Critic weights, >= 0 (0 switches a critic off).
    costmap : float
        Weight of the costmap critic, >= 0 (default 3.81: Nav2's ``CostCritic.cost_weight``,
        whose cost is also the mean over the trajectory of the cell cost / 254).
    dynamic_obstacle : float
        Weight [1/m²] of the dynamic-obstacle critic, >= 0 (default 200, set on a disc coming
        head-on at 0.5 m/s, ``tests/test_mppi_perception.py``: with the tracks' soft cost
        weighted by their certainty, 100 passed it 2-5 cm off, 200 0.21-0.30 m; a sure track
        within r_dyn all along then costs 50, what 2.5 m off the path for the whole horizon
        does).
    inflation : float
        Clearance r_infl [m] below which the obstacle critic starts to cost, > 0.
    dynamic_inflation : float
        r_dyn [m], > 0: distance past a track's contact and its uncertainty κσ within which the
        dynamic-obstacle critic costs (default 0.5 m: the social zone the crowd-navigation
        literature scores as discomfort is 0.2 m; more leaves room for the prediction's error).
    dynamic_sigma_scale : float
        κ, >= 0: how many σ of the prediction the dynamic-obstacle critic keeps clear.
    dynamic_acceleration_noise : float
        q [m²/s³], >= 0: the tracks' white-acceleration prediction noise
        (:data:`~wheelbase.control.obstacle_critics.ACCELERATION_NOISE`).
    dynamic_hold_time : float
        Time [s], >= 0, the rollout's final pose is held against the tracks, soft cost only
        (:data:`~wheelbase.control.obstacle_critics.HOLD_TIME` = 5 s: a rollout should not end
        in the way of a walker; 0 switches the check off).
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
    costmap: float = 3.81
    dynamic_obstacle: float = 200.0
    inflation: float = 0.4
    collision_cost: float = 1.0e6
    dynamic_inflation: float = 0.5
    dynamic_sigma_scale: float = 1.0
    dynamic_acceleration_noise: float = ACCELERATION_NOISE
    dynamic_hold_time: float = HOLD_TIME
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
        "costmap",
        "dynamic_obstacle",
    )
    VECTOR = (*WEIGHTS[:10], "inflation", "collision_cost", "costmap", "dynamic_obstacle",
              "dynamic_inflation")  # fmt: skip

    def __post_init__(self) -> None:
        for name in self.WEIGHTS:
            value = finite(name, getattr(self, name))
            if value < 0.0:
                raise ConfigError(f"critic weight {name} must be >= 0 (got {value:g})")
            object.__setattr__(self, name, value)
        object.__setattr__(self, "inflation", positive("inflation", self.inflation, "m"))
        object.__setattr__(self, "collision_cost", positive("collision_cost", self.collision_cost))
        object.__setattr__(
            self, "dynamic_inflation", positive("dynamic_inflation", self.dynamic_inflation, "m")
        )
        object.__setattr__(
            self,
            "dynamic_sigma_scale",
            nonnegative("dynamic_sigma_scale", self.dynamic_sigma_scale),
        )
        object.__setattr__(
            self,
            "dynamic_acceleration_noise",
            nonnegative("dynamic_acceleration_noise", self.dynamic_acceleration_noise, "m²/s³"),
        )
        object.__setattr__(
            self, "dynamic_hold_time", nonnegative("dynamic_hold_time", self.dynamic_hold_time, "s")
        )
        object.__setattr__(
            self, "goal_distance", positive("goal_distance", self.goal_distance, "m")
        )
        near = finite("near_goal_distance", self.near_goal_distance)
        if near < 0.0:
            raise ConfigError(f"near_goal_distance must be >= 0 m (got {near:g})")
        object.__setattr__(self, "near_goal_distance", near)
        stride = self.path_stride
        if (
            isinstance(stride, bool)
            or not isinstance(stride, (int, np.integer))
            or not 1 <= stride <= MAX_SAMPLE_STEPS
        ):  # a stride past the horizon is checked once: no need for more than the work bound
            raise ConfigError(
                f"path_stride must be an integer in [1, {MAX_SAMPLE_STEPS}] (got {stride!r})"
            )
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
        return critics_from_mapping(cls, values, "critic")

    def vector(self) -> np.ndarray:
        """The weights and shape parameters the kernels read, in the order of :attr:`VECTOR`,
        float64."""
        return np.array([getattr(self, name) for name in self.VECTOR], dtype=np.float64)


def critics_from_mapping(cls: type, values: Any, label: str) -> Any:
    """Critics of dataclass ``cls`` from a mapping of plain keyword values (a scenario file), as
    given when already one, the defaults for ``None``.

    Parameters
    ----------
    cls : type
        The critics' dataclass (:class:`MPPICritics`, :class:`~wheelbase.control.DWACritics`).
    values : dict, cls or None
        Values by name.
    label : str
        What an unknown name is called in the error (``"critic"``, ``"DWA critic"``).

    Returns
    -------
    cls
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
        raise ConfigError(f"unknown {label} {unknown[0]!r}; allowed: {', '.join(sorted(known))}")
    return cls(**values)


def split_critic_gains(gains: dict, cls: type) -> tuple[dict, dict]:
    """Split a scenario's flat gains into the critics' (by field name of ``cls``, merged over a
    ``critics={...}`` entry) and the others.

    Parameters
    ----------
    gains : dict
        The gains as given.
    cls : type
        The critics' dataclass.

    Returns
    -------
    critics, options : dict
    """
    options = dict(gains)
    names = {f.name for f in fields(cls)}
    critics = options.pop("critics", None) or {}
    if not isinstance(critics, dict):
        raise ConfigError(f"critics must be a mapping of weights (got {critics!r})")
    critics = dict(critics)
    for name in list(options):
        if name in names:
            critics[name] = options.pop(name)
    return critics, options
