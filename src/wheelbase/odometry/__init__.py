"""Wheel encoders, dead reckoning, real odometry data and odometry calibration (document 003)."""

from wheelbase.odometry.dead_reckoning import (
    DEAD_RECKONING_METHODS,
    WheelOdometry,
    dead_reckon,
    integrate_increments,
    pose_increment,
)
from wheelbase.odometry.encoder import (
    Encoder,
    rad_per_s_to_rpm,
    rpm_to_rad_per_s,
    ticks_to_distance,
    ticks_to_rpm,
    unwrap_ticks,
)

__all__ = [
    "DEAD_RECKONING_METHODS",
    "Encoder",
    "WheelOdometry",
    "dead_reckon",
    "integrate_increments",
    "pose_increment",
    "rad_per_s_to_rpm",
    "rpm_to_rad_per_s",
    "ticks_to_distance",
    "ticks_to_rpm",
    "unwrap_ticks",
]
