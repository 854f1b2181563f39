"""Kinematic models of wheeled mobile robots, one module each, one protocol in ``base``."""

from typing import TYPE_CHECKING

from wheelbase._lazy import attach

if TYPE_CHECKING:  # the names, for type checkers and IDEs; imported on first use
    from wheelbase.models.base import KinematicModel, ModelBase
    from wheelbase.models.bicycle import Ackermann, Bicycle, RearWheelBicycle
    from wheelbase.models.diffdrive import DiffDrive
    from wheelbase.models.path import (
        PoseTrajectory,
        PureMotion,
        pure_motions,
        reference_from_derivatives,
        reference_from_xy,
    )
    from wheelbase.models.unicycle import BodyTwist, Unicycle
    from wheelbase.models.wheeled import Wheel, WheeledBase, mecanum4, omni3

_EXPORTS = {
    "KinematicModel": "wheelbase.models.base",
    "ModelBase": "wheelbase.models.base",
    "Ackermann": "wheelbase.models.bicycle",
    "Bicycle": "wheelbase.models.bicycle",
    "RearWheelBicycle": "wheelbase.models.bicycle",
    "DiffDrive": "wheelbase.models.diffdrive",
    "PoseTrajectory": "wheelbase.models.path",
    "PureMotion": "wheelbase.models.path",
    "pure_motions": "wheelbase.models.path",
    "reference_from_derivatives": "wheelbase.models.path",
    "reference_from_xy": "wheelbase.models.path",
    "BodyTwist": "wheelbase.models.unicycle",
    "Unicycle": "wheelbase.models.unicycle",
    "Wheel": "wheelbase.models.wheeled",
    "WheeledBase": "wheelbase.models.wheeled",
    "mecanum4": "wheelbase.models.wheeled",
    "omni3": "wheelbase.models.wheeled",
}
__getattr__, __dir__ = attach(__name__, _EXPORTS)

__all__ = [
    "Ackermann",
    "Bicycle",
    "BodyTwist",
    "DiffDrive",
    "KinematicModel",
    "ModelBase",
    "PoseTrajectory",
    "PureMotion",
    "RearWheelBicycle",
    "Unicycle",
    "Wheel",
    "WheeledBase",
    "mecanum4",
    "omni3",
    "pure_motions",
    "reference_from_derivatives",
    "reference_from_xy",
]
