"""Wheel odometry that takes out the slip its own torques cause (a robot that knows its floor).

A driven wheel slips in proportion to the force it transmits: to push a robot up a grade a
drive wheel turns faster than the ground passes under it, and plain encoder odometry counts the
difference as travel. On a 10 % ramp with a 100 % payload (RM100 on dry concrete, half the
weight on the drive wheels) the wheels carry ~0.22 of their load and slip ~1.7 %: 6 m of ramp
up and down put the odometry 0.16 m off.

:class:`SlipCompensatedOdometry` reads, besides the ticks, the wheel torques τ_k commanded over
the step (the engine passes them to an estimator with ``reads_command``) and, per drive wheel
k on hard ground:

1. the force it transmits F_k = τ_k/a − c_rr·N_k·sgn(w_k) − J_w·Δw_k/(a²·Δt) (the wheel's own
   dynamics J_w·ω̇ = τ − a·F − M_rr: its rolling-resistance moment and the torque that spins
   it up taken out), w_k = D_k/Δt its rim speed from the ticks, Δw_k its change since the last
   step (none on the first). Counted as ground force, the spin-up (J_w·ẇ/a² is 2.4 N per m/s² of
   rim acceleration on the RM100, against 6.4 N of grip a wheel has on ice) made a wheel that
   speeds up look as if it pushed the ground harder: its slip, and the heading, came out wrong;
2. its normal load N_k from the static weight m·g·cos α on the contacts
   (:func:`~wheelbase.terrain.normal_loads`, the CG of the model, the slope under the
   estimate) with the load transfer of the tangential force ΣF_k at the CG height;
3. the slip that force needs on the rising branch of the floor's friction curve
   μ(σ) = D·sin(C·atan(B·σ)) under the wheel (:class:`~wheelbase.terrain.FrictionCurve`),
   σ = tan(asin(|F_k|/(D·N_k))/C)/B, at most the peak slip σ_p, with the sign of F_k;
4. the ground speed of the wheel from Pacejka's slip ratio κ = (a·ω − v_x)/|v_x| (the
   plant's :mod:`~wheelbase.terrain.dynamics` away from standstill):
   v_x = w_k/(1 + κ·sgn(w_k)), and dead reckoning on the distances v_x·Δt.

On soil the thrust is not a function of the slip alone that one could invert for a wheel that
sinks; there (and off the terrain map's rectangle, where its default surface lies) the wheel
counts as without slip only where the surface is hard: soil wheels are left uncompensated.
Lateral slip (a turn's side force) is not modelled: the correction is along each wheel.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, ClassVar

import numpy as np

from wheelbase.dynamics import GRAVITY, DiffDriveDynamics
from wheelbase.errors import ConfigError
from wheelbase.sim.sensing import EncoderOdometry

__all__ = ["SPIN_UP_TIME", "SlipCompensatedOdometry", "slip_from_force"]

SPIN_UP_TIME = 0.05
"""Time constant [s] of the filter on the rim speed whose change is the wheel's spin-up."""


def slip_from_force(force: np.ndarray, load: np.ndarray, curves: np.ndarray) -> np.ndarray:
    """Slip κ that transmits ``force`` under ``load`` on the rising branch of a magic formula.

    Parameters
    ----------
    force : numpy.ndarray
        Longitudinal ground force F [N] (signed).
    load : numpy.ndarray
        Normal load N [N], same shape (≤ 0: no slip).
    curves : numpy.ndarray, shape (..., 3)
        Pacejka (B, C, D) per entry (D = 0: no curve, no slip).

    Returns
    -------
    numpy.ndarray
        κ with the sign of F, |κ| ≤ the curve's peak slip tan(π/(2C))/B.

    Examples
    --------
    >>> from wheelbase.terrain import FrictionCurve
    >>> curve = FrictionCurve(0.85, 0.75, 0.16)
    >>> kappa = slip_from_force(np.array(50.0), np.array(100.0), np.array(curve.coefficients))
    >>> bool(np.isclose(curve.mu(kappa), 0.5))
    True
    """
    b, c, d = curves[..., 0], curves[..., 1], curves[..., 2]
    ok = (load > 0.0) & (d > 0.0)
    ratio = np.where(ok, np.abs(force) / np.where(ok, load * d, 1.0), 0.0)
    c_safe = np.where(ok, c, 1.0)
    sigma = np.tan(np.arcsin(np.minimum(ratio, 1.0)) / c_safe) / np.where(ok, b, 1.0)
    return np.where(ok, np.sign(force) * sigma, 0.0)


@dataclass(frozen=True)
class SlipCompensatedOdometry(EncoderOdometry):
    """Encoder odometry with the slip of the commanded torques taken out (module docstring).

    Parameters
    ----------
    encoder : Encoder
        The encoders of both wheels of the encoder axle.
    odometry : WheelOdometry
        The dead reckoning with the *nominal* geometry.
    model : DiffDriveDynamics
        The robot as the estimator believes it: mass [kg], CG [m], wheel radius [m].
    contacts : WheelContacts
        Drive wheels and casters (the load sharing, the CG height).
    terrain : TerrainMap
        The floor the robot knows: the surface under each wheel, the slope under it.
    """

    model: Any = None
    contacts: Any = None
    terrain: Any = None
    reads_command: ClassVar[bool] = True
    _table: Any = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        super().__post_init__()
        from wheelbase.terrain.contact import WheelContacts
        from wheelbase.terrain.map import TerrainMap

        if not isinstance(self.model, DiffDriveDynamics):
            raise ConfigError(
                f"model must be a DiffDriveDynamics (got {type(self.model).__name__})"
            )
        if not isinstance(self.contacts, WheelContacts):
            raise ConfigError(
                f"contacts must be WheelContacts (got {type(self.contacts).__name__})"
            )
        if not isinstance(self.terrain, TerrainMap):
            raise ConfigError(f"terrain must be a TerrainMap (got {type(self.terrain).__name__})")
        rows = []
        for surface in self.terrain.surfaces:
            if surface.friction is None:  # soil: left uncompensated
                rows.append((0.0, 0.0, 0.0, 0.0))
            else:
                rows.append((*surface.friction.coefficients, surface.rolling_resistance))
        object.__setattr__(self, "_table", np.array(rows, dtype=np.float64))

    def start(self, poses: np.ndarray, seeds: np.ndarray) -> np.ndarray:
        """The rim speeds (left, right) [m/s] of the last step, ``(N, 2)``: none yet (NaN).

        Parameters
        ----------
        poses : numpy.ndarray, shape (N, 3)
            Start poses.
        seeds : numpy.ndarray
            The robots' seeds (unused).
        """
        return np.full((np.shape(poses)[0], 2), np.nan)

    def wheel_loads(self, estimate: np.ndarray, tangential: np.ndarray) -> np.ndarray:
        """Normal loads (left, right) [N] at the estimated poses ``(M, 3)`` (module docstring).

        Parameters
        ----------
        estimate : numpy.ndarray, shape (M, 3)
            Estimated poses.
        tangential : numpy.ndarray, shape (M,)
            Longitudinal ground force on the body [N] (load transfer).
        """
        from wheelbase.terrain.contact import normal_loads

        body = self.model.body
        slope = self.terrain.slope_at(estimate[:, :2])
        cos_a = np.sqrt(np.maximum(1.0 - np.sum(slope**2, axis=-1), 0.0))
        out = np.empty((estimate.shape[0], 2))
        for i in range(estimate.shape[0]):
            loads = normal_loads(
                self.contacts, self.model.half_track, body.mass * GRAVITY * cos_a[i],
                body.cg_offset, tangential=(tangential[i], 0.0),
            )  # fmt: skip
            out[i] = loads[:2]
        return out

    def travel(self, estimate, ticks, dt, *, state=None, index=None, command=None):
        """The distance [m] and rotation [rad] of one step on the slip-corrected wheel
        distances, ``(N,)`` each, and the rim speeds after (:meth:`start`).

        Parameters
        ----------
        estimate : numpy.ndarray, shape (N, 3)
            The estimate at the start of the step (the surface and the loads under it).
        ticks : numpy.ndarray, shape (N, 2)
            Tick differences counted during the step.
        dt : float
            Step [s].
        state : numpy.ndarray, shape (M, 2), optional
            The rim speeds of every robot's last step (:meth:`start`; None: no spin-up).
        index : numpy.ndarray, optional
            Which rows of ``state`` these robots are (default: all).
        command : numpy.ndarray, shape (N, 2), optional
            The wheel torques (left, right) [N·m] held over the step; without them, plain
            encoder odometry.
        """
        if command is None:
            return super().travel(estimate, ticks, dt, state=state, index=index)

        distances = self.odometry.wheel_distances(ticks)
        rim = distances / dt
        tau = np.asarray(command, dtype=np.float64).reshape(-1, 2)
        under = self.terrain.under_wheels(estimate, self.model.half_track)
        rows = self._table[under]  # (N, 2, 4): B, C, D, c_rr
        pushed = tau / self.model.wheel_radius
        loads = self.wheel_loads(estimate, pushed.sum(axis=1))
        spin_up = np.zeros_like(rim)
        if state is not None:
            rows_of = slice(None) if index is None else index
            last = np.asarray(state, dtype=np.float64)[rows_of]
            # the rim speed filtered over SPIN_UP_TIME before it is differentiated: one tick
            # in one step is a rim acceleration of tick/Δt², tens of newtons on ice
            gain = min(1.0, dt / SPIN_UP_TIME)
            change = np.where(np.isfinite(last), gain * (rim - last), 0.0)
            spin_up = change / dt
            state = np.array(state, dtype=np.float64)
            state[rows_of] = np.where(np.isfinite(last), last + change, rim)
        a = self.model.wheel_radius
        inertia = self.contacts.wheel_inertia
        force = pushed - rows[..., 3] * loads * np.sign(rim) - inertia * spin_up / a**2
        kappa = slip_from_force(force, loads, rows[..., :3])
        ground = rim / (1.0 + kappa * np.sign(rim))
        corrected = ground * dt
        left, right = corrected[:, 0], corrected[:, 1]
        return 0.5 * (left + right), (right - left) / self.odometry.track, state
