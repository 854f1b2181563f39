"""A scenario's world beyond the map and how the robot navigates in it: the schema of the keys.

``world`` is the truth the robot does not know (static obstacles that are not on ``map``,
moving agents); only its sensors see it. ``fleet`` puts several controlled robots in one world.
``costmap``, ``tracker``, ``replanning`` and ``recovery`` configure what the robot makes of its
lidar and what it does when its plan is blocked; ``control_rate_hz`` lets the controller run
slower than the plant (Nav2's controller server runs at 20 Hz).

Angles in files are degrees, as everywhere in scenarios. The geometric checks (agents that fit
their region, obstacles clear of the start and goals) need the map and are made when the
scenario is prepared (:mod:`wheelbase.runner`), with errors naming the key.
"""

from __future__ import annotations

import math
from typing import Any, Literal

from pydantic import BaseModel, ConfigDict, Field, field_validator, model_validator

from wheelbase.limits import MAX_COORDINATE

__all__ = [
    "FleetRobotSpec",
    "PathBoxesSpec",
    "RecoverySpec",
    "ReplanningSpec",
    "WorldSpec",
    "goal_alias",
]


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True, validate_default=True)


def goal_alias(data: Any) -> Any:
    """A mapping's ``goal: pose`` as ``goals: [pose]`` (the one-goal spelling of scenarios and
    of a fleet's robots); both given is an error."""
    if isinstance(data, dict) and "goal" in data:
        if "goals" in data:
            raise ValueError("give either goal or goals, not both")
        data = dict(data)
        data["goals"] = [data.pop("goal")]
    return data


def _finite(values: Any) -> bool:
    if isinstance(values, (tuple, list)):
        return all(_finite(value) for value in values)
    return math.isfinite(float(values)) and abs(float(values)) <= MAX_COORDINATE


class PathBoxesSpec(_Strict):
    """Boxes dropped on the planned path after planning, at random (each seed its own)."""

    count: tuple[int, int] = Field(
        (1, 3), description="Fewest and most boxes (drawn uniformly between)."
    )
    size: tuple[float, float] = Field(
        (0.4, 0.8), description="Smallest and largest side [m] of a box (each side drawn)."
    )
    clear: float = Field(
        1.5, ge=0, description="No box nearer than this to the start or the goal [m]."
    )

    @model_validator(mode="after")
    def _ranges(self):
        if not 0 <= self.count[0] <= self.count[1] <= 100:
            raise ValueError(
                f"count must be (low, high) with 0 <= low <= high <= 100 (got {self.count})"
            )
        if not 0 < self.size[0] <= self.size[1] <= 10 or not _finite(self.size):
            raise ValueError(
                f"size must be (low, high) with 0 < low <= high <= 10 m (got {self.size})"
            )
        return self


class WorldSpec(_Strict):
    """The truth beyond ``map``, unknown to the robot, seen only through its sensors.

    The entries of ``obstacles`` and ``agents`` and the parameter sets are checked by
    :func:`wheelbase.world.world_from_spec` when the scenario is prepared (it needs the map);
    its errors name the key (``world.agents[0].speed: ...``).
    """

    obstacles: tuple[dict[str, Any], ...] = Field(
        (),
        description="Static obstacles that are not on the map, each one of {box: [x, y, "
        "length, width, yaw_deg]}, {disc: [x, y, radius]}, {polygon: [[x, y], ...]} [m].",
    )
    agents: tuple[dict[str, Any], ...] = Field(
        (),
        description="Groups of moving agents: {count, radius [m], speed [m/s], behaviour "
        "(straight | wander | waypoints | social_force | orca), region [x0, y0, x1, y1] [m], "
        "reacts_to_robot, waypoints [[x, y], ...]}.",
    )
    social_force: dict[str, Any] | None = Field(
        None, description="Parameters of the social force model (wheelbase.world.SocialForce)."
    )
    orca: dict[str, Any] | None = Field(
        None, description="Parameters of ORCA (wheelbase.world.ORCA)."
    )
    path_boxes: PathBoxesSpec | None = Field(
        None,
        description="Boxes dropped at random on the planned path after planning (seeded).",
    )

    def truth(self) -> dict[str, Any]:
        """The section as :func:`wheelbase.world.world_from_spec` reads it."""
        return self.model_dump(exclude={"path_boxes"}, exclude_none=True)


class FleetRobotSpec(_Strict):
    """One robot of a fleet: its start and its goal(s); the robot itself is ``robot``."""

    start: tuple[float, float, float] = Field(..., description="(x [m], y [m], heading [deg]).")
    goals: tuple[tuple[float, float, float], ...] = Field(..., min_length=1)

    @model_validator(mode="before")
    @classmethod
    def _goal_alias(cls, data: Any) -> Any:
        return goal_alias(data)

    @field_validator("start", "goals")
    @classmethod
    def _finite_poses(cls, value):
        if not _finite(value):
            raise ValueError(f"must be finite and within ±{MAX_COORDINATE:g} m (got {value})")
        return value


class ReplanningSpec(_Strict):
    """When the global plan (Hybrid A*) is made again on what the robot has seen."""

    enabled: bool = Field(True, description="Replan at all (false: the first plan is kept).")
    rate_hz: float = Field(
        1.0,
        ge=0,
        le=100,
        description="Replans per second (Nav2's default tree: 1 Hz); 0: only when blocked. A "
        "replan is skipped when nothing the planner sees changed since the last one.",
    )
    lookahead: float = Field(
        3.0, gt=0, description="How far ahead along the plan [m] a blocked cell forces a replan."
    )
    max_expansions: int = Field(
        200_000,
        ge=1,
        le=100_000_000,
        description="Hybrid A* expansions one replan may take: a budget in states, not "
        "seconds, so that a run repeats exactly on any machine.",
    )
    moving_speed: float = Field(
        0.2,
        ge=0,
        description="Tracks faster than this [m/s] are moving obstacles: the local controller "
        "avoids them, the global plan ignores them (a walker crossing the aisle does not "
        "block the route).",
    )


class RecoverySpec(_Strict):
    """What the robot does when no plan exists (Nav2's recoveries), and how often."""

    behaviours: tuple[Literal["wait", "back_up", "spin"], ...] = Field(
        ("wait", "back_up", "spin"),
        min_length=1,
        description="Recoveries tried in turn when no plan is found.",
    )
    max_retries: int = Field(
        6, ge=0, le=1000, description="Recoveries before the robot stops as blocked (Nav2: 6)."
    )
    wait_time: float = Field(2.0, gt=0, le=600, description="Duration of wait [s].")
    back_up_distance: float = Field(0.3, gt=0, le=10, description="How far back_up reverses [m].")
    back_up_speed: float = Field(0.1, gt=0, le=5, description="Speed of back_up [m/s].")
    spin_angle_deg: float = Field(
        90.0, gt=0, le=360, description="How far spin turns on the spot [deg]."
    )
    yield_time: float = Field(
        60.0,
        ge=0,
        le=3600,
        description="Longest a robot of a fleet other than the first waits aside for a robot "
        "with the right of way [s] (the fleet's order is its priority; 0: never yield).",
    )
    spin_rate_deg: float = Field(60.0, gt=0, le=3600, description="Yaw rate of spin [deg/s].")
