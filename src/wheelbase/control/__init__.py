"""Controllers: one module per family; each controller holds gains and limits and is called as
``controller(t, pose, reference) -> command``."""

from typing import TYPE_CHECKING

from wheelbase._lazy import attach

if TYPE_CHECKING:  # the names, for type checkers and IDEs; imported on first use
    from wheelbase.control.adaptive import AdaptiveComputedTorque
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
    from wheelbase.control.dwa import DWA, DWA_BACKENDS, DWACritics, DWAPlan
    from wheelbase.control.goal import (
        FIGURE8_GOALS,
        DriveTrain,
        GoToGoal,
        saturate_keep_turn_rate,
    )
    from wheelbase.control.mppi import MPPI, MPPI_BACKENDS, MPPICritics, MPPIPlan
    from wheelbase.control.path import (
        PathFollower,
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
    from wheelbase.control.schedule import ModelSchedule
    from wheelbase.control.torque import (
        ComputedTorquePID,
        InverseDynamicsTorques,
        TorqueGains,
        TwistTorqueLoop,
    )
    from wheelbase.control.tracking import Kanayama, LinearTracker
    from wheelbase.control.traction import TractionControl

_EXPORTS = {
    "AdaptiveComputedTorque": "wheelbase.control.adaptive",
    "ModelSchedule": "wheelbase.control.schedule",
    "TractionControl": "wheelbase.control.traction",
    "STEERING_COMMAND": "wheelbase.control.base",
    "VELOCITY_COMMAND": "wheelbase.control.base",
    "Controller": "wheelbase.control.base",
    "GoalController": "wheelbase.control.base",
    "SteeringLimits": "wheelbase.control.base",
    "VelocityLimits": "wheelbase.control.base",
    "command_to_inputs": "wheelbase.control.base",
    "saturate_steering": "wheelbase.control.base",
    "saturate_velocity": "wheelbase.control.base",
    "steering_to_velocity": "wheelbase.control.base",
    "velocity_to_steering": "wheelbase.control.base",
    "velocity_to_wheel_speeds": "wheelbase.control.base",
    "DWA": "wheelbase.control.dwa",
    "DWA_BACKENDS": "wheelbase.control.dwa",
    "DWACritics": "wheelbase.control.dwa",
    "DWAPlan": "wheelbase.control.dwa",
    "FIGURE8_GOALS": "wheelbase.control.goal",
    "DriveTrain": "wheelbase.control.goal",
    "GoToGoal": "wheelbase.control.goal",
    "saturate_keep_turn_rate": "wheelbase.control.goal",
    "MPPI": "wheelbase.control.mppi",
    "MPPI_BACKENDS": "wheelbase.control.mppi",
    "MPPICritics": "wheelbase.control.mppi",
    "MPPIPlan": "wheelbase.control.mppi",
    "PathFollower": "wheelbase.control.path",
    "PurePursuit": "wheelbase.control.path",
    "RearWheelFeedback": "wheelbase.control.path",
    "SegmentFollower": "wheelbase.control.path",
    "Stanley": "wheelbase.control.path",
    "ANTI_WINDUP": "wheelbase.control.pid",
    "PID": "wheelbase.control.pid",
    "GoToPoint": "wheelbase.control.point",
    "POSE_LAWS": "wheelbase.control.pose",
    "Aicardi": "wheelbase.control.pose",
    "LineArc": "wheelbase.control.pose",
    "PolarPose": "wheelbase.control.pose",
    "ViaDirection": "wheelbase.control.pose",
    "ViaPoint": "wheelbase.control.pose",
    "make_pose_law": "wheelbase.control.pose",
    "ComputedTorquePID": "wheelbase.control.torque",
    "TorqueGains": "wheelbase.control.torque",
    "InverseDynamicsTorques": "wheelbase.control.torque",
    "TwistTorqueLoop": "wheelbase.control.torque",
    "Kanayama": "wheelbase.control.tracking",
    "LinearTracker": "wheelbase.control.tracking",
}
__getattr__, __dir__ = attach(__name__, _EXPORTS)

__all__: list[str] = [
    "ANTI_WINDUP",
    "DWA",
    "DWA_BACKENDS",
    "FIGURE8_GOALS",
    "MPPI",
    "MPPI_BACKENDS",
    "PID",
    "POSE_LAWS",
    "STEERING_COMMAND",
    "VELOCITY_COMMAND",
    "AdaptiveComputedTorque",
    "Aicardi",
    "ComputedTorquePID",
    "Controller",
    "DWACritics",
    "DWAPlan",
    "DriveTrain",
    "GoToGoal",
    "GoToPoint",
    "GoalController",
    "InverseDynamicsTorques",
    "Kanayama",
    "LineArc",
    "LinearTracker",
    "MPPICritics",
    "MPPIPlan",
    "ModelSchedule",
    "PathFollower",
    "PolarPose",
    "PurePursuit",
    "RearWheelFeedback",
    "SegmentFollower",
    "Stanley",
    "SteeringLimits",
    "TorqueGains",
    "TractionControl",
    "TwistTorqueLoop",
    "VelocityLimits",
    "ViaDirection",
    "ViaPoint",
    "command_to_inputs",
    "make_pose_law",
    "saturate_keep_turn_rate",
    "saturate_steering",
    "saturate_velocity",
    "steering_to_velocity",
    "velocity_to_steering",
    "velocity_to_wheel_speeds",
]
