"""wheelbase: model, simulate, plan for and control wheeled mobile robots.

The curated public API; everything else lives in its module (``wheelbase.geometry``,
``wheelbase.integrate`` …).
"""

from wheelbase.errors import (
    ConfigError,
    DataError,
    InputError,
    MapError,
    PlanningError,
    ScenarioError,
    WheelbaseError,
)
from wheelbase.geometry import wrap_angle
from wheelbase.integrate import METHODS, SimResult, simulate
from wheelbase.models import BodyTwist, DiffDrive, KinematicModel, Unicycle

__version__ = "0.1.0"

__all__ = [
    "METHODS",
    "BodyTwist",
    "ConfigError",
    "DataError",
    "DiffDrive",
    "InputError",
    "KinematicModel",
    "MapError",
    "PlanningError",
    "ScenarioError",
    "SimResult",
    "Unicycle",
    "WheelbaseError",
    "__version__",
    "simulate",
    "wrap_angle",
]
