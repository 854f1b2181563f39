"""Kinematic models of wheeled mobile robots, one module each, one protocol in ``base``."""

from wheelbase.models.base import KinematicModel, ModelBase
from wheelbase.models.diffdrive import DiffDrive
from wheelbase.models.unicycle import BodyTwist, Unicycle

__all__ = ["BodyTwist", "DiffDrive", "KinematicModel", "ModelBase", "Unicycle"]
