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
from wheelbase.localization.ukf import UKF

__all__ = [
    "AMCL",
    "EKF",
    "GLOBAL_LOCALIZATION",
    "UKF",
    "AMCLInfo",
    "AMCLState",
    "Cluster",
    "KalmanFilter",
    "OdometryMotion",
    "PoseEstimate",
    "UpdateInfo",
    "VelocityMotion",
    "arc_move",
    "chi2_gate",
    "kld_particles",
    "low_variance_resample",
    "odometry_delta",
]
