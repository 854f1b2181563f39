"""The dynamic window approach (DWA) for (v, ω) robots, in the form of Nav2's DWB controller.

Fox, Burgard & Thrun, "The dynamic window approach to collision avoidance", IEEE Robotics &
Automation Magazine 4(1), 1997: at each call the robot may reach, within one control period Δ,
the velocities of the *dynamic window*

    V_d = [v_c − a_dec·Δ, v_c + a_acc·Δ] × [ω_c − α·Δ, ω_c + α·Δ],

cut to the limits [v_min, v_max] × [−ω_max, ω_max] (v_c, ω_c the current velocity: the last
command, which a kinematic plant follows; Δ the time since the last call, or
``control_period``). ``v_samples`` × ``w_samples`` velocities of V_d (a grid that includes 0
where V_d does) are each held for ``sim_time`` (a circular arc,
:mod:`wheelbase.control.dwa_kernels`) and scored by critics, as Nav2's DWB splits the method
into a trajectory generator and critics (nav2_dwb_controller; weights from Nav2's
``nav2_params.yaml``, converted from DWB's cell units at its 0.05 m resolution to metres):

====================  ============================================================  ========
critic (weight)       score of one trajectory                                       default
====================  ============================================================  ========
``path_dist``         distance [m] from its end to the path window (DWB PathDist,   640 /m
                      32 per cell)
``goal_dist``         distance [m] from its end to the local goal: the window's     480 /m
                      last point, ``lookahead`` ahead (DWB GoalDist, 24 per cell)
``path_align``        ``path_dist`` of the point ``forward_point_distance`` ahead   640 /m
                      of its end (DWB PathAlign)
``goal_align``        ``goal_dist`` of that point (DWB GoalAlign)                   480 /m
``costmap``           mean over its steps of the costmap cost / 252 (DWB            3000
                      BaseObstacle; see below)
``obstacle``          mean over its steps of (r_infl − c)², c the footprint's       320 /m²
                      clearance on the static map, as MPPI's (half ``path_dist``,
                      MPPI's balance)
``dynamic_obstacle``  Σ over its steps (and its held end) of Σ_tracks g², /         1e4 /m²
                      steps, g the scaled gap, against the tracks predicted at
                      each step (shared with MPPI:
                      :mod:`wheelbase.control.obstacle_critics`)
``rotate_to_goal``    within the goal's position tolerance: |θ_end − θ_goal| [rad]  32 /rad
                      (+ ``slowing_factor``·v² while still slowing down)
====================  ============================================================  ========

The velocities of one period's window, held, are ``trajectory_generator="limited_accel"``
(DWB's LimitedAccelGenerator, Fox et al.'s method, the default). ``"standard"`` is DWB's
StandardTrajectoryGenerator, Nav2's default: the window spans what the robot can reach over
the whole ``sim_time``,
[v_c − a_dec·T, v_c + a_acc·T] × [ω_c − α·T, ω_c + α·T], and each sample is a target the
trajectory ramps to at the acceleration limits
(:func:`~wheelbase.control.dwa_kernels.ramp_profile`): from a stop it sees where it could be
at full speed, not only the crawl a single period allows. DWB sends the target and leaves the
ramp to the base; here the command is the ramp's velocity after Δ, so the robot keeps the
limits the trajectory was scored with.

Two defaults were set on the cases of ``tests/test_dwa.py``, not taken from Nav2: ``costmap``
(DWB's BaseObstacle scale, 0.02 per cost unit summed over the 9 poses of its default
trajectory, is 45 here: DWA then grazed a 0.6 m box on the path, 0 m; 1000: 0 m; 3000: 6.5 cm
off) and ``dynamic_obstacle`` (a disc coming head-on at 0.5 m/s: 3000 passed it 2 cm off,
5000 0.42 m; since the tracks' soft cost is weighted by their certainty, 5000 passed it 9 cm
off, 10000 0.54 m).
Collisions (the static map's footprint disks, the costmap's lethal and inscribed cells,
contact with a predicted track) make a trajectory inadmissible, as Fox et al.'s admissible
velocities; ``path_align`` and ``goal_align`` are off within ``forward_point_distance`` of the
section's end (DWB switches them off near the goal).

Rules of DWB kept as legality (a trajectory that breaks one is not chosen while another is
legal): **oscillation** (DWB OscillationCritic): after the sign of v or ω flips, the old sign is
barred until the robot has moved ``oscillation_reset_distance`` or turned
``oscillation_reset_angle`` since; **rotate to goal**: within the goal's position tolerance the
robot first slows down (|v| below the current |v|), then, once it can stop within a period,
turns in place (v = 0) to the goal heading. When no legal trajectory is free of collision the
legality rules are dropped; when none is free of collision at all the command is a stop
(0, 0) and :attr:`DWAPlan.status` is ``"all_collide"``: it never drives on blindly. With a
``perception=`` view a stop may be struck sooner than some trajectory would be (a walker that
does not avoid the robot): that trajectory is then driven, with the status ``"evading"``, by
MPPI's rule (:func:`~wheelbase.control.obstacle_critics.evasion_choice`). It pays with the
standard generator, whose ramps reach speeds that one period's window does not hold
(``crowd_crossing``, 20 walkers, seeds 0–11: 9 of 12 arrived, 8 without the evasion, 6 with
``limited_accel``, whose evasion from a stop turned on the spot: 5). Within both goal
tolerances the command is a stop and the status ``"arrived"``.

Backends: ``numba`` (the default, one parallel compiled loop over the samples) and ``numpy``
(the reference it is held to).
"""

from __future__ import annotations

import inspect
import math
from dataclasses import dataclass, fields
from dataclasses import field as dataclass_field
from typing import Any, ClassVar

import numpy as np
from numpy.typing import ArrayLike

from wheelbase._validate import (
    as_float_array,
    check_choice,
    finite,
    flag,
    integer,
    nonnegative,
    positive,
)
from wheelbase.control.base import VELOCITY_COMMAND
from wheelbase.control.dwa_kernels import (
    SCORES,
    arc_poses,
    dwa_kernel,
    dwa_scores_numpy,
    goal_distance_field,
    profile_poses,
    ramp_profile,
)
from wheelbase.control.footprint_field import FootprintField, footprint_disks
from wheelbase.control.local_path import PathWindow
from wheelbase.control.mppi_bounds import KIND_VELOCITY, model_kind
from wheelbase.control.mppi_critics import critics_from_mapping, split_critic_gains
from wheelbase.control.mppi_numba import run_kernel
from wheelbase.control.obstacle_critics import (
    ACCELERATION_NOISE,
    HOLD_TIME,
    PerceptionInputs,
    evasion_choice,
    path_blocked,
    struck_step,
)
from wheelbase.errors import ConfigError, InputError
from wheelbase.geometry import wrap_angle
from wheelbase.limits import MAX_SAMPLE_STEPS

__all__ = ["DWA", "DWA_BACKENDS", "DWACritics", "DWAPlan"]

DWA_BACKENDS: tuple[str, ...] = ("numba", "numpy")
TRAJECTORY_GENERATORS: tuple[str, ...] = ("limited_accel", "standard")
STATUSES: tuple[str, ...] = ("ok", "all_collide", "evading", "arrived")


@dataclass(frozen=True)
class DWACritics:
    """Weights and shape parameters of the DWA critics (see the module table).

    Parameters
    ----------
    path_dist, goal_dist, path_align, goal_align, costmap, obstacle, dynamic_obstacle
        Critic weights, >= 0 (0 switches a critic off); units in the module table.
    rotate_to_goal : float
        Weight [1/rad] of the heading error once within the goal's position tolerance, >= 0.
    slowing_factor : float
        DWB's ``slowing_factor``, >= 0: weight [s²/m²] of v² (times ``rotate_to_goal``) while
        the robot slows down within the goal's tolerance.
    forward_point_distance : float
        Distance [m] ahead of a trajectory's end of the point the align critics score, >= 0
        (Nav2's ``nav2_params.yaml``: 0.1 m).
    inflation : float
        r_infl [m] of the static map's obstacle critic, > 0.
    dynamic_inflation : float
        r_dyn [m] of the dynamic-obstacle critic, > 0.
    dynamic_sigma_scale : float
        κ, >= 0.
    dynamic_acceleration_noise : float
        q [m²/s³], >= 0.
    dynamic_hold_time : float
        Time [s] the trajectory's final pose is held against the tracks, >= 0 (as MPPI's).
    oscillation : bool
        Apply DWB's oscillation rule.

    Examples
    --------
    >>> DWACritics(costmap=0.0).costmap
    0.0
    """

    path_dist: float = 640.0
    goal_dist: float = 480.0
    path_align: float = 640.0
    goal_align: float = 480.0
    costmap: float = 3000.0
    obstacle: float = 320.0
    dynamic_obstacle: float = 10000.0
    rotate_to_goal: float = 32.0
    slowing_factor: float = 5.0
    forward_point_distance: float = 0.1
    inflation: float = 0.4
    dynamic_inflation: float = 0.5
    dynamic_sigma_scale: float = 1.0
    dynamic_acceleration_noise: float = ACCELERATION_NOISE
    dynamic_hold_time: float = HOLD_TIME
    oscillation: bool = True

    WEIGHTS: ClassVar[tuple[str, ...]] = SCORES

    def __post_init__(self) -> None:
        shapes = ("slowing_factor", "forward_point_distance", "dynamic_sigma_scale",
                  "dynamic_acceleration_noise", "dynamic_hold_time")  # fmt: skip
        for name in (*self.WEIGHTS, *shapes):
            object.__setattr__(self, name, nonnegative(f"DWA critic {name}", getattr(self, name)))
        for name in ("inflation", "dynamic_inflation"):
            object.__setattr__(self, name, positive(name, getattr(self, name), "m"))
        object.__setattr__(self, "oscillation", flag("oscillation", self.oscillation))

    @classmethod
    def from_mapping(cls, values: dict | DWACritics | None) -> DWACritics:
        """Critics from a mapping of plain keyword values (a scenario file), or as given.

        Parameters
        ----------
        values : dict, DWACritics or None
            Values by name; ``None`` gives the defaults.

        Returns
        -------
        DWACritics
        """
        return critics_from_mapping(cls, values, "DWA critic")

    def vector(self) -> np.ndarray:
        """The weights of :data:`~wheelbase.control.dwa_kernels.SCORES`, in that order."""
        return np.array([getattr(self, name) for name in self.WEIGHTS], dtype=np.float64)


@dataclass(frozen=True)
class DWAPlan:
    """One DWA iteration.

    Attributes
    ----------
    command : numpy.ndarray, shape (2,)
        The command sent (v [m/s], ω [rad/s]).
    samples : numpy.ndarray, shape (S, 2)
        The sampled velocities of the dynamic window.
    costs : numpy.ndarray, shape (S,)
        Weighted cost of each trajectory.
    scores : numpy.ndarray, shape (S, 8)
        Raw critic values (:data:`~wheelbase.control.dwa_kernels.SCORES`).
    collided : numpy.ndarray of bool, shape (S,)
        Trajectories that collide.
    legal : numpy.ndarray of bool, shape (S,)
        Trajectories the choice was made among.
    status : str
        ``"ok"``, ``"all_collide"``, ``"evading"`` or ``"arrived"``.
    pose : numpy.ndarray, shape (3,)
        The measured pose the trajectories start from.
    start_velocity : numpy.ndarray, shape (2,)
        The current velocity (v_c, ω_c) the trajectories started from.
    rates : numpy.ndarray, shape (3,)
        (a_up, a_down, α) the standard generator's ramps used.
    """

    command: np.ndarray
    samples: np.ndarray
    costs: np.ndarray
    scores: np.ndarray
    collided: np.ndarray
    legal: np.ndarray
    status: str
    pose: np.ndarray
    start_velocity: np.ndarray = dataclass_field(default_factory=lambda: np.zeros(2))
    rates: np.ndarray = dataclass_field(default_factory=lambda: np.zeros(3))


class DWA:
    """Dynamic window approach for one (v, ω) robot (see the module docstring).

    Parameters
    ----------
    model : KinematicModel
        Unicycle or DiffDrive.
    max_speed : float
        v_max [m/s], > 0.
    min_speed : float
        v_min [m/s], in [−max_speed, 0] (Nav2's ``min_vel_x`` 0: forward only).
    max_yaw_rate : float
        ω_max [rad/s], > 0.
    max_acceleration, max_deceleration : float
        a_acc, a_dec [m/s²], > 0 (Nav2: 2.5 and 2.5).
    max_yaw_acceleration : float
        α [rad/s²], > 0 (Nav2: 3.2).
    sim_time : float
        Time [s] each velocity is held, > 0 (Nav2: 1.7 s).
    sim_dt : float
        Step [s] of the simulated trajectories, > 0 (0.05 s: 2.5 cm at 0.5 m/s).
    v_samples, w_samples : int
        Samples of v and ω across the dynamic window, >= 1 (Nav2: 20 and 20).
    critics : DWACritics, dict or None
        Critic weights (``None``: defaults).
    grid : OccupancyGrid, optional
        Static map for collisions and the obstacle critic.
    footprint : Footprint, optional
        Robot outline (default: a point).
    goal_tolerance : (float, float)
        (position [m], heading [rad]): within the position tolerance of the path's end the
        robot rotates to the goal; within both it stops, ``"arrived"``.
    control_period : float
        Δ [s] of the dynamic window at the first call or after a gap of more than 1 s (Nav2's
        20 Hz: 0.05 s); otherwise the time between calls.
    lookahead : float, optional
        Length [m] of path ahead in the window; its last point is the local goal (default
        2·max_speed·sim_time: beyond the reach of every trajectory, so the fastest progress
        along the path scores best).
    path_spacing : float
        Spacing [m] of the densified path, > 0.
    cusp_tolerance : float
        Distance [m] to a cusp at which the next path section becomes active, > 0.
    oscillation_reset_distance : float
        Distance [m] after which an oscillation flag is reset (DWB: 0.05 m), > 0.
    oscillation_reset_angle : float
        Turn [rad] after which an oscillation flag is reset (DWB: 0.2 rad), > 0.
    trajectory_generator : str
        ``"limited_accel"`` (velocities of one period's window, held) or ``"standard"``
        (targets of the whole ``sim_time``'s window, ramped to): see the module docstring.
    backend : str
        One of :data:`DWA_BACKENDS`.

    Examples
    --------
    >>> from wheelbase.models import Unicycle
    >>> dwa = DWA(Unicycle(), max_speed=0.5)
    >>> dwa(0.0, [0.0, 0.0, 0.0], [[0.0, 0.0], [2.0, 0.0]]).shape
    (2,)
    """

    command_names: ClassVar[tuple[str, ...]] = VELOCITY_COMMAND
    per_robot: ClassVar[bool] = True  # current velocity, oscillation flags: one copy each
    uses_perception: ClassVar[bool] = True  # the engine passes ``perception=`` (a LocalView)

    def __init__(
        self,
        model: Any,
        *,
        max_speed: float = 0.5,
        min_speed: float = 0.0,
        max_yaw_rate: float = 1.5,
        max_acceleration: float = 2.5,
        max_deceleration: float = 2.5,
        max_yaw_acceleration: float = 3.2,
        sim_time: float = 1.7,
        sim_dt: float = 0.05,
        v_samples: int = 20,
        w_samples: int = 20,
        critics: DWACritics | dict | None = None,
        grid: Any = None,
        footprint: Any = None,
        goal_tolerance: tuple[float, float] = (0.05, 0.25),
        control_period: float = 0.05,
        lookahead: float | None = None,
        path_spacing: float = 0.05,
        cusp_tolerance: float = 0.05,
        oscillation_reset_distance: float = 0.05,
        oscillation_reset_angle: float = 0.2,
        trajectory_generator: str = "limited_accel",
        backend: str = "numba",
    ) -> None:
        kind, _ = model_kind(model)
        if kind != KIND_VELOCITY:
            raise ConfigError(
                "DWA drives (v, ω) robots: Unicycle or DiffDrive (got "
                f"{type(model).__name__}); use MPPI for steered and holonomic bases"
            )
        self.model = model
        self.max_speed = positive("max_speed", max_speed, "m/s")
        self.min_speed = finite("min_speed", min_speed, "m/s")
        if not -self.max_speed <= self.min_speed <= 0.0:
            raise ConfigError(
                f"min_speed must be in [-max_speed, 0] = [{-self.max_speed:g}, 0] m/s (the "
                f"robot must be able to stop; got {self.min_speed:g})"
            )
        self.max_yaw_rate = positive("max_yaw_rate", max_yaw_rate, "rad/s")
        self.max_acceleration = positive("max_acceleration", max_acceleration, "m/s²")
        self.max_deceleration = positive("max_deceleration", max_deceleration, "m/s²")
        self.max_yaw_acceleration = positive("max_yaw_acceleration", max_yaw_acceleration,
                                             "rad/s²")  # fmt: skip
        self.sim_time = positive("sim_time", sim_time, "s")
        self.sim_dt = positive("sim_dt", sim_dt, "s")
        self.v_samples = integer("v_samples", v_samples, minimum=1)
        self.w_samples = integer("w_samples", w_samples, minimum=1)
        if self.sim_dt > self.sim_time:  # no step would fit the horizon
            raise ConfigError(
                f"sim_dt must be <= sim_time ({self.sim_time:g} s), got {self.sim_dt:g} s"
            )
        self.steps = math.ceil(min(self.sim_time / self.sim_dt, 1e12) - 1e-9)
        work = self.v_samples * self.w_samples * self.steps
        if work > MAX_SAMPLE_STEPS:
            raise ConfigError(
                f"v_samples × w_samples × sim_time/sim_dt = {work:.3g} trajectory steps: more "
                f"than {MAX_SAMPLE_STEPS:.0e}; use fewer samples or a larger sim_dt"
            )
        self.critics = DWACritics.from_mapping(critics)
        if np.ndim(goal_tolerance) != 1 or np.size(goal_tolerance) != 2:
            raise ConfigError(
                f"goal_tolerance must be (position [m], heading [rad]) (got {goal_tolerance!r})"
            )
        self.goal_tolerance = (
            positive("goal position tolerance", goal_tolerance[0], "m"),
            positive("goal heading tolerance", goal_tolerance[1], "rad"),
        )
        self.control_period = positive("control_period", control_period, "s")
        reach = 2.0 * self.max_speed * self.sim_time
        self.lookahead = reach if lookahead is None else positive("lookahead", lookahead, "m")
        self.path_spacing = positive("path_spacing", path_spacing, "m")
        self.cusp_tolerance = positive("cusp_tolerance", cusp_tolerance, "m")
        self.oscillation_reset_distance = positive(
            "oscillation_reset_distance", oscillation_reset_distance, "m"
        )
        self.oscillation_reset_angle = positive(
            "oscillation_reset_angle", oscillation_reset_angle, "rad"
        )
        self.trajectory_generator = check_choice(
            "trajectory_generator", trajectory_generator, TRAJECTORY_GENERATORS
        )
        self.backend = check_choice("backend", backend, DWA_BACKENDS)
        self.grid, self.footprint = grid, footprint
        self._field = FootprintField(grid, footprint)
        c = self.critics
        self._perception = PerceptionInputs(
            footprint, footprint_disks(footprint, outline=False), c.dynamic_inflation,
            c.dynamic_sigma_scale, c.dynamic_acceleration_noise, c.dynamic_hold_time,
        )  # fmt: skip
        self._step_times = self.sim_dt * np.arange(1, self.steps + 1)
        # 0.5 m: within it a crossed cusp line switches section (MPPI's goal_distance)
        self._path = PathWindow(self.path_spacing, self.lookahead, 0.5, self.cusp_tolerance)
        self.reset()

    @classmethod
    def from_gains(
        cls, model: Any, *, grid: Any = None, footprint: Any = None, **gains: Any
    ) -> DWA:
        """A DWA from plain keyword gains, as a scenario file gives them.

        Parameters
        ----------
        model : KinematicModel
            The robot model (Unicycle or DiffDrive).
        grid : OccupancyGrid, optional
            Static map.
        footprint : Footprint, optional
            Robot outline.
        **gains
            Any keyword of :class:`DWA` (``max_speed``, ``sim_time``, ``v_samples``, ...) and
            any field of :class:`DWACritics` by name (``path_dist=320``), or ``critics={...}``.

        Returns
        -------
        DWA

        Examples
        --------
        >>> from wheelbase.models import Unicycle
        >>> DWA.from_gains(Unicycle(), sim_time=2.0, costmap=90.0).critics.costmap
        90.0
        """
        critics, options = split_critic_gains(gains, DWACritics)
        critic_names = {f.name for f in fields(DWACritics)}
        allowed = set(inspect.signature(cls).parameters) - {"model", "critics", "grid",
                                                             "footprint"}  # fmt: skip
        unknown = sorted(set(options) - allowed)
        if unknown:
            names = allowed | critic_names
            raise ConfigError(
                f"unknown DWA gain {unknown[0]!r}; allowed: {', '.join(sorted(names))}"
            )
        return cls(model, critics=critics, grid=grid, footprint=footprint, **options)

    def reset(self) -> None:
        """Forget the current velocity, the path progress, the oscillation flags and the goal
        latch."""
        self._velocity = np.zeros(2)
        self._t_last: float | None = None
        self._path.reset()
        self._sign = np.zeros(2)  # last sign of (v, ω) sent
        self._only = np.zeros(2)  # +1 / −1: only that sign allowed (an oscillation flag)
        self._flag_pose: np.ndarray | None = None
        self._near_goal = False  # latched once within the goal's position tolerance
        self.status = "ok"
        self.last_plan: DWAPlan | None = None

    # ------------------------------------------------------------------ call
    def __call__(
        self, t: float, pose: ArrayLike, reference_path: Any, *, perception: Any = None
    ) -> np.ndarray:
        """Command for the measured pose, following the reference path.

        Parameters
        ----------
        t : float
            Time [s]: sets the period of the dynamic window and the tracks' prediction.
        pose : array_like, shape (3,) or (1, 3)
            Measured pose (x [m], y [m], θ [rad]).
        reference_path : PlannedPath or array_like (M, 2)
            The path to follow.
        perception : LocalView, optional
            Costmap, tracks and time (see :mod:`wheelbase.control.obstacle_critics`).

        Returns
        -------
        numpy.ndarray
            (v [m/s], ω [rad/s]), shape (2,) or (1, 2) like ``pose``.
        """
        array = as_float_array("pose", pose, 3, min_ndim=1, max_ndim=2)
        if array.ndim == 2 and array.shape[0] != 1:
            raise InputError(f"DWA controls one robot: pose (3,) or (1, 3) (got {array.shape})")
        plan = self.plan(array.reshape(3), reference_path, perception=perception, t=t)
        return plan.command.reshape((*array.shape[:-1], 2))

    def plan(
        self,
        pose: ArrayLike,
        reference_path: Any,
        *,
        perception: Any = None,
        t: float | None = None,
    ) -> DWAPlan:
        """One DWA iteration from ``pose``; updates the current velocity and the flags.

        Parameters
        ----------
        pose : array_like, shape (3,)
            Measured pose (x [m], y [m], θ [rad]).
        reference_path : PlannedPath or array_like (M, 2)
            The path to follow.
        perception : LocalView, optional
            Costmap, tracks and time.
        t : float, optional
            Time [s] of the call (``None``: one ``control_period`` after the last).

        Returns
        -------
        DWAPlan
        """
        pose = as_float_array("pose", pose, 3, min_ndim=1, max_ndim=1).copy()
        pose[2] = float(wrap_angle(pose[2]))
        if t is not None:
            t = finite("t", t, "s", InputError)
        period = self.control_period
        if t is not None and self._t_last is not None and 0.0 < t - self._t_last <= 1.0:
            period = t - self._t_last
        self._t_last = t
        tables = self._path.tables(reference_path)
        window, info = self._path.window(pose, tables)
        last_section = self._path.last_section(tables)
        if last_section and math.hypot(info[1], info[2]) <= self.goal_tolerance[0]:
            self._near_goal = True
        near_goal = self._near_goal and last_section
        if near_goal and abs(float(wrap_angle(pose[2] - info[3]))) <= self.goal_tolerance[1]:
            return self._stop(pose, "arrived")
        samples = self.window_samples(period)
        local_map = self._field.geometry.copy()
        local_map[:2] -= pose[:2]
        relief = self._field.relief(pose, local_map)
        seen = self._perception.arrays(perception, pose, t, self._step_times, self.max_speed)
        goal, field, fgeo = self._local_goal(window, info, near_goal, seen)
        c = self.critics
        forward, direction = c.forward_point_distance, float(info[4])
        context = (window, goal, field, fgeo, forward, info, direction, local_map, relief, seen)
        profile = self._profile(samples)
        scores, first = self._score(pose, samples, profile, context)
        collided = first < self.steps
        weights = c.vector()
        if info[5] <= forward:
            weights[2] = weights[3] = 0.0  # align critics off at the section's end
        if path_blocked(window, self._field, local_map, seen):
            weights[0] = weights[2] = 0.0  # the path collides: do not pull the robot onto it
        rotating = False
        if near_goal:
            # DWB's RotateToGoal: slow down, then turn in place once a stop is within reach
            rotating = abs(self._velocity[0]) <= self.max_deceleration * period
        else:
            weights[7] = 0.0
        unreachable = scores[:, 1] < 0.0  # DWB: "trajectory hits unreachable area"
        scores[unreachable, 1] = scores[unreachable, 3] = np.max(scores[:, 1], initial=0.0)
        costs = scores @ weights
        legal = ~collided & ~unreachable
        if near_goal:
            v = samples[:, 0]
            if rotating:
                legal &= v == 0.0
            else:
                legal &= (np.abs(v) < abs(self._velocity[0])) | (v == 0.0)
                costs = costs + c.rotate_to_goal * c.slowing_factor * v * v
        if c.oscillation:
            legal &= ~self._oscillating(samples)
        free = ~collided
        start, rates = self._velocity.copy(), self._rates()
        status = "ok"
        if not free.any():
            best = None
            if perception is not None:
                # a stop, held: what all_collide would do, against the walkers coming on
                standing = int(self._score(pose, np.zeros((1, 2)), None, context)[1][0])
                struck = struck_step(seen, float(pose[2]), self.steps)
                best = evasion_choice(first, standing, costs, self.sim_dt, struck)
            if best is None:
                plan = self._stop(pose, "all_collide")
                plan = DWAPlan(plan.command, samples, costs, scores, collided, legal,
                               plan.status, pose.copy(), start, rates)  # fmt: skip
                self.last_plan = plan
                return plan
            status = "evading"
        else:
            if not legal.any():  # the legality rules give way to a collision-free command
                legal = free
            best = int(np.argmin(np.where(legal, costs, np.inf)))
        command = samples[best].copy()
        if profile is not None:  # the ramp's velocity after this period, not its target
            command = ramp_profile(start, command[None], rates, period, 1)[0, 0]
        self._debrief(pose, command)
        self.status = status
        plan = DWAPlan(command, samples, costs, scores, collided, legal, status, pose.copy(),
                       start, rates)  # fmt: skip
        self.last_plan = plan
        return plan

    def _local_goal(self, window: np.ndarray, info: np.ndarray, near_goal: bool, seen: Any):
        """The local goal (x, y, heading) relative to the robot and its distance field: the
        last window point on a passable cell of the costmap (DWB: where the path leaves the
        local costmap), or the path's end near the goal; without a costmap straight
        distances."""
        goal = window[-1, :3].copy()
        if near_goal:
            goal[:] = info[1], info[2], info[3]
        if not seen.has_costmap:
            return goal, np.full((1, 1), -1.0), np.array([0.0, 0.0, 1.0, 0.0])
        reach = self.lookahead + self.max_speed * self.sim_time + 0.5
        if not near_goal:
            x0, y0, res = seen.geometry[:3]
            rows, cols = seen.cost.shape
            col = np.floor((window[:, 0] - x0) / res)
            row = np.floor((window[:, 1] - y0) / res)
            inside = (row >= 0) & (row < rows) & (col >= 0) & (col < cols)
            r = np.clip(row, 0, rows - 1).astype(np.int64)
            q = np.clip(col, 0, cols - 1).astype(np.int64)
            passable = np.flatnonzero(inside & (seen.cost[r, q] < 253))
            if passable.size:  # a goal inside an obstacle would make every end unreachable
                goal = window[passable[-1], :3].copy()
        field, fgeo = goal_distance_field(seen.cost, seen.geometry, goal[:2], reach)
        return goal, field, fgeo

    def window_samples(self, period: float | None = None) -> np.ndarray:
        """The sampled velocities ``(S, 2)`` (v [m/s], ω [rad/s]) of the dynamic window from
        the current velocity (module docstring); 0 is among them where the window holds it.

        Parameters
        ----------
        period : float, optional
            Δ [s] (default ``control_period``).

        Returns
        -------
        numpy.ndarray
        """
        delta = self.control_period if period is None else positive("period", period, "s")
        if self.trajectory_generator == "standard":
            delta = self.sim_time  # the targets the ramps reach within the trajectory
        v, w = self._velocity
        up, down, _alpha = self._rates()
        speeds = _axis(v - down * delta, v + up * delta, self.min_speed, self.max_speed,
                       self.v_samples)  # fmt: skip
        turn = self.max_yaw_acceleration * delta
        rates = _axis(w - turn, w + turn, -self.max_yaw_rate, self.max_yaw_rate, self.w_samples)
        grid_v, grid_w = np.meshgrid(speeds, rates, indexing="ij")
        return np.ascontiguousarray(np.stack([grid_v.ravel(), grid_w.ravel()], -1))

    def _score(
        self, pose: np.ndarray, samples: np.ndarray, profile: np.ndarray | None, context: tuple
    ) -> tuple[np.ndarray, np.ndarray]:
        """Scores ``(S, 8)`` and first colliding steps ``(S,)`` of the trajectories of
        ``samples`` (held, or ramped along ``profile``); ``context``: the call's window, local
        goal and its field, forward point, path info, direction, map, relief and perception."""
        window, goal, field, fgeo, forward, info, direction, local_map, relief, seen = context
        c = self.critics
        if self.backend == "numpy":
            return dwa_scores_numpy(
                pose[2], samples, self.sim_dt, self.steps, window, goal, field, fgeo, forward,
                info[1:3], direction, self._field, local_map, relief, c.inflation, seen,
                c.dynamic_inflation, profile,
            )  # fmt: skip
        scores = np.empty((samples.shape[0], len(SCORES)))
        first = np.empty(samples.shape[0], np.int64)
        ramped = profile is not None
        run_kernel(
            dwa_kernel, samples.shape[0] * self.steps,
            pose[2], samples, self.sim_dt, self.steps, window, goal, field, fgeo, forward,
            info[1:3].copy(), direction, self._field.distance_field, local_map,
            self._field.circles, relief, c.inflation, seen.cost, seen.near, seen.geometry,
            seen.polygon, seen.table, seen.relief, seen.disks, seen.order, seen.counts,
            c.dynamic_inflation, ramped, profile if ramped else np.zeros((1, 1, 2)), scores,
            first,
        )  # fmt: skip
        return scores, first

    def _rates(self) -> np.ndarray:
        """(a_up, a_down [m/s²], α [rad/s²]) from the current velocity: growing |v| is
        accelerating, whichever its sign."""
        v = self._velocity[0]
        up, down = (self.max_acceleration, self.max_deceleration) if v >= 0.0 else (
            self.max_deceleration, self.max_acceleration)  # fmt: skip
        return np.array([up, down, self.max_yaw_acceleration])

    def _profile(self, samples: np.ndarray) -> np.ndarray | None:
        """The ramped velocities of the standard generator (``None``: held samples)."""
        if self.trajectory_generator != "standard":
            return None
        return ramp_profile(self._velocity, samples, self._rates(), self.sim_dt, self.steps)

    def _oscillating(self, samples: np.ndarray) -> np.ndarray:
        only = self._only
        return np.any(((only > 0) & (samples < 0.0)) | ((only < 0) & (samples > 0.0)), axis=1)

    def _debrief(self, pose: np.ndarray, command: np.ndarray) -> None:
        """Update the current velocity and DWB's oscillation flags with the command sent."""
        sign = np.sign(command)
        flipped = (sign != 0.0) & (self._sign != 0.0) & (sign != self._sign)
        if np.any(flipped):
            self._only = np.where(flipped, sign, self._only)
            self._flag_pose = pose.copy()
        elif np.any(self._only != 0.0) and self._flag_pose is not None:
            moved = math.hypot(*(pose[:2] - self._flag_pose[:2]))
            turned = abs(float(wrap_angle(pose[2] - self._flag_pose[2])))
            if moved >= self.oscillation_reset_distance or turned >= self.oscillation_reset_angle:
                self._only = np.zeros(2)
                self._sign = np.zeros(2)
                self._flag_pose = None
        self._sign = np.where(sign != 0.0, sign, self._sign)
        self._velocity = command.copy()

    def _stop(self, pose: np.ndarray, status: str) -> DWAPlan:
        self.status = status
        self._velocity = np.zeros(2)
        empty = np.zeros((0, 2))
        plan = DWAPlan(np.zeros(2), empty, np.zeros(0), np.zeros((0, len(SCORES))),
                       np.zeros(0, bool), np.zeros(0, bool), status, pose.copy())  # fmt: skip
        self.last_plan = plan
        return plan

    def predict(self, plan: DWAPlan | None = None, controls: ArrayLike | None = None) -> np.ndarray:
        """Poses ``(..., steps + 1, 3)`` of held velocities from a plan's pose (world frame).

        Parameters
        ----------
        plan : DWAPlan, optional
            The plan (default: the last one).
        controls : array_like, shape (2,) or (K, 2), optional
            Velocities (v, ω) (default: the plan's command), e.g. some samples for a fan.

        Returns
        -------
        numpy.ndarray
        """
        plan = self.last_plan if plan is None else plan
        if plan is None:
            raise InputError("predict needs a plan: call the controller first")
        seq = plan.command if controls is None else as_float_array("controls", controls, 2)
        many = seq.ndim == 2
        velocities = seq if many else seq[None]
        poses = np.empty((velocities.shape[0], self.steps + 1, 3))
        poses[:, 0] = plan.pose
        if self.trajectory_generator == "standard":
            # from the velocity the plan started at (the command sent since is the ramp's)
            start = plan.start_velocity
            profile = ramp_profile(start, velocities, plan.rates, self.sim_dt, self.steps)
            arcs = profile_poses(float(plan.pose[2]), profile, self.sim_dt)
        else:
            arcs = arc_poses(float(plan.pose[2]), velocities, self.sim_dt, self.steps)
        poses[:, 1:, :2] = arcs[..., :2] + plan.pose[:2]
        poses[:, 1:, 2] = wrap_angle(arcs[..., 2])
        return poses if many else poses[0]


def _axis(low: float, high: float, floor: float, ceiling: float, count: int) -> np.ndarray:
    """``count`` values across [low, high] ∩ [floor, ceiling] (the nearest limit where they do
    not meet), with 0 put in place of the value nearest it where the range holds 0."""
    low, high = min(max(low, floor), ceiling), max(min(high, ceiling), floor)
    low, high = min(low, high), max(low, high)
    values = np.linspace(low, high, count) if count > 1 else np.array([0.5 * (low + high)])
    if low <= 0.0 <= high:
        values[int(np.argmin(np.abs(values)))] = 0.0
    return values
