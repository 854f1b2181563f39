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
warm start is cleared and :attr:`MPPI.status` is ``"all_collide"``.

Backends: ``numpy`` (the reference, in this module; noise from ``numpy.random.Generator``),
``numba`` (:mod:`wheelbase.control.mppi_numba`: one parallel compiled loop that draws the noise,
rolls each sample out and scores it, ``cache=True``; its noise comes from a counter-based
SplitMix64 stream keyed by (seed, call, sample, step) through an inverse-CDF table, so it does
not depend on the threads), ``jax`` (:mod:`wheelbase.control.mppi_jax`: ``jax.jit`` +
``lax.scan`` over the horizon; float32 by default, float64 with ``jax_float64=True``; install
``wheelbase[jax]``).
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
from dataclasses import dataclass
from dataclasses import fields as dataclass_fields
from typing import Any, ClassVar

import numpy as np
from numpy.typing import ArrayLike
from scipy.signal import savgol_filter

from wheelbase._jax import X64, import_jax
from wheelbase._validate import as_float_array, check_choice, count_text, flag, integer, positive
from wheelbase.control.base import (
    HOLONOMIC_COMMAND,
    STEERING_COMMAND,
    VELOCITY_COMMAND,
    SteeringLimits,
    VelocityLimits,
)
from wheelbase.control.mppi_critics import MPPICritics, PathTables
from wheelbase.control.mppi_jax import jax_function
from wheelbase.control.mppi_numba import (
    KIND_FRONT,
    KIND_HOLONOMIC,
    KIND_REAR,
    KIND_VELOCITY,
    NORMAL_TABLE,
    mppi_kernel,
)
from wheelbase.control.path import _as_polyline, path_key, same_path
from wheelbase.errors import ConfigError, InputError
from wheelbase.geometry import wrap_angle
from wheelbase.integrate import integrate_step
from wheelbase.limits import MAX_COORDINATE, MAX_SAMPLE_STEPS

__all__ = ["MPPI", "MPPI_BACKENDS", "MPPICritics", "MPPIPlan"]

MPPI_BACKENDS: tuple[str, ...] = ("numpy", "numba", "jax")
STATUSES: tuple[str, ...] = ("ok", "all_collide", "arrived")


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
        ``"ok"`` or ``"all_collide"``.
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
        One of :data:`MPPI_BACKENDS`.
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
        :attr:`status` is ``"arrived"``.
    cusp_tolerance : float
        Distance [m] to a cusp at which the next path section becomes active.
    jax_float64 : bool
        Run the ``jax`` backend in float64 (default float32).
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
        backend: str = "numpy",
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
        self._kind, self._wheel_base = _model_kind(model)
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
        self.command_names = {
            KIND_VELOCITY: VELOCITY_COMMAND, KIND_HOLONOMIC: HOLONOMIC_COMMAND,
        }.get(self._kind, STEERING_COMMAND)  # fmt: skip
        self._lo, self._hi = self._bounds(limits)
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
        self._set_map(grid, footprint)
        if self.backend == "jax":
            import_jax()
        reach = self.horizon_steps * self.dt * float(self._hi[0])
        if reach > MAX_COORDINATE:
            raise ConfigError(
                f"the horizon reaches {reach:.3g} m (horizon_steps × dt × max_speed): more than "
                f"{MAX_COORDINATE:g} m, beyond which the rollouts' costs overflow; use a smaller dt"
            )
        ahead = 1.2 * reach + 2.0 * self.path_spacing
        # points of the path window: the reach of the horizon, cut to the path (see _path_tables)
        self._reach_points = math.ceil(min(ahead / self.path_spacing, 1e12)) + 1
        self._window_points = self._reach_points
        self._tables: tuple[object, PathTables, tuple] | None = None
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
        options = dict(gains)
        critic_names = {f.name for f in dataclass_fields(MPPICritics)}
        critics = options.pop("critics", None) or {}
        if not isinstance(critics, dict):
            raise ConfigError(f"critics must be a mapping of weights (got {critics!r})")
        critics = dict(critics)
        for name in list(options):
            if name in critic_names:
                critics[name] = options.pop(name)
        max_speed = options.pop("max_speed", 0.5)
        max_yaw_rate = options.pop("max_yaw_rate", 1.5)
        kind, _base = _model_kind(model)
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

    # ------------------------------------------------------------------ set-up
    def _bounds(self, limits: Any) -> tuple[np.ndarray, np.ndarray]:
        if self._kind in (KIND_VELOCITY, KIND_HOLONOMIC):
            if not isinstance(limits, VelocityLimits):
                raise ConfigError(
                    "limits must be VelocityLimits for (v, ω) or (vx, vy, ω) commands"
                )
            # a holonomic base: |v_y| is bounded by max_speed as |v_x| is
            speeds = [limits.max_speed] * (self.nu - 1)
            top = np.array([*speeds, limits.max_yaw_rate])
        else:
            if not isinstance(limits, SteeringLimits):
                raise ConfigError("limits must be SteeringLimits for (v, δ) commands")
            steer = min(limits.max_steering, float(self.model.max_steering))
            top = np.array([limits.max_speed, steer])
        if not np.all(np.isfinite(top)):
            raise ConfigError(f"MPPI needs finite command limits (got {top.tolist()})")
        low = -top.copy()
        if not self.allow_reverse:
            low[0] = 0.0
        return low, top

    def _set_map(self, grid: Any, footprint: Any) -> None:
        self.grid = grid
        if grid is None:
            self._df = np.zeros((1, 1))
            self._map = np.array([0.0, 0.0, 1.0, 0.0])  # x0, y0, resolution, enabled
        else:
            self._df = np.ascontiguousarray(np.minimum(grid.distance_field, 1.0e3))
            self._map = np.array([grid.origin[0], grid.origin[1], grid.resolution, 1.0])
        # Disks (x, y, radius) in the body frame whose clearance is the footprint's.
        if footprint is not None:
            _check_disk_count(footprint)
        if footprint is None:
            self._circles = np.zeros((1, 3))
        elif footprint.circle_overshoot > 0.25:
            # A long outline (a car): the covering circles would see a wall 0.5 m early.
            self._circles = footprint.outline_circles(OUTLINE_SPACING)
        else:
            circles = np.asarray(footprint.circles, dtype=np.float64)
            radius = np.full((len(circles), 1), float(footprint.circle_radius))
            self._circles = np.ascontiguousarray(np.hstack([circles, radius]))
        self.footprint = footprint
        self._jax_map: tuple | None = None  # the map on the JAX device, made at the first call

    def reset(self) -> None:
        """Forget the warm start, the path progress and the noise counter."""
        self._mean = np.zeros((self.horizon_steps, self.nu))
        self._mean[:, 0] = np.clip(0.0, self._lo[0], self._hi[0])
        self._last = np.zeros(self.nu)
        self._progress: int | None = None
        self._section = 0
        self._calls = 0
        self._rng = np.random.default_rng(self.seed)
        self.status = "ok"
        self.last_plan: MPPIPlan | None = None

    # ------------------------------------------------------------------ call
    def __call__(self, t: float, pose: ArrayLike, reference: Any) -> np.ndarray:
        """Command for the measured pose, following the reference path.

        Parameters
        ----------
        t : float
            Time [s] (unused: the path is followed by position).
        pose : array_like, shape (3,) or (1, 3)
            Measured pose (x [m], y [m], θ [rad]).
        reference : PlannedPath or array_like (M, 2)
            The reference path (a planned path's directions mark reversing sections).

        Returns
        -------
        numpy.ndarray
            Command of shape (m,) or (1, m) like ``pose`` (m = 2, or 3 for a holonomic base).
        """
        array = as_float_array("pose", pose, 3, min_ndim=1, max_ndim=2)
        if array.ndim == 2 and array.shape[0] != 1:
            raise InputError(f"MPPI controls one robot: pose (3,) or (1, 3) (got {array.shape})")
        plan = self.plan(array.reshape(3), reference)
        return plan.command.reshape((*array.shape[:-1], self.nu))

    def plan(self, pose: ArrayLike, reference: Any, noise: ArrayLike | None = None) -> MPPIPlan:
        """One MPPI iteration from ``pose``; updates the warm start.

        Parameters
        ----------
        pose : array_like, shape (3,)
            Measured pose (x [m], y [m], θ [rad]).
        reference : PlannedPath or array_like (M, 2)
            The reference path.
        noise : array_like, shape (K, T, m), optional
            The perturbations ε to use instead of drawing them (cross-backend checks).

        Returns
        -------
        MPPIPlan
        """
        pose = as_float_array("pose", pose, 3, min_ndim=1, max_ndim=1).copy()
        pose[2] = float(wrap_angle(pose[2]))  # any finite heading, wrapped on entry
        tables = self._path_tables(reference)
        # The costs are computed relative to the robot: the window, the goal and the map origin
        # are shifted by its position, so the backends see the same numbers anywhere (float32
        # keeps 0.5 km at 4.5e9 m absolute, and float64 only micrometres).
        window, info = self._window(pose, tables)
        local = np.array([0.0, 0.0, pose[2]])
        local_map = self._map.copy()
        local_map[:2] -= pose[:2]
        last_section = self._section == tables.n_sections - 1
        settling = last_section and info[0] > 0.5  # within goal_distance of the goal
        if settling:
            gap = math.hypot(info[1], info[2])
            turn = abs(float(wrap_angle(pose[2] - info[3])))
            if gap <= self.goal_tolerance[0] and turn <= self.goal_tolerance[1]:
                return self._stop(pose, "arrived")
        weights = self.critics.vector()
        if last_section and info[5] <= self.critics.near_goal_distance:
            weights[5] = 0.0  # obstacle repulsion off near the goal (collisions stay lethal)
        blocked = self._path_blocked(window, local_map)
        if self._map[3] > 0.5:
            # Where the critics already see the footprint in collision (their clearance is
            # conservative by a cell diagonal and the disks' overshoot; a planned path may pass
            # closer), every rollout would be lethal and the robot frozen for good: then only
            # rollouts that get deeper than now (by 1 cm) count as collisions. A footprint that
            # truly overlaps an obstacle keeps every rollout lethal: a safe stop.
            now, _ = self._clearance(local, mp=local_map)
            if now <= 0.0 and not self._truly_colliding(pose):
                info[6] = float(now) - 0.01
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
        lo, hi = self._call_bounds(info, blocked, settling)
        args = (local, mean, lo, hi, self._hi, window, info, self._last, weights)
        if self.backend == "numpy":
            if noise is None:
                noise = self._rng.standard_normal((self.samples, self.horizon_steps, self.nu))
                noise *= self.noise_std
            costs, controls = self._costs_numpy(*args, noise, local_map)
        elif self.backend == "numba":
            has_noise = noise is not None
            buffer = np.ascontiguousarray(noise) if has_noise else np.zeros((1, 1, self.nu))
            costs = np.empty(self.samples)
            controls = np.empty((self.samples, self.horizon_steps, self.nu))
            mppi_kernel(
                local, mean, lo, hi, self._hi, window, info, self._last, buffer, has_noise,
                self.noise_std, np.uint64(self.seed), np.uint64(self._calls), self._kind,
                self._wheel_base, self.dt, weights, self._df, local_map, self._circles,
                int(self.critics.path_stride), NORMAL_TABLE, costs, controls,
            )  # fmt: skip
        else:
            costs, controls = self._costs_jax(*args, noise, local_map)
        self._calls += 1
        if self.critics.extra is not None:
            controls = np.asarray(controls, np.float64)  # the user's critic is NumPy code
            extra = np.asarray(
                self.critics.extra(self._rollout_many(pose, controls), controls), np.float64
            )
            if extra.shape != (self.samples,):
                raise InputError(
                    f"extra critic must return shape ({self.samples},) (got {extra.shape})"
                )
            costs = costs + np.where(np.isfinite(extra), np.maximum(extra, 0.0), 1e6)
        return self._update(pose, costs, controls, lo, hi)

    def _call_bounds(
        self, info: np.ndarray, blocked: bool, settling: bool
    ) -> tuple[np.ndarray, np.ndarray]:
        """Command bounds of this call: the speed keeps the sign of the path section unless
        ``reverse_against_path``, the path ahead is blocked, the last call found every rollout
        colliding, or the robot is settling at the goal (where a small correction backwards may
        be needed). Sampling both signs where the optimum
        is about zero makes the weighted mean flip sign: the robot would twitch back and forth."""
        lo, hi = self._lo.copy(), self._hi.copy()
        # Slow down into cusps and the goal: |v| <= √(2·a·d), d the distance left to the
        # section's end, as the time parametrisation of the path does (floor: 10 % of top speed).
        cap = max(math.sqrt(2.0 * self.approach_deceleration * info[5]), 0.1 * hi[0])
        speeds = self.nu - 1  # v, or v_x and v_y of a holonomic base
        lo[:speeds], hi[:speeds] = np.maximum(lo[:speeds], -cap), np.minimum(hi[:speeds], cap)
        # After a call where every rollout collided, both signs: backing off may be the way out.
        recovering = self.status == "all_collide"
        free = self.reverse_against_path or self._kind == KIND_HOLONOMIC  # holonomic: any way
        if free or blocked or settling or recovering or not self.allow_reverse:
            return lo, hi
        if info[4] > 0.0:
            lo[0] = 0.0
        else:
            hi[0] = 0.0
        return lo, hi

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
    ) -> MPPIPlan:
        best = float(np.min(costs))
        with np.errstate(over="ignore", under="ignore"):  # exp(−inf) = 0: the intended limit
            weights = np.exp(-(costs - best) / self.temperature)
        weights /= np.sum(weights)
        if best >= self.critics.collision_cost:
            self.status = "all_collide"
            command = np.zeros(self.nu)
            sequence = np.zeros_like(self._mean)
            self._mean = np.zeros_like(self._mean)
            self._mean[:, 0] = np.clip(0.0, self._lo[0], self._hi[0])
        else:
            self.status = "ok"
            sequence = _weighted_mean(weights, controls, self.jax_float64)
            sequence = self._clip(self._smooth(sequence), lo, hi)  # this call's bounds
            command = sequence[0].copy()
            self._mean = np.concatenate([sequence[1:], sequence[-1:]], axis=0)
        self._last = command
        if not isinstance(controls, np.ndarray):  # JAX: keep the first samples on the host
            jax, _jnp = import_jax()
            with X64(jax, self.jax_float64):
                controls = np.asarray(controls[:KEPT_DEVICE_SAMPLES], np.float64)
        plan = MPPIPlan(command, sequence, costs, weights, self.status, pose.copy(), controls)
        self.last_plan = plan
        return plan

    def _clip(self, controls: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
        """Commands clipped to the bounds; a holonomic base's (v_x, v_y) also to the disk of
        radius ``hi[0]``: its speed limit holds in every direction (a box would let it go √2
        faster diagonally, and the progress critic would turn it 45° to do so)."""
        out = np.clip(controls, lo, hi)
        if self._kind == KIND_HOLONOMIC:
            speed = np.hypot(out[..., 0], out[..., 1])
            with np.errstate(divide="ignore", invalid="ignore"):
                scale = np.where(speed > hi[0], hi[0] / speed, 1.0)
            out[..., :2] *= scale[..., None]
        return out

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
        poses = self._rollout_many(plan.pose, seq if many else seq[None])
        return poses if many else poses[0]

    # ------------------------------------------------------------------ path
    def _path_tables(self, reference: Any) -> PathTables:
        # The path is known by its content, not by the object: a caller that builds a fresh
        # array on every call keeps its progress along the path (and its cusp section).
        if self._tables is not None and self._tables[0] is reference:
            return self._tables[1]
        line = _as_polyline(reference)
        key = path_key(line, reference)
        if self._tables is not None and same_path(self._tables[2], key):
            self._tables = (reference, self._tables[1], self._tables[2])
            return self._tables[1]
        points = np.asarray(line.points)
        self._anchor = points[0].copy()  # the tables' origin: their numbers stay small
        tables = PathTables(
            points - self._anchor, np.asarray(line.directions), self.path_spacing, key[2]
        )
        self._tables = (reference, tables, key)
        # A window never holds more points than the path (a huge dt reaches 1e6 m ahead).
        self._window_points = min(self._reach_points, len(tables.xy) + 1)
        self._progress, self._section = None, 0
        return tables

    def _window(self, pose: np.ndarray, tab: PathTables) -> tuple[np.ndarray, np.ndarray]:
        """The local path window (M, 4) = (x, y, heading, arc length from its first point) and the
        scalars the critics need: (goal mode 0/1, section end x, y, heading, direction ±1,
        distance left to it [m], collision relief [m]); positions relative to the robot."""
        rel = pose[:2] - self._anchor  # the robot in the tables' frame
        end = int(tab.section_end[self._section])
        start = 0 if self._section == 0 else int(tab.section_end[self._section - 1])
        if self._progress is None:
            lo, hi = start, end + 1
        else:
            lo = max(start, self._progress - 10)
            hi = min(end + 1, self._progress + 4 * self._window_points)
        d2 = np.sum((tab.xy[lo:hi] - rel) ** 2, axis=1)
        index = lo + int(np.argmin(d2))
        if self._progress is None:
            # First call: the earliest point about as near as the nearest one (a closed path
            # starts where it ends: begin at its start, not at its end).
            near = np.sqrt(d2) <= np.sqrt(d2[index - lo]) + 0.1
            index = lo + int(np.argmax(near))
        self._progress = max(index, self._progress or 0) if self._progress is not None else index
        last_section = self._section == tab.n_sections - 1
        if not last_section and self._reached_cusp(pose, tab, end):
            self._section += 1
            self._progress = end
            return self._window(pose, tab)
        stop = min(self._progress + self._window_points, end + 1)
        idx = np.arange(self._progress, self._progress + self._window_points)
        idx = np.minimum(idx, stop - 1)
        along = tab.arc[idx] - tab.arc[self._progress]
        window = np.stack(
            [tab.xy[idx, 0] - rel[0], tab.xy[idx, 1] - rel[1], tab.heading[idx], along], -1
        )
        remaining = tab.arc[end] - tab.arc[self._progress]
        goal_mode = 1.0 if remaining <= self.critics.goal_distance else 0.0
        info = np.array(
            [
                goal_mode,
                tab.xy[end, 0] - rel[0],
                tab.xy[end, 1] - rel[1],
                tab.heading[end],
                tab.direction[end],
                # distance left to the section's end: along the path, or straight if farther
                max(remaining, float(np.hypot(*(tab.xy[end] - rel)))),
                0.0,  # collision relief, set by ``plan``
            ]
        )
        return np.ascontiguousarray(window), info

    def _reached_cusp(self, pose: np.ndarray, tab: PathTables, end: int) -> bool:
        """Within ``cusp_tolerance`` of the cusp, or past the line through it square to the path
        while within ``goal_distance`` of it (as the path followers switch): a car that cannot
        close the last few centimetres sideways must not stall before the cusp."""
        offset = pose[:2] - self._anchor - tab.xy[end]
        distance = float(np.hypot(*offset))
        if distance <= self.cusp_tolerance:
            return True
        if distance > self.critics.goal_distance or end == 0:
            return False
        incoming = tab.xy[end] - tab.xy[end - 1]
        return float(offset @ incoming) >= 0.0

    def _path_blocked(self, window: np.ndarray, mp: np.ndarray) -> bool:
        """Whether more than 7 % of the window's poses put the footprint in collision (Nav2's
        ``max_path_occupancy_ratio``): the path critics are then switched off for this call."""
        if self._map[3] < 0.5:
            return False
        _clearance, collided = self._clearance(window[:, :3], mp=mp)
        return bool(np.mean(collided) > 0.07)

    def _truly_colliding(self, pose: np.ndarray) -> bool:
        """Whether the exact footprint (or the point) overlaps an obstacle or leaves the map."""
        if self.footprint is None:
            inside = bool(self.grid.contains(pose[None, :2])[0])
            return not inside or bool(self.grid.is_occupied(pose[None, :2])[0])
        return bool(np.asarray(self.grid.in_collision(self.footprint, pose[None])).reshape(-1)[0])

    def _clearance(
        self, poses: np.ndarray, relief: float = 0.0, mp: np.ndarray | None = None
    ) -> tuple[np.ndarray, np.ndarray]:
        """The critics' footprint clearance [m] of poses ``(..., 3)`` (the least over the disks
        of distance field − disk radius − √2·cell − ``relief``; 0 off the map) and whether each
        is in collision (<= 0 or off the map)."""
        x0, y0, res = (self._map if mp is None else mp)[:3]
        cos, sin = np.cos(poses[..., 2]), np.sin(poses[..., 2])
        rows, cols = self._df.shape
        collided = np.zeros(poses.shape[:-1], bool)
        clearance = np.full(poses.shape[:-1], np.inf)
        for cx, cy, radius in self._circles:
            px = poses[..., 0] + cos * cx - sin * cy
            py = poses[..., 1] + sin * cx + cos * cy
            col = np.floor((px - x0) / res).astype(np.int64)
            row = np.floor((py - y0) / res).astype(np.int64)
            inside = (row >= 0) & (row < rows) & (col >= 0) & (col < cols)
            field = self._df[np.clip(row, 0, rows - 1), np.clip(col, 0, cols - 1)]
            clear = field - radius - math.sqrt(2.0) * res - relief
            collided |= ~inside | (clear <= 0.0)
            clearance = np.minimum(clearance, np.where(inside, clear, 0.0))
        return clearance, collided

    # ------------------------------------------------------------------ NumPy reference
    def _twist(self, controls: np.ndarray) -> np.ndarray:
        from wheelbase.control.base import command_to_inputs

        return self.model.twist(command_to_inputs(controls, self.command_names, self.model))

    def _rollout_many(self, pose: np.ndarray, controls: np.ndarray) -> np.ndarray:
        n, steps = controls.shape[:2]
        twist = self._twist(controls)
        poses = np.empty((n, steps + 1, 3))
        poses[:, 0] = pose
        for t in range(steps):
            z = twist[:, t]
            poses[:, t + 1] = integrate_step(poses[:, t], z, z, z, self.dt, "euler")
        return poses

    def _costs_numpy(self, pose, mean, lo, hi, scale, window, info, last, w, noise, mp):
        c = self.critics
        controls = self._clip(mean[None] + noise, lo, hi)
        poses = self._rollout_many(pose, controls)
        after = poses[:, 1:]
        steps = self.horizon_steps
        cost = np.zeros(self.samples)
        goal_mode = info[0] > 0.5
        checked = np.arange(c.path_stride - 1, steps, c.path_stride)
        if checked.size:
            pts = after[:, checked]
            d2 = (pts[..., 0, None] - window[:, 0]) ** 2 + (pts[..., 1, None] - window[:, 1]) ** 2
            nearest = np.argmin(d2, axis=-1)
            dmin = np.take_along_axis(d2, nearest[..., None], -1)[..., 0]
            err = wrap_angle(pts[..., 2] - window[nearest, 2])
            cost += w[0] * np.sum(np.sqrt(dmin), axis=1) / checked.size
            cost += w[1] * np.sum(err * err, axis=1) / checked.size
        if not goal_mode:
            end = after[:, -1]
            d2 = (end[:, 0, None] - window[:, 0]) ** 2 + (end[:, 1, None] - window[:, 1]) ** 2
            cost += c.follow * (window[-1, 3] - window[np.argmin(d2, axis=-1), 3])
        else:
            dist = np.hypot(after[..., 0] - info[1], after[..., 1] - info[2])
            cost += c.goal * np.sum(dist, axis=1) / steps
            cost += c.goal_heading * np.abs(wrap_angle(after[:, -1, 2] - info[3]))
        if self._map[3] > 0.5:
            clearance, collided = self._clearance(after, info[6], mp)
            collided = np.any(collided, axis=1)
            gap = np.where(clearance > 0.0, np.maximum(c.inflation - clearance, 0.0), 0.0)
            cost += w[5] * np.sum(gap * gap, axis=1) / steps
            cost += np.where(collided, c.collision_cost, 0.0)
        v = controls[..., 0]
        cost += c.prefer_forward * np.sum(np.maximum(-info[4] * v, 0.0), axis=1) * self.dt
        cost += c.effort * np.sum((controls / scale) ** 2, axis=(1, 2)) / steps
        previous = np.concatenate(
            [np.broadcast_to(last, (self.samples, 1, self.nu)), controls[:, :-1]], 1
        )
        cost += c.rate * np.sum(((controls - previous) / scale) ** 2, axis=(1, 2)) / steps
        if self._kind in (KIND_VELOCITY, KIND_HOLONOMIC):
            cost += c.twirl * np.sum(np.abs(controls[..., -1]), axis=1) / (steps * scale[-1])
        return cost, controls

    # ------------------------------------------------------------------ JAX
    def _costs_jax(self, pose, mean, lo, hi, scale, window, info, last, w, noise, mp):
        """Costs and sampled commands from the JAX backend; with ``noise=None`` the noise is
        drawn on the device from a key folded from (seed, call)."""
        jax, jnp = import_jax()
        if noise is None and jax.default_backend() == "cpu":
            # NumPy draws normals about twice as fast as XLA's threefry on a CPU; on a GPU the
            # draw stays on the device (no (K, T, m) transfer at every call).
            noise = self._rng.standard_normal((self.samples, self.horizon_steps, self.nu))
            noise *= self.noise_std
        draw = noise is None
        function = jax_function(
            self.horizon_steps, int(self.critics.path_stride), self._kind, self.jax_float64,
            self.samples if draw else None,
        )  # fmt: skip
        dtype = np.float64 if self.jax_float64 else np.float32
        with X64(jax, self.jax_float64):
            if self._jax_map is None or self._jax_map[0] != dtype:
                # The map goes to the device once, not at every call (its origin relative to
                # the robot, four numbers, at every call).
                arrays = (self._df, self._circles)
                self._jax_map = (dtype, *(jnp.asarray(a, dtype=dtype) for a in arrays))
            _, df, circles = self._jax_map
            if draw:
                noise = jax.random.fold_in(jax.random.PRNGKey(self.seed), self._calls)
            else:
                noise = np.asarray(noise, dtype)
            extra = np.array([0.0, self.dt, self._wheel_base, *self.noise_std])
            small = (np.asarray(v, dtype) for v in (pose, mean, lo, hi, scale, window, info, last))
            costs, controls = function(*small, noise, np.asarray(w, dtype), df,
                                       np.asarray(mp, dtype), circles,
                                       np.asarray(extra, dtype))  # fmt: skip
            if jax.default_backend() == "cpu":  # host and device are one: NumPy is quicker
                return np.asarray(costs, np.float64), np.asarray(controls, np.float64)
            # On a GPU the sampled commands stay there: (K, T, m) is 0.9 GB at a million
            # samples in float64; the weighted mean is taken there (see _weighted_mean).
            return np.asarray(costs, np.float64), controls


# --------------------------------------------------------------------------- helpers
KEPT_DEVICE_SAMPLES = 256
"""With the jax backend, :attr:`MPPIPlan.samples` holds the first this many samples (enough for a
fan of rollouts); the others never leave the device."""


def _weighted_mean(weights: np.ndarray, controls: Any, float64: bool) -> np.ndarray:
    """Σ_i w_i V_i, shape (T, m): on the host for NumPy arrays, on the device for JAX arrays
    (only K weights go there and T·m numbers come back), in float64 when ``float64``."""
    if isinstance(controls, np.ndarray):
        return np.tensordot(weights, controls, axes=1)
    jax, jnp = import_jax()
    with X64(jax, float64):
        device_weights = jnp.asarray(weights, dtype=controls.dtype)
        return np.asarray(jnp.tensordot(device_weights, controls, axes=1), np.float64)


MAX_FOOTPRINT_DISKS = 100_000
"""Most disks (outline or covering) a footprint may need: each is checked at every step of every
rollout (a 4.5 × 1.8 m car needs 67; 100,000 is a 10 km outline)."""


def _check_disk_count(footprint: Any) -> None:
    """Refuse a footprint whose disks would not fit in memory or time (a 1e9 m car asked for
    2.2 TiB), before any of them is made."""
    poly = np.asarray(footprint.polygon, dtype=np.float64)
    extent = np.ptp(poly, axis=0)
    long_side, short_side = float(np.max(extent)), float(np.min(extent))
    perimeter = float(np.sum(np.hypot(*(np.roll(poly, -1, axis=0) - poly).T)))
    covering = 2.0 * long_side / short_side if short_side > 0 else math.inf
    count = max(covering, perimeter / OUTLINE_SPACING + covering)
    if not count <= MAX_FOOTPRINT_DISKS:
        raise ConfigError(
            f"footprint ({long_side:.3g} × {short_side:.3g} m) needs {count:.3g} outline disks "
            f"of {OUTLINE_SPACING} m or covering circles: more than {MAX_FOOTPRINT_DISKS}, each "
            "checked at every step of every rollout"
        )


def _model_kind(model: Any) -> tuple[int, float]:
    from wheelbase.models import Bicycle

    names = tuple(getattr(model, "input_names", ()))
    if names in (VELOCITY_COMMAND, ("omega_left", "omega_right")):
        return KIND_VELOCITY, 0.0
    if names == ("u", "v", "r") or getattr(model, "is_holonomic", False):
        return KIND_HOLONOMIC, 0.0
    if names == STEERING_COMMAND:
        front = isinstance(model, Bicycle)
        return (KIND_FRONT if front else KIND_REAR), float(model.wheel_base)
    raise ConfigError(
        "MPPI supports Unicycle, DiffDrive, Bicycle, RearWheelBicycle, Ackermann, BodyTwist "
        f"and holonomic wheeled bases (got {type(model).__name__})"
    )


SAVGOL_MATRIX_STEPS = 1024
"""Horizons up to this many steps smooth with a precomputed T × T matrix (8 MB at 1024)."""

OUTLINE_SPACING = 0.2
"""Spacing [m] of the edge disks that stand for a long footprint (see ``_set_map``)."""
