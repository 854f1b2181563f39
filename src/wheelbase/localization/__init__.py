"""Localisation: EKF and UKF with known landmarks, and AMCL (a particle filter as Nav2's)."""

from wheelbase.localization.amcl import (
    AMCL,
    GLOBAL_LOCALIZATION,
    AMCLInfo,
    AMCLState,
    PoseEstimate,
)
from wheelbase.localization.ekf import EKF
from wheelbase.localization.kalman import KalmanFilter, UpdateInfo, chi2_gate
from wheelbase.localization.motion import OdometryMotion, VelocityMotion, arc_move, odometry_delta
from wheelbase.localization.particles import Cluster, kld_particles, low_variance_resample
from wheelbase.localization.trials import (
    AMCLRun,
    clear_pose,
    kidnapped_run,
    noisy_odometry,
    run_amcl,
    wander,
)
from wheelbase.localization.ukf import UKF

__all__ = [
    "AMCL",
    "EKF",
    "GLOBAL_LOCALIZATION",
    "UKF",
    "AMCLInfo",
    "AMCLRun",
    "AMCLState",
    "Cluster",
    "KalmanFilter",
    "OdometryMotion",
    "PoseEstimate",
    "UpdateInfo",
    "VelocityMotion",
    "arc_move",
    "chi2_gate",
    "clear_pose",
    "kidnapped_run",
    "kld_particles",
    "low_variance_resample",
    "noisy_odometry",
    "odometry_delta",
    "run_amcl",
    "wander",
]
