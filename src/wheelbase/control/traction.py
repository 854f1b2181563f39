"""Traction control: wheel torques limited by the friction the ground gives, so wheels don't spin.

A wheel transmits at most μ·N to the ground; a torque beyond a·μ·N only spins it up, and a
spinning wheel both loses traction (past the peak of the friction curve) and drives the
odometry off. :class:`TractionControl` wraps any torque controller and clips each wheel's
torque to

    |τ_i| ≤ margin · a · μ̂_i · N̂_i,     N̂_i = s · m̂ · g / 2,

N̂ the static load of a drive wheel (share s of the weight m̂·g of the controller's model:
an unknown payload only adds grip), μ̂ the friction it believes in:

- a known coefficient (``friction=0.1`` on ice), or
- ``"auto"``: estimated from the wheels. A wheel observer gives the force the ground takes,
  F̂_i = (τ_i − J_w·ω̇_i)/a (the torque sent last step, the wheel's acceleration from its
  encoder rate, filtered); a gripping wheel needs F_i ≈ (m̂/2)·a·ω̇_i to accelerate its share
  of the robot, so a wheel accelerating while the ground takes less than half of that is
  spinning, and then μ̂_i drops to F̂_i/N̂_i. Between spins μ̂ creeps back up to its start
  value at ``recovery`` per second, to find the grip again when the floor improves.
"""

from __future__ import annotations

import math
from typing import ClassVar

import numpy as np
from numpy.typing import ArrayLike

from wheelbase._validate import as_float_array, finite, positive
from wheelbase.dynamics import GRAVITY, DiffDriveDynamics
from wheelbase.errors import ConfigError

__all__ = ["TractionControl"]


class TractionControl:
    """Wrap a torque controller: each wheel's torque limited by the friction (module docstring).

    Parameters
    ----------
    law : callable
        A controller giving wheel torques (``command_names`` (tau_left, tau_right)).
    model : DiffDriveDynamics
        The controller's model (mass, wheel radius, half track).
    friction : float or "auto"
        The friction coefficient to respect, in (0, 3], or ``"auto"`` to estimate it.
    margin : float
        Share of the friction limit the torques may use, in (0, 1].
    drive_load_share : float
        Share s of the weight on the drive wheels, in (0, 1].
    wheel_inertia : float
        J_w of a drive wheel [kg·m²], > 0 (for the observer).
    initial_friction : float
        μ̂ before any spin is seen (``auto``), in (0, 3].
    recovery : float
        Rate [1/s] at which μ̂ creeps back to ``initial_friction``, ≥ 0.
    filter_time : float
        Time constant of the wheel-acceleration filter [s], > 0.
    """

    command_names: ClassVar[tuple[str, ...]] = ("tau_left", "tau_right")

    def __init__(
        self,
        law: object,
        model: DiffDriveDynamics,
        *,
        friction: float | str = "auto",
        margin: float = 0.8,
        drive_load_share: float = 0.5,
        wheel_inertia: float = 0.01,
        initial_friction: float = 0.85,
        recovery: float = 0.05,
        filter_time: float = 0.05,
    ) -> None:
        if not callable(law) or tuple(getattr(law, "command_names", ())) != self.command_names:
            raise ConfigError("traction control wraps a controller that gives wheel torques")
        if not isinstance(model, DiffDriveDynamics):
            raise ConfigError(f"model must be a DiffDriveDynamics (got {type(model).__name__})")
        self.law = law
        self.model = model
        if friction != "auto":
            friction = finite("friction", friction)
            if not 0.0 < friction <= 3.0:
                raise ConfigError(f"friction must be 'auto' or in (0, 3] (got {friction:g})")
        self.friction = friction
        self.margin = _share("margin", margin)
        self.drive_load_share = _share("drive_load_share", drive_load_share)
        self.wheel_inertia = positive("wheel_inertia", wheel_inertia, "kg·m²")
        initial = finite("initial_friction", initial_friction)
        if not 0.0 < initial <= 3.0:
            raise ConfigError(f"initial_friction must be in (0, 3] (got {initial:g})")
        self.initial_friction = initial
        recovery = finite("recovery", recovery, "1/s")
        if recovery < 0:
            raise ConfigError(f"recovery must be >= 0 1/s (got {recovery:g})")
        self.recovery = recovery
        self.filter_time = positive("filter_time", filter_time, "s")
        self.reset()

    # ------------------------------------------------------------------ passed through
    def reset(self) -> None:
        """Forget the estimates; reset the wrapped law."""
        self._n = 0
        self._last_t: float | None = None
        reset = getattr(self.law, "reset", None)
        if reset is not None:
            reset()

    @property
    def per_robot(self) -> bool:
        """Whether the wrapped law needs one copy per robot."""
        return bool(getattr(self.law, "per_robot", False))

    @property
    def status(self) -> str | None:
        """The wrapped law's status, if it has one."""
        return getattr(self.law, "status", None)

    @property
    def estimated_friction(self) -> np.ndarray:
        """μ̂ ``(N, 2)`` of each robot's wheels now."""
        if not self._n:
            start = self.initial_friction if self.friction == "auto" else self.friction
            return np.full((1, 2), start)
        return self._mu.copy()

    def limits(self) -> np.ndarray:
        """The torque limits ``(N, 2)`` [N·m] now."""
        load = self.drive_load_share * self.model.body.mass * GRAVITY / 2.0
        return self.margin * self.model.wheel_radius * self.estimated_friction * load

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
        n = flat.shape[0]
        raw = np.asarray(self.law(t, s.copy(), reference), dtype=np.float64).reshape(n, 2)
        a, d = self.model.wheel_radius, self.model.half_track
        omega = np.column_stack([flat[:, 3] - d * flat[:, 5], flat[:, 3] + d * flat[:, 5]]) / a
        dt = 0.0 if self._last_t is None else t - self._last_t
        self._last_t = t
        if self._n != n:
            self._n = n
            start = self.initial_friction if self.friction == "auto" else self.friction
            self._mu = np.full((n, 2), float(start))
            self._omega = omega.copy()
            self._accel = np.zeros((n, 2))
            self._sent = np.zeros((n, 2))
        elif dt > 0 and self.friction == "auto":
            self._observe(omega, dt)
        self._omega = omega.copy()
        torques = np.clip(raw, -self.limits(), self.limits())
        self._sent = torques.copy()
        return torques.reshape((*s.shape[:-1], 2))

    def _observe(self, omega: np.ndarray, dt: float) -> None:
        """Update μ̂ from the wheels' acceleration and the torques sent (module docstring)."""
        alpha = -math.expm1(-dt / self.filter_time)
        self._accel += alpha * ((omega - self._omega) / dt - self._accel)
        a = self.model.wheel_radius
        ground = (self._sent - self.wheel_inertia * self._accel) / a  # F̂ the ground takes
        needed = 0.5 * self.model.body.mass * a * self._accel  # if the wheel gripped
        load = self.drive_load_share * self.model.body.mass * GRAVITY / 2.0
        spinning = (np.abs(a * self._accel) > 0.2) & (
            np.abs(ground) < 0.5 * np.abs(needed)
        )  # accelerating faster than the ground pushes: spinning
        seen = np.clip(np.abs(ground) / load, 0.02, self.initial_friction)
        self._mu = np.where(spinning, np.minimum(self._mu, seen), self._mu)
        self._mu = np.minimum(self._mu + self.recovery * dt, self.initial_friction)


def _share(name: str, value: float) -> float:
    number = finite(name, value)
    if not 0.0 < number <= 1.0:
        raise ConfigError(f"{name} must be in (0, 1] (got {number:g})")
    return number
