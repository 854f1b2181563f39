"""Controllers: one module per family; each controller holds gains and limits and is called as
``controller(t, pose, reference) -> command``."""

from wheelbase.control.base import (
    STEERING_COMMAND,
    VELOCITY_COMMAND,
    Controller,
    GoalController,
    SteeringLimits,
    VelocityLimits,
    command_to_inputs,
    saturate_steering,
    saturate_velocity,
    steering_to_velocity,
    velocity_to_steering,
    velocity_to_wheel_speeds,
)
from wheelbase.control.goal import (
    FIGURE8_GOALS,
    DriveTrain,
    GoToGoal,
    GoToGoalLog,
    run_go_to_goal,
    saturate_keep_turn_rate,
)
from wheelbase.control.mppi import MPPI, MPPI_BACKENDS, MPPICritics, MPPIPlan
from wheelbase.control.path import (
    PathFollower,
    Polyline,
    PurePursuit,
    RearWheelFeedback,
    SegmentFollower,
    Stanley,
)
from wheelbase.control.pid import ANTI_WINDUP, PID
from wheelbase.control.point import GoToPoint
from wheelbase.control.pose import (
    POSE_LAWS,
    Aicardi,
    LineArc,
    PolarPose,
    ViaDirection,
    ViaPoint,
    make_pose_law,
)
from wheelbase.control.torque import (
    ComputedTorquePID,
    TorqueGains,
    TrackingResult,
    TwistTorqueLoop,
    track_trajectory,
    tune_computed_torque,
)
from wheelbase.control.tracking import Kanayama, LinearTracker

__all__: list[str] = [
    "ANTI_WINDUP",
    "FIGURE8_GOALS",
    "MPPI",
    "MPPI_BACKENDS",
    "PID",
    "POSE_LAWS",
    "STEERING_COMMAND",
    "VELOCITY_COMMAND",
    "Aicardi",
    "ComputedTorquePID",
    "Controller",
    "DriveTrain",
    "GoToGoal",
    "GoToGoalLog",
    "GoToPoint",
    "GoalController",
    "Kanayama",
    "LineArc",
    "LinearTracker",
    "MPPICritics",
    "MPPIPlan",
    "PathFollower",
    "PolarPose",
    "Polyline",
    "PurePursuit",
    "RearWheelFeedback",
    "SegmentFollower",
    "Stanley",
    "SteeringLimits",
    "TorqueGains",
    "TrackingResult",
    "TwistTorqueLoop",
    "VelocityLimits",
    "ViaDirection",
    "ViaPoint",
    "command_to_inputs",
    "make_pose_law",
    "run_go_to_goal",
    "saturate_keep_turn_rate",
    "saturate_steering",
    "saturate_velocity",
    "steering_to_velocity",
    "track_trajectory",
    "tune_computed_torque",
    "velocity_to_steering",
    "velocity_to_wheel_speeds",
]
