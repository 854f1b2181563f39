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

from wheelbase._validate import count_text, read_text
from wheelbase.errors import ScenarioError
from wheelbase.limits import MAX_COORDINATE, MAX_MAP_CELLS, MAX_STEPS
from wheelbase.scenario_terrain import (
    ContactsSpec,
    PayloadSpec,
    SlopeFeedForwardSpec,
    TerrainSpec,
    TractionSpec,
)
from wheelbase.scenario_world import (
    FleetRobotSpec,
    RecoverySpec,
    ReplanningSpec,
    WorldSpec,
    goal_alias,
)

__all__ = [
    "EMPTY_MAP_MARGIN",
    "EMPTY_MAP_RESOLUTION",
    "ControllerSpec",
    "ImuSpec",
    "LandmarkSpec",
    "LidarSpec",
    "LocalizationSpec",
    "OdometrySpec",
    "PlannerSpec",
    "ResourceSpec",
    "RobotSpec",
    "Scenario",
    "SensorsSpec",
    "TrajectorySpec",
    "empty_map",
    "empty_map_shape",
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
    payload: PayloadSpec | None = Field(
        None, description="What the robot carries from the start (a dynamic plant)."
    )
    contacts: ContactsSpec | None = Field(
        None, description="Drive wheels, casters and load sharing on terrain (default RM100's)."
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
    model_payload: bool | PayloadSpec = Field(
        True,
        description="The payload of the controller's model: true, the robot's (as goals change "
        "it); false, none; or a payload of its own (a mismatch with the truth).",
    )
    traction_control: TractionSpec | None = Field(
        None, description="Limit the wheel torques by the estimated friction (a dynamic plant)."
    )
    slope_feedforward: bool | SlopeFeedForwardSpec = Field(
        False,
        description="Add the wheel torques that hold the controller's model against the slope "
        "of the terrain under its estimated pose (the robot knows its floor's grades; a dynamic "
        "plant with terrain). A mapping {rolling_resistance: true} also feeds forward the "
        "rolling resistance the terrain gives under each contact; true is {} (the slope alone).",
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
    slip_compensation: bool = Field(
        False,
        description="Take out of the wheel distances the slip the commanded torques cause on "
        "the terrain's friction curves (wheelbase.sim.SlipCompensatedOdometry: the robot knows "
        "its floor; a dynamic plant, localization: odometry).",
    )
    gyro: bool = Field(
        False,
        description="Gyrodometry: the heading increment from the IMU's gyro while it and the "
        "wheels disagree over a window by more than the ticks' quantisation (a wheel spins or "
        "skids), else the wheels' (wheelbase.sim.gyrodometry; needs sensors.imu, "
        "odometry.mode: encoders and localization: odometry).",
    )


class LidarSpec(_Strict):
    """A simulated 2-D lidar (:class:`wheelbase.sensors.Lidar`) read at the true pose."""

    beams: int = Field(60, gt=0, description="Beams per scan.")
    fov_deg: float = Field(360.0, gt=0, le=360, description="Field of view [deg].")
    max_range: float = Field(8.0, gt=0, description="Largest range [m].")
    min_range: float = Field(
        0.0, ge=0, description="Smallest valid range [m]; shorter readings are NaN."
    )
    range_std: float = Field(0.02, gt=0, description="σ of a hit [m].")
    rate_hz: float = Field(10.0, gt=0, description="Scans per second.")
    mount: tuple[float, float, float] = Field(
        (0.0, 0.0, 0.0), description="Sensor pose in the body frame (x [m], y [m], yaw [deg])."
    )
    beam_model: dict[str, float] = Field(
        default_factory=dict,
        description="Weights z_hit, z_short, z_max, z_rand (adding up to 1) and lambda_short "
        "[1/m] of the beam model (Thrun et al. §6.3); default: Gaussian hits only.",
    )

    @model_validator(mode="after")
    def _ranges(self):
        if self.min_range >= self.max_range:
            raise ValueError(
                f"min_range must be < max_range = {self.max_range:g} m (got {self.min_range:g})"
            )
        allowed = {"z_hit", "z_short", "z_max", "z_rand", "lambda_short"}
        unknown = sorted(set(self.beam_model) - allowed)
        if unknown:
            raise ValueError(
                f"beam_model: unknown key {unknown[0]!r}; allowed: {', '.join(sorted(allowed))}"
            )
        return self


class LandmarkSpec(_Strict):
    """Identified landmarks and the range–bearing sensor that sees them
    (:class:`wheelbase.sensors.LandmarkSensor`)."""

    positions: tuple[tuple[float, float], ...] = Field(
        ..., min_length=1, description="Landmark positions (x [m], y [m]); identity = index."
    )
    max_range: float = Field(6.0, gt=0, description="Largest range at which one is seen [m].")
    fov_deg: float = Field(360.0, gt=0, le=360, description="Field of view [deg].")
    range_std: float = Field(0.05, gt=0, description="σ of the range [m].")
    bearing_std_deg: float = Field(2.0, gt=0, description="σ of the bearing [deg].")
    detection_probability: float = Field(
        1.0, gt=0, le=1, description="Probability that a landmark in view is detected."
    )
    false_rate: float = Field(
        0.0, ge=0, description="Mean number of false detections per reading (clutter)."
    )
    rate_hz: float = Field(5.0, gt=0, description="Readings per second.")

    @field_validator("positions")
    @classmethod
    def _finite_positions(cls, value):
        for x, y in value:
            if not (math.isfinite(x) and math.isfinite(y)) or max(abs(x), abs(y)) > MAX_COORDINATE:
                raise ValueError(
                    f"positions must be finite and within ±{MAX_COORDINATE:g} m (got ({x}, {y}))"
                )
        return value


class ImuSpec(_Strict):
    """A planar MEMS IMU (:class:`wheelbase.sensors.Imu`): the yaw rate and the body's
    horizontal linear acceleration (gravity removed by its attitude filter), read every step
    from the true motion (a dynamic plant). Defaults: the MPU-6050's noise densities; the
    biases are what a start-up calibration at rest leaves."""

    gyro_noise_density_deg: float = Field(
        0.005, ge=0, le=10, allow_inf_nan=False,
        description="White-noise density of the yaw rate [deg/s/√Hz] (MPU-6050: 0.005).",
    )  # fmt: skip
    gyro_bias_std_deg: float = Field(
        0.1, ge=0, le=100, allow_inf_nan=False,
        description="σ of the yaw rate's constant bias over a run [deg/s].",
    )  # fmt: skip
    accel_noise_density: float = Field(
        400e-6 * 9.80665, ge=0, le=10, allow_inf_nan=False,
        description="White-noise density of each horizontal accelerometer axis [m/s²/√Hz] "
        "(MPU-6050: 400 µg/√Hz = 0.0039).",
    )  # fmt: skip
    accel_bias_std: float = Field(
        0.1, ge=0, le=10, allow_inf_nan=False,
        description="σ of each accelerometer axis' constant bias over a run [m/s²] (the "
        "start-up calibration's residual and the attitude filter's tilt error).",
    )  # fmt: skip
    mount: tuple[float, float] = Field(
        (0.0, 0.0), description="Sensor position in the body frame (x [m], y [m]), within ±10 m."
    )

    @field_validator("mount")
    @classmethod
    def _mount(cls, value):
        if not all(math.isfinite(v) and abs(v) <= 10.0 for v in value):
            raise ValueError(f"must be finite and within ±10 m (got {list(value)})")
        return value


class SensorsSpec(_Strict):
    """Sensors: exteroceptive ones read at the true pose, an IMU read from the true motion
    (none by default)."""

    lidar: LidarSpec | None = Field(None, description="A 2-D lidar on the map.")
    landmarks: LandmarkSpec | None = Field(None, description="Range–bearing landmarks.")
    imu: ImuSpec | None = Field(
        None, description="A yaw-rate gyro and horizontal accelerometers (a dynamic plant); "
        "traction control's friction estimate reads it."
    )  # fmt: skip


# Options of each localisation method besides ``method`` and ``initial_std``.
LOCALIZATION_OPTIONS: dict[str, frozenset[str]] = {
    "odometry": frozenset(),
    "ekf": frozenset({"range_std", "bearing_std_deg", "gate_probability", "motion"}),
    "ukf": frozenset(
        {"range_std", "bearing_std_deg", "gate_probability", "motion", "alpha", "beta", "kappa"}
    ),
    "amcl": frozenset(
        {
            "min_particles", "max_particles", "alpha1", "alpha2", "alpha3", "alpha4",
            "sigma_hit", "z_hit", "z_rand", "max_beams", "likelihood_max_dist",
            "update_min_d", "update_min_a_deg", "resample_interval", "kld_err", "kld_delta",
            "recovery_alpha_slow", "recovery_alpha_fast", "range_std", "bearing_std_deg",
            "global_start",
        }
    ),
}  # fmt: skip


class LocalizationSpec(_Strict):
    """How the controller's estimate is made: wheel odometry alone, or a filter that fuses it
    with the sensors. Options left unset take the defaults given here; options of another
    method are errors."""

    method: Literal["odometry", "ekf", "ukf", "amcl"] = Field(
        "odometry",
        description="odometry: dead reckoning alone; ekf, ukf: Kalman filters on the landmarks; "
        "amcl: a particle filter on the lidar (likelihood field) and the landmarks.",
    )
    initial_std: tuple[float, float, float] | None = Field(
        None,
        description="σ (x [m], y [m], heading [deg]) of the belief at the start pose (default "
        "ekf/ukf 0.01 m, 0.01 m, 1 deg; amcl 0.02 m, 0.02 m, 1 deg).",
    )
    range_std: float | None = Field(
        None, gt=0, description="σ of a landmark range the filter assumes [m] (default: the "
        "sensor's)."
    )  # fmt: skip
    bearing_std_deg: float | None = Field(
        None, gt=0, description="σ of a landmark bearing the filter assumes [deg] (default: "
        "the sensor's)."
    )  # fmt: skip
    gate_probability: float | None = Field(
        None, gt=0, le=1, description="χ² gate of the Kalman filters (default 0.99)."
    )
    motion: dict[str, float] | None = Field(
        None,
        description="Kalman filters' motion noise (VelocityMotion: distance_per_m, "
        "distance_per_rad, heading_per_m, heading_per_rad, distance_per_s, heading_per_s); "
        "default: the encoders' tick noise per second plus 1e-4 m²/m, 1e-4 rad²/m, "
        "1e-4 rad²/rad.",
    )
    alpha: float | None = Field(None, gt=0, description="UKF sigma-point spread (default 1).")
    beta: float | None = Field(None, ge=0, description="UKF β (default 2).")
    kappa: float | None = Field(None, description="UKF κ (default 0).")
    min_particles: int | None = Field(None, gt=0, description="AMCL (default 500).")
    max_particles: int | None = Field(None, gt=0, description="AMCL (default 2000).")
    alpha1: float | None = Field(
        None, ge=0, description="AMCL rotation noise from rotation (default 1e-3; Nav2 0.2)."
    )
    alpha2: float | None = Field(
        None, ge=0, description="AMCL rotation noise from translation [rad²/m²] (default "
        "5e-3; Nav2 0.2)."
    )  # fmt: skip
    alpha3: float | None = Field(
        None, ge=0, description="AMCL translation noise from translation (default 1e-4; "
        "Nav2 0.2)."
    )  # fmt: skip
    alpha4: float | None = Field(
        None, ge=0, description="AMCL translation noise from rotation [m²/rad²] (default "
        "1e-4; Nav2 0.2)."
    )  # fmt: skip
    sigma_hit: float | None = Field(
        None, gt=0, description="AMCL likelihood-field σ [m] (default 0.05; Nav2 0.2)."
    )
    z_hit: float | None = Field(None, gt=0, description="AMCL (default 0.9; Nav2 0.5).")
    z_rand: float | None = Field(None, ge=0, description="AMCL (default 0.1; Nav2 0.5).")
    max_beams: int | None = Field(None, gt=0, description="AMCL beams used (default 60).")
    likelihood_max_dist: float | None = Field(None, gt=0, description="AMCL [m] (default 2).")
    update_min_d: float | None = Field(
        None, ge=0, description="AMCL: update after this much travel [m] (default 0.25)."
    )
    update_min_a_deg: float | None = Field(
        None, ge=0, description="AMCL: or after this much turn [deg] (default 11.5 = 0.2 rad)."
    )
    resample_interval: int | None = Field(None, gt=0, description="AMCL (default 1).")
    kld_err: float | None = Field(None, gt=0, description="AMCL KLD ε (default 0.05).")
    kld_delta: float | None = Field(None, gt=0, lt=1, description="AMCL KLD δ (default 0.01).")
    recovery_alpha_slow: float | None = Field(
        None, ge=0, le=1, description="AMCL recovery (default 0: off)."
    )
    recovery_alpha_fast: float | None = Field(
        None, ge=0, le=1, description="AMCL recovery (default 0: off)."
    )
    global_start: bool | None = Field(
        None, description="AMCL: spread the particles over the free space (unknown start)."
    )

    @field_validator("initial_std")
    @classmethod
    def _nonnegative_std(cls, value):
        if value is not None and not all(math.isfinite(v) and v >= 0 for v in value):
            raise ValueError(f"must be three finite values >= 0 (got {list(value)})")
        return value

    @model_validator(mode="after")
    def _options_of_the_method(self):
        allowed = LOCALIZATION_OPTIONS[self.method]
        for name in sorted(self.model_fields_set - {"method", "initial_std"}):
            if name not in allowed and getattr(self, name) is not None:
                users = [m for m, keys in LOCALIZATION_OPTIONS.items() if name in keys]
                raise ValueError(
                    f"{name} is an option of {' and '.join(users)}, not of method {self.method!r}"
                )
        if self.method == "odometry" and self.initial_std is not None:
            raise ValueError("initial_std is an option of the filters, not of method 'odometry'")
        return self


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
        description="Bundled map name, path to a ROS YAML (an image with its resolution) / "
        "Moving AI .map / polygon world, or 'empty' for an obstacle-free field around the "
        "start and goals.",
    )
    robot: RobotSpec = Field(default_factory=RobotSpec)
    plant: Literal["kinematic", "dynamic"] = Field("kinematic")
    planner: PlannerSpec = Field(default_factory=PlannerSpec)
    trajectory: TrajectorySpec = Field(default_factory=TrajectorySpec)
    controller: ControllerSpec = Field(default_factory=ControllerSpec)
    odometry: OdometrySpec = Field(default_factory=OdometrySpec)
    sensors: SensorsSpec = Field(
        default_factory=SensorsSpec, description="A lidar and/or landmarks read at the true pose."
    )
    localization: LocalizationSpec = Field(
        default_factory=LocalizationSpec,
        description="odometry (default), ekf, ukf or amcl, with the filter's options beside "
        "the method.",
    )
    seed: int = Field(0, ge=0, le=2**64 - 1, description="Noise seed (a 64-bit unsigned integer).")
    start: tuple[float, float, float] = Field(..., description="(x [m], y [m], heading [deg]).")
    goals: tuple[tuple[float, float, float], ...] = Field(
        ..., min_length=1, description="Goals (x [m], y [m], heading [deg]) visited in order."
    )
    goal_tolerance: tuple[float, float] = Field(
        (0.05, 5.0), description="Arrival tolerance (position [m], heading [deg])."
    )
    duration: float = Field(
        120.0, gt=0, description="Longest run [s]: the time limit (status timeout)."
    )
    settle_time: float | None = Field(
        None, ge=0, description="End the run this long [s] after the reference trajectory "
        "ends (status timeout), when that comes before duration (default: none, duration "
        "governs)."
    )  # fmt: skip
    dt: float = Field(0.01, gt=0, description="Simulation and control step [s].")
    resources: ResourceSpec = Field(
        default_factory=ResourceSpec, description="Resource limits (raise them on purpose)."
    )
    world: WorldSpec | None = Field(
        None,
        description="The truth beyond map (obstacles, moving agents), seen only by the sensors.",
    )
    fleet: tuple[FleetRobotSpec, ...] | None = Field(
        None,
        min_length=1,
        description="Several robots (each its start and goals) in one world, each seeing the "
        "others; start and goal then come from the fleet's first robot.",
    )
    costmap: dict[str, float | int | bool] | None = Field(
        None,
        description="Layered costmap options (wheelbase.perception.CostmapSpec: "
        "inflation_radius [m], cost_scaling_factor [1/m], obstacle_max_range [m], "
        "raytrace_max_range [m], window [m], ...); default Nav2's.",
    )
    tracker: dict[str, float | int | bool] | None = Field(
        None,
        description="Tracker of moving obstacles (wheelbase.perception.TrackerSpec options).",
    )
    replanning: ReplanningSpec = Field(
        default_factory=ReplanningSpec,
        description="Replanning on the costmap (with a lidar and a path-following law).",
    )
    recovery: RecoverySpec = Field(
        default_factory=RecoverySpec, description="Recoveries when no plan exists."
    )
    control_rate_hz: float | None = Field(
        None,
        gt=0,
        description="Controller calls per second (default: every step dt); the command is "
        "held between calls.",
    )
    terrain: TerrainSpec | None = Field(
        None,
        description="The ground: surfaces, regions with grades, wheel slip (a dynamic plant).",
    )
    goal_payloads: tuple[PayloadSpec | None, ...] | None = Field(
        None,
        description="The payload from each goal on (None: unchanged; mass 0: dropped); a goal "
        "written {pose: [x, y, deg], payload: {...}} fills it.",
    )

    @model_validator(mode="before")
    @classmethod
    def _goal_alias(cls, data: Any) -> Any:
        data = goal_alias(data)
        if isinstance(data, dict) and data.get("fleet"):
            fleet = data["fleet"]
            if "start" in data or "goals" in data:
                raise ValueError(
                    "with fleet, give each robot's start and goal in the fleet, not start/goal"
                )
            first = fleet[0] if isinstance(fleet, (list, tuple)) else None
            if isinstance(first, dict):
                data = dict(data)
                data["start"] = first.get("start")
                data["goals"] = first.get("goals", [first["goal"]] if "goal" in first else None)
        return data

    @model_validator(mode="before")
    @classmethod
    def _goals_with_payloads(cls, data: Any) -> Any:
        # a goal may be {pose: [x, y, deg], payload: {...} | null}: split it into the pose and
        # goal_payloads (null drops the load: mass 0)
        if not isinstance(data, dict):
            return data
        key = "goals" if "goals" in data else "goal" if "goal" in data else None
        goals = data.get(key) if key else None
        entries = [goals] if key == "goal" else goals
        if not isinstance(entries, (list, tuple)) or not any(isinstance(g, dict) for g in entries):
            return data
        if "goal_payloads" in data:
            raise ValueError("give payloads in the goals or in goal_payloads, not both")
        poses, payloads = [], []
        for index, goal in enumerate(entries):
            if not isinstance(goal, dict):
                poses.append(goal)
                payloads.append(None)
                continue
            unknown = sorted(set(goal) - {"pose", "payload"})
            if unknown or "pose" not in goal:
                raise ValueError(
                    f"goals[{index}]: a goal mapping has pose: [x, y, deg] and optionally "
                    f"payload (got keys {sorted(goal)})"
                )
            poses.append(goal["pose"])
            if "payload" in goal:
                payloads.append(goal["payload"] if goal["payload"] is not None else {"mass": 0})
            else:
                payloads.append(None)
        data = dict(data)
        data[key] = poses[0] if key == "goal" else poses
        data["goal_payloads"] = payloads
        return data

    @model_validator(mode="after")
    def _terrain_needs(self):
        dynamic = self.plant == "dynamic"
        for name, given in (
            ("terrain", self.terrain is not None),
            ("robot.payload", self.robot.payload is not None),
            ("goal_payloads", self.goal_payloads is not None),
            ("controller.traction_control", self.controller.traction_control is not None),
            ("controller.slope_feedforward", self.controller.slope_feedforward is not False),
            ("odometry.slip_compensation", self.odometry.slip_compensation),
        ):
            if given and not dynamic:
                raise ValueError(f"{name} acts on the dynamics: set plant: dynamic")
        if self.sensors.imu is not None and not dynamic:
            raise ValueError(
                "sensors.imu reads the accelerations of the dynamics: set plant: dynamic"
            )
        if self.odometry.gyro and self.sensors.imu is None:
            raise ValueError("odometry.gyro reads the IMU's gyro: give sensors.imu")
        if self.goal_payloads is not None and len(self.goal_payloads) != len(self.goals):
            raise ValueError(
                f"goal_payloads has {len(self.goal_payloads)} entries for {len(self.goals)} goals"
            )
        return self

    @field_validator("start", "goals", "goal_tolerance", "duration", "dt", "settle_time")
    @classmethod
    def _finite(cls, value):
        if value is not None and not all(math.isfinite(number) for number in _numbers(value)):
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
    def _localization_needs(self):
        method = self.localization.method
        if method == "odometry":
            return self
        if self.odometry.mode != "encoders":
            raise ValueError(
                f"localization: {method} fuses wheel-encoder odometry with the sensors: set "
                "odometry.mode: encoders"
            )
        if method in ("ekf", "ukf") and self.sensors.landmarks is None:
            raise ValueError(
                f"localization: {method} corrects with landmarks: give sensors.landmarks"
            )
        if method == "amcl" and self.sensors.lidar is None and self.sensors.landmarks is None:
            raise ValueError("localization: amcl needs sensors.lidar or sensors.landmarks")
        return self

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
            rows, cols = empty_map_shape(self.robot_poses())
            limit = self.resources.max_map_cells
            if rows * cols > limit:
                raise ValueError(
                    f"map: empty around the start and goals would be {rows} × {cols} = "
                    f"{count_text(rows * cols)} cells of {EMPTY_MAP_RESOLUTION} m: more than "
                    f"resources.max_map_cells = {limit}; bring them closer, use a map file, or "
                    "raise resources.max_map_cells"
                )
        return self

    def robot_poses(self) -> list[tuple[float, float, float]]:
        """Every start and goal of every robot (the fleet's, or the one robot's) [m, m, deg]."""
        if self.fleet is None:
            return [self.start, *self.goals]
        return [pose for robot in self.fleet for pose in (robot.start, *robot.goals)]

    def to_yaml(self) -> str:
        """The resolved scenario (all defaults filled) as YAML, loadable again."""
        data = self.model_dump(mode="json")
        # the filter options left unset: their defaults depend on the method (see the schema)
        data["localization"] = {k: v for k, v in data["localization"].items() if v is not None}
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


def empty_map(points: Any, max_cells: int = MAX_MAP_CELLS) -> Any:
    """The ``map: empty`` field: an obstacle-free grid around ``points``, walled by its edge.

    The one rule of ``empty`` for scenarios, ``wheelbase plan empty`` and ``wheelbase control
    --map empty``: :data:`EMPTY_MAP_MARGIN` around the points' bounding box (rounded out to
    whole metres) at :data:`EMPTY_MAP_RESOLUTION`.

    Parameters
    ----------
    points : sequence of array_like
        Poses or points (x [m], y [m], ...): the start and the goals.
    max_cells : int
        Most cells allowed (``resources.max_map_cells``).

    Returns
    -------
    OccupancyGrid

    Raises
    ------
    MapError
        If the field would hold more than ``max_cells`` cells.
    """
    import numpy as np

    from wheelbase.errors import MapError
    from wheelbase.planning import OccupancyGrid

    rows, cols = empty_map_shape(points)
    if rows * cols > max_cells:
        raise MapError(
            f"map: empty around the start and goals would be {rows} × {cols} = "
            f"{count_text(rows * cols)} cells of {EMPTY_MAP_RESOLUTION} m: more than "
            f"max_map_cells = {max_cells}; bring them closer or use a map file"
        )
    low = [math.floor(min(p[k] for p in points) - EMPTY_MAP_MARGIN) for k in (0, 1)]
    return OccupancyGrid.from_array(
        np.zeros((rows, cols), bool), EMPTY_MAP_RESOLUTION, origin=(float(low[0]), float(low[1]))
    )


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
        terrain = data.get("terrain")
        raster = terrain.get("raster") if isinstance(terrain, dict) else None
        image = raster.get("image") if isinstance(raster, dict) else None
        if isinstance(image, str) and not Path(image).is_absolute():  # as the map
            beside = path.parent / image
            if beside.exists():
                data = {**data, "terrain": {**terrain, "raster": {**raster, "image": str(beside)}}}
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
