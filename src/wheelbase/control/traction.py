"""Traction control: wheel torques limited by the friction the ground gives, so wheels don't spin.

A wheel transmits at most μ·N to the ground, along and across together (the friction circle);
a torque beyond what is left of it only spins the wheel up, and a spinning wheel both loses
traction (past the peak of the friction curve) and drives the odometry off.
:class:`TractionControl` wraps any torque controller and clips each wheel's torque to

    |τ_i| ≤ margin · a · √((μ̂_i·N̂_i)² − F_y²),   N̂_i = s·m̂·g/2,   F_y = m̂·|u·r|/2,

N̂ the static load of a drive wheel (share s of the weight m̂·g of the controller's model:
an unknown payload only adds grip), F_y its share of the centripetal force of a turn (the
casters take none), at least a fifth of the circle left for braking, and μ̂ the friction it
believes in:

- ``friction="estimate"``: its own online estimate, per wheel, from the wheel rates its
  encoders give, the torques it commanded and its model — never the terrain
  (:class:`~wheelbase.control.friction_estimate.FrictionEstimator`: a wheel whose slip speed
  against the body the model predicts grows in the direction of its force is spinning, and the
  friction the ground gave it meanwhile is the estimate). While a wheel spins its torque is cut
  to ``regrip`` times what the ground gave (below the sliding friction, so it grips again);
- a coefficient it is given (``friction=0.1`` on ice);
- the peak friction of the floor it knows, looked up under each wheel's estimated position in
  its terrain map (``friction="map"``: :attr:`wheelbase.terrain.Surface.peak_friction`).

**Holding the integrators** (``hold_integrators=True``): a clipped torque is a saturation the
wrapped law does not see, so its integrators wind up while traction clips and the robot
overshoots once grip allows (on ice the demo's computed-torque PID reached 1.4 m/s on a
0.6 m/s reference, skidded and collided). With it the law's own torque limit is lowered to the
smallest friction limit during the call, so its anti-windup (conditional integration) holds.

Up to the peak slip the friction curve rises with the slip, so a wheel whose force stays below
margin·μ_p·N settles below its peak slip and never spins.

**Slowing down** (``slow_down=True``): the lateral grip a turn needs, m·|u·r|/2 per drive
wheel, cannot be limited by torque alone: the reference goes round the turn at its speed. With
``slow_down`` the wrapper runs the reference on a clock of its own that advances at the rate
κ = min(1, √(margin·μ̂·s·g / |u_ref·r_ref|), √(margin·μ̂·s·g / |u̇_ref|)) (μ̂ the lower estimate
of the two wheels), and scales the reference's speeds by κ and its accelerations by κ²: the same
path, driven at the speed the friction allows (a wrapped law that samples a timed reference,
:class:`~wheelbase.control.torque.ComputedTorquePID` and the adaptive law).
"""

from __future__ import annotations

import math
from typing import ClassVar

import numpy as np
from numpy.typing import ArrayLike

from wheelbase._validate import as_float_array, finite
from wheelbase.control.base import WrappedLaw
from wheelbase.dynamics import GRAVITY, DiffDriveDynamics
from wheelbase.errors import ConfigError

__all__ = ["SLOW_DOWN_RATE", "TractionControl"]

SLOW_DOWN_RATE = 0.5
"""Fastest change of the reference clock's rate κ with ``slow_down`` [1/s]."""


class TractionControl(WrappedLaw):
    """Wrap a torque controller: each wheel's torque limited by the friction (module docstring).

    Parameters
    ----------
    law : callable
        A controller giving wheel torques (``command_names`` (tau_left, tau_right)).
    model : DiffDriveDynamics
        The controller's model (mass, wheel radius, half track).
    friction : float, "map" or "estimate"
        The friction coefficient to respect, in (0, 3]; ``"map"``: the peak friction under
        each wheel in ``terrain``; ``"estimate"``: the online estimate (module docstring).
    margin : float
        Share of the friction limit the torques may use, in (0, 1].
    drive_load_share : float
        Share s of the weight on the drive wheels, in (0, 1].
    wheel_inertia : float
        J_w of a drive wheel [kg·m²], > 0 (for the observer).
    terrain : TerrainMap, optional
        The floor the robot knows (``friction="map"``; never read with ``"estimate"``).
    initial_friction : float
        The estimate's prior μ̂ before any spin (``friction="estimate"``), in (0, 3].
    regrip : float
        Share of the transmitted force a spinning wheel's torque is cut to, in (0, 1].
    slow_down : bool
        Drive the reference slower where the friction is low (module docstring).
    hold_integrators : bool
        Give the wrapped law (the innermost one with a ``max_torque``) the smallest friction
        limit as its torque saturation during the call, so that its anti-windup stops its
        integrators while traction clips (module docstring).
    """

    command_names: ClassVar[tuple[str, ...]] = ("tau_left", "tau_right")

    def __init__(
        self,
        law: object,
        model: DiffDriveDynamics,
        *,
        friction: float | str = "map",
        margin: float = 0.8,
        drive_load_share: float = 0.5,
        wheel_inertia: float = 0.01,
        terrain: object = None,
        initial_friction: float = 1.0,
        regrip: float = 0.5,
        slow_down: bool = False,
        hold_integrators: bool = False,
    ) -> None:
        if not callable(law) or tuple(getattr(law, "command_names", ())) != self.command_names:
            raise ConfigError("traction control wraps a controller that gives wheel torques")
        if not isinstance(model, DiffDriveDynamics):
            raise ConfigError(f"model must be a DiffDriveDynamics (got {type(model).__name__})")
        self.law = law
        self.model = model
        if friction == "map":
            from wheelbase.terrain.map import TerrainMap

            if not isinstance(terrain, TerrainMap):
                raise ConfigError("friction 'map' needs the terrain map (a TerrainMap)")
            self._peaks = np.array([surface.peak_friction for surface in terrain.surfaces])
        elif friction == "estimate":
            terrain = None  # the estimate never reads the floor
        else:
            friction = finite("friction", friction)
            if not 0.0 < friction <= 3.0:
                raise ConfigError(
                    f"friction must be 'map', 'estimate' or in (0, 3] (got {friction:g})"
                )
        self.friction = friction
        self.terrain = terrain
        self.margin = _share("margin", margin)
        self.drive_load_share = _share("drive_load_share", drive_load_share)
        self.regrip = _share("regrip", regrip)
        if not isinstance(slow_down, bool):
            raise ConfigError(f"slow_down must be true or false (got {slow_down!r})")
        self.slow_down = slow_down
        if not isinstance(hold_integrators, bool):
            raise ConfigError(f"hold_integrators must be true or false (got {hold_integrators!r})")
        self.hold_integrators = hold_integrators
        self.estimator = None
        if friction == "estimate":
            from wheelbase.control.friction_estimate import FrictionEstimator

            self.estimator = FrictionEstimator(
                model, wheel_inertia=wheel_inertia, drive_load_share=self.drive_load_share,
                initial=initial_friction,
            )  # fmt: skip
        self._last: np.ndarray | None = None
        self._clock: tuple[float, float, float] | None = None  # (t, reference time, rate)

    # ------------------------------------------------------------------ passed through
    def reset(self) -> None:
        """Reset the wrapped law and the friction estimate."""
        self._last = None
        self._clock = None
        if self.estimator is not None:
            self.estimator.reset()
        super().reset()

    # ------------------------------------------------------------------ limits
    def friction_at(self, state: ArrayLike) -> np.ndarray:
        """μ̂ ``(N, 2)`` under each wheel of the estimated states ``(N, 6)``.

        Parameters
        ----------
        state : array_like, shape (N, 6)
            Estimated (x, y, θ, u, v, r).
        """
        s = np.asarray(state, dtype=np.float64).reshape(-1, 6)
        if self.friction == "estimate":
            known = self.estimator.friction
            if known is None or known.shape[0] != s.shape[0]:
                return np.full((s.shape[0], 2), self.estimator.initial)
            return known.copy()
        if self.friction != "map":
            return np.full((s.shape[0], 2), float(self.friction))
        return self._peaks[self.terrain.under_wheels(s, self.model.half_track)]

    def limits(self, state: ArrayLike) -> np.ndarray:
        """The torque limits ``(N, 2)`` [N·m] at the estimated states (module docstring).

        Parameters
        ----------
        state : array_like, shape (N, 6)
            Estimated states (position: the floor; u and r: the turn's lateral force).
        """
        s = np.asarray(state, dtype=np.float64).reshape(-1, 6)
        mass = self.model.body.mass
        grip = self.friction_at(s) * self.drive_load_share * mass * GRAVITY / 2.0
        lateral = 0.5 * mass * np.abs(s[:, 3] * s[:, 5])[:, None]
        grip = np.sqrt(np.maximum(grip**2 - lateral**2, (0.2 * grip) ** 2))
        share = np.full(grip.shape, self.margin)
        spinning = None if self.estimator is None else self.estimator.spinning
        if spinning is not None and spinning.shape == share.shape:
            share = np.where(spinning, self.regrip, share)
        return share * self.model.wheel_radius * grip

    # ------------------------------------------------------------------ control
    def __call__(self, t: float, state: ArrayLike, reference: object) -> np.ndarray:
        """The wrapped law's wheel torques, each clipped to its friction limit.

        Parameters
        ----------
        t : float
            Time [s].
        state : array_like, shape (..., 6)
            Estimated (x, y, θ, u, v, r).
        reference : object
            Passed to the law.
        """
        s = as_float_array("state", state, 6)
        flat = s.reshape(-1, 6)
        if self.estimator is not None:
            last = self._last
            if last is None or last.shape != (flat.shape[0], 2):
                last = np.zeros((flat.shape[0], 2))
            self.estimator.update(t, flat, last)
        if self.slow_down:
            reference = self._slowed(t, flat, reference)
        inner = self._saturated_law() if self.hold_integrators else None
        nominal = None if inner is None else inner.max_torque
        if inner is not None:
            inner.max_torque = min(nominal, float(np.min(self.limits(flat))))
        try:
            raw = np.asarray(self.law(t, s.copy(), reference), dtype=np.float64)
        finally:
            if inner is not None:
                inner.max_torque = nominal
        raw = raw.reshape(flat.shape[0], 2)
        limit = self.limits(flat)
        out = np.clip(raw, -limit, limit)
        self._last = out.copy()
        return out.reshape((*s.shape[:-1], 2))

    def _saturated_law(self) -> object | None:
        """The innermost wrapped law with a ``max_torque`` (None without one)."""
        law = self.law
        while not hasattr(law, "max_torque") and hasattr(law, "law"):
            law = law.law
        return law if hasattr(law, "max_torque") else None

    # ------------------------------------------------------------------ slowing down
    def _slowed(self, t: float, flat: np.ndarray, reference: object) -> object:
        """The reference's row on the wrapper's own clock (module docstring)."""
        from wheelbase.control.torque import TimedRows
        from wheelbase.models.path import PoseTrajectory

        if not isinstance(reference, TimedRows | PoseTrajectory):
            return reference  # a path, not a timed reference: nothing to slow
        sample = getattr(self.law, "row", None)  # the law's own rows (its bounded feed-forward)

        def row_at(time: float) -> np.ndarray:
            if sample is not None:
                return np.asarray(sample(time, reference), dtype=np.float64)
            if isinstance(reference, TimedRows):
                return reference.at(time)
            return reference.at([time]).reference()[0]

        if self._clock is None or t < self._clock[0]:
            self._clock = (t, t, 1.0)
        before, clock, rate = self._clock
        clock += rate * (t - before)
        row = row_at(clock)
        grip = self.margin * float(np.min(self.friction_at(flat))) * self.drive_load_share * GRAVITY
        need = max(abs(row[3] * row[5]), abs(row[6]), 1e-9)
        wanted = min(1.0, math.sqrt(grip / need))
        step = SLOW_DOWN_RATE * max(t - before, 0.0)
        new_rate = min(max(wanted, rate - step), rate + step)
        self._clock = (t, clock, new_rate)
        rate_dot = (new_rate - rate) / (t - before) if t > before else 0.0
        out = row.copy()
        out[3:6] = new_rate * row[3:6]
        out[6:9] = new_rate**2 * row[6:9] + rate_dot * row[3:6]
        return out


def _share(name: str, value: float) -> float:
    number = finite(name, value)
    if not 0.0 < number <= 1.0:
        raise ConfigError(f"{name} must be in (0, 1] (got {number:g})")
    return number
