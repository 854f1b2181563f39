"""Computed-torque PID trajectory tracking for a differential drive (document 000 §5.3).

Document 000 feeds the inverse-dynamics wheel torques open loop into the forward model
(figure 5.12) and reports the drift (figure 5.13); then it closes the loop with a PID on the pose
error in the body frame whose output replaces V̇ in M·V̇ + C·V = τ, and maps τ to wheel torques
with τ* = J†ᵀ·τ (figures 5.14–5.16). :class:`ComputedTorquePID` implements that loop:

1. pose error in the body frame: (e_x, e_y) = R(ψ)ᵀ(p_ref − p), e_ψ = wrap(ψ_ref − ψ); its rate
   from the measured twist, ė = −[r]×(e_x, e_y) + R(ψ)ᵀṗ_ref − (u, v), ė_ψ = r_ref − r (no
   numerical differentiation: no derivative kick, no noise amplification; an optional
   first-order filter T_f smooths it);
2. desired body acceleration a = V̇_ref + PID(e) (the feed-forward V̇_ref can be switched off to
   get the document's pure PID): a_u = u̇_ref + PID_x(e_x) and
   a_r = ṙ_ref + PID_ψ(e_ψ) + sgn(u_ref)·PID_y(e_y). The no-slip constraint v = 0 leaves no
   lateral acceleration to command (a_v = 0), so the lateral error steers the yaw instead — as a
   car corrects its lane by turning — with the sign of the direction of travel, and is off
   during turns in place (u_ref = 0);
3. computed torque with the controller's model (its mass and inertia may be wrong):
   τ = M·a + C(V)·V (+ modelled resistance), then wheel torques τ* = Wᵀ·τ (document 000's
   J†ᵀ: F_y is dropped, the ground carries it), saturated at ``max_torque``;
4. anti-windup by conditional integration: the integrators stop while a wheel torque saturates.

Linearised about a straight reference at speed U with an exact model, the errors obey
ë_x + k_dx ė_x + k_px e_x + k_ix ∫e_x = 0 and, with ė_y = U·e_ψ,
s⁴ + k_dψ s³ + (k_pψ + U k_dy) s² + (k_iψ + U k_py) s + U k_iy = 0 for the lateral/heading pair.
:meth:`TorqueGains.pole_placement` puts the poles at −ω (triple for x, quadruple for y/ψ at the
nominal speed); :func:`tune_computed_torque` minimises the integrated squared error with
``scipy.optimize`` instead.

The whole closed loop runs in one compiled kernel (:func:`track_trajectory`); the controller
object is also callable step by step as ``controller(t, pose, reference, twist=...)``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, ClassVar

import numba
import numpy as np
from numpy.typing import ArrayLike

from wheelbase._validate import as_float_array, finite, nonnegative, positive
from wheelbase.control.base import WrappedLaw
from wheelbase.dynamics import DiffDriveDynamics
from wheelbase.errors import ConfigError, InputError
from wheelbase.geometry_numba import wrap_angle_scalar
from wheelbase.models.path import PoseTrajectory

__all__ = [
    "ComputedTorquePID",
    "InverseDynamicsTorques",
    "TimedRows",
    "TorqueGains",
    "TwistTorqueLoop",
    "interpolate_rows",
    "velocity_torques",
]


# --------------------------------------------------------------------------- gains
@dataclass(frozen=True)
class TorqueGains:
    """PID gains of the three channels (x: along-track, y: lateral, ψ: heading).

    Parameters
    ----------
    kp : tuple of float
        Proportional gains (x [1/s²], y [rad/(m·s²)], ψ [1/s²]).
    ki : tuple of float
        Integral gains (x [1/s³], y [rad/(m·s³)], ψ [1/s³]).
    kd : tuple of float
        Derivative gains (x [1/s], y [rad/(m·s)], ψ [1/s]).
    """

    kp: tuple[float, float, float]
    ki: tuple[float, float, float]
    kd: tuple[float, float, float]

    def __post_init__(self) -> None:
        for name in ("kp", "ki", "kd"):
            arr = as_float_array(name, getattr(self, name), 3, max_ndim=1)
            if np.any(arr < 0):
                raise ConfigError(f"{name} must be >= 0 (got {arr.tolist()})")
            object.__setattr__(self, name, tuple(float(x) for x in arr))

    def matrix(self) -> np.ndarray:
        """Rows (kp, ki, kd), columns (x, y, ψ): the kernel's layout (3×3)."""
        return np.array([self.kp, self.ki, self.kd])

    @classmethod
    def pole_placement(
        cls, bandwidth: float = 1.0, yaw_bandwidth: float | None = None, speed: float = 0.1
    ) -> TorqueGains:
        """Gains that put the linearised error poles at −ω (see the module docstring).

        Parameters
        ----------
        bandwidth : float
            ω_x of the along-track loop [rad/s]: (s + ω_x)³.
        yaw_bandwidth : float, optional
            ω of the heading/lateral loop [rad/s]: (s + ω)⁴ at ``speed``; default ``bandwidth``.
        speed : float
            Nominal forward speed U [m/s] of the lateral design, > 0.

        Examples
        --------
        >>> TorqueGains.pole_placement(1.0, speed=0.5).kp
        (3.0, 6.0, 6.0)
        """
        w = positive("bandwidth", bandwidth, "rad/s")
        wy = w if yaw_bandwidth is None else positive("yaw_bandwidth", yaw_bandwidth, "rad/s")
        u = positive("speed", speed, "m/s")
        # s⁴ + 4ω s³ + 6ω² s² + 4ω³ s + ω⁴ with k_dψ = 4ω, k_pψ = 6ω², k_dy = 0,
        # k_iψ + U k_py = 4ω³ split as k_iψ = ω³, k_py = 3ω³/U, and U k_iy = ω⁴.
        return cls(
            kp=(3 * w**2, 3 * wy**3 / u, 6 * wy**2),
            ki=(w**3, wy**4 / u, wy**3),
            kd=(3 * w, 0.0, 4 * wy),
        )


# --------------------------------------------------------------------------- compiled law
@numba.njit(cache=True)
def _control(ref, s, mp, g, tf, max_torque, ff, clamp, cst, dt):
    """One step of the computed-torque PID; updates the controller state ``cst`` (7,)."""
    c, sn = math.cos(s[2]), math.sin(s[2])
    dx, dy = ref[0] - s[0], ref[1] - s[1]
    ex = c * dx + sn * dy
    ey = -sn * dx + c * dy
    epsi = wrap_angle_scalar(ref[2] - s[2])
    cr, sr = math.cos(ref[2]), math.sin(ref[2])
    vxr = cr * ref[3] - sr * ref[4]
    vyr = sr * ref[3] + cr * ref[4]
    u, v, r = s[3], s[4], s[5]
    raw = (
        r * ey + c * vxr + sn * vyr - u,
        -r * ex - sn * vxr + c * vyr - v,
        ref[5] - r,
    )
    started = cst[6] > 0.5
    for j in range(3):
        if tf > 0.0 and started:
            cst[3 + j] = (tf * cst[3 + j] + dt * raw[j]) / (tf + dt)
        else:
            cst[3 + j] = raw[j]
    cst[6] = 1.0
    sigma = 0.0
    if ref[3] > 1e-9:
        sigma = 1.0
    elif ref[3] < -1e-9:
        sigma = -1.0
    px = g[0, 0] * ex + cst[0] + g[2, 0] * cst[3]
    py = sigma * (g[0, 1] * ey + cst[1] + g[2, 1] * cst[4])
    pp = g[0, 2] * epsi + cst[2] + g[2, 2] * cst[5]
    au = px + ff * ref[6]
    ar = pp + py + ff * ref[8]
    m, xb, yb, ib, a, d = mp[0], mp[1], mp[2], mp[3], mp[4], mp[5]
    fx = m * au - m * yb * ar - m * r * (v + xb * r) + mp[6] * u + mp[8] * math.tanh(u / 1e-3)
    mz = -m * yb * au + ib * ar + m * r * (xb * u + yb * v) + mp[7] * r
    tl = 0.5 * a * fx - 0.5 * a / d * mz
    tr = 0.5 * a * fx + 0.5 * a / d * mz
    saturated = abs(tl) > max_torque or abs(tr) > max_torque
    tl = min(max(tl, -max_torque), max_torque)
    tr = min(max(tr, -max_torque), max_torque)
    if not (clamp and saturated):
        cst[0] += g[1, 0] * ex * dt
        if sigma != 0.0:
            cst[1] += g[1, 1] * ey * dt
        cst[2] += g[1, 2] * epsi * dt
    return tl, tr


# --------------------------------------------------------------------------- reference rows
def interpolate_rows(times: np.ndarray, table: np.ndarray, t: float) -> np.ndarray:
    """Row of ``table`` ``(T, k)`` linearly interpolated at time ``t`` [s], held at the ends.

    Parameters
    ----------
    times : numpy.ndarray, shape (T,)
        Non-decreasing sample times [s].
    table : numpy.ndarray, shape (T, k)
        One row per time (unwrap angles before: the interpolation is linear).
    t : float
        Time [s].
    """
    index = int(np.searchsorted(times, t, side="right")) - 1
    if index < 0:
        return table[0].copy()
    if index >= len(times) - 1:
        return table[-1].copy()
    weight = (t - times[index]) / (times[index + 1] - times[index])
    return (1.0 - weight) * table[index] + weight * table[index + 1]


class TimedRows:
    """A reference as rows (x, y, ψ, u, v, r, u̇, v̇, ṙ) at sample times, for the PID.

    :meth:`at` interpolates linearly between samples (the heading unwrapped, then wrapped
    again) and holds the ends, which is exact at the sample times: a loop whose control times
    are the samples gets the trajectory's own rows without evaluating it at every step.

    Parameters
    ----------
    times : array_like, shape (T,)
        Increasing sample times [s].
    rows : array_like, shape (T, 9)
        The rows at those times [m, m, rad, m/s, m/s, rad/s, m/s², m/s², rad/s²].
    """

    def __init__(self, times: ArrayLike, rows: ArrayLike) -> None:
        self.times = as_float_array("times", times, min_ndim=1, max_ndim=1)
        table = as_float_array("rows", rows, 9, min_ndim=2, max_ndim=2).copy()
        if table.shape[0] != self.times.size or self.times.size == 0:
            raise InputError(f"rows must have one row per time (got {table.shape[0]} rows "
                             f"for {self.times.size} times)")  # fmt: skip
        if np.any(np.diff(self.times) <= 0):
            raise InputError("times must increase")
        table[:, 2] = np.unwrap(table[:, 2])
        self.rows = table

    @classmethod
    def from_pose_trajectory(cls, trajectory: PoseTrajectory, times: ArrayLike) -> TimedRows:
        """The trajectory's exact rows at ``times`` [s].

        Parameters
        ----------
        trajectory : PoseTrajectory
            The reference.
        times : array_like, shape (T,)
            Sample times [s].
        """
        times = as_float_array("times", times, min_ndim=1, max_ndim=1)
        return cls(times, trajectory.at(times).reference())

    def at(self, t: float) -> np.ndarray:
        """The row ``(9,)`` at time ``t`` [s].

        Parameters
        ----------
        t : float
            Time [s].
        """
        row = interpolate_rows(self.times, self.rows, t)
        row[2] = wrap_angle_scalar(row[2])
        return row


# --------------------------------------------------------------------------- controller
class ComputedTorquePID:
    """Computed-torque PID tracking controller (document 000 §5.3.2, corrected and completed).

    Parameters
    ----------
    model : DiffDriveDynamics
        The controller's model of the robot (mass, inertia, CG offset, wheels); give a
        perturbed one to study model error.
    gains : TorqueGains or sequence of TorqueGains, optional
        Channel gains; default ``TorqueGains.pole_placement(1.0, speed=0.1)``. A sequence
        gives robot ``i`` of a batch the gains ``gains[i]`` (as :func:`tune_computed_torque`
        runs its candidates).
    max_torque : float
        Wheel-torque saturation [N·m], > 0 (inf: none).
    derivative_filter : float
        Time constant T_f of the filter on the error rates [s], ≥ 0.
    feedforward : bool
        Add the reference acceleration V̇_ref to the PID output (computed torque); ``False``
        gives document 000's pure PID in place of V̇.
    anti_windup : bool
        Stop the integrators while a wheel torque saturates.

    Notes
    -----
    Called as ``controller(t, pose, reference, twist=...)`` it returns the wheel torques
    (τ_L, τ_R) [N·m]. ``reference`` is a :class:`~wheelbase.models.PoseTrajectory`
    (evaluated at t) or one row (x, y, ψ, u, v, r, u̇, v̇, ṙ); ``twist`` is the measured body
    twist (u, v, r), or pass the full state (x, y, ψ, u, v, r) as ``pose``. ``dt`` defaults to
    the time since the previous call.
    """

    command_names: ClassVar[tuple[str, ...]] = ("tau_left", "tau_right")

    def __init__(
        self,
        model: DiffDriveDynamics,
        gains: TorqueGains | None = None,
        *,
        max_torque: float = math.inf,
        derivative_filter: float = 0.0,
        feedforward: bool = True,
        anti_windup: bool = True,
    ) -> None:
        if not isinstance(model, DiffDriveDynamics):
            raise ConfigError(f"model must be a DiffDriveDynamics (got {type(model).__name__})")
        if gains is None:
            gains = TorqueGains.pole_placement(1.0, speed=0.1)
        many = gains if isinstance(gains, (list, tuple)) else [gains]
        if not many or not all(isinstance(g, TorqueGains) for g in many):
            raise ConfigError(
                f"gains must be TorqueGains or a non-empty sequence of them (got {gains!r})"
            )
        self.model = model
        self.gains = gains
        self._gain_matrices = np.stack([g.matrix() for g in many])
        if max_torque != math.inf:
            max_torque = positive("max_torque", max_torque, "N·m")
        self.max_torque = float(max_torque)
        self.derivative_filter = nonnegative("derivative_filter", derivative_filter, "s")
        self.feedforward = bool(feedforward)
        self.anti_windup = bool(anti_windup)
        self.reset()

    def reset(self) -> None:
        """Forget the integrals, the filtered error rates and the last call time."""
        self._state = np.zeros((0, 7))
        self._last_t: float | None = None

    def _kernel_args(self) -> tuple:
        return (
            self.model._params,
            self._gain_matrices,
            self.derivative_filter,
            self.max_torque,
            1.0 if self.feedforward else 0.0,
            self.anti_windup,
        )

    def __call__(
        self,
        t: float,
        pose: ArrayLike,
        reference: PoseTrajectory | ArrayLike,
        twist: ArrayLike | None = None,
        dt: float | None = None,
    ) -> np.ndarray:
        """Wheel torques (τ_L, τ_R) [N·m] for one robot or a batch at time ``t``.

        Parameters
        ----------
        t : float
            Time [s].
        pose : array_like, shape (..., 3) or (..., 6)
            Measured poses (x, y, ψ), or full states (x, y, ψ, u, v, r).
        reference : PoseTrajectory, TimedRows or array_like, shape (9,) or (..., 9)
            The trajectory (or its sampled rows), or its row (x, y, ψ, u, v, r, u̇, v̇, ṙ) at
            ``t`` (one for all robots, or one per robot).
        twist : array_like, shape (..., 3), optional
            Measured body twists (u, v, r) when ``pose`` has 3 columns.
        dt : float, optional
            Control period [s]; default the time since the previous call (first call: none
            integrated).

        Returns
        -------
        numpy.ndarray, shape (..., 2)
            Wheel torques; the integrators are kept per robot (a new batch size restarts them).
        """
        t = finite("t", t, "s")
        state = as_float_array("pose", pose, min_ndim=1)
        if state.shape[-1] == 3:
            if twist is None:
                raise InputError("ComputedTorquePID needs the measured twist (u, v, r)")
            measured = as_float_array("twist", twist, 3)
            state = np.concatenate(np.broadcast_arrays(state, measured), axis=-1)
        elif state.shape[-1] != 6:
            raise InputError(f"pose must have 3 or 6 columns (got shape {state.shape})")
        flat = np.ascontiguousarray(state.reshape(-1, 6))
        if isinstance(reference, TimedRows):
            row = reference.at(t)
        elif isinstance(reference, PoseTrajectory):
            row = reference.at([t]).reference()[0]
        else:
            row = as_float_array("reference", reference, 9)
        # writable and contiguous: Numba dispatches read-only views through a slow path
        rows = np.array(np.broadcast_to(row.reshape(-1, 9), (flat.shape[0], 9)))
        if dt is None:
            dt = 0.0 if self._last_t is None else t - self._last_t
        else:
            dt = positive("dt", dt, "s")
        self._last_t = t
        if self._state.shape[0] != flat.shape[0]:
            self._state = np.zeros((flat.shape[0], 7))
        if self._gain_matrices.shape[0] not in (1, flat.shape[0]):
            raise ConfigError(
                f"{self._gain_matrices.shape[0]} gain sets for {flat.shape[0]} robots"
            )
        out = np.empty((flat.shape[0], 2))
        _control_many(rows, flat, *self._kernel_args(), self._state, max(dt, 0.0), out)
        return out.reshape((*state.shape[:-1], 2))


@numba.njit(cache=True)
def _control_many(refs, states, mp, g, tf, max_torque, ff, clamp, cst, dt, out):
    """:func:`_control` for every robot (rows of ``states``), torques into ``out`` (N, 2);
    gains ``g`` (1 or N, 3, 3): shared or per robot."""
    for i in range(states.shape[0]):
        gains = g[i] if g.shape[0] > 1 else g[0]
        out[i, 0], out[i, 1] = _control(
            refs[i], states[i], mp, gains, tf, max_torque, ff, clamp, cst[i], dt
        )


# --------------------------------------------------------------------------- closed loop
def velocity_torques(
    dynamics: Any,
    state: np.ndarray,
    command: np.ndarray,
    gains: tuple[float, float] = (30.0, 30.0),
    max_torque: float = math.inf,
) -> np.ndarray:
    """Wheel torques ``(..., 2)`` that make a dynamic robot follow ``(v, ω)`` commands.

    The torque layer between a kinematic controller and the dynamics: a computed-torque velocity
    loop. The desired body acceleration is a = (k_u·(v − u), 0, k_r·(ω − r)) and the torques are
    the inverse dynamics of :class:`wheelbase.dynamics.DiffDriveDynamics`, τ = M·a + C(V)·V
    mapped to the wheels by Wᵀ (document 000 §5.2), clipped to ``max_torque`` [N·m]. With an
    exact model each velocity error decays as e^(−k t).

    Parameters
    ----------
    dynamics : DiffDriveDynamics
        The robot's model.
    state : numpy.ndarray, shape (..., 6)
        (x, y, ψ, u, v, r).
    command : numpy.ndarray, shape (..., 2)
        (v [m/s], ω [rad/s]).
    gains : (float, float)
        k_u, k_r [1/s].
    max_torque : float
        Wheel torque limit [N·m].
    """
    velocity = state[..., 3:]
    accel = np.stack(
        [
            gains[0] * (command[..., 0] - velocity[..., 0]),
            np.zeros_like(command[..., 0]),
            gains[1] * (command[..., 1] - velocity[..., 2]),
        ],
        -1,
    )
    _force, torques = dynamics.inverse(velocity, accel)
    return np.clip(torques, -max_torque, max_torque)


class TwistTorqueLoop(WrappedLaw):
    """A kinematic control law on the dynamic plant: its (v, ω) tracked by computed torque.

    Any law of :mod:`wheelbase.control` with velocity commands (pure pursuit, Kanayama, MPPI,
    ...) thinks in body twists; a dynamic plant takes wheel torques. Each call asks the law for
    (v, ω) at the estimated pose and turns it into wheel torques with
    :func:`velocity_torques`: body acceleration a = k·(ζ_ref − ζ) with
    ζ_ref = (v, 0, ω) (a_v = 0: the no-slip constraint leaves the lateral velocity to the
    ground), inverse dynamics τ = M·a + C(ζ)·ζ (+ resistances), τ* = Wᵀ·τ, saturated at
    ``max_torque``. With an exact
    model and no saturation, u and r follow the law's commands as first-order lags of time
    constant 1/k.

    Parameters
    ----------
    law : callable
        ``law(t, pose (3,), reference) -> (v [m/s], ω [rad/s])`` with
        ``command_names == ("v", "omega")``.
    model : DiffDriveDynamics
        The controller's model of the robot.
    bandwidth : float
        k [1/s], > 0.
    max_torque : float
        Wheel-torque saturation [N·m], > 0 (inf: none).

    Examples
    --------
    >>> from wheelbase.control import PurePursuit
    >>> from wheelbase.dynamics import RM100
    >>> loop = TwistTorqueLoop(PurePursuit(speed=0.3), RM100, bandwidth=8.0, max_torque=5.0)
    >>> loop(0.0, np.zeros(6), [[0.0, 0.0], [2.0, 0.0]]).round(3).tolist()
    [2.044, 2.044]
    """

    command_names: ClassVar[tuple[str, ...]] = ("tau_left", "tau_right")

    def __init__(
        self,
        law: object,
        model: DiffDriveDynamics,
        *,
        bandwidth: float = 10.0,
        max_torque: float = math.inf,
    ) -> None:
        if not callable(law):
            raise ConfigError(f"law must be a control law (got {type(law).__name__})")
        names = tuple(getattr(law, "command_names", ("v", "omega")))
        if names != ("v", "omega"):
            raise ConfigError(f"the torque loop tracks (v, omega) commands; this law gives {names}")
        if not isinstance(model, DiffDriveDynamics):
            raise ConfigError(f"model must be a DiffDriveDynamics (got {type(model).__name__})")
        self.law = law
        self.model = model
        self.bandwidth = positive("bandwidth", bandwidth, "1/s")
        if max_torque != math.inf:
            max_torque = positive("max_torque", max_torque, "N·m")
        self.max_torque = float(max_torque)

    @property
    def last_plan(self) -> object:
        """The law's last plan (MPPI), if it has one."""
        return getattr(self.law, "last_plan", None)

    def predict(self, *args: object, **kwargs: object) -> np.ndarray:
        """The law's rollouts (MPPI's :meth:`~wheelbase.control.MPPI.predict`)."""
        return self.law.predict(*args, **kwargs)  # type: ignore[attr-defined]

    def summary(self) -> dict:
        """The law's account of its run (a navigator's replans and recoveries), if any."""
        summary = getattr(self.law, "summary", None)
        return summary() if callable(summary) else {}

    @property
    def uses_perception(self) -> bool:
        """Whether the law reads the robot's perception (a navigator, MPPI among obstacles)."""
        return bool(getattr(self.law, "uses_perception", False))

    def __call__(
        self, t: float, state: ArrayLike, reference: object, perception: object = None
    ) -> np.ndarray:
        """Wheel torques (left, right) [N·m] for one robot or a batch.

        Parameters
        ----------
        t : float
            Time [s].
        state : array_like, shape (..., 6)
            Estimated (x [m], y [m], θ [rad], u [m/s], v [m/s], r [rad/s]).
        reference : object
            Passed to the law unchanged.
        perception : LocalView, optional
            Passed to a law that reads it (``uses_perception``).

        Returns
        -------
        numpy.ndarray, shape (..., 2)
        """
        state = as_float_array("state", state, 6)
        extra = {"perception": perception} if self.uses_perception else {}
        command = np.asarray(
            self.law(t, state[..., :3].copy(), reference, **extra), dtype=np.float64
        )
        command = command.reshape((*state.shape[:-1], 2))
        gains = (self.bandwidth, self.bandwidth)
        return velocity_torques(self.model, state, command, gains, self.max_torque)


class InverseDynamicsTorques:
    """The open-loop "controller" of document 000 §5.3.1: the inverse-dynamics wheel torques of
    a model along the reference at time t, whatever the robot does.

    Parameters
    ----------
    model : DiffDriveDynamics
        The model whose inverse dynamics give the torques (the plant, or a wrong one).
    """

    command_names: ClassVar[tuple[str, ...]] = ("tau_left", "tau_right")

    def __init__(self, model: DiffDriveDynamics) -> None:
        if not isinstance(model, DiffDriveDynamics):
            raise ConfigError(f"model must be a DiffDriveDynamics (got {type(model).__name__})")
        self.model = model

    def reset(self) -> None:
        """Nothing to forget."""

    def __call__(
        self, t: float, state: ArrayLike, reference: PoseTrajectory | TimedRows
    ) -> np.ndarray:
        """Wheel torques ``(..., 2)`` [N·m] of the reference at ``t``, for every robot.

        Parameters
        ----------
        t : float
            Time [s].
        state : array_like, shape (..., 6)
            Measured states (unused: open loop).
        reference : PoseTrajectory or TimedRows
            The trajectory, or its sampled rows.
        """
        row = reference.at(t) if isinstance(reference, TimedRows) else None
        if row is None:
            row = reference.at([t]).reference()[0]
        _force, torques = self.model.inverse(row[3:6], row[6:9])
        return np.broadcast_to(torques, (*np.shape(state)[:-1], 2)).copy()
