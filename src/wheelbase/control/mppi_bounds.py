"""Command kinds and bounds of the sampling controllers (private helpers of MPPI and DWA).

A model's command is ``(v, ω)`` (unicycle, differential drive: :data:`KIND_VELOCITY`),
``(v, δ)`` (rear-driven steered: :data:`KIND_REAR`; front-driven bicycle: :data:`KIND_FRONT`) or
the body twist ``(v_x, v_y, ω)`` of a holonomic base (:data:`KIND_HOLONOMIC`). The bounds of one
call narrow the limits' box: the speed is capped at √(2·a·d) before a cusp or the goal, d away,
and keeps the sign of the path section where that avoids twitching (see :func:`call_bounds`).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from wheelbase.control.base import (
    STEERING_COMMAND,
    VELOCITY_COMMAND,
    SteeringLimits,
    VelocityLimits,
)
from wheelbase.errors import ConfigError

__all__ = [
    "KIND_FRONT",
    "KIND_HOLONOMIC",
    "KIND_REAR",
    "KIND_VELOCITY",
    "call_bounds",
    "clip_commands",
    "command_bounds",
    "model_kind",
]

# twist kinds of the compiled backends: (v, ω); rear-driven (v, δ); front-driven (v, α);
# holonomic (v_x, v_y, ω)
KIND_VELOCITY, KIND_REAR, KIND_FRONT, KIND_HOLONOMIC = 0, 1, 2, 3


def model_kind(model: Any) -> tuple[int, float]:
    """The command kind of a kinematic model and its wheel base [m] (0 where it has none).

    Parameters
    ----------
    model : KinematicModel
        Unicycle, DiffDrive, Bicycle, RearWheelBicycle, Ackermann, BodyTwist or a holonomic
        wheeled base.

    Returns
    -------
    kind : int
        One of the ``KIND_*`` constants.
    wheel_base : float
        L [m] of a steered model, else 0.
    """
    from wheelbase.models import Bicycle

    names = tuple(getattr(model, "input_names", ()))
    if names in (VELOCITY_COMMAND, ("omega_left", "omega_right")):
        return KIND_VELOCITY, 0.0
    if names == ("u", "v", "r") or getattr(model, "is_holonomic", False):
        return KIND_HOLONOMIC, 0.0
    if names == STEERING_COMMAND:
        front = isinstance(model, Bicycle)
        return (KIND_FRONT if front else KIND_REAR), float(model.wheel_base)
    raise ConfigError(
        "MPPI supports Unicycle, DiffDrive, Bicycle, RearWheelBicycle, Ackermann, BodyTwist "
        f"and holonomic wheeled bases (got {type(model).__name__})"
    )


def command_bounds(
    kind: int, model: Any, limits: VelocityLimits | SteeringLimits, allow_reverse: bool
) -> tuple[np.ndarray, np.ndarray]:
    """The box ``lo <= u <= hi`` of the commands from the limits.

    Parameters
    ----------
    kind : int
        The command kind (:func:`model_kind`).
    model : KinematicModel
        The model (its ``max_steering`` bounds a steered model's δ too).
    limits : VelocityLimits or SteeringLimits
        Command limits; they must be finite.
    allow_reverse : bool
        Whether v may be negative (down to −max_speed).

    Returns
    -------
    lo, hi : numpy.ndarray, shape (m,)
        Lower and upper bounds (m = 2, or 3 for a holonomic base).
    """
    if kind in (KIND_VELOCITY, KIND_HOLONOMIC):
        if not isinstance(limits, VelocityLimits):
            raise ConfigError("limits must be VelocityLimits for (v, ω) or (vx, vy, ω) commands")
        # a holonomic base: |v_y| is bounded by max_speed as |v_x| is
        speeds = [limits.max_speed] * (2 if kind == KIND_HOLONOMIC else 1)
        top = np.array([*speeds, limits.max_yaw_rate])
    else:
        if not isinstance(limits, SteeringLimits):
            raise ConfigError("limits must be SteeringLimits for (v, δ) commands")
        steer = min(limits.max_steering, float(model.max_steering))
        top = np.array([limits.max_speed, steer])
    if not np.all(np.isfinite(top)):
        raise ConfigError(f"MPPI needs finite command limits (got {top.tolist()})")
    low = -top.copy()
    if not allow_reverse:
        low[0] = 0.0
    return low, top


def call_bounds(
    lo: np.ndarray,
    hi: np.ndarray,
    *,
    kind: int,
    distance_left: float,
    direction: float,
    deceleration: float,
    two_signs: bool,
) -> tuple[np.ndarray, np.ndarray]:
    """Command bounds of one call.

    |v| <= √(2·a·d), d the distance left to the section's end, as the time parametrisation of
    the path does (floor: 10 % of the top speed), so the robot stops at cusps and the goal
    instead of overshooting; and, unless ``two_signs`` (or the model is holonomic, which has no
    forward), v keeps the sign of the path section: sampling both signs where the optimum is
    about zero makes the weighted mean flip sign, and the robot would twitch back and forth.

    Parameters
    ----------
    lo, hi : numpy.ndarray, shape (m,)
        The limits' box (:func:`command_bounds`).
    kind : int
        The command kind.
    distance_left : float
        d [m] to the end of the path section.
    direction : float
        ±1, the section's direction.
    deceleration : float
        a [m/s²], > 0.
    two_signs : bool
        Sample v of both signs (reverse against the path allowed, path blocked, recovering
        after every rollout collided, settling at the goal, or no reverse at all).

    Returns
    -------
    lo, hi : numpy.ndarray, shape (m,)
    """
    lo, hi = lo.copy(), hi.copy()
    cap = max(math.sqrt(2.0 * deceleration * distance_left), 0.1 * hi[0])
    speeds = 2 if kind == KIND_HOLONOMIC else 1  # v, or v_x and v_y of a holonomic base
    lo[:speeds], hi[:speeds] = np.maximum(lo[:speeds], -cap), np.minimum(hi[:speeds], cap)
    if two_signs or kind == KIND_HOLONOMIC:
        return lo, hi
    if direction > 0.0:
        lo[0] = 0.0
    else:
        hi[0] = 0.0
    return lo, hi


def clip_commands(kind: int, controls: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """Commands clipped to the bounds; a holonomic base's (v_x, v_y) also to the disk of radius
    ``hi[0]``: its speed limit holds in every direction (a box would let it go √2 faster
    diagonally, and the progress critic would turn it 45° to do so).

    Parameters
    ----------
    kind : int
        The command kind.
    controls : numpy.ndarray, shape (..., m)
        Commands.
    lo, hi : numpy.ndarray, shape (m,)
        Bounds.

    Returns
    -------
    numpy.ndarray
        Clipped copy.
    """
    out = np.clip(controls, lo, hi)
    if kind == KIND_HOLONOMIC:
        speed = np.hypot(out[..., 0], out[..., 1])
        with np.errstate(divide="ignore", invalid="ignore"):
            scale = np.where(speed > hi[0], hi[0] / speed, 1.0)
        out[..., :2] *= scale[..., None]
    return out
