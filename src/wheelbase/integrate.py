"""Numerical integration of kinematic models, and :func:`simulate`.

Every kinematic model maps its inputs to a body twist ζ = (u, v, r) that does not depend on the
pose, so the pose obeys η̇ = J(θ)·ζ(t). The integrators below advance a pose over one step of
length h from the twist at the start (ζ₀), the middle (ζₘ) and the end (ζ₁) of the step:

============  =========================================================================  =====
method        update                                                                     order
============  =========================================================================  =====
``euler``     η += h·J(θ)ζ₀ (document 002 eq. 6/7; document 000's MATLAB loop)            1
``midpoint``  heading at mid-step: x += h·R(θ + h·rₘ/2)(uₘ, vₘ) (doc 002 eq. 8)           2
``rk4``       classical Runge–Kutta on η̇ = J(θ)ζ(t)                                       4
``exact``     closed-form arc (SE(2) exponential) of ζₘ held over the step                2*
``simpson``   θ(t) integrated exactly for a quadratic yaw rate, x = ∫u cos θ − v sin θ    4
              and y likewise by Simpson's 1/3 rule (document 001 §III/IV)
============  =========================================================================  =====

(*) ``exact`` is exact (to rounding) whenever the inputs are constant over each step — constant
inputs and sampled input arrays, which are zero-order holds — and second order for inputs that
vary within a step (the twist is frozen at its mid-step value).

Inputs given as an array sampled at the steps are a zero-order hold: ζ₀ = ζₘ = ζ₁ = the sample
of that step. Inputs given as a callable of time are evaluated at t, t + h/2 and t + h.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from wheelbase._io import write_csv
from wheelbase._validate import as_float_array, check_choice, finite, integer, positive
from wheelbase.errors import ConfigError, InputError
from wheelbase.geometry import se2_exp, to_world_frame, wrap_angle
from wheelbase.limits import MAX_STEPS
from wheelbase.models.base import KinematicModel

__all__ = ["METHODS", "SimResult", "integrate_step", "simulate", "time_grid"]

METHODS: tuple[str, ...] = ("euler", "midpoint", "rk4", "exact", "simpson")
BACKENDS: tuple[str, ...] = ("auto", "numba", "numpy", "jax")
_METHOD_ID = {name: index for index, name in enumerate(METHODS)}

InputsLike = ArrayLike | Callable[[float], ArrayLike]


# --------------------------------------------------------------------------- NumPy reference
def integrate_step(
    pose: ArrayLike,
    twist_start: ArrayLike,
    twist_mid: ArrayLike,
    twist_end: ArrayLike,
    h: float,
    method: str = "rk4",
) -> np.ndarray:
    """Advance poses ``(..., 3)`` by one step of ``h`` seconds (NumPy reference).

    Parameters
    ----------
    pose : array_like, shape (..., 3)
        Poses (x [m], y [m], θ [rad]) at the start of the step.
    twist_start, twist_mid, twist_end : array_like, shape (..., 3)
        Body twists (u [m/s], v [m/s], r [rad/s]) at t, t + h/2 and t + h.
    h : float
        Step length [s].
    method : str
        One of :data:`METHODS`.

    Returns
    -------
    numpy.ndarray, shape (..., 3)
        Poses at t + h, heading wrapped to (−π, π].
    """
    check_choice("method", method, METHODS)
    pose = np.asarray(pose, dtype=np.float64)
    z0, zm, z1 = (np.asarray(z, dtype=np.float64) for z in (twist_start, twist_mid, twist_end))
    theta = pose[..., 2]
    if method == "euler":
        new = pose + h * to_world_frame(theta, z0)
    elif method == "midpoint":
        rate = to_world_frame(theta + 0.5 * h * zm[..., 2], zm)
        new = pose + h * rate
    elif method == "rk4":
        k1 = to_world_frame(theta, z0)
        k2 = to_world_frame(theta + 0.5 * h * k1[..., 2], zm)
        k3 = to_world_frame(theta + 0.5 * h * k2[..., 2], zm)
        k4 = to_world_frame(theta + h * k3[..., 2], z1)
        new = pose + h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
    elif method == "exact":
        return se2_exp(pose, zm, h)
    else:  # simpson
        r0, rm, r1 = z0[..., 2], zm[..., 2], z1[..., 2]
        # θ at mid-step and end from the quadratic through (r0, rm, r1): exact for such r(t).
        theta_mid = theta + h / 24.0 * (5.0 * r0 + 8.0 * rm - r1)
        theta_end = theta + h / 6.0 * (r0 + 4.0 * rm + r1)
        f0 = to_world_frame(theta, z0)
        fm = to_world_frame(theta_mid, zm)
        f1 = to_world_frame(theta_end, z1)
        new = pose + h / 6.0 * (f0 + 4.0 * fm + f1)
        new[..., 2] = theta_end
    new[..., 2] = wrap_angle(new[..., 2])
    return new


# --------------------------------------------------------------------------- Numba kernels
_PARALLEL_MIN_ROBOTS = 256


# --------------------------------------------------------------------------- result
@dataclass(frozen=True)
class SimResult:
    """The outcome of :func:`simulate`.

    Attributes
    ----------
    t : numpy.ndarray, shape (T,)
        Recorded times [s].
    poses : numpy.ndarray, shape (T, 3) or (T, N, 3)
        Poses (x [m], y [m], θ [rad] wrapped to (−π, π]) at those times.
    inputs : numpy.ndarray, shape (T, k) or (T, N, k)
        The model inputs in force from each recorded time on (at the last time: its value
        there), in the order and units of ``model.input_names``.
    model : KinematicModel
        The model that was simulated.
    method : str
        The integration method.
    dt : float
        The nominal step [s] (the last step is shorter when ``t_end`` is not a multiple).
    """

    t: np.ndarray
    poses: np.ndarray
    inputs: np.ndarray
    model: KinematicModel
    method: str
    dt: float

    @property
    def is_batch(self) -> bool:
        """Whether this result holds several robots (a middle axis N)."""
        return self.poses.ndim == 3

    def to_csv(self, path: str | Path, *, overwrite: bool = False) -> Path:
        """Write ``t, x, y, theta`` and the inputs to CSV (one robot only).

        Parameters
        ----------
        path : str or Path
            Output file.
        overwrite : bool
            Replace ``path`` if it exists (default: refuse).

        Raises
        ------
        FileExistsError
            If ``path`` exists and ``overwrite`` is false.
        InputError
            For a batch result (write one robot: ``result.robot(i).to_csv(...)``).
        """
        if self.is_batch:
            raise InputError("to_csv writes one robot; select one with result.robot(i)")
        names = ["t", "x", "y", "theta", *self.model.input_names]
        values = np.column_stack([self.t, self.poses, self.inputs]).T
        return write_csv(path, dict(zip(names, values, strict=True)), overwrite=overwrite)

    def robot(self, index: int) -> SimResult:
        """The result of robot ``index`` of a batch, as a single-robot result."""
        if not self.is_batch:
            raise InputError("robot(i) needs a batch result")
        return SimResult(
            self.t,
            self.poses[:, index],
            self.inputs[:, index],
            self.model,
            self.method,
            self.dt,
        )

    def plot(self, **kwargs: Any) -> Any:
        """Plot the path and the states over time (see :func:`wheelbase.plot.plot_result`)."""
        from wheelbase.plot import plot_result

        return plot_result(self, **kwargs)


# --------------------------------------------------------------------------- simulate
def time_grid(t_end: float, dt: float, max_steps: int = MAX_STEPS) -> np.ndarray:
    """Times 0, dt, 2·dt, …, t_end [s]; the last step is shortened to land on ``t_end``.

    Parameters
    ----------
    t_end : float
        Duration [s], > 0.
    dt : float
        Step [s], 0 < dt <= t_end.
    max_steps : int
        Most steps t_end / dt (default :data:`wheelbase.limits.MAX_STEPS` = 1e6): a typo such
        as ``dt=1e-9`` is an error, not a loop of 1e11 steps.

    Raises
    ------
    ConfigError
        If ``dt`` or ``t_end`` is not finite and positive, ``dt > t_end``, or there would be
        more than ``max_steps`` steps.
    """
    t_end = positive("t_end", t_end, "s")
    dt = positive("dt", dt, "s")
    if dt > t_end:
        raise ConfigError(f"dt must be <= t_end (got dt={dt:g} s, t_end={t_end:g} s)")
    max_steps = integer("max_steps", max_steps, minimum=1)
    steps = t_end / dt
    if steps - 1e-9 > max_steps:
        raise ConfigError(
            f"t_end / dt = {steps:.4g} steps: more than max_steps = {max_steps}; use a larger "
            "dt or a shorter t_end, or raise max_steps"
        )
    n_steps = max(1, math.ceil(t_end / dt - 1e-9))
    times = dt * np.arange(n_steps + 1, dtype=np.float64)
    times[-1] = t_end
    return times


def _record_indices(n_steps: int, record_every: int) -> np.ndarray:
    index = np.arange(0, n_steps + 1, record_every)
    if index[-1] != n_steps:
        index = np.append(index, n_steps)
    return index.astype(np.int64)


def simulate(
    model: KinematicModel,
    pose0: ArrayLike,
    inputs: InputsLike,
    t_end: float,
    dt: float,
    method: str = "rk4",
    *,
    record_every: int = 1,
    backend: str = "auto",
    max_steps: int = MAX_STEPS,
) -> SimResult:
    """Simulate a kinematic model from ``pose0`` under ``inputs`` for ``t_end`` seconds.

    Parameters
    ----------
    model : KinematicModel
        Any model of :mod:`wheelbase.models` (``DiffDrive``, ``Unicycle``, ``Bicycle`` …).
    pose0 : array_like, shape (3,) or (N, 3)
        Initial pose(s) (x [m], y [m], θ [rad]); an (N, 3) array simulates N robots at once.
    inputs : array_like or callable
        Model inputs in the order and units of ``model.input_names``, as

        - constants: shape (k,), or (N, k) for a batch (one row per robot);
        - a callable ``f(t) -> (k,) or (N, k)`` of time [s];
        - an array sampled at the steps (a zero-order hold): shape (S, k) for one robot or
          (S, N, k) for a batch, with S = number of steps (or steps + 1, the last row unused).
    t_end : float
        Duration [s], > 0.
    dt : float
        Step [s], 0 < dt <= t_end; the last step is shortened to end at ``t_end``.
    method : {"euler", "midpoint", "rk4", "exact", "simpson"}
        Integration method (see the module docstring).
    record_every : int
        Keep every ``record_every``-th step (and always the last) so that a long batch fits in
        memory.
    backend : {"auto", "numba", "numpy", "jax"}
        ``numpy`` is the reference implementation; ``numba`` runs compiled, parallel kernels
        (same arithmetic, results equal to rounding); ``jax`` runs one jit-compiled
        ``lax.scan`` in float64 (extra ``wheelbase[jax]``; on a GPU when JAX has one; see
        :mod:`wheelbase.integrate_jax`); ``auto`` picks ``numba``.
    max_steps : int
        Most steps t_end / dt (default :data:`wheelbase.limits.MAX_STEPS` = 1e6); raise it on
        purpose.

    Returns
    -------
    SimResult
        With ``t`` (T,), ``poses`` (T, 3) or (T, N, 3) and the inputs used.

    Raises
    ------
    ConfigError
        Bad ``t_end``, ``dt``, ``method``, ``backend`` or ``record_every``.
    InputError
        Bad shapes, non-finite values, or inputs outside what the model allows.

    Examples
    --------
    >>> from wheelbase import DiffDrive, simulate
    >>> robot = DiffDrive(wheel_radius=0.05, half_track=0.2)
    >>> result = simulate(robot, [0, 0, np.pi / 2], (0.8, 0.6), t_end=100, dt=0.1, method="euler")
    >>> result.poses.shape
    (1001, 3)
    """
    check_choice("method", method, METHODS)
    check_choice("backend", backend, BACKENDS)
    if isinstance(record_every, bool) or not isinstance(record_every, (int, np.integer)):
        raise ConfigError(f"record_every must be an integer >= 1 (got {record_every!r})")
    if record_every < 1:
        raise ConfigError(f"record_every must be an integer >= 1 (got {record_every})")
    times = time_grid(t_end, dt, max_steps)
    n_steps = times.size - 1
    pose0 = as_float_array("pose0", pose0, 3, min_ndim=1, max_ndim=2)
    batch = pose0.ndim == 2
    poses0 = np.ascontiguousarray(pose0.reshape(-1, 3))
    n_robots = poses0.shape[0]
    k = len(model.input_names)
    record = _record_indices(n_steps, int(record_every))
    engine = {"auto": "numba"}.get(backend, backend)

    def per_robot(values: np.ndarray, what: str) -> np.ndarray:
        """Broadcast validated inputs (k,) or (N, k) to (N, k)."""
        if values.ndim == 1 or (values.ndim == 2 and values.shape[0] in (1, n_robots)):
            return np.broadcast_to(values.reshape(-1, k), (n_robots, k))
        raise InputError(f"{what} must have shape ({k},) or ({n_robots}, {k}) (got {values.shape})")

    if callable(inputs):
        return _simulate_callable(
            model, poses0, inputs, times, method, record, per_robot, batch, engine, dt
        )

    values = model.validate_inputs(inputs)
    sampled_ndim = 3 if batch else 2
    if values.ndim == sampled_ndim:
        return _simulate_sampled(
            model, poses0, values, times, method, record, per_robot, batch, engine, dt
        )
    if values.ndim > sampled_ndim:
        raise InputError(
            f"inputs have too many dimensions for pose0 of shape {pose0.shape} "
            f"(got shape {values.shape})"
        )
    constant = np.ascontiguousarray(per_robot(values, "inputs"))
    twist = np.ascontiguousarray(model.twist(constant))
    if engine == "numba":
        out = np.empty((record.size, n_robots, 3))
        from wheelbase.integrate_numba import roll_constant

        roll_constant(poses0, twist, times, _METHOD_ID[method], record, out)
    elif engine == "jax":
        from wheelbase.integrate_jax import roll_twists

        pose = poses0.copy()
        pose[:, 2] = wrap_angle(pose[:, 2])
        out = roll_twists(pose, *(twist[None],) * 3, np.diff(times), method, record)
    else:
        out = np.empty((record.size, n_robots, 3))
        pose = poses0.copy()
        pose[:, 2] = wrap_angle(pose[:, 2])
        slot = 0
        if record[0] == 0:
            out[0] = pose
            slot = 1
        for step in range(n_steps):
            pose = integrate_step(pose, twist, twist, twist, times[step + 1] - times[step], method)
            if slot < record.size and record[slot] == step + 1:
                out[slot] = pose
                slot += 1
    used = np.broadcast_to(constant, (record.size, n_robots, k))
    return _result(times[record], out, used, model, method, batch, dt)


def _simulate_sampled(model, poses0, values, times, method, record, per_robot, batch, engine, dt):
    n_steps = times.size - 1
    if values.shape[0] not in (n_steps, n_steps + 1):
        raise InputError(
            f"sampled inputs need {n_steps} rows (one per step) or {n_steps + 1} "
            f"(got {values.shape[0]})"
        )
    rows = [per_robot(values[i], "each row of the sampled inputs") for i in range(n_steps)]
    twists = [np.ascontiguousarray(model.twist(row)) for row in rows]

    def twist_at(step):
        z = twists[step]
        return z, z, z

    out = _step_loop(poses0, times, method, record, twist_at, engine)
    used = np.stack([rows[min(i, n_steps - 1)] for i in record])
    return _result(times[record], out, used, model, method, batch, dt)


def _simulate_callable(
    model, poses0, function, times, method, record, per_robot, batch, engine, dt
):
    recorded_times = set(times[record].tolist())
    used_rows: dict[float, np.ndarray] = {}
    last: dict[float, np.ndarray] = {}  # the end of one step is the start of the next

    def twist_of(t: float) -> np.ndarray:
        if t in last:
            return last[t]
        try:
            raw = function(float(t))
        except Exception as error:  # a user callable: say where it failed
            raise InputError(f"inputs({t:g}) raised {type(error).__name__}: {error}") from error
        row = per_robot(model.validate_inputs(raw), f"inputs({t:g})")
        if t in recorded_times:
            used_rows[t] = np.array(row)
        twist = np.ascontiguousarray(model.twist(row))
        last.clear()
        last[t] = twist
        return twist

    def twist_at(step):
        t0, t1 = times[step], times[step + 1]
        z0 = twist_of(t0)
        zm = twist_of(0.5 * (t0 + t1))
        return z0, zm, twist_of(t1)

    out = _step_loop(poses0, times, method, record, twist_at, engine)
    used = np.stack([used_rows[t] for t in times[record].tolist()])
    return _result(times[record], out, used, model, method, batch, dt)


def _step_loop(poses0, times, method, record, twist_at, engine):
    n_steps = times.size - 1
    if engine == "jax":
        from wheelbase.integrate_jax import roll_twists

        pose = poses0.copy()
        pose[:, 2] = wrap_angle(pose[:, 2])
        z0, zm, z1 = (np.stack(z) for z in zip(*(twist_at(k) for k in range(n_steps)), strict=True))
        return roll_twists(pose, z0, zm, z1, np.diff(times), method, record)
    out = np.empty((record.size, poses0.shape[0], 3))
    pose = poses0.copy()
    pose[:, 2] = wrap_angle(pose[:, 2])
    slot = 0
    if record[0] == 0:
        out[0] = pose
        slot = 1
    method_id = _METHOD_ID[method]
    from wheelbase.integrate_numba import step_batch, step_batch_serial

    kernel = step_batch if poses0.shape[0] >= _PARALLEL_MIN_ROBOTS else step_batch_serial
    for step in range(n_steps):
        h = times[step + 1] - times[step]
        z0, zm, z1 = twist_at(step)
        if engine == "numba":
            kernel(pose, z0, zm, z1, h, method_id)
        else:
            pose = integrate_step(pose, z0, zm, z1, h, method)
        if slot < record.size and record[slot] == step + 1:
            out[slot] = pose
            slot += 1
    return out


def _result(t, out, used, model, method, batch, dt):
    used = np.array(used, dtype=np.float64)
    if not batch:
        out, used = out[:, 0, :], used[:, 0, :]
    if not np.all(np.isfinite(out)):  # only reachable through overflow of huge inputs
        raise InputError("the simulation produced non-finite poses; inputs are too large")
    return SimResult(t=t, poses=out, inputs=used, model=model, method=method, dt=finite("dt", dt))
