"""Adaptive computed torque: the PID of document 000 §5.3 on a model that learns its payload.

The no-slip dynamics are linear in θ = (m, m·x_c, m·y_c, I_B, F_0) — mass, CG moments, yaw
inertia about the axle centre (:mod:`wheelbase.inertial`) and a longitudinal force F_0 the
ground and gravity take (rolling resistance while the robot drives one way, a slope's pull while
its heading holds):

    F_x = m·u̇ − (m x_c)·r² − (m y_c)·ṙ + F_0
    M_z = (m x_c)·r·u − (m y_c)·u̇ + I_B·ṙ                  i.e.  τ = Y(ν, ν̇)·θ.

(A rolling resistance F_r·sign(u) beside F_0 would be the same column while the robot drives
forward: the two could not be told apart.) What the model leaves out biases it: on a floor with
rolling resistance the casters resist a turn on the spot with a moment no column explains, which
the estimates of I_B and m·x_c take up — the projection below keeps them to what a load on the
robot could be.

The controller estimates θ by recursive least squares on the *filtered* regressor. Over one
control step of length h the held torque changes the velocity by M·Δν = τ·h − ∫(nonlinear
terms)dt, so with the step's mean acceleration Δν/h and its mean r² and r·u (the trapezoid of
the step's ends) the step's own regressor row satisfies τ ≈ Y_k·θ to O(h²).
Measured velocities are quantised (encoder ticks), so the rows are smoothed before they are
used: both sides through the same second-order low-pass filter H²(z), H the discrete
first-order filter of time constant T. A filter applied to both sides keeps the identity
τ_f = Y_f·θ for constant θ, and H² keeps the quantisation noise of Δν/h out of the regressor
(noise in a regressor biases least squares low). Each step

    K = P·Y_fᵀ·(λ·I + Y_f·P·Y_fᵀ)⁻¹,   θ̂ ← θ̂ + K·(τ_f − Y_f·θ̂),   P ← (P − K·Y_f·P)/λ,

with the forgetting factor λ (1: none; below 1 it follows a payload that changes), and then
P ← P + Q·h: F_0 drifts (a random walk of ``force_drift`` N/√s: the ground, the slope and the
direction of travel change along the route) while the inertial parameters keep their whole
history. The
estimates are kept physical (mass and I_B at least a fifth of the model's, |c| ≤ 1 m) and the
certainty-equivalence computed torque of :class:`~wheelbase.control.ComputedTorquePID` runs on
the model they give: τ = M̂(a_ref + PID(e)) + Ĉ(ν)·ν + F̂_0 (same gains, same
anti-windup; F̂_0 enters as the body acceleration M̂⁻¹(F̂_0, 0) added to the reference's).

The body force applied over a step is known from the wheel torques the controller itself sent
(F_x = (τ_L + τ_R)/a, M_z = d(τ_R − τ_L)/a): the wheel geometry is the one thing it must know.
"""

from __future__ import annotations

import math
from typing import ClassVar

import numba
import numpy as np
from numpy.typing import ArrayLike

from wheelbase._validate import as_float_array, finite, positive
from wheelbase.control.torque import ComputedTorquePID, TimedRows, TorqueGains, _control
from wheelbase.dynamics import GRAVITY, DiffDriveDynamics
from wheelbase.errors import ConfigError, InputError
from wheelbase.models.path import PoseTrajectory

__all__ = ["ESTIMATE_NAMES", "AdaptiveComputedTorque", "step_regressor"]

ESTIMATE_NAMES: tuple[str, ...] = ("mass", "moment_x", "moment_y", "inertia_b", "force")
"""θ̂ = (m [kg], m·x_c [kg·m], m·y_c [kg·m], I_B [kg·m²], F_0 [N])."""
_P = len(ESTIMATE_NAMES)


def step_regressor(velocity: ArrayLike, previous: ArrayLike, dt: float) -> np.ndarray:
    """Y_k ``(..., 2, 5)``: rows F_x, M_z of one step's regressor (module docstring).

    Parameters
    ----------
    velocity : array_like, shape (..., 2)
        (u [m/s], r [rad/s]) at the end of the step.
    previous : array_like, shape (..., 2)
        (u, r) at its start.
    dt : float
        The step h [s], > 0.
    """
    nu = as_float_array("velocity", velocity, 2)
    before = as_float_array("previous", previous, 2)
    acc = (nu - before) / positive("dt", dt, "s")
    mid = 0.5 * (nu + before)
    u, r = mid[..., 0], mid[..., 1]
    out = np.zeros((*u.shape, 2, _P))
    out[..., 0, 0], out[..., 0, 1], out[..., 0, 2] = acc[..., 0], -r * r, -acc[..., 1]
    out[..., 0, 4] = 1.0
    out[..., 1, 1], out[..., 1, 2], out[..., 1, 3] = r * u, -acc[..., 0], acc[..., 1]
    return out


@numba.njit(cache=True)
def _control_models(refs, states, models, g, tf, max_torque, ff, clamp, cst, dt, out):
    """The computed-torque PID of every robot on its own model ``models[i]`` (N, 10)."""
    for i in range(states.shape[0]):
        gains = g[i] if g.shape[0] > 1 else g[0]
        out[i, 0], out[i, 1] = _control(
            refs[i], states[i], models[i], gains, tf, max_torque, ff, clamp, cst[i], dt
        )


class AdaptiveComputedTorque:
    """Computed-torque PID whose model's inertial parameters are estimated online (RLS).

    Parameters
    ----------
    model : DiffDriveDynamics
        The initial model (what the controller believes before it learns: e.g. the RM100
        without its payload); its wheels and damping are taken as known.
    gains : TorqueGains, optional
        PID gains (default ``TorqueGains.pole_placement(1.0, speed=0.1)``).
    max_torque : float
        Wheel-torque saturation [N·m] (inf: none).
    derivative_filter : float
        Filter time constant of the PID's error rates [s], ≥ 0.
    forgetting : float
        RLS forgetting factor λ per call, in (0.9, 1].
    filter_time : float
        T of the regressor filter [s], > 0.
    force_drift : float
        How fast F_0 may drift [N/√s], ≥ 0 (0: a constant, the default: on a level floor a
        drifting F_0 takes up part of the weakly excited m·u̇ — on document 000's route 1 N/√s
        leaves the mass 10 % low; on slopes it must drift, as the pull changes with the grade
        and the heading: ``wheelbase.run`` gives 1 N/√s to a scenario with graded terrain).
    reach : float
        Farthest a load's mass can lie from the axle centre [m], > 0 (the footprint's
        half-diagonal): bounds the CG offset and the inertia a payload can add.
    initial_spread : float
        Initial standard deviation of the estimates in units of the model's values (mass,
        inertia; 0.1 m of CG offset; 5 % of the weight for F_r), > 0. Large: the initial
        model is a weak prior (on the document-000 route a spread of 1 leaves the weakly
        excited CG moment 5 % short of the truth, 30 within 1 %).
    feedforward, anti_windup : bool
        As :class:`~wheelbase.control.ComputedTorquePID`.

    Attributes
    ----------
    estimates : numpy.ndarray, shape (N, 5)
        θ̂ of each robot now (:data:`ESTIMATE_NAMES`).
    history : list of (float, numpy.ndarray)
        (t, θ̂ of every robot) at each call, for plotting.
    """

    command_names: ClassVar[tuple[str, ...]] = ("tau_left", "tau_right")

    def __init__(
        self,
        model: DiffDriveDynamics,
        gains: TorqueGains | None = None,
        *,
        max_torque: float = math.inf,
        derivative_filter: float = 0.0,
        forgetting: float = 1.0,
        filter_time: float = 0.3,
        initial_spread: float = 30.0,
        force_drift: float = 0.0,
        reach: float = 0.5,
        feedforward: bool = True,
        anti_windup: bool = True,
    ) -> None:
        # the PID's checks and gain layout, reused
        self._pid = ComputedTorquePID(
            model, gains, max_torque=max_torque, derivative_filter=derivative_filter,
            feedforward=feedforward, anti_windup=anti_windup,
        )  # fmt: skip
        self.model = model
        forgetting = finite("forgetting", forgetting)
        if not 0.9 < forgetting <= 1.0:
            raise ConfigError(f"forgetting must be in (0.9, 1] (got {forgetting:g})")
        self.forgetting = forgetting
        self.filter_time = positive("filter_time", filter_time, "s")
        self.initial_spread = positive("initial_spread", initial_spread)
        drift = finite("force_drift", force_drift, "N/√s")
        if drift < 0:
            raise ConfigError(f"force_drift must be >= 0 N/√s (got {drift:g})")
        self.force_drift = drift
        self.reach = positive("reach", reach, "m")
        body = model.body
        xc, yc = body.cg_offset
        self._theta0 = np.array(
            [body.mass, body.mass * xc, body.mass * yc, body.inertia_centroid, 0.0]
        )
        scale = np.array(
            [body.mass, 0.1 * body.mass, 0.1 * body.mass, body.inertia_centroid,
             0.1 * body.mass * GRAVITY]
        )  # fmt: skip
        self._p0 = np.diag((self.initial_spread * scale) ** 2)
        self._q = np.diag([0.0, 0.0, 0.0, 0.0, drift**2])
        self.reset()

    # ------------------------------------------------------------------ state
    def reset(self) -> None:
        """Back to the initial model: estimates, covariance, filters, PID integrals."""
        self._pid.reset()
        self._n = 0
        self._last_t: float | None = None
        self.history: list[tuple[float, np.ndarray]] = []

    def _start(self, n: int) -> None:
        self._n = n
        self._theta = np.tile(self._theta0, (n, 1))
        self._p = np.tile(self._p0, (n, 1, 1))
        self._once = np.zeros((n, 2 * _P + 2))  # H·(Y_k (2 × 6 entries), F_x, M_z)
        self._twice = np.zeros((n, 2 * _P + 2))  # H² of the same
        self._nu = np.zeros((n, 2))
        self._force = np.zeros((n, 2))
        self._cst = np.zeros((n, 7))
        self._started = False

    @property
    def estimates(self) -> np.ndarray:
        """θ̂ ``(N, 5)`` now (:data:`ESTIMATE_NAMES`)."""
        return self._theta.copy() if self._n else self._theta0[None].copy()

    def _models(self) -> np.ndarray:
        """The parameter rows of the compiled PID for every robot's estimate (N, 10)."""
        base = self.model.params
        theta = self._theta
        rows = np.tile(base, (self._n, 1))
        rows[:, 0] = theta[:, 0]
        rows[:, 1] = theta[:, 1] / theta[:, 0]
        rows[:, 2] = theta[:, 2] / theta[:, 0]
        rows[:, 3] = theta[:, 3]
        return np.ascontiguousarray(rows)

    def _force_acceleration(self) -> np.ndarray:
        """(δu̇, δṙ) ``(N, 2)`` = M̂_r⁻¹·(F̂_0, 0): F̂_0 as a change of the reference's
        acceleration, so that the PID kernel's M̂·a adds exactly F̂_0 (and nothing to M_z)."""
        m, _mx, my, ib, f0 = self._theta.T
        det = m * ib - my * my  # of [[m, −m y_c], [−m y_c, I_B]]
        return np.column_stack([ib * f0 / det, my * f0 / det])

    # ------------------------------------------------------------------ estimation
    def _learn(self, nu: np.ndarray, dt: float) -> None:
        """One RLS step with the force applied over the last ``dt`` and the velocity now."""
        alpha = -math.expm1(-dt / self.filter_time)
        rows = step_regressor(nu, self._nu, dt).reshape(-1, 2 * _P)
        self._once += alpha * (np.column_stack([rows, self._force]) - self._once)
        self._twice += alpha * (self._once - self._twice)
        y = self._twice[:, : 2 * _P].reshape(-1, 2, _P)
        force = self._twice[:, 2 * _P :]
        lam = self.forgetting
        p = self._p
        py = p @ np.swapaxes(y, 1, 2)  # (N, 5, 2)
        s = lam * np.eye(2) + y @ py  # (N, 2, 2)
        gain = np.swapaxes(np.linalg.solve(s, np.swapaxes(py, 1, 2)), 1, 2)  # P Yᵀ S⁻¹
        error = force - np.einsum("nij,nj->ni", y, self._theta)
        self._theta = self._theta + np.einsum("nij,nj->ni", gain, error)
        self._p = (p - gain @ y @ p) / lam + self._q * dt
        self._p = 0.5 * (self._p + np.swapaxes(self._p, 1, 2))
        self._project()

    def _project(self) -> None:
        """Keep the estimates physical: mass at least a fifth of the model's; the CG within
        ``reach`` of B; I_B between a fifth of the model's and what the added mass can add
        within ``reach`` (its spin and its offset: 2·Δm·reach²), and above m·|c|²."""
        theta, first = self._theta, self._theta0
        theta[:, 0] = np.maximum(theta[:, 0], 0.2 * first[0])
        bound = theta[:, 0:1] * self.reach
        theta[:, 1:3] = np.clip(theta[:, 1:3], -bound, bound)
        floor = (theta[:, 1] ** 2 + theta[:, 2] ** 2) / theta[:, 0]
        added = np.maximum(theta[:, 0] - first[0], 0.0)
        top = first[3] + 2.0 * added * self.reach**2
        theta[:, 3] = np.clip(theta[:, 3], np.maximum(0.2 * first[3], 1.01 * floor), top)

    # ------------------------------------------------------------------ control
    def __call__(
        self,
        t: float,
        pose: ArrayLike,
        reference: PoseTrajectory | TimedRows | ArrayLike,
        twist: ArrayLike | None = None,
        dt: float | None = None,
    ) -> np.ndarray:
        """Wheel torques (τ_L, τ_R) [N·m] for one robot or a batch at time ``t`` [s].

        Parameters
        ----------
        t : float
            Time [s].
        pose : array_like, shape (..., 3) or (..., 6)
            Measured poses, or full states (x, y, ψ, u, v, r).
        reference : PoseTrajectory, TimedRows or array_like, shape (9,) or (..., 9)
            As :class:`~wheelbase.control.ComputedTorquePID`.
        twist : array_like, shape (..., 3), optional
            Measured twists when ``pose`` has 3 columns.
        dt : float, optional
            Control period [s] (default: the time since the last call).
        """
        t = finite("t", t, "s")
        state = as_float_array("pose", pose, min_ndim=1)
        if state.shape[-1] == 3:
            if twist is None:
                raise InputError("AdaptiveComputedTorque needs the measured twist (u, v, r)")
            state = np.concatenate(np.broadcast_arrays(state, as_float_array("twist", twist, 3)),
                                   axis=-1)  # fmt: skip
        elif state.shape[-1] != 6:
            raise InputError(f"pose must have 3 or 6 columns (got shape {state.shape})")
        flat = np.ascontiguousarray(state.reshape(-1, 6))
        if isinstance(reference, TimedRows):
            row = reference.at(t)
        elif isinstance(reference, PoseTrajectory):
            row = reference.at([t]).reference()[0]
        else:
            row = as_float_array("reference", reference, 9)
        rows = np.array(np.broadcast_to(row.reshape(-1, 9), (flat.shape[0], 9)))
        if dt is None:
            dt = 0.0 if self._last_t is None else t - self._last_t
        else:
            dt = positive("dt", dt, "s")
        self._last_t = t
        if self._n != flat.shape[0]:
            self._start(flat.shape[0])
        nu = flat[:, [3, 5]]
        if self._started and dt > 0:
            self._learn(nu, dt)
        self._nu = nu.copy()
        rows[:, [6, 8]] += self._force_acceleration()
        g = self._pid._gain_matrices
        out = np.empty((flat.shape[0], 2))
        args = self._pid._kernel_args()
        _control_models(rows, flat, self._models(), g, args[2], args[3], args[4], args[5],
                        self._cst, max(dt, 0.0), out)  # fmt: skip
        a, d = self.model.wheel_radius, self.model.half_track
        self._force = np.column_stack([out[:, 0] + out[:, 1], d * (out[:, 1] - out[:, 0])]) / a
        self._started = True
        self.history.append((t, self._theta.copy()))
        return out.reshape((*state.shape[:-1], 2))
