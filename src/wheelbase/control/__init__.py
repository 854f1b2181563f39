"""Controllers: one module per family; each controller holds gains and limits and is called as
``controller(t, pose, reference) -> command``."""

from wheelbase.control.base import (
    STEERING_COMMAND,
    VELOCITY_COMMAND,
    Controller,
    SteeringLimits,
    VelocityLimits,
    saturate_steering,
    saturate_velocity,
    steering_to_velocity,
    velocity_to_steering,
    velocity_to_wheel_speeds,
)

__all__: list[str] = [
    "STEERING_COMMAND",
    "VELOCITY_COMMAND",
    "Controller",
    "SteeringLimits",
    "VelocityLimits",
    "saturate_steering",
    "saturate_velocity",
    "steering_to_velocity",
    "velocity_to_steering",
    "velocity_to_wheel_speeds",
]
