"""Kinematic models of wheeled mobile robots, one module each, one protocol in ``base``."""

from wheelbase.models.base import KinematicModel, ModelBase
from wheelbase.models.bicycle import Ackermann, Bicycle, RearWheelBicycle
from wheelbase.models.diffdrive import DiffDrive
from wheelbase.models.path import (
    PathReference,
    PureMotion,
    pure_motions,
    reference_from_derivatives,
    reference_from_xy,
)
from wheelbase.models.unicycle import BodyTwist, Unicycle
from wheelbase.models.wheeled import Wheel, WheeledBase, mecanum4, omni3

__all__ = [
    "Ackermann",
    "Bicycle",
    "BodyTwist",
    "DiffDrive",
    "KinematicModel",
    "ModelBase",
    "PathReference",
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
