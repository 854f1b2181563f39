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
from wheelbase.models import (
    Ackermann,
    Bicycle,
    BodyTwist,
    DiffDrive,
    KinematicModel,
    PathReference,
    RearWheelBicycle,
    Unicycle,
    Wheel,
    WheeledBase,
    mecanum4,
    omni3,
    pure_motions,
    reference_from_derivatives,
    reference_from_xy,
)
from wheelbase.runner import RunResult, run
from wheelbase.scenario import Scenario, load_scenario
from wheelbase.timing import SpeedLimits, time_parametrize

__version__ = "0.1.0"

__all__ = [
    "METHODS",
    "Ackermann",
    "Bicycle",
    "BodyTwist",
    "ConfigError",
    "DataError",
    "DiffDrive",
    "InputError",
    "KinematicModel",
    "MapError",
    "PathReference",
    "PlanningError",
    "RearWheelBicycle",
    "RunResult",
    "Scenario",
    "ScenarioError",
    "SimResult",
    "SpeedLimits",
    "Unicycle",
    "Wheel",
    "WheelbaseError",
    "WheeledBase",
    "__version__",
    "load_scenario",
    "mecanum4",
    "omni3",
    "pure_motions",
    "reference_from_derivatives",
    "reference_from_xy",
    "run",
    "simulate",
    "time_parametrize",
    "wrap_angle",
]
