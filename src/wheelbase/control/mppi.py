"""Model Predictive Path Integral control (MPPI) on batched rollouts.

Each call (Williams et al., "Information-theoretic MPC for model-based reinforcement learning",
ICRA 2017; the form of Nav2's MPPI controller):

1. warm start: the previous optimal command sequence U (T, m), shifted by one step (m = 2
   command components, 3 for a holonomic base);
2. K samples V_i = clip(U + ε_i, limits) with Gaussian ε_i ~ N(0, diag(σ²)); this call's
   limits keep v at the sign of the path section (unless ``reverse_against_path``, near the goal
   or where the path is blocked) and cap |v| at √(2·a·d) before a cusp or the goal, d away;
3. each V_i is rolled out from the measured pose through the model's body twist with the
   Euler step of :func:`wheelbase.integrate.integrate_step` (the same arithmetic);
4. the critics of :mod:`wheelbase.control.mppi_critics` score each rollout: S_i;
5. w_i = exp(−(S_i − min S)/λ) / Σ exp(−(S_j − min S)/λ) (the minimum subtracted: the best
   sample has weight exp(0) = 1 before normalising, so nothing overflows at any λ);
6. U ← Savitzky–Golay(Σ w_i V_i) along the horizon, clipped; the command is U[0].

When every sample collides (min S >= the collision cost) the command is a stop (0, 0), the
warm start is cleared and :attr:`MPPIPlan.status` is ``"all_collide"`` — unless, with a
``perception=`` view, standing still collides too, sooner than some sample does: a walker that
does not avoid the robot strikes a stopped one (measured: every contact of the crowd benchmark
was a walker striking the robot stopped by ``all_collide``). The command is then the first of
the sample that stays clear longest (at least
:data:`~wheelbase.control.obstacle_critics.EVADE_TIME`; the cheapest of those), its sequence
the warm start, and the status ``"evading"``. A static obstacle never strikes a
stopped robot, so among static obstacles the rule is the stop it always was.

With a view, the optimal sequence of step 6 is itself rolled out and checked: a weighted mean of
samples that each avoid a walker, some passing left and some right, can run into it (measured
in ``crowd_crossing``: a mean through a walker 1.1 s ahead while 5 % of the samples were
clear, then a contact). Where it collides and some sample does not, the command is the first
of the cheapest sample (its sequence the warm start) and the status ``"guarded"``.

With a ``perception=`` view (a :class:`wheelbase.perception.LocalView`: costmap, tracks of
moving obstacles, time) the critics also score the costmap and the tracks predicted over the
horizon (:mod:`wheelbase.control.obstacle_critics`); without one the controller is the map-only
controller it always was.

Backends: ``numba`` (the default: :mod:`wheelbase.control.mppi_numba`: one parallel compiled
loop that draws the noise, rolls each sample out and scores it, ``cache=True``; its noise comes
from a counter-based SplitMix64 stream keyed by (seed, call, sample, step) through an
inverse-CDF table, so it does not depend on the threads), ``numpy`` (the reference,
:mod:`wheelbase.control.mppi_numpy`; noise from ``numpy.random.Generator``; about ten times
slower), ``jax`` (:mod:`wheelbase.control.mppi_jax`: ``jax.jit`` + ``lax.scan`` over the
horizon; float32 by default, float64 with ``jax_float64=True``; install ``wheelbase[jax]``; no
perception).
The path window is :mod:`wheelbase.control.local_path`'s, the command bounds
:mod:`wheelbase.control.mppi_bounds`', the static map's footprint check
:mod:`wheelbase.control.footprint_field`'s.
Steps 1, 5 and 6 are shared NumPy code, so with the same noise (``plan(..., noise=...)``) the
backends return the same command to rounding.

Commands are ``(v [m/s], ω [rad/s])`` for :class:`~wheelbase.models.Unicycle` and
:class:`~wheelbase.models.DiffDrive` (``limits``: :class:`VelocityLimits`), and
``(v [m/s], δ [rad])`` for the steered models (``limits``: :class:`SteeringLimits`), and the
body twist ``(v_x [m/s], v_y [m/s], ω [rad/s])`` for :class:`~wheelbase.models.BodyTwist` and
holonomic wheeled bases (mecanum, omni; ``limits``: :class:`VelocityLimits`, whose
``max_speed`` bounds the speed √(v_x² + v_y²) in every direction). A holonomic base samples
speeds of both signs: it has no forward.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from dataclasses import fields as dataclass_fields
from typing import Any, ClassVar

import numpy as np
from numpy.typing import ArrayLike
from scipy.signal import savgol_filter

from wheelbase._jax import import_jax
from wheelbase._validate import (
    as_float_array,
    check_choice,
    count_text,
    finite,
    flag,
    integer,
    positive,
)
from wheelbase.control.base import (
    HOLONOMIC_COMMAND,
    STEERING_COMMAND,
    VELOCITY_COMMAND,
    SteeringLimits,
    VelocityLimits,
)
from wheelbase.control.footprint_field import FootprintField, footprint_disks
from wheelbase.control.local_path import PathWindow
from wheelbase.control.mppi_bounds import (
    KIND_HOLONOMIC,
    KIND_VELOCITY,
    call_bounds,
    clip_commands,
    command_bounds,
    model_kind,
)
from wheelbase.control.mppi_critics import MPPICritics, split_critic_gains
from wheelbase.control.mppi_jax import host_samples, jax_costs, weighted_mean
from wheelbase.control.mppi_numba import NORMAL_TABLE, mppi_kernel, mppi_work, run_kernel
from wheelbase.control.mppi_numpy import contact_steps, numpy_costs, rollout
from wheelbase.control.obstacle_critics import (
    PerceptionArrays,
    PerceptionInputs,
    evasion_choice,
    path_blocked,
    struck_step,
)
from wheelbase.errors import ConfigError, InputError
from wheelbase.geometry import wrap_angle
from wheelbase.limits import MAX_COORDINATE, MAX_SAMPLE_STEPS

__all__ = ["MPPI", "MPPI_BACKENDS", "MPPICritics", "MPPIPlan"]

MPPI_BACKENDS: tuple[str, ...] = ("numpy", "numba", "jax")
STATUSES: tuple[str, ...] = ("ok", "all_collide", "evading", "guarded", "arrived")


@dataclass(frozen=True)
class MPPIPlan:
    """One MPPI iteration.

    Attributes
    ----------
    command : numpy.ndarray, shape (2,)
        The command sent (first of ``controls``, or a stop).
    controls : numpy.ndarray, shape (T, m)
        The smoothed optimal command sequence.
    costs : numpy.ndarray, shape (K,)
        Cost of each sample.
    weights : numpy.ndarray, shape (K,)
        Softmin weights (sum 1).
    status : str
        ``"ok"``, ``"all_collide"``, ``"evading"``, ``"guarded"`` or ``"arrived"``.
    pose : numpy.ndarray, shape (3,)
        The measured pose the plan starts from (see :meth:`MPPI.predict`).
    samples : numpy.ndarray, shape (K, T, m)
        The sampled (clipped) command sequences, e.g. for a fan of rollouts (the jax backend
        keeps the first ``KEPT_DEVICE_SAMPLES`` = 256 only: the rest stay on the device).
    """

    command: np.ndarray
    controls: np.ndarray
    costs: np.ndarray
    weights: np.ndarray
    status: str
    pose: np.ndarray
    samples: np.ndarray


class MPPI:
    """Sampling-based predictive controller for one robot (see the module docstring).

    Parameters
    ----------
    model : KinematicModel
        Unicycle, DiffDrive, Bicycle, RearWheelBicycle, Ackermann, BodyTwist or a holonomic
        WheeledBase (``mecanum4``, ``omni3``).
    horizon_steps : int
        T, steps of the horizon, >= 1.
    dt : float
        Step [s], > 0.
    samples : int
        K, rollouts per call, >= 1.
    noise_std : sequence of float
        σ of the Gaussian perturbation of each command component (SI units), > 0: two values,
        three for a holonomic base (one value: the same for all).
    temperature : float
        λ of the softmin, > 0.
    critics : MPPICritics, dict or None
        Critic weights (``None``: defaults).
    limits : VelocityLimits or SteeringLimits
        Command limits; ``max_speed`` (and ``max_yaw_rate`` for velocity commands) finite.
    seed : int
        Seed of the noise.
    backend : str
        One of :data:`MPPI_BACKENDS` (default ``"numba"``, the fast one: about ten times the
        calls per second of ``"numpy"``, the reference; ``benchmarks/mppi.py`` measures both).
    grid : OccupancyGrid, optional
        Map for the obstacle critic.
    footprint : Footprint, optional
        Robot outline (default: a point robot), checked against the distance field as disks:
        its covering circles, or, where those reach more than 0.25 m past the outline (a car:
        0.56 m past its ends), :meth:`~wheelbase.planning.Footprint.outline_circles` every
        ``OUTLINE_SPACING`` = 0.2 m (slower: 67 disks for a 4.5 × 1.8 m car, against 5).
    allow_reverse : bool
        Whether v may be negative (down to −max_speed); otherwise v >= 0.
    reverse_against_path : bool
        Sample speeds of both signs all along the path (Nav2's way; the ``prefer_forward``
        critic then penalises the wrong sign). Off by default: v keeps the sign of the current
        path section except near the goal and where the path ahead is blocked, which stops the
        robot twitching back and forth where its best speed is about zero.
    approach_deceleration : float
        a [m/s²], > 0: the speed is capped at √(2·a·d) with d the distance left to the next
        cusp or the goal (at least 10 % of the top speed), so the robot stops at them instead of
        overshooting.
    savgol_window : int
        Savitzky–Golay window (odd, >= 3; shortened to fit the horizon); 0 switches it off.
    path_spacing : float
        Spacing [m] of the densified path the path critics use.
    goal_tolerance : (float, float)
        (position [m], heading [rad]): within both of the path's end the command is a stop and
        :attr:`MPPIPlan.status` is ``"arrived"``.
    cusp_tolerance : float
        Distance [m] to a cusp at which the next path section becomes active.
    jax_float64 : bool
        Run the ``jax`` backend in float64 (default float32).
    held_noise_fraction : float
        With a ``perception=`` view, this fraction of the samples (the last ones) holds its
        first perturbation over the whole horizon, in [0, 1] (default 0.1): white noise
        averages out over the horizon (the heading spread of 56 steps of σ_ω = 0.4 rad/s,
        dt 0.05 s, is 0.15 rad), too little to swerve round a walker coming head-on; a held
        one draws arcs (1.1 rad). Without a view the sampling is unchanged.
    max_sample_steps : int
        Most samples × horizon_steps per call (default :data:`wheelbase.limits.MAX_SAMPLE_STEPS`
        = 1e7: the NumPy backend then holds about 1.6 GB of intermediates and takes ~4 s per
        call); raise it on purpose, e.g. for the jax backend on a GPU.

    Examples
    --------
    >>> from wheelbase.models import Unicycle
    >>> mppi = MPPI(Unicycle(), 20, 0.1, 64, (0.2, 0.5), 1.0, None,
    ...             VelocityLimits(max_speed=0.5, max_yaw_rate=1.5), seed=1)
    >>> mppi(0.0, [0.0, 0.0, 0.0], [[0.0, 0.0], [2.0, 0.0]]).shape
    (2,)
    """

    command_names: ClassVar[tuple[str, ...]] = VELOCITY_COMMAND
    per_robot: ClassVar[bool] = True  # one warm-started sequence per robot: one copy each
    uses_perception: ClassVar[bool] = True  # the engine passes ``perception=`` (a LocalView)

    def __init__(
        self,
        model: Any,
        horizon_steps: int,
        dt: float,
        samples: int,
        noise_std: ArrayLike,
        temperature: float,
        critics: MPPICritics | dict | None,
        limits: VelocityLimits | SteeringLimits,
        *,
        seed: int = 0,
        backend: str = "numba",
        grid: Any = None,
        footprint: Any = None,
        allow_reverse: bool = True,
        reverse_against_path: bool = False,
        approach_deceleration: float = 0.5,
        savgol_window: int = 9,
        path_spacing: float = 0.05,
        goal_tolerance: tuple[float, float] = (0.05, 0.25),
        cusp_tolerance: float = 0.05,
        jax_float64: bool = False,
        max_sample_steps: int = MAX_SAMPLE_STEPS,
        held_noise_fraction: float = 0.1,
    ) -> None:
        self.model = model
        self.horizon_steps = integer("horizon_steps", horizon_steps, minimum=1)
        self.samples = integer("samples", samples, minimum=1)
        limit = integer("max_sample_steps", max_sample_steps, minimum=1)
        if self.samples * self.horizon_steps > limit:
            raise ConfigError(
                f"samples × horizon_steps = {count_text(self.samples * self.horizon_steps)}: "
                "more than "
                f"max_sample_steps = {limit}; use fewer samples or a shorter horizon, or raise "
                "max_sample_steps"
            )
        self.dt = positive("dt", dt, "s")
        self.temperature = positive("temperature", temperature)
        self._kind, self._wheel_base = model_kind(model)
        self.nu = 3 if self._kind == KIND_HOLONOMIC else 2
        try:
            sigma = np.asarray(noise_std, dtype=np.float64).reshape(-1)
        except (TypeError, ValueError):
            sigma = np.zeros(0)
        if sigma.size == 1:
            sigma = np.repeat(sigma, self.nu)
        if sigma.size != self.nu or not np.all(np.isfinite(sigma)) or np.any(sigma <= 0.0):
            raise ConfigError(
                f"noise_std must be {self.nu} values > 0, one per command (got {noise_std!r})"
            )
        self.noise_std = sigma
        self.critics = MPPICritics.from_mapping(critics)
        self.backend = check_choice("backend", backend, MPPI_BACKENDS)
        self.seed = integer("seed", seed, 0, 2**64 - 1)  # the numba noise counters are 64-bit
        self.path_spacing = positive("path_spacing", path_spacing, "m")
        self.cusp_tolerance = positive("cusp_tolerance", cusp_tolerance, "m")
        if np.ndim(goal_tolerance) != 1 or np.size(goal_tolerance) != 2:
            raise ConfigError(
                f"goal_tolerance must be (position [m], heading [rad]) (got {goal_tolerance!r})"
            )
        self.goal_tolerance = (
            positive("goal position tolerance", goal_tolerance[0], "m"),
            positive("goal heading tolerance", goal_tolerance[1], "rad"),
        )
        self.allow_reverse = flag("allow_reverse", allow_reverse)
        self.reverse_against_path = flag("reverse_against_path", reverse_against_path)
        self.approach_deceleration = positive(
            "approach_deceleration", approach_deceleration, "m/s²"
        )
        self.jax_float64 = flag("jax_float64", jax_float64)
        self.held_noise_fraction = finite("held_noise_fraction", held_noise_fraction)
        if not 0.0 <= self.held_noise_fraction <= 1.0:
            raise ConfigError(
                f"held_noise_fraction must be in [0, 1] (got {self.held_noise_fraction:g})"
            )
        self.command_names = {
            KIND_VELOCITY: VELOCITY_COMMAND, KIND_HOLONOMIC: HOLONOMIC_COMMAND,
        }.get(self._kind, STEERING_COMMAND)  # fmt: skip
        self._lo, self._hi = command_bounds(self._kind, model, limits, self.allow_reverse)
        self.limits = limits
        try:
            window = integer("savgol_window", savgol_window, minimum=0)
        except ConfigError:
            window = 2
        if window != 0 and (window < 3 or window % 2 == 0):
            raise ConfigError(
                f"savgol_window must be 0 or an odd integer >= 3 (got {savgol_window!r})"
            )
        self.savgol_window = window
        # Savitzky–Golay as a matrix along the horizon: the filter is linear in the sequence
        # (a long horizon is filtered directly: its T × T matrix would not fit in memory).
        steps = self.horizon_steps
        window = min(window, steps if steps % 2 else steps - 1)
        self._savgol: np.ndarray | tuple[int, int] | None = None
        if window >= 3:
            order = min(3, window - 1)
            if steps <= SAVGOL_MATRIX_STEPS:
                self._savgol = savgol_filter(np.eye(steps), window, order, axis=0, mode="interp")
            else:
                self._savgol = (window, order)
        self._field = FootprintField(grid, footprint)
        self.grid, self.footprint = grid, footprint
        self._jax_map: tuple | None = None  # the map on the JAX device, made at the first call
        self._perception = PerceptionInputs(
            footprint, footprint_disks(footprint, outline=False), self.critics.dynamic_inflation,
            self.critics.dynamic_sigma_scale, self.critics.dynamic_acceleration_noise,
            self.critics.dynamic_hold_time,
        )  # fmt: skip
        self._step_times = self.dt * np.arange(1, self.horizon_steps + 1)
        if self.backend == "jax":
            import_jax()
        reach = self.horizon_steps * self.dt * float(self._hi[0])
        if reach > MAX_COORDINATE:
            raise ConfigError(
                f"the horizon reaches {reach:.3g} m (horizon_steps × dt × max_speed): more than "
                f"{MAX_COORDINATE:g} m, beyond which the rollouts' costs overflow; use a smaller dt"
            )
        # the path window: the reach of the horizon, cut to the path
        self._path = PathWindow(self.path_spacing, 1.2 * reach + 2.0 * self.path_spacing,
                                self.critics.goal_distance, self.cusp_tolerance)  # fmt: skip
        self.reset()

    @classmethod
    def from_gains(
        cls,
        model: Any,
        *,
        grid: Any = None,
        footprint: Any = None,
        **gains: Any,
    ) -> MPPI:
        """An MPPI from plain keyword gains, as a scenario file gives them.

        Parameters
        ----------
        model : KinematicModel
            The robot model.
        grid : OccupancyGrid, optional
            Map for the obstacle critic.
        footprint : Footprint, optional
            Robot outline.
        **gains
            ``horizon_steps`` (56), ``dt`` (0.05 s), ``samples`` (2000), ``noise_std``
            ((0.2, 0.4): Nav2's σ of v and ω), ``temperature`` (0.03), ``seed`` (0),
            ``backend`` ("numba"),
            ``max_speed`` (0.5 m/s), ``max_yaw_rate`` (1.5 rad/s, velocity commands) or
            ``max_steering`` (the model's, steered models), any keyword of :class:`MPPI`
            (``allow_reverse``, ``savgol_window``, ...) and any critic weight of
            :class:`MPPICritics` by name (``obstacle=30``), or ``critics={...}``.

        Returns
        -------
        MPPI

        Examples
        --------
        >>> from wheelbase.models import Unicycle
        >>> MPPI.from_gains(Unicycle(), samples=100, obstacle=30.0).critics.obstacle
        30.0
        """
        critics, options = split_critic_gains(gains, MPPICritics)
        critic_names = {f.name for f in dataclass_fields(MPPICritics)}
        max_speed = options.pop("max_speed", 0.5)
        max_yaw_rate = options.pop("max_yaw_rate", 1.5)
        kind, _base = model_kind(model)
        if kind in (KIND_VELOCITY, KIND_HOLONOMIC):
            limits: Any = VelocityLimits(max_speed=max_speed, max_yaw_rate=max_yaw_rate)
            options.pop("max_steering", None)
        else:
            steering = positive("max_steering", options.pop("max_steering", model.max_steering))
            limits = SteeringLimits(min(steering, 1.5), max_speed=max_speed)
        allowed = {
            "horizon_steps", "dt", "samples", "noise_std", "temperature", "seed", "backend",
            "allow_reverse", "reverse_against_path", "approach_deceleration", "savgol_window",
            "path_spacing", "goal_tolerance", "cusp_tolerance", "jax_float64", "max_sample_steps",
            "held_noise_fraction",
        }  # fmt: skip
        unknown = sorted(set(options) - allowed)
        if unknown:
            names = allowed | critic_names | {"max_speed", "max_yaw_rate", "max_steering"}
            raise ConfigError(
                f"unknown MPPI gain {unknown[0]!r}; allowed: {', '.join(sorted(names))}"
            )
        return cls(
            model,
            options.pop("horizon_steps", 56),
            options.pop("dt", 0.05),
            options.pop("samples", 2000),
            options.pop("noise_std", (0.2, 0.2, 0.4) if kind == KIND_HOLONOMIC else (0.2, 0.4)),
            options.pop("temperature", 0.03),
            critics,
            limits,
            seed=options.pop("seed", 0),
            backend=options.pop("backend", "numba"),
            grid=grid,
            footprint=footprint,
            **options,
        )

    def reset(self) -> None:
        """Forget the warm start, the path progress and the noise counter."""
        self._mean = np.zeros((self.horizon_steps, self.nu))
        self._mean[:, 0] = np.clip(0.0, self._lo[0], self._hi[0])
        self._last = np.zeros(self.nu)
        self._path.reset()
        self._calls = 0
        self._rng = np.random.default_rng(self.seed)
        self.status = "ok"
        self.last_plan: MPPIPlan | None = None

    # ------------------------------------------------------------------ call
    def __call__(
        self, t: float, pose: ArrayLike, reference: Any, *, perception: Any = None
    ) -> np.ndarray:
        """Command for the measured pose, following the reference path.

        Parameters
        ----------
        t : float
            Time [s]: the path is followed by position; the tracks of ``perception`` are
            predicted from the view's time to ``t`` and on over the horizon.
        pose : array_like, shape (3,) or (1, 3)
            Measured pose (x [m], y [m], θ [rad]).
        reference : PlannedPath or array_like (M, 2)
            The reference path (a planned path's directions mark reversing sections).
        perception : LocalView, optional
            What the robot perceives: ``costmap``, ``tracks`` and ``time`` (see
            :mod:`wheelbase.control.obstacle_critics`); ``None``: the map only.

        Returns
        -------
        numpy.ndarray
            Command of shape (m,) or (1, m) like ``pose`` (m = 2, or 3 for a holonomic base).
        """
        array = as_float_array("pose", pose, 3, min_ndim=1, max_ndim=2)
        if array.ndim == 2 and array.shape[0] != 1:
            raise InputError(f"MPPI controls one robot: pose (3,) or (1, 3) (got {array.shape})")
        plan = self.plan(array.reshape(3), reference, perception=perception, t=t)
        return plan.command.reshape((*array.shape[:-1], self.nu))

    def plan(
        self,
        pose: ArrayLike,
        reference: Any,
        noise: ArrayLike | None = None,
        *,
        perception: Any = None,
        t: float | None = None,
    ) -> MPPIPlan:
        """One MPPI iteration from ``pose``; updates the warm start.

        Parameters
        ----------
        pose : array_like, shape (3,)
            Measured pose (x [m], y [m], θ [rad]).
        reference : PlannedPath or array_like (M, 2)
            The reference path.
        noise : array_like, shape (K, T, m), optional
            The perturbations ε to use instead of drawing them (cross-backend checks).
        perception : LocalView, optional
            Costmap, tracks and time (see ``MPPI.__call__``).
        t : float, optional
            The time [s] of the call (default: the view's time: no latency).

        Returns
        -------
        MPPIPlan
        """
        pose = as_float_array("pose", pose, 3, min_ndim=1, max_ndim=1).copy()
        pose[2] = float(wrap_angle(pose[2]))  # any finite heading, wrapped on entry
        if perception is not None and self.backend == "jax":
            raise ConfigError(
                "perception is not supported on the jax backend; use backend='numba' (the "
                "default) or 'numpy'"
            )
        tables = self._path.tables(reference)
        # The costs are computed relative to the robot: the window, the goal and the map origin
        # are shifted by its position, so the backends see the same numbers anywhere (float32
        # keeps 0.5 km at 4.5e9 m absolute, and float64 only micrometres).
        window, info = self._path.window(pose, tables)
        local = np.array([0.0, 0.0, pose[2]])
        local_map = self._field.geometry.copy()
        local_map[:2] -= pose[:2]
        seen = self._perception.arrays(perception, pose, t, self._step_times, float(self._hi[0]))
        last_section = self._path.last_section(tables)
        settling = last_section and info[0] > 0.5  # within goal_distance of the goal
        if settling:
            gap = math.hypot(info[1], info[2])
            turn = abs(float(wrap_angle(pose[2] - info[3])))
            if gap <= self.goal_tolerance[0] and turn <= self.goal_tolerance[1]:
                return self._stop(pose, "arrived")
        weights = self.critics.vector()
        if last_section and info[5] <= self.critics.near_goal_distance:
            # obstacle and costmap repulsion off near the goal (collisions stay lethal)
            weights[5] = weights[12] = 0.0
        blocked = path_blocked(window, self._field, local_map, seen)
        info[6] = self._field.relief(pose, local_map)  # see FootprintField.relief
        if blocked:
            weights[:2] = 0.0  # the path itself collides: do not pull the robot onto it
        mean = self._mean
        if noise is not None:
            noise = as_float_array("noise", noise, self.nu, min_ndim=3, max_ndim=3)
            if noise.shape[:2] != (self.samples, self.horizon_steps):
                raise InputError(
                    f"noise must have shape ({self.samples}, {self.horizon_steps}, {self.nu}) "
                    f"(got {noise.shape})"
                )
        two_signs = (
            self.reverse_against_path or blocked or settling or not self.allow_reverse
            # after a call where every rollout collided, both signs: backing off may be the
            # way out
            or self.status == "all_collide"
        )  # fmt: skip
        lo, hi = call_bounds(
            self._lo, self._hi, kind=self._kind, distance_left=float(info[5]),
            direction=float(info[4]), deceleration=self.approach_deceleration,
            two_signs=two_signs,
        )  # fmt: skip
        args = (local, mean, lo, hi, self._hi, window, info, self._last, weights)
        # With a view, the last `held_noise_fraction` of the samples hold their first
        # perturbation over the horizon (sustained arcs to swerve round what comes).
        held_from = self.samples
        if perception is not None:
            held_from -= round(self.held_noise_fraction * self.samples)
        if self.backend == "numpy":
            if noise is None:
                noise = self._rng.standard_normal((self.samples, self.horizon_steps, self.nu))
                noise *= self.noise_std
            noise = noise.copy()
            noise[held_from:] = noise[held_from:, :1]
            costs, controls, first = numpy_costs(self, *args, noise, local_map, seen)
        elif self.backend == "numba":
            costs, controls, first = self._costs_numba(args, noise, local_map, seen, held_from)
        else:
            costs, controls = jax_costs(self, *args, noise, local_map)
            first = None  # no perception on this backend: never evading
        self._calls += 1
        if self.critics.extra is not None:
            controls = np.asarray(controls, np.float64)  # the user's critic is NumPy code
            extra = np.asarray(
                self.critics.extra(rollout(self, pose, controls), controls), np.float64
            )
            if extra.shape != (self.samples,):
                raise InputError(
                    f"extra critic must return shape ({self.samples},) (got {extra.shape})"
                )
            costs = costs + np.where(np.isfinite(extra), np.maximum(extra, 0.0), 1e6)
        evasion = collides = None
        if perception is not None:

            def contacts(sequences: np.ndarray) -> np.ndarray:
                return self._first_contacts(args, sequences, local_map, seen)

            if float(np.min(costs)) >= self.critics.collision_cost:
                evasion = self._evasion(first, costs, contacts, seen, float(pose[2]))

            def collides(sequence: np.ndarray) -> bool:
                return bool(contacts(sequence[None])[0] < self.horizon_steps)

        return self._update(pose, costs, controls, lo, hi, evasion, collides)

    def _evasion(
        self,
        first: np.ndarray,
        costs: np.ndarray,
        contacts: Callable[[np.ndarray], np.ndarray],
        seen: PerceptionArrays,
        heading: float,
    ) -> int | None:
        """When every sample collides: the sample that stays clear longest (the cheapest of
        those), by :func:`~wheelbase.control.obstacle_critics.evasion_choice`; else None
        (a stop). ``first``: each sample's first colliding step, from the costs; ``contacts``:
        the first colliding steps of command sequences ``(N, T, m)``; ``seen`` and ``heading``
        [rad]: the call's arrays and the robot's heading (when a track strikes it standing)."""
        stop = np.zeros((1, self.horizon_steps, self.nu))
        struck = struck_step(seen, heading, self.horizon_steps)
        return evasion_choice(first, int(contacts(stop)[0]), costs, self.dt, struck)

    def _first_contacts(
        self,
        args: tuple,
        sequences: np.ndarray,
        local_map: np.ndarray,
        seen: PerceptionArrays,
    ) -> np.ndarray:
        """The first colliding step of each command sequence ``(N, T, m)`` (T where it never
        collides) under this call's map, costmap and tracks: on the numba backend the kernel's
        own rules, fed the sequences as its perturbations of a zero mean (a NumPy rollout of one
        sequence cost 2.4 ms a call in the crowd loop), else
        :func:`~wheelbase.control.mppi_numpy.contact_steps`."""
        local, mean, _lo, _hi, _scale, _window, info, *_rest = args
        if self.backend == "numba":
            probe = (local, np.zeros_like(mean), *args[2:])
            return self._costs_numba(probe, sequences, local_map, seen, len(sequences))[2]
        return contact_steps(self, local, sequences, info, local_map, seen)

    def _costs_numba(
        self,
        args: tuple,
        noise: np.ndarray | None,
        local_map: np.ndarray,
        seen: PerceptionArrays,
        held_from: int,
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        has_noise = noise is not None
        buffer = np.ascontiguousarray(noise) if has_noise else np.zeros((1, 1, self.nu))
        count = buffer.shape[0] if has_noise else self.samples
        costs = np.empty(count)
        controls = np.empty((count, self.horizon_steps, self.nu))
        first = np.empty(count, np.int64)
        local, mean, lo, hi, scale, window, info, last, weights = args
        run_kernel(
            mppi_kernel, mppi_work(count, self.horizon_steps, seen.table.shape[1]),
            local, mean, lo, hi, scale, window, info, last, buffer, has_noise, held_from,
            self.noise_std,
            np.uint64(self.seed), np.uint64(self._calls), self._kind, self._wheel_base, self.dt,
            weights, self._field.distance_field, local_map, self._field.circles,
            int(self.critics.path_stride), NORMAL_TABLE, seen.cost, seen.near, seen.geometry,
            seen.polygon, seen.table, seen.relief, seen.disks, seen.order, seen.counts, costs,
            controls, first,
        )  # fmt: skip
        return costs, controls, first

    def _stop(self, pose: np.ndarray, status: str) -> MPPIPlan:
        self.status = status
        self._mean = np.zeros_like(self._mean)
        self._last = np.zeros(self.nu)
        costs = np.zeros(self.samples)
        weights = np.full(self.samples, 1.0 / self.samples)
        samples = np.zeros((0, self.horizon_steps, self.nu))
        plan = MPPIPlan(
            np.zeros(self.nu), self._mean.copy(), costs, weights, status, pose.copy(), samples
        )
        self.last_plan = plan
        return plan

    def _update(
        self,
        pose: np.ndarray,
        costs: np.ndarray,
        controls: np.ndarray,
        lo: np.ndarray,
        hi: np.ndarray,
        evasion: int | None = None,
        collides: Callable[[np.ndarray], bool] | None = None,
    ) -> MPPIPlan:
        best = float(np.min(costs))
        with np.errstate(over="ignore", under="ignore"):  # exp(−inf) = 0: the intended limit
            weights = np.exp(-(costs - best) / self.temperature)
        weights /= np.sum(weights)
        if evasion is not None:
            self.status = "evading"
            sequence = np.array(controls[evasion], np.float64)
            command = sequence[0].copy()
            self._mean = np.concatenate([sequence[1:], sequence[-1:]], axis=0)
        elif best >= self.critics.collision_cost:
            self.status = "all_collide"
            command = np.zeros(self.nu)
            sequence = np.zeros_like(self._mean)
            self._mean = np.zeros_like(self._mean)
            self._mean[:, 0] = np.clip(0.0, self._lo[0], self._hi[0])
        else:
            self.status = "ok"
            sequence = weighted_mean(weights, controls, self.jax_float64)
            sequence = clip_commands(self._kind, self._smooth(sequence), lo, hi)  # this call's
            if collides is not None and collides(sequence):
                self.status = "guarded"  # the mean runs into what its samples avoid
                sequence = np.array(controls[int(np.argmin(costs))], np.float64)
            command = sequence[0].copy()
            self._mean = np.concatenate([sequence[1:], sequence[-1:]], axis=0)
        self._last = command
        controls = host_samples(controls, self.jax_float64)  # JAX: the first samples only
        plan = MPPIPlan(command, sequence, costs, weights, self.status, pose.copy(), controls)
        self.last_plan = plan
        return plan

    def _smooth(self, sequence: np.ndarray) -> np.ndarray:
        if self._savgol is None:
            return sequence
        if isinstance(self._savgol, tuple):
            window, order = self._savgol
            return savgol_filter(sequence, window, order, axis=0, mode="interp")
        return self._savgol @ sequence

    def predict(
        self, plan: MPPIPlan | None = None, controls: ArrayLike | None = None
    ) -> np.ndarray:
        """Poses ``(..., T + 1, 3)`` of command sequences rolled out from a plan's pose.

        Parameters
        ----------
        plan : MPPIPlan, optional
            The plan (default: the last one).
        controls : array_like, shape (T, m) or (K, T, m), optional
            Sequences to roll out (default: the plan's optimal one), e.g. a few samples for a
            fan of rollouts.

        Returns
        -------
        numpy.ndarray
        """
        plan = self.last_plan if plan is None else plan
        if plan is None:
            raise InputError("predict needs a plan: call the controller first")
        seq = plan.controls if controls is None else as_float_array("controls", controls, self.nu)
        many = seq.ndim == 3
        poses = rollout(self, plan.pose, seq if many else seq[None])
        return poses if many else poses[0]


SAVGOL_MATRIX_STEPS = 1024
"""Horizons up to this many steps smooth with a precomputed T × T matrix (8 MB at 1024)."""
