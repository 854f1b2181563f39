"""Wheel encoders, dead reckoning, real odometry data and odometry calibration (document 003)."""

from wheelbase.odometry.calibration import (
    UMBmarkCalibration,
    UMBmarkCorrection,
    UMBmarkResult,
    calibrate_umbmark,
    umbmark_correction,
    umbmark_test,
)
from wheelbase.odometry.dead_reckoning import (
    DEAD_RECKONING_METHODS,
    WheelOdometry,
    dead_reckon,
    integrate_increments,
    pose_increment,
)
from wheelbase.odometry.drift import CurvyDrive, drift_table
from wheelbase.odometry.encoder import (
    Encoder,
    rad_per_s_to_rpm,
    rpm_to_rad_per_s,
    ticks_to_distance,
    ticks_to_rpm,
    unwrap_ticks,
)
from wheelbase.odometry.error_model import OdometryErrors
from wheelbase.odometry.mrclam import (
    MrclamData,
    dead_reckoning_errors,
    load_mrclam,
    yaw_rate_fit,
)

__all__ = [
    "DEAD_RECKONING_METHODS",
    "CurvyDrive",
    "Encoder",
    "MrclamData",
    "OdometryErrors",
    "UMBmarkCalibration",
    "UMBmarkCorrection",
    "UMBmarkResult",
    "WheelOdometry",
    "calibrate_umbmark",
    "dead_reckon",
    "dead_reckoning_errors",
    "drift_table",
    "integrate_increments",
    "load_mrclam",
    "pose_increment",
    "rad_per_s_to_rpm",
    "rpm_to_rad_per_s",
    "ticks_to_distance",
    "ticks_to_rpm",
    "umbmark_correction",
    "umbmark_test",
    "unwrap_ticks",
    "yaw_rate_fit",
]
