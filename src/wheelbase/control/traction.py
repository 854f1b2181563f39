"""Traction control: wheel torques limited by the friction the ground gives, so wheels don't spin.

A wheel transmits at most μ·N to the ground, along and across together (the friction circle);
a torque beyond what is left of it only spins the wheel up, and a spinning wheel both loses
traction (past the peak of the friction curve) and drives the odometry off.
:class:`TractionControl` wraps any torque controller and clips each wheel's torque to

    |τ_i| ≤ margin · a · √((μ̂_i·N̂_i)² − F_y²),   N̂_i = s·m̂·g/2,   F_y = m̂·|u·r|/2,

N̂ the static load of a drive wheel (share s of the weight m̂·g of the controller's model:
an unknown payload only adds grip), F_y its share of the centripetal force of a turn (the
casters take none), at least a fifth of the circle left for braking, and μ̂ the friction it
believes in: a coefficient it is given (``friction=0.1`` on ice), or the peak friction of the
floor it knows, looked up under each wheel's estimated position in its terrain map
(``friction="map"``: :attr:`wheelbase.terrain.Surface.peak_friction`). Up to the peak slip the
friction curve rises with the slip, so a wheel whose force stays below margin·μ_p·N settles
below its peak slip and never spins.

(An online estimate from the wheels alone — a rim accelerating faster than the torques could
accelerate the robot — was tried: with 2048-tick encoders at 100 Hz the quantisation hides the
onset of a spin on ice, whose rim accelerates by under 1 m/s², and it was left out.)
"""

from __future__ import annotations

from typing import ClassVar

import numpy as np
from numpy.typing import ArrayLike

from wheelbase._validate import as_float_array, finite
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
    friction : float or "map"
        The friction coefficient to respect, in (0, 3], or ``"map"``: the peak friction under
        each wheel in ``terrain``.
    margin : float
        Share of the friction limit the torques may use, in (0, 1].
    drive_load_share : float
        Share s of the weight on the drive wheels, in (0, 1].
    wheel_inertia : float
        J_w of a drive wheel [kg·m²], > 0 (for the observer).
    terrain : TerrainMap, optional
        The floor the robot knows (``friction="map"``).
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
        terrain: object = None,
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
        else:
            friction = finite("friction", friction)
            if not 0.0 < friction <= 3.0:
                raise ConfigError(f"friction must be 'map' or in (0, 3] (got {friction:g})")
        self.friction = friction
        self.terrain = terrain
        self.margin = _share("margin", margin)
        self.drive_load_share = _share("drive_load_share", drive_load_share)

    # ------------------------------------------------------------------ passed through
    def reset(self) -> None:
        """Reset the wrapped law."""
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

    # ------------------------------------------------------------------ limits
    def friction_at(self, state: ArrayLike) -> np.ndarray:
        """μ̂ ``(N, 2)`` under each wheel of the estimated states ``(N, 6)``.

        Parameters
        ----------
        state : array_like, shape (N, 6)
            Estimated (x, y, θ, u, v, r).
        """
        s = np.asarray(state, dtype=np.float64).reshape(-1, 6)
        if self.friction != "map":
            return np.full((s.shape[0], 2), float(self.friction))
        d = self.model.half_track
        c, sn = np.cos(s[:, 2]), np.sin(s[:, 2])
        wheels = np.stack(
            [np.column_stack([s[:, 0] - sn * d, s[:, 1] + c * d]),
             np.column_stack([s[:, 0] + sn * d, s[:, 1] - c * d])], axis=1,
        )  # fmt: skip
        return self._peaks[self.terrain.index(wheels)]

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
        return self.margin * self.model.wheel_radius * grip

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
        raw = np.asarray(self.law(t, s.copy(), reference), dtype=np.float64)
        raw = raw.reshape(flat.shape[0], 2)
        limit = self.limits(flat)
        return np.clip(raw, -limit, limit).reshape((*s.shape[:-1], 2))


def _share(name: str, value: float) -> float:
    number = finite(name, value)
    if not 0.0 < number <= 1.0:
        raise ConfigError(f"{name} must be in (0, 1] (got {number:g})")
    return number
