"""Exceptions raised by wheelbase.

Every error a user can trigger with bad input is a :class:`WheelbaseError` whose message says
what was wrong and what is allowed, e.g. ``half_track must be > 0 m (got -0.2)``. The subclasses
also derive from the built-in exception a Python user would expect (``ValueError`` for bad
values), so ``except ValueError`` keeps working.
"""

from __future__ import annotations

__all__ = [
    "ConfigError",
    "DataError",
    "DependencyError",
    "EstimationError",
    "InputError",
    "MapError",
    "PlanningError",
    "ScenarioError",
    "WheelbaseError",
]


class WheelbaseError(Exception):
    """Base class of every error wheelbase raises on purpose."""


class ConfigError(WheelbaseError, ValueError):
    """A parameter of a model, controller, planner or integrator is invalid."""


class InputError(WheelbaseError, ValueError):
    """An input array (poses, wheel speeds, times) has the wrong shape or non-finite values."""


class MapError(WheelbaseError, ValueError):
    """A map is empty, malformed, or a query lies outside it."""


class PlanningError(WheelbaseError):
    """A planner could not find a path (start or goal in collision, goal unreachable, budget)."""


class DataError(WheelbaseError, ValueError):
    """A data file (log, dataset, map image) cannot be read or is malformed."""


class ScenarioError(ConfigError):
    """A scenario file is invalid; the message names the file and the field path."""


class DependencyError(WheelbaseError, ImportError):
    """An optional dependency is missing; the message names the extra that installs it."""


class EstimationError(WheelbaseError, ArithmeticError):
    """An estimator's belief broke down (a covariance no longer positive definite, all particle
    weights zero): the message names the filter, the robot and the parameters to look at."""
