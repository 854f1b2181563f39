"""Slope feed-forward: the wheel torques that hold the controller's model against gravity.

A computed-torque law models M·V̇ + C·V = τ on level ground. On a grade the weight pulls the
robot downhill with m·g·s along the ground (s = sin α·(cos β, sin β), the slope vector of
:mod:`wheelbase.terrain.map`); the law's integrators then take up m·g·sin α only after the
error has grown. With the PID of :class:`~wheelbase.control.torque.ComputedTorquePID`
(along-track poles at −ω, triple) a step of the slope's pull g·sin α, as an acceleration,
gives the error e(t) = g·sin α·t²·e^(−ωt)/2, largest at t = 2/ω:

    e_max = 2·e⁻²·g·sin α / ω²  (0.116 m on a 10 % grade at ω = 1.5 rad/s).

:class:`SlopeFeedForward` wraps a torque controller and adds, at the estimated pose, the wheel
torques that cancel the model's weight on the slope under it (the robot knows its floor's
grades, as traction control's ``friction="map"`` knows its friction). In the body frame the
weight's tangential part acts at the CG (x_c, y_c):

    F_g = −m·g·(cos ψ·s_x + sin ψ·s_y,  −sin ψ·s_x + cos ψ·s_y),   M_g = x_c·F_g,y − y_c·F_g,x,

and the wheels produce the force and moment (−F_g,x, −M_g) with

    Δτ_L = a·(−F_g,x/2 + M_g/(2d)),   Δτ_R = a·(−F_g,x/2 − M_g/(2d))

(document 000's τ* = Wᵀτ, the lateral part carried by the ground as in the no-slip model).
The sum is clipped to the wrapped law's ``max_torque``. On level ground the wrapper adds
nothing: the wrapped law's torques to the last bit.
"""

from __future__ import annotations

import math
from typing import Any, ClassVar

import numpy as np
from numpy.typing import ArrayLike

from wheelbase._validate import as_float_array
from wheelbase.control.base import WrappedLaw
from wheelbase.dynamics import GRAVITY, DiffDriveDynamics
from wheelbase.errors import ConfigError

__all__ = ["SlopeFeedForward", "slope_torques"]


def slope_torques(model: DiffDriveDynamics, state: ArrayLike, slope: ArrayLike) -> np.ndarray:
    """Wheel torques (left, right) [N·m] that hold ``model`` still on ``slope`` (module docstring).

    Parameters
    ----------
    model : DiffDriveDynamics
        The controller's model: mass m [kg], CG (x_c, y_c) [m], wheel radius a and half track
        d [m].
    state : array_like, shape (..., 3) or (..., 6)
        Poses (x [m], y [m], ψ [rad]) (further columns ignored).
    slope : array_like, shape (..., 2)
        Slope vectors s = sin α·(cos β, sin β) under the poses (map frame).

    Returns
    -------
    numpy.ndarray, shape (..., 2)
        Δτ (left, right).

    Examples
    --------
    >>> from wheelbase.dynamics import RM100
    >>> tau = slope_torques(RM100, [0.0, 0.0, 0.0], [0.1, 0.0])
    >>> bool(np.isclose(tau[0], RM100.body.mass * GRAVITY * 0.1 * RM100.wheel_radius / 2))
    True
    """
    s = np.asarray(state, dtype=np.float64)
    g = np.asarray(slope, dtype=np.float64)
    body = model.body
    mass, (xc, yc) = body.mass, body.cg_offset
    c, sn = np.cos(s[..., 2]), np.sin(s[..., 2])
    fx = -mass * GRAVITY * (c * g[..., 0] + sn * g[..., 1])
    fy = -mass * GRAVITY * (-sn * g[..., 0] + c * g[..., 1])
    mz = xc * fy - yc * fx
    a, d = model.wheel_radius, model.half_track
    return np.stack([a * (-0.5 * fx + 0.5 * mz / d), a * (-0.5 * fx - 0.5 * mz / d)], axis=-1)


class SlopeFeedForward(WrappedLaw):
    """Wrap a torque controller: add the torques that hold its model on the slope (module
    docstring).

    Parameters
    ----------
    law : callable
        A controller giving wheel torques (``command_names`` (tau_left, tau_right)), called as
        ``law(t, state, reference)``.
    model : DiffDriveDynamics
        The controller's model; when the law has a ``model`` attribute (a
        :class:`~wheelbase.control.schedule.ModelSchedule` changes it with a payload) that one
        is read at each call instead.
    terrain : TerrainMap
        The floor the robot knows: the slope under its estimated position.

    Examples
    --------
    >>> from wheelbase.control.torque import ComputedTorquePID
    >>> from wheelbase.dynamics import RM100
    >>> from wheelbase.terrain import SURFACES, TerrainMap
    >>> law = ComputedTorquePID(RM100)
    >>> wrapped = SlopeFeedForward(law, RM100, TerrainMap.uniform(SURFACES["dry_concrete"]))
    >>> wrapped.command_names
    ('tau_left', 'tau_right')
    """

    command_names: ClassVar[tuple[str, ...]] = ("tau_left", "tau_right")

    def __init__(self, law: Any, model: DiffDriveDynamics, terrain: Any) -> None:
        from wheelbase.terrain.map import TerrainMap

        if not callable(law) or tuple(getattr(law, "command_names", ())) != self.command_names:
            raise ConfigError("slope feed-forward wraps a controller that gives wheel torques")
        if not isinstance(model, DiffDriveDynamics):
            raise ConfigError(f"model must be a DiffDriveDynamics (got {type(model).__name__})")
        if not isinstance(terrain, TerrainMap):
            raise ConfigError(
                f"slope feed-forward needs the terrain map (got {type(terrain).__name__})"
            )
        self.law = law
        self._model = model
        self.terrain = terrain

    # ------------------------------------------------------------------ passed through
    @property
    def model(self) -> DiffDriveDynamics:
        """The model in force: the wrapped law's when it has one."""
        return getattr(self.law, "model", None) or self._model

    @property
    def max_torque(self) -> float:
        """The wrapped law's torque limit [N·m] (infinite without one)."""
        return float(getattr(self.law, "max_torque", math.inf))

    def __getattr__(self, name: str) -> Any:  # estimates, history, row: the wrapped law's
        if name.startswith("_") or name in {"law", "terrain"}:
            raise AttributeError(name)
        return getattr(self.law, name)

    # ------------------------------------------------------------------ control
    def __call__(self, t: float, state: ArrayLike, reference: object) -> np.ndarray:
        """The wrapped law's wheel torques plus the slope's (module docstring).

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
        raw = np.asarray(self.law(t, s.copy(), reference), dtype=np.float64)
        slope = self.terrain.slope_at(s[..., :2])
        if not np.any(slope):
            return raw
        out = raw + slope_torques(self.model, s, slope).reshape(raw.shape)
        limit = self.max_torque
        return np.clip(out, -limit, limit) if math.isfinite(limit) else out
