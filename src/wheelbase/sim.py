"""The closed loop: controller → plant → encoders → odometry → controller, step by step.

:func:`run_loop` is the plain-data core of :func:`wheelbase.run`: it takes parameters and a
reference, steps the true robot with the integrators of :mod:`wheelbase.integrate`, measures the
wheels with encoders, estimates the pose by odometry, asks the controller for a command from that
estimate, and records everything in a :class:`Log`. It stops when the robot has arrived at the
goal (within tolerance and at rest), when the footprint collides with the map, or at the time
limit; the status says which. It never raises for what happens during a run: a collision is an
outcome, not an exception.

The true robot and its odometry
-------------------------------
The controller commands (v, ω) (differential drive, unicycle) or (v, δ) (steered models); the
model turns that into a body twist. The encoders sit on the wheels of the axle through the
reference point (the two drive wheels of a differential drive, the rear wheels of a car), so the
true wheel rates are ω_{L,R} = (u ∓ d_true·r)/a_{L,R,true} for every model. Odometry turns their
ticks back into a pose with the *nominal* radius and half track: the difference between the true
and the nominal geometry is the systematic odometry error (Borenstein's E_d, E_b); encoder noise
is the random one.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from wheelbase._io import write_csv
from wheelbase._validate import as_float_array, positive
from wheelbase.errors import InputError
from wheelbase.geometry import wrap_angle
from wheelbase.integrate import integrate_step
from wheelbase.models.base import KinematicModel

__all__ = ["STATUSES", "Log", "OdometrySetup", "run_loop"]

STATUSES = ("arrived", "missed_goal", "collision", "timeout", "diverged")


@dataclass(frozen=True)
class OdometrySetup:
    """Wheel encoders and the odometry that reads them, plus the true wheel geometry.

    Parameters
    ----------
    wheel_radius : float
        Nominal wheel radius of the encoder axle [m].
    half_track : float
        Nominal half distance between the encoder wheels [m].
    encoder : object or None
        A :class:`wheelbase.odometry.Encoder`; ``None`` feeds the true pose to the controller
        (perfect state), while wheel angles and ticks are still logged.
    odometry : object or None
        A :class:`wheelbase.odometry.WheelOdometry` reading the encoder; required with
        ``encoder``.
    radius_scale : tuple of float
        True (left, right) wheel radius divided by the nominal one.
    track_scale : float
        True track divided by the nominal one.
    seed : int
        Seed of the encoder noise.
    """

    wheel_radius: float
    half_track: float
    encoder: Any = None
    odometry: Any = None
    radius_scale: tuple[float, float] = (1.0, 1.0)
    track_scale: float = 1.0
    seed: int = 0

    def __post_init__(self) -> None:
        positive("wheel_radius", self.wheel_radius, "m")
        positive("half_track", self.half_track, "m")
        positive("track_scale", self.track_scale)
        for value in self.radius_scale:
            positive("radius_scale", value)
        if (self.encoder is None) != (self.odometry is None):
            raise InputError("give both encoder and odometry, or neither (perfect state)")

    def true_wheel_rates(self, twist: np.ndarray) -> np.ndarray:
        """True wheel angular rates (left, right) [rad/s] for a body twist (u, v, r)."""
        half = self.half_track * self.track_scale
        u, r = twist[..., 0], twist[..., 2]
        radii = self.wheel_radius * np.asarray(self.radius_scale)
        return np.stack([(u - half * r) / radii[0], (u + half * r) / radii[1]], -1)

    def true_twist(self, wheel_rates: np.ndarray) -> np.ndarray:
        """Body twist that true wheel rates (left, right) produce (inverse of the above)."""
        half = self.half_track * self.track_scale
        radii = self.wheel_radius * np.asarray(self.radius_scale)
        left, right = wheel_rates[..., 0] * radii[0], wheel_rates[..., 1] * radii[1]
        return np.stack(
            [0.5 * (left + right), np.zeros_like(left), 0.5 * (right - left) / half], -1
        )


@dataclass(frozen=True)
class Log:
    """Everything a closed-loop run recorded, one row per control step.

    Attributes
    ----------
    t : numpy.ndarray, shape (T,)
        Times [s].
    true_pose, estimated_pose, reference_pose : numpy.ndarray, shape (T, 3)
        True pose, the controller's estimate, and the reference at each time [m, m, rad].
    command : numpy.ndarray, shape (T, 2)
        Controller output ((v, ω) or (v, δ), or wheel torques (left, right) [N·m]).
    wheel_rates : numpy.ndarray, shape (T, 2)
        True wheel angular rates (left, right) [rad/s] of the encoder axle.
    ticks : numpy.ndarray of int64, shape (T, 2)
        Cumulative encoder counts (left, right) (zeros with perfect state).
    torques : numpy.ndarray, shape (T, 2) or None
        Wheel torques (left, right) [N·m] on a dynamic plant.
    command_names : tuple of str
        Names of the command columns.
    status : str
        One of :data:`STATUSES`.
    controller_statuses : dict of str to int
        How many steps a controller that reports a ``status`` (MPPI: ``ok``, ``all_collide``,
        ``arrived``) reported each one.
    rollout_fans : dict of int to numpy.ndarray
        For a sampling controller (MPPI), some of its sampled rollouts ``(K, H + 1, 2)`` [m]
        at a few steps (key: row of the log), for drawing.
    """

    t: np.ndarray
    true_pose: np.ndarray
    estimated_pose: np.ndarray
    reference_pose: np.ndarray
    command: np.ndarray
    wheel_rates: np.ndarray
    ticks: np.ndarray
    torques: np.ndarray | None = None
    command_names: tuple[str, ...] = ("v", "omega")
    status: str = "timeout"
    extras: dict[str, np.ndarray] = field(default_factory=dict)
    controller_statuses: dict[str, int] = field(default_factory=dict)
    rollout_fans: dict[int, np.ndarray] = field(default_factory=dict)

    def columns(self) -> dict[str, np.ndarray]:
        """The log as named columns (what :meth:`to_csv` writes)."""
        out = {"t": self.t}
        for prefix, array in (
            ("true", self.true_pose),
            ("est", self.estimated_pose),
            ("ref", self.reference_pose),
        ):
            for index, axis in enumerate(("x", "y", "theta")):
                out[f"{prefix}_{axis}"] = array[:, index]
        for index, name in enumerate(self.command_names):
            out[f"cmd_{name}"] = self.command[:, index]
        out["wheel_rate_left"], out["wheel_rate_right"] = self.wheel_rates.T
        if self.torques is not None:
            out["torque_left"], out["torque_right"] = self.torques.T
        out["ticks_left"], out["ticks_right"] = self.ticks.T
        out.update(self.extras)
        return out

    def to_csv(self, path: str | Path, *, overwrite: bool = False) -> Path:
        """Write :meth:`columns` to a CSV file.

        Parameters
        ----------
        path : str or Path
            Output file.
        overwrite : bool
            Replace an existing file (default: raise FileExistsError).
        """
        return write_csv(path, self.columns(), overwrite=overwrite)


Controller = Callable[[float, np.ndarray, Any], np.ndarray]


def run_loop(
    model: KinematicModel,
    controller: Controller,
    reference: Any,
    pose0: ArrayLike,
    *,
    dt: float,
    duration: float,
    command_to_inputs: Callable[[np.ndarray], np.ndarray],
    odometry: OdometrySetup,
    reference_pose: Callable[[float], np.ndarray],
    goal: ArrayLike,
    tolerance: tuple[float, float] = (0.05, math.radians(5.0)),
    in_collision: Callable[[np.ndarray], bool] | None = None,
    command_names: tuple[str, ...] = ("v", "omega"),
    integrator: str = "rk4",
    end_time: float = 0.0,
    settle_time: float = 0.0,
    progress: Callable[[float], None] | None = None,
    dynamics: Any = None,
    fan_every: int = 0,
    fan_size: int = 20,
) -> Log:
    """Run a closed loop from ``pose0`` until arrival, collision or ``duration``.

    The run ends ``arrived`` when, after ``end_time``, the robot has (nearly) stopped and its
    *estimated* pose is within tolerance of the goal — a robot stops when it believes it is
    there — and the true pose is too; ``missed_goal`` when only the estimate is (odometry
    drift); ``collision`` when the footprint touches an obstacle; ``timeout`` at the time
    limit; ``diverged`` on a non-finite command.

    Parameters
    ----------
    model : KinematicModel
        The robot's kinematics; the plant integrates its twist with ``integrator``.
    controller : callable
        ``controller(t, estimated_pose, reference) -> command`` (shape (2,)).
    reference : object
        Passed to the controller unchanged (a trajectory, path or goal).
    pose0 : array_like, shape (3,)
        True start pose [m, m, rad]; odometry starts from it too.
    dt : float
        Control and integration step [s].
    duration : float
        Time limit [s].
    command_to_inputs : callable
        Maps a command to the model's inputs (e.g. (v, ω) → wheel speeds).
    odometry : OdometrySetup
        Encoders, odometry and the true wheel geometry.
    reference_pose : callable
        ``reference_pose(t) -> (3,)``: the pose the controller should be at (for the log).
    goal : array_like, shape (3,)
        Final pose [m, m, rad].
    tolerance : tuple of float
        Arrival tolerance (position [m], heading [rad]); the robot must also be at rest
        (forward speed below 1 cm/s) once the reference has ended.
    in_collision : callable, optional
        ``in_collision(pose) -> bool``; a collision ends the run with status ``collision``.
    command_names : tuple of str
        Names of the two command components, for the log.
    integrator : str
        Integration method for the plant (:data:`wheelbase.integrate.METHODS`).
    end_time : float
        When the reference ends [s]: arrival is only judged after it.
    settle_time : float
        Time after ``end_time`` during which the robot may still converge [s];
        the run ends as ``timeout`` when it has not arrived by then.
    progress : callable, optional
        Called with the simulated time now and then (for progress bars).
    dynamics : DiffDriveDynamics, optional
        A dynamic plant: the controller then returns wheel torques (left, right) [N·m] and is
        called with the estimated state (x, y, θ, u, v, r) of shape (6,) — the twist estimated
        from the encoder ticks of the last step (or the true one with perfect state); the
        state (pose, twist) is integrated with RK4 under torques held over the step, from rest.
    fan_every : int
        Every this many steps (0: never), keep ``fan_size`` of the sampled rollouts of a
        controller that has them (``last_plan.samples`` and ``predict``, as MPPI).
    fan_size : int
        Rollouts kept per fan.

    Returns
    -------
    Log
        The recorded run and its status.
    """
    dt = positive("dt", dt, "s")
    duration = positive("duration", duration, "s")
    pose = as_float_array("pose0", pose0, 3, max_ndim=1).copy()
    goal = as_float_array("goal", goal, 3, max_ndim=1)
    n_max = math.ceil(duration / dt - 1e-9)
    estimate = pose.copy()
    wheel_angle = np.zeros(2)
    ticks = np.zeros(2, dtype=np.int64)
    rng = np.random.default_rng(odometry.seed)
    use_encoders = odometry.encoder is not None

    rows_t, rows_true, rows_est, rows_ref = [], [], [], []
    rows_cmd, rows_rates, rows_ticks = [], [], []
    twist_true = np.zeros(3)
    statuses: dict[str, int] = {}
    nominal = OdometrySetup(odometry.wheel_radius, odometry.half_track)
    geometry_error = odometry.radius_scale != (1.0, 1.0) or odometry.track_scale != 1.0
    fans: dict[int, np.ndarray] = {}
    twist_estimate = np.zeros(3)
    status = "timeout"
    limit = min(duration, end_time + settle_time) if settle_time > 0 else duration

    for step in range(n_max + 1):
        t = step * dt
        measured = estimate if dynamics is None else np.concatenate([estimate, twist_estimate])
        command = np.asarray(controller(t, measured.copy(), reference), dtype=np.float64)
        if fan_every > 0 and step % fan_every == 0:
            plan = getattr(controller, "last_plan", None)
            if plan is not None and getattr(plan, "samples", None) is not None:
                rollouts = controller.predict(plan, plan.samples[:fan_size])
                fans[len(rows_t)] = np.asarray(rollouts)[..., :2]
        reported = getattr(controller, "status", None)
        if isinstance(reported, str):
            statuses[reported] = statuses.get(reported, 0) + 1
        if command.shape != (2,) or not np.all(np.isfinite(command)):
            status = "diverged"
            command = np.zeros(2)
        if dynamics is not None:
            twist = twist_true
            rates = odometry.true_wheel_rates(twist)
        else:
            # The command was computed for the nominal geometry: the wheels turn at the rates
            # the nominal geometry asks for, and the true geometry decides the motion.
            twist = np.asarray(model.twist(command_to_inputs(command)), dtype=np.float64)
            rates = nominal.true_wheel_rates(twist)
            if geometry_error:
                twist = odometry.true_twist(rates)

        rows_t.append(t)
        rows_true.append(pose.copy())
        rows_est.append(estimate.copy())
        rows_ref.append(np.asarray(reference_pose(t), dtype=np.float64))
        rows_cmd.append(command)
        rows_rates.append(rates)
        rows_ticks.append(ticks.copy())
        if progress is not None and step % 200 == 0:
            progress(t)
        if status == "diverged":
            break
        if in_collision is not None and in_collision(pose):
            status = "collision"
            break
        if t >= end_time and abs(twist[0]) < 0.01 and _arrived(estimate, goal, tolerance):
            # The robot stops when it believes it has arrived; the truth may differ.
            status = "arrived" if _arrived(pose, goal, tolerance) else "missed_goal"
            break
        if step == n_max or t >= limit:
            break

        if dynamics is None:
            pose = integrate_step(pose, twist, twist, twist, dt, integrator)
            new_angle = wheel_angle + rates * dt
        else:
            state = dynamics.step(np.concatenate([pose, twist_true]), command, dt)
            pose, twist_true = state[:3], state[3:]
            pose[2] = wrap_angle(pose[2])
            # The wheels turn by the integral of their rate: trapezoid of the step's two ends.
            new_angle = wheel_angle + 0.5 * (rates + odometry.true_wheel_rates(twist_true)) * dt
        if use_encoders:
            delta = odometry.encoder.tick_deltas(wheel_angle, new_angle, rng)
            ticks = ticks + delta
            estimate = odometry.odometry.update(estimate, delta)
            v_est, w_est = odometry.odometry.velocity(delta, dt)
            twist_estimate = np.array([float(v_est), 0.0, float(w_est)])
        else:
            estimate = pose.copy()
            twist_estimate = twist_true.copy()
        wheel_angle = new_angle

    if progress is not None:
        progress(rows_t[-1])
    commands = np.asarray(rows_cmd)
    return Log(
        t=np.asarray(rows_t),
        true_pose=np.asarray(rows_true),
        estimated_pose=np.asarray(rows_est),
        reference_pose=np.asarray(rows_ref),
        command=commands,
        wheel_rates=np.asarray(rows_rates),
        ticks=np.asarray(rows_ticks, dtype=np.int64),
        torques=commands if dynamics is not None else None,
        command_names=command_names,
        status=status,
        controller_statuses=statuses,
        rollout_fans=fans,
    )


def _arrived(pose: np.ndarray, goal: np.ndarray, tolerance: tuple[float, float]) -> bool:
    distance = math.hypot(pose[0] - goal[0], pose[1] - goal[1])
    return distance <= tolerance[0] and abs(wrap_angle(pose[2] - goal[2])) <= tolerance[1]
