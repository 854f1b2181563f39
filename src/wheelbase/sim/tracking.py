"""Computed-torque trajectory tracking on the engine (document 000 §5.3), and its tuning.

:func:`track_trajectory` drives the dynamic robot along a
:class:`~wheelbase.models.PoseTrajectory` open loop (the inverse-dynamics torques, figure
5.12/5.13) or with a :class:`~wheelbase.control.ComputedTorquePID` (figures 5.14–5.16);
:func:`tune_computed_torque` picks the PID's bandwidths by running a grid of candidates as one
batch.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike

from wheelbase._validate import as_float_array, nonnegative, positive
from wheelbase.control.torque import (
    ComputedTorquePID,
    InverseDynamicsTorques,
    TimedRows,
    TorqueGains,
)
from wheelbase.dynamics import DiffDriveDynamics, inverse_dynamics
from wheelbase.errors import ConfigError, InputError
from wheelbase.geometry import wrap_angle
from wheelbase.integrate import time_grid
from wheelbase.models.path import PoseTrajectory
from wheelbase.sim.engine import Arrival, Engine
from wheelbase.sim.log import Log, status_code
from wheelbase.sim.plants import DynamicPlant

__all__ = ["track_trajectory", "tune_computed_torque"]


def track_trajectory(
    plant: DiffDriveDynamics,
    reference: PoseTrajectory,
    controller: ComputedTorquePID | None = None,
    *,
    model: DiffDriveDynamics | None = None,
    dt: float = 0.01,
    state0: ArrayLike | None = None,
    t_end: float | None = None,
    tolerance: tuple[float, float] = (0.05, math.radians(5.0)),
) -> Log:
    """Drive ``plant`` along ``reference``: open loop (document 000 §5.3.1) or with a controller.

    A thin use of the engine (:class:`wheelbase.sim.Engine` on a
    :class:`~wheelbase.sim.DynamicPlant`, perfect state): torques are held over each control
    period and the plant is integrated by RK4 with the same step. The reference's end is the
    arrival: a run that reaches it ends ``arrived`` when the robot is within ``tolerance`` of
    the reference's last pose, ``missed_goal`` when it is not (an open loop that drifted
    away); a run stopped earlier by ``t_end`` ends ``timeout``.

    Parameters
    ----------
    plant : DiffDriveDynamics
        The true robot.
    reference : PoseTrajectory
        The trajectory, e.g. from :func:`~wheelbase.trajectory.feasible_trajectory`.
    controller : ComputedTorquePID, optional
        None: the inverse-dynamics torques of ``model`` are fed open loop (figure 5.12/5.13).
    model : DiffDriveDynamics, optional
        The model of the open-loop inverse dynamics (default ``plant``); the controller carries
        its own.
    dt : float
        Control period [s].
    state0 : array_like, shape (6,) or (N, 6), optional
        Initial state(s) (x, y, ψ, u, v, r); default the reference's first pose and twist
        (one robot).
    t_end : float, optional
        Stop after this time [s]; default the reference's duration.
    tolerance : tuple of float
        (position [m], heading [rad]) of arrival at the reference's last pose.

    Returns
    -------
    Log
        One robot per initial state; ``reference_pose`` is the trajectory's pose, so
        :meth:`~wheelbase.sim.Log.metrics` gives the tracking errors; a run whose state stops
        being finite ends ``diverged``.
    """
    if not isinstance(plant, DiffDriveDynamics):
        raise ConfigError(f"plant must be a DiffDriveDynamics (got {type(plant).__name__})")
    if not isinstance(reference, PoseTrajectory):
        raise InputError("reference must be a PoseTrajectory")
    if controller is None:
        controller = InverseDynamicsTorques(plant if model is None else model)
    elif not isinstance(controller, ComputedTorquePID):
        raise ConfigError("controller must be a ComputedTorquePID")
    if state0 is None:
        s0 = reference.at([0.0]).reference()[0, :6].copy()
        if plant.constrained:
            s0[4] = 0.0
    else:
        s0 = as_float_array("state0", state0, 6, min_ndim=1, max_ndim=2)
    s0 = s0.reshape(-1, 6)
    duration = reference.duration if t_end is None else positive("t_end", t_end, "s")
    rows = TimedRows.from_pose_trajectory(reference, time_grid(duration, dt))
    arrival = None
    if duration >= reference.duration - 1e-9:  # the run reaches the reference's end
        arrival = Arrival(
            reference.poses[-1], tolerance, end_time=reference.duration, judge_at_limit=True
        )
    engine = Engine(
        DynamicPlant(plant),
        controller,
        rows,  # sampled once, exactly at the control times: no evaluation per step
        dt=dt,
        duration=duration,
        arrival=arrival,
        reference_pose=lambda t: rows.at(t)[:3],
    )
    return engine.run(s0[:, :3], twists=s0[:, 3:])


def tune_computed_torque(
    plant: DiffDriveDynamics,
    reference: PoseTrajectory,
    *,
    model: DiffDriveDynamics | None = None,
    dt: float = 0.01,
    heading_weight: float = 1.0,
    effort_weight: float = 0.02,
    max_torque: float = math.inf,
    initial_bandwidth: float = 1.0,
    initial_offset: tuple[float, float, float] = (0.05, 0.05, 0.05),
    horizon: float = 60.0,
    grid: int = 7,
    rounds: int = 3,
) -> TorqueGains:
    """Tune the pole-placement bandwidths by minimising the integrated squared error.

    J = ∫ (|p_ref − p|² + w_ψ·e_ψ² + w_τ·|τ − τ_ff|²) dt over the first ``horizon`` seconds of
    the closed loop started off the reference by ``initial_offset``, minimised over
    (log ω_x, log ω_ψ) by a coarse-to-fine grid: each round runs ``grid²`` candidate pairs as
    one batch on the engine (one robot per pair, :func:`track_trajectory`), then narrows the
    grid around the best. Along a smooth reference the error falls as 1/ω² for ever; the
    recovery from the initial offset costs feedback torque (τ − τ_ff, growing as ω²), which is
    what makes the optimum finite.

    Parameters
    ----------
    plant : DiffDriveDynamics
        The true robot.
    reference : PoseTrajectory
        The trajectory to tune on.
    model : DiffDriveDynamics, optional
        The controller's model (default ``plant``).
    dt : float
        Control period [s].
    heading_weight : float
        w_ψ [m²/rad²], ≥ 0.
    effort_weight : float
        w_τ [m²/(N·m)²], ≥ 0.
    max_torque : float
        Wheel-torque saturation of the controller [N·m].
    initial_bandwidth : float
        Centre of the first grid [rad/s]; the grid spans a factor e^2.5 (about 12) each way.
    initial_offset : tuple of float
        Start error (Δx [m], Δy [m], Δψ [rad]) added to the reference's first pose.
    horizon : float
        Duration of the tuning runs [s] (at most the reference's).
    grid : int
        Candidates per axis and round, >= 3.
    rounds : int
        Refinements, >= 1; each narrows the span to two grid steps around the best.

    Returns
    -------
    TorqueGains
    """
    model = plant if model is None else model
    w_h = nonnegative("heading_weight", heading_weight, "m²/rad²")
    w_t = nonnegative("effort_weight", effort_weight, "m²/(N·m)²")
    w0 = positive("initial_bandwidth", initial_bandwidth, "rad/s")
    for name, value, low in (("grid", grid, 3), ("rounds", rounds, 1)):
        if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < low:
            raise ConfigError(f"{name} must be an integer >= {low} (got {value!r})")
    speed = max(float(np.abs(reference.twist[:, 0]).max()), 1e-3)
    t_end = min(positive("horizon", horizon, "s"), reference.duration)
    offset = as_float_array("initial_offset", initial_offset, 3, max_ndim=1)
    state0 = reference.at([0.0]).reference()[0, :6]
    state0[:3] += offset
    if plant.constrained:
        state0[4] = 0.0

    def costs(pairs: np.ndarray) -> np.ndarray:
        gains = [TorqueGains.pole_placement(wx, wy, speed=speed) for wx, wy in np.exp(pairs)]
        ctrl = ComputedTorquePID(model, gains, max_torque=max_torque)
        states = np.tile(state0, (len(gains), 1))
        log = track_trajectory(plant, reference, ctrl, dt=dt, state0=states, t_end=t_end)
        ff = inverse_dynamics(model, reference.at(log.t)).torques
        error = log.true_pose - log.reference_pose
        heading = wrap_angle(error[..., 2])
        with np.errstate(over="ignore", invalid="ignore"):  # a diverging candidate is inf
            integrand = np.sum(error[..., :2] ** 2, -1) + w_h * heading**2
            integrand = integrand + w_t * np.sum((log.torques - ff) ** 2, -1)
            value = np.sum(integrand[:, :-1] * np.diff(log.t), axis=1)
        failed = (log.status == status_code("diverged")) | ~np.isfinite(value)
        return np.where(failed, np.inf, value)

    centre, span = np.log([w0, w0]), 2.5
    best = centre
    for _ in range(rounds):
        axis = np.linspace(-span, span, grid)
        pairs = np.clip(centre + np.stack(np.meshgrid(axis, axis), -1).reshape(-1, 2), -5.0, 4.0)
        values = costs(pairs)
        if np.isfinite(values).any():
            best = pairs[int(np.argmin(values))]
        centre, span = best, 2.0 * span / (grid - 1)
    wx, wy = np.exp(best)
    return TorqueGains.pole_placement(float(wx), float(wy), speed=speed)
