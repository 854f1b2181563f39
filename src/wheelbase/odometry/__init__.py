"""Wheel encoders, dead reckoning, real odometry data and odometry calibration (document 003)."""

from typing import TYPE_CHECKING

from wheelbase._lazy import attach

if TYPE_CHECKING:  # the names, for type checkers and IDEs; imported on first use
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
    from wheelbase.odometry.mrclam import command_response, dead_reckoning_errors, yaw_rate_fit

_EXPORTS = {
    "UMBmarkCalibration": "wheelbase.odometry.calibration",
    "UMBmarkCorrection": "wheelbase.odometry.calibration",
    "UMBmarkResult": "wheelbase.odometry.calibration",
    "calibrate_umbmark": "wheelbase.odometry.calibration",
    "umbmark_correction": "wheelbase.odometry.calibration",
    "umbmark_test": "wheelbase.odometry.calibration",
    "DEAD_RECKONING_METHODS": "wheelbase.odometry.dead_reckoning",
    "WheelOdometry": "wheelbase.odometry.dead_reckoning",
    "dead_reckon": "wheelbase.odometry.dead_reckoning",
    "integrate_increments": "wheelbase.odometry.dead_reckoning",
    "pose_increment": "wheelbase.odometry.dead_reckoning",
    "CurvyDrive": "wheelbase.odometry.drift",
    "drift_table": "wheelbase.odometry.drift",
    "Encoder": "wheelbase.odometry.encoder",
    "rad_per_s_to_rpm": "wheelbase.odometry.encoder",
    "rpm_to_rad_per_s": "wheelbase.odometry.encoder",
    "ticks_to_distance": "wheelbase.odometry.encoder",
    "ticks_to_rpm": "wheelbase.odometry.encoder",
    "unwrap_ticks": "wheelbase.odometry.encoder",
    "OdometryErrors": "wheelbase.odometry.error_model",
    "dead_reckoning_errors": "wheelbase.odometry.mrclam",
    "yaw_rate_fit": "wheelbase.odometry.mrclam",
    "command_response": "wheelbase.odometry.mrclam",
}
__getattr__, __dir__ = attach(__name__, _EXPORTS)

__all__ = [
    "DEAD_RECKONING_METHODS",
    "CurvyDrive",
    "Encoder",
    "OdometryErrors",
    "UMBmarkCalibration",
    "UMBmarkCorrection",
    "UMBmarkResult",
    "WheelOdometry",
    "calibrate_umbmark",
    "command_response",
    "dead_reckon",
    "dead_reckoning_errors",
    "drift_table",
    "integrate_increments",
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
