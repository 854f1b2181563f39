"""Law 1: control to a reference position (go-to-point), forward and bidirectional.

Document 002 lists "control to reference pose" after Klančar et al., *Wheeled Mobile Robotics*
(2017) §3.2.1: the robot turns towards the goal while driving at a speed proportional to the
distance,

    φ_r = atan2(y_r − y, x_r − x),   e_φ = wrap(φ_r − φ),   ω = K₁·e_φ,   v = K₂·D,

with D the distance to the goal. The bidirectional variant drives backwards when the goal is
behind: e_φ' = atan(tan e_φ) ∈ (−π/2, π/2) is the heading error of whichever end of the robot
faces the goal, ω = K₁·e_φ' and v = K₂·D·sgn(cos e_φ).

Stability (derived here; the scaling of :func:`~wheelbase.control.saturate_velocity` is a
positive time change and keeps it): with λ the bearing of the goal, λ̇ = −v·sin(φ − λ)/D, so
ė_φ = K₂·sin e_φ − K₁·e_φ and Ḋ = −K₂·D·cos e_φ. The heading error converges to 0 from every
e_φ iff K₁ > K₂ (then ė_φ·e_φ < 0); for (2/π)·K₂ < K₁ ≤ K₂ it settles at e* ≠ 0 with
K₂ sin e* = K₁ e* and the robot spirals in (D still → 0 since |e*| < π/2); for
K₁ ≤ (2/π)·K₂, |e*| ≥ π/2 and the robot circles the goal for ever. The first case is the
stated condition (a warning when it fails), the last an error.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass

import numpy as np

from wheelbase._validate import positive
from wheelbase.control.base import GoalController
from wheelbase.errors import ConfigError
from wheelbase.geometry import wrap_angle

__all__ = ["GoToPoint", "check_point_gains", "go_to_point_law"]


def check_point_gains(k_heading: float, k_speed: float, *, name: str = "GoToPoint") -> None:
    """Validate the gains of the go-to-point law (see the module docstring).

    Parameters
    ----------
    k_heading : float
        K₁ [1/s].
    k_speed : float
        K₂ [1/s].
    name : str
        The law's name, for the messages.

    Raises
    ------
    ConfigError
        If a gain is not positive, or ``k_heading <= 2/π · k_speed`` (the robot orbits).

    Warns
    -----
    UserWarning
        If ``k_heading <= k_speed``: the robot still reaches the goal but spirals in.
    """
    k1 = positive("k_heading", k_heading, "1/s")
    k2 = positive("k_speed", k_speed, "1/s")
    if k1 <= 2.0 / math.pi * k2:
        raise ConfigError(
            f"{name}: k_heading must be > (2/π)·k_speed = {2 / math.pi * k2:g} 1/s or the robot "
            f"circles the goal (got k_heading={k1:g}, k_speed={k2:g})"
        )
    if k1 <= k2:
        warnings.warn(
            f"{name}: k_heading={k1:g} <= k_speed={k2:g}; the heading error does not vanish "
            "and the robot spirals into the goal",
            UserWarning,
            stacklevel=3,
        )


def go_to_point_law(
    dx: np.ndarray,
    dy: np.ndarray,
    heading: np.ndarray,
    k_heading: float,
    k_speed: float,
    bidirectional: bool = False,
) -> tuple[np.ndarray, np.ndarray]:
    """The go-to-point law on arrays: ``(v, ω)`` towards a point ``(dx, dy)`` away.

    Parameters
    ----------
    dx, dy : numpy.ndarray
        Goal position minus robot position [m], world (or any common) frame.
    heading : numpy.ndarray
        Robot heading φ in the same frame [rad].
    k_heading, k_speed : float
        K₁ [1/s] and K₂ [1/s].
    bidirectional : bool
        Reverse when the goal is behind (e_φ' = atan(tan e_φ), v·sgn(cos e_φ)).
    """
    distance = np.hypot(dx, dy)
    error = wrap_angle(np.arctan2(dy, dx) - heading)
    if bidirectional:
        # atan(tan e) without the poles of tan: the error folded into [−π/2, π/2].
        sign = np.where(np.cos(error) >= 0.0, 1.0, -1.0)
        error = np.arctan2(np.sin(error) * sign, np.abs(np.cos(error)))
        return k_speed * distance * sign, k_heading * error
    return k_speed * distance, k_heading * error


@dataclass(frozen=True)
class GoToPoint(GoalController):
    """Go-to-point (Klančar et al. 2017 §3.2.1; document 002 "control to reference pose").

    Reaches the goal *position*; the final heading is wherever the approach ends (use a pose
    law of :mod:`wheelbase.control.pose` for the heading too).

    Parameters
    ----------
    k_heading : float
        K₁ [1/s], > (2/π)·K₂ (error), > K₂ for the heading to converge (warning otherwise).
    k_speed : float
        K₂ [1/s], > 0.
    bidirectional : bool
        Drive backwards when the goal is behind.
    stop_distance : float
        Distance [m] under which the command is zero (default 0: never stop).
    limits : VelocityLimits, optional
        Command limits (curvature-keeping saturation).

    Examples
    --------
    >>> law = GoToPoint(k_heading=3.0, k_speed=0.5)
    >>> law(0.0, [0.0, 0.0, 0.0], [0.0, 2.0, 0.0]).round(3).tolist()  # goal to the left
    [1.0, 4.712]
    """

    k_heading: float = 3.0
    k_speed: float = 0.5
    bidirectional: bool = False
    stop_distance: float = 0.0

    def __post_init__(self) -> None:
        check_point_gains(self.k_heading, self.k_speed, name=type(self).__name__)
        object.__setattr__(self, "k_heading", float(self.k_heading))
        object.__setattr__(self, "k_speed", float(self.k_speed))
        if self.stop_distance != 0.0:
            object.__setattr__(
                self, "stop_distance", positive("stop_distance", self.stop_distance, "m")
            )

    def _law(self, t, x, y, theta):
        v, omega = go_to_point_law(-x, -y, theta, self.k_heading, self.k_speed, self.bidirectional)
        stopped = np.hypot(x, y) < self.stop_distance
        return np.where(stopped, 0.0, v), np.where(stopped, 0.0, omega)
