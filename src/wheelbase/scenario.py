"""Scenario files: one YAML document describes a closed-loop run.

A scenario names a map, a robot, the plant, the planner, the limits that time-parametrise the
plan, the controller, the odometry, the noise seed, the start, the goal(s), the duration and the
step. Every field has a default except ``start`` and ``goal``/``goals``; unknown keys are errors.
Angles in files are in degrees (the edge of the system); everything is converted to radians on
entry. :func:`load_scenario` returns a validated :class:`Scenario`; its errors name the file, the
field path and what is allowed, e.g. ``demo.yaml: controller.gains.k_beta: must be < 0 (got 2.0)``.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any, Literal

import yaml
from pydantic import BaseModel, ConfigDict, Field, ValidationError, field_validator, model_validator

from wheelbase._validate import read_text
from wheelbase.errors import ScenarioError
from wheelbase.limits import MAX_COORDINATE, MAX_MAP_CELLS, MAX_STEPS

__all__ = [
    "EMPTY_MAP_MARGIN",
    "EMPTY_MAP_RESOLUTION",
    "ControllerSpec",
    "OdometrySpec",
    "PlannerSpec",
    "ResourceSpec",
    "RobotSpec",
    "Scenario",
    "TrajectorySpec",
    "format_validation_error",
    "load_scenario",
    "scenario_json_schema",
]


EMPTY_MAP_MARGIN = 3.0
"""Margin [m] of the ``map: empty`` field around the start and the goals."""
EMPTY_MAP_RESOLUTION = 0.05
"""Cell size [m] of the ``map: empty`` field."""

# Keywords of HybridAStar that a scenario sets elsewhere, and where.
_PLANNER_SET_ELSEWHERE = {
    "grid": "map",
    "footprint": "robot.footprint (grown by planner.margin)",
    "turning_radius": "planner.turning_radius",
    "reverse": "planner.reverse",
    "rear_axle_to_center": "robot.center_offset",
}


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True, validate_default=True)


class RobotSpec(_Strict):
    """The robot: a kinematic model with its parameters, or a preset."""

    model: Literal["diffdrive", "unicycle", "rear_bicycle", "bicycle", "ackermann"] = Field(
        "diffdrive", description="Kinematic model of the robot."
    )
    preset: Literal["rm100"] | None = Field(
        None, description="A named robot; its parameters fill in the fields left unset."
    )
    wheel_radius: float | None = Field(None, gt=0, description="Wheel radius [m].")
    half_track: float | None = Field(None, gt=0, description="Half the wheel separation [m].")
    wheel_base: float | None = Field(
        None, gt=0, description="Axle distance of car-like robots [m]."
    )
    track: float | None = Field(None, gt=0, description="Front track of an Ackermann car [m].")
    max_steering_deg: float | None = Field(
        None, gt=0, lt=90, description="Steering stop of car-like robots [deg]."
    )
    footprint: tuple[float, float] | None = Field(
        None, description="Rectangle (length, width) [m] centred on the body centre."
    )
    center_offset: float = Field(
        0.0,
        description="Distance from the reference point (wheel axle centre) forward to the "
        "footprint centre [m].",
    )
    max_wheel_speed: float | None = Field(
        None, gt=0, description="Wheel angular speed limit of a differential drive [rad/s]."
    )

    @field_validator("footprint")
    @classmethod
    def _positive_footprint(cls, value):
        if value is not None and (value[0] <= 0 or value[1] <= 0):
            raise ValueError(f"must be two lengths > 0 m (got {list(value)})")
        return value


class PlannerSpec(_Strict):
    """Hybrid A* options (see :class:`wheelbase.planning.HybridAStar`)."""

    turning_radius: float | None = Field(
        None,
        ge=0,
        description="Minimum turning radius [m]; 0 lets a differential drive turn "
        "in place; default from the robot (0 for differential drive, wheel_base / "
        "tan(max steering) for car-like robots).",
    )
    reverse: bool = Field(True, description="Allow driving backwards.")
    margin: float = Field(
        0.1,
        ge=0,
        description="Clearance [m] added around the footprint while planning, so that "
        "tracking and odometry errors do not touch obstacles.",
    )
    options: dict[str, Any] = Field(
        default_factory=dict, description="Further HybridAStar keyword arguments."
    )

    @field_validator("options")
    @classmethod
    def _known_options(cls, value: dict[str, Any]) -> dict[str, Any]:
        if not value:
            return value
        import inspect

        from wheelbase.planning.hybrid_astar import HybridAStar

        keywords = set(inspect.signature(HybridAStar).parameters) - set(_PLANNER_SET_ELSEWHERE)
        for key in value:
            if key in _PLANNER_SET_ELSEWHERE:
                raise ValueError(
                    f"{key!r} is set by the scenario: use {_PLANNER_SET_ELSEWHERE[key]}"
                )
            if key not in keywords:
                raise ValueError(f"unknown option {key!r}; allowed: {', '.join(sorted(keywords))}")
        return value


class TrajectorySpec(_Strict):
    """Limits that time-parametrise the plan (see :class:`wheelbase.timing.SpeedLimits`)."""

    max_speed: float = Field(0.5, gt=0, description="[m/s]")
    max_acceleration: float = Field(0.5, gt=0, description="[m/s²]")
    max_yaw_rate: float = Field(1.0, gt=0, description="[rad/s]")
    max_yaw_acceleration: float = Field(2.0, gt=0, description="[rad/s²]")
    max_lateral_acceleration: float = Field(math.inf, gt=0, description="[m/s²]")
    reverse_speed_factor: float = Field(1.0, gt=0, le=1, description="Reverse speed fraction.")


class TorqueLoopSpec(_Strict):
    """How a kinematic law drives a dynamic plant: its (v, ω) tracked by computed torque."""

    bandwidth: float = Field(10.0, gt=0, description="Twist-loop bandwidth k [1/s].")
    max_torque: float = Field(5.0, gt=0, description="Wheel-torque saturation [N·m].")


class ControllerSpec(_Strict):
    """The tracking controller: a law of :mod:`wheelbase.control` and its gains."""

    law: str = Field("kanayama", description="Name of the control law.")
    gains: dict[str, bool | int | float | str | tuple[float, ...]] = Field(
        default_factory=dict,
        description="Gains and options of the law (numbers; MPPI also takes backend names, "
        "flags and per-input noise tuples).",
    )
    torque_loop: TorqueLoopSpec = Field(
        default_factory=TorqueLoopSpec,
        description="On a dynamic plant, a law other than computed_torque commands (v, ω), "
        "tracked by computed torque with these settings.",
    )


class OdometrySpec(_Strict):
    """How the controller learns the pose: perfect state or wheel-encoder odometry."""

    mode: Literal["perfect", "encoders"] = Field("encoders")
    pulses_per_revolution: int = Field(2048, gt=0, description="Encoder resolution.")
    method: Literal["euler", "midpoint", "exact"] = Field("exact")
    tick_noise_std: float = Field(
        0.0,
        ge=0,
        description="σ [ticks] of Gaussian noise (rounded) added to each tick difference, i.e. "
        "at every step dt; the counts wander as a random walk (σ√n ticks after n steps), so "
        "the same σ drifts more with a smaller dt.",
    )
    wheel_radius_scale: tuple[float, float] = Field(
        (1.0, 1.0),
        description="True (left, right) wheel radius / nominal: systematic odometry error.",
    )
    track_scale: float = Field(1.0, gt=0, description="True track / nominal track.")


class ResourceSpec(_Strict):
    """Resource limits of a run (see :mod:`wheelbase.limits`): raise them on purpose."""

    max_steps: int = Field(
        MAX_STEPS, ge=1, description="Most simulation steps duration / dt of the run."
    )
    max_map_cells: int = Field(
        MAX_MAP_CELLS, ge=1, description="Most cells of the map (checked here for map: empty)."
    )


class Scenario(_Strict):
    """A validated closed-loop scenario."""

    name: str = Field("scenario", description="Name used in reports.")
    map: str = Field(
        "warehouse",
        description="Bundled map name, path to a ROS YAML / Moving AI .map / image map, or "
        "'empty' for an obstacle-free field around the start and goals.",
    )
    robot: RobotSpec = Field(default_factory=RobotSpec)
    plant: Literal["kinematic", "dynamic"] = Field("kinematic")
    planner: PlannerSpec = Field(default_factory=PlannerSpec)
    trajectory: TrajectorySpec = Field(default_factory=TrajectorySpec)
    controller: ControllerSpec = Field(default_factory=ControllerSpec)
    odometry: OdometrySpec = Field(default_factory=OdometrySpec)
    seed: int = Field(0, ge=0, le=2**64 - 1, description="Noise seed (a 64-bit unsigned integer).")
    start: tuple[float, float, float] = Field(..., description="(x [m], y [m], heading [deg]).")
    goals: tuple[tuple[float, float, float], ...] = Field(
        ..., min_length=1, description="Goals (x [m], y [m], heading [deg]) visited in order."
    )
    goal_tolerance: tuple[float, float] = Field(
        (0.05, 5.0), description="Arrival tolerance (position [m], heading [deg])."
    )
    duration: float = Field(120.0, gt=0, description="Longest run [s].")
    dt: float = Field(0.01, gt=0, description="Simulation and control step [s].")
    resources: ResourceSpec = Field(
        default_factory=ResourceSpec, description="Resource limits (raise them on purpose)."
    )

    @model_validator(mode="before")
    @classmethod
    def _goal_alias(cls, data: Any) -> Any:
        if isinstance(data, dict) and "goal" in data:
            if "goals" in data:
                raise ValueError("give either goal or goals, not both")
            data = dict(data)
            data["goals"] = [data.pop("goal")]
        return data

    @field_validator("start", "goals", "goal_tolerance", "duration", "dt")
    @classmethod
    def _finite(cls, value):
        if not all(math.isfinite(number) for number in _numbers(value)):
            raise ValueError(f"must be finite (got {value})")
        return value

    @field_validator("start", "goals")
    @classmethod
    def _poses(cls, value):
        poses = value if isinstance(value[0], tuple) else (value,)
        for x, y, _heading in poses:
            if max(abs(x), abs(y)) > MAX_COORDINATE:
                raise ValueError(
                    f"x and y must be within ±{MAX_COORDINATE:g} m, where float64 still "
                    f"resolves micrometres (got ({x:g}, {y:g}))"
                )
        # Headings of any finite value are wrapped to (−180, 180] deg on entry.
        wrapped = tuple((x, y, _wrap_degrees(heading)) for x, y, heading in poses)
        return wrapped if isinstance(value[0], tuple) else wrapped[0]

    @field_validator("goal_tolerance")
    @classmethod
    def _tolerance(cls, value):
        position, heading = value
        if position <= 0.0:
            raise ValueError(f"position must be > 0 m (got {position:g})")
        if not 0.0 < heading <= 180.0:
            raise ValueError(f"heading must be in (0, 180] deg (got {heading:g})")
        return value

    @model_validator(mode="after")
    def _sizes(self):
        if self.dt > self.duration:
            raise ValueError(f"dt must be <= duration (got dt={self.dt}, duration={self.duration})")
        steps = self.duration / self.dt
        limit = self.resources.max_steps
        if steps > limit:
            raise ValueError(
                f"duration / dt = {steps:.3g} steps: more than resources.max_steps = {limit}; "
                "use a larger dt or a shorter duration, or raise resources.max_steps"
            )
        if self.map == "empty":
            rows, cols = empty_map_shape([self.start, *self.goals])
            limit = self.resources.max_map_cells
            if rows * cols > limit:
                raise ValueError(
                    f"map: empty around the start and goals would be {rows} × {cols} = "
                    f"{rows * cols:.3g} cells of {EMPTY_MAP_RESOLUTION} m: more than "
                    f"resources.max_map_cells = {limit}; bring them closer, use a map file, or "
                    "raise resources.max_map_cells"
                )
        return self

    def to_yaml(self) -> str:
        """The resolved scenario (all defaults filled) as YAML, loadable again."""
        data = self.model_dump(mode="json")
        return yaml.safe_dump(data, sort_keys=False)


def empty_map_shape(points: list[tuple[float, ...]]) -> tuple[int, int]:
    """(rows, columns) of the ``map: empty`` field around ``points`` (x [m], y [m], ...).

    Parameters
    ----------
    points : list of tuple of float
        The start and the goals.
    """
    xs = [point[0] for point in points]
    ys = [point[1] for point in points]
    width = math.ceil(max(xs) + EMPTY_MAP_MARGIN) - math.floor(min(xs) - EMPTY_MAP_MARGIN)
    height = math.ceil(max(ys) + EMPTY_MAP_MARGIN) - math.floor(min(ys) - EMPTY_MAP_MARGIN)
    return math.ceil(height / EMPTY_MAP_RESOLUTION), math.ceil(width / EMPTY_MAP_RESOLUTION)


def _numbers(value: Any) -> list[float]:
    if isinstance(value, (tuple, list)):
        return [number for item in value for number in _numbers(item)]
    return [float(value)]


def _wrap_degrees(angle: float) -> float:
    wrapped = math.remainder(angle, 360.0)
    return 180.0 if wrapped == -180.0 else wrapped


def format_validation_error(error: ValidationError, source: str) -> str:
    """One line per problem: ``source: field.path: message (got value)``.

    Parameters
    ----------
    error : pydantic.ValidationError
        The error pydantic raised.
    source : str
        The file name (or ``<dict>``) to prefix.
    """
    lines = []
    for item in error.errors():
        path = ".".join(str(part) for part in item["loc"])
        message = item["msg"].removeprefix("Value error, ")
        if item["type"] == "extra_forbidden":
            message = "unknown key (check the spelling; `wheelbase schema` lists the keys)"
        elif item["type"] == "missing":
            message = "required field is missing"
        elif "got" not in message and "input" in item and path:
            message = f"{message} (got {item['input']!r})"
        lines.append(f"{source}: {path}: {message}" if path else f"{source}: {message}")
    return "\n".join(lines)


def load_scenario(source: str | Path | dict[str, Any]) -> Scenario:
    """Load and validate a scenario from a YAML file, a bundled name, or a dict.

    Parameters
    ----------
    source : str, Path or dict
        A path to a YAML file, the name of a bundled scenario (``demo``, see
        :func:`bundled_scenarios`), or the parsed mapping.

    Raises
    ------
    ScenarioError
        Missing file, malformed YAML, or a field that fails validation; the message names the
        file and the field path.
    """
    if isinstance(source, dict):
        label, data = "<dict>", source
    elif not isinstance(source, (str, Path)):
        raise ScenarioError(
            "a scenario is a file path, a bundled name or a mapping of keys to values "
            f"(got {type(source).__name__} {source!r})"
        )
    else:
        path = _resolve(source)
        label = path.name
        text = read_text(path, "scenario", ScenarioError, label)
        try:
            data = yaml.safe_load(text)
        except (ValueError, RecursionError) as error:
            # e.g. an integer of more than 4300 digits, or lists nested thousands deep
            raise ScenarioError(f"{label}: unreadable YAML: {error}") from None
        except yaml.YAMLError as error:
            mark = getattr(error, "problem_mark", None)
            where = f" at line {mark.line + 1}, column {mark.column + 1}" if mark else ""
            problem = getattr(error, "problem", None) or str(error)
            raise ScenarioError(f"{label}: malformed YAML{where}: {problem}") from None
        if not isinstance(data, dict):
            raise ScenarioError(f"{label}: a scenario must be a mapping of keys to values")
        # A map path in a file is relative to that file, as a user who moves the pair expects.
        map_name = data.get("map")
        if isinstance(map_name, str) and not Path(map_name).is_absolute():
            beside = path.parent / map_name
            if beside.exists():
                data = {**data, "map": str(beside)}
    try:
        return Scenario.model_validate(data)
    except ValidationError as error:
        raise ScenarioError(format_validation_error(error, label)) from None


def bundled_scenarios() -> dict[str, Path]:
    """Names and paths of the scenarios shipped in ``wheelbase/data/scenarios/``."""
    folder = Path(__file__).parent / "data" / "scenarios"
    return {path.stem: path for path in sorted(folder.glob("*.yaml"))}


def _resolve(source: str | Path) -> Path:
    path = Path(source)
    if path.is_file():
        return path
    bundled = bundled_scenarios()
    if str(source) in bundled:
        return bundled[str(source)]
    if path.exists():
        raise ScenarioError(f"{path}: not a file")
    names = ", ".join(bundled) or "none"
    raise ScenarioError(f"{path}: no such file (bundled scenarios: {names})")


def scenario_json_schema() -> dict[str, Any]:
    """The JSON Schema of scenario files (what ``wheelbase schema`` prints)."""
    schema = Scenario.model_json_schema()
    schema["properties"]["goal"] = {
        "description": "A single goal (x [m], y [m], heading [deg]); alias of goals: [goal].",
        "type": "array",
        "items": {"type": "number"},
        "minItems": 3,
        "maxItems": 3,
    }
    schema["required"] = [name for name in schema.get("required", []) if name != "goals"]
    schema["anyOf"] = [{"required": ["goal"]}, {"required": ["goals"]}]
    schema["$schema"] = "https://json-schema.org/draft/2020-12/schema"
    schema["title"] = "wheelbase scenario"
    return schema
