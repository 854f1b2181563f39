"""A scenario's ``odometry``, ``sensors`` and ``localization`` sections resolved to objects.

:func:`build_sensors` turns ``sensors`` into the engine's
:class:`~wheelbase.sim.sensors.SensorSuite`; :func:`build_estimator` turns ``odometry`` and
``localization`` into the estimator the controller reads: perfect state, wheel-encoder
odometry, or a filter of :mod:`wheelbase.sim.localizers` that fuses the encoders with the
sensors. Angles in the scenario are degrees; they are converted here.

Defaults where the scenario is silent (measured on the noisy demo batch,
``benchmarks/localization_loop.py``):

- EKF and UKF: the filter assumes the landmark sensor's own noise; the motion noise is the
  encoders' tick noise as a random walk per second (the variance of a rounded Gaussian tick
  error, σ² + 1/12, through the wheel geometry) plus 1e-4 m²/m, 1e-4 rad²/m and 1e-4 rad²/rad
  for what is not modelled (a wheel-radius error of a few per mille).
- AMCL: Nav2's particle counts, beams and update thresholds, but odometry noise α₁…α₄ =
  1e-3, 5e-3, 1e-4, 1e-4 (Nav2's 0.2 each is for real robots that slip; on the demo the
  estimate then jumps by centimetres at every update and 4 of 10 runs missed the 5 cm goal
  tolerance) and a sharper likelihood field, σ_hit = 0.05 m, z_hit = 0.9, z_rand = 0.1 (Nav2
  0.2, 0.5, 0.5), which suits a lidar with 2 cm noise on a 10 cm map.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from wheelbase.scenario import Scenario

__all__ = [
    "AMCL_DEFAULTS",
    "build_estimator",
    "build_imu",
    "build_odometry",
    "build_sensors",
    "world_grid",
]

AMCL_DEFAULTS: dict[str, float] = {
    "alpha1": 1e-3,
    "alpha2": 5e-3,
    "alpha3": 1e-4,
    "alpha4": 1e-4,
    "sigma_hit": 0.05,
    "z_hit": 0.9,
    "z_rand": 0.1,
}
"""The closed loop's AMCL options where they differ from :class:`wheelbase.localization.AMCL`
(module docstring)."""

_KALMAN_MOTION = {"distance_per_m": 1e-4, "heading_per_m": 1e-4, "heading_per_rad": 1e-4}


def world_grid(world: Any) -> Any:
    """The occupancy grid of a world (a polygon world's raster).

    Parameters
    ----------
    world : OccupancyGrid or PolygonWorld
        The scenario's map.
    """
    from wheelbase.planning import PolygonWorld

    return world.raster if isinstance(world, PolygonWorld) else world


def build_sensors(scenario: Scenario, world: Any) -> Any:
    """The scenario's sensors, or None when it has none.

    Parameters
    ----------
    scenario : Scenario
        The validated scenario.
    world : OccupancyGrid or PolygonWorld
        What the lidar sees.

    Returns
    -------
    SensorSuite or None
    """
    from wheelbase.sensors import BeamModel, LandmarkSensor, Lidar
    from wheelbase.sim.sensors import SensorSuite

    spec = scenario.sensors
    if spec.lidar is None and spec.landmarks is None:
        return None
    options: dict[str, Any] = {}
    if spec.lidar is not None:
        lidar = spec.lidar
        x, y, yaw = lidar.mount
        options.update(
            world=world,
            lidar=Lidar(
                beams=lidar.beams,
                fov=math.radians(lidar.fov_deg),
                max_range=lidar.max_range,
                min_range=lidar.min_range,
                range_std=lidar.range_std,
                mount=(x, y, math.radians(yaw)),
                beam_model=BeamModel(**lidar.beam_model),
            ),
            lidar_rate_hz=lidar.rate_hz,
        )
    if spec.landmarks is not None:
        marks = spec.landmarks
        options.update(
            landmarks=np.array(marks.positions, dtype=np.float64),
            landmark_sensor=LandmarkSensor(
                max_range=marks.max_range,
                fov=math.radians(marks.fov_deg),
                range_std=marks.range_std,
                bearing_std=math.radians(marks.bearing_std_deg),
                detection_probability=marks.detection_probability,
                false_rate=marks.false_rate,
            ),
            landmark_rate_hz=marks.rate_hz,
        )
    return SensorSuite(**options)


def build_imu(scenario: Scenario) -> Any:
    """The scenario's IMU (:class:`~wheelbase.sensors.Imu`, angles in radians), or None.

    Parameters
    ----------
    scenario : Scenario
        The validated scenario.
    """
    from wheelbase.sensors.imu import Imu

    spec = scenario.sensors.imu
    if spec is None:
        return None
    return Imu(
        gyro_noise_density=math.radians(spec.gyro_noise_density_deg),
        gyro_bias_std=math.radians(spec.gyro_bias_std_deg),
        accel_noise_density=spec.accel_noise_density,
        accel_bias_std=spec.accel_bias_std,
        mount=tuple(spec.mount),
    )


def build_odometry(scenario: Scenario, robot: Any) -> Any:
    """Perfect state or the wheel-encoder odometry of the scenario's ``odometry`` section.

    Parameters
    ----------
    scenario : Scenario
        The validated scenario.
    robot : Robot
        The resolved robot (its wheel radius and half track are the odometry's nominal ones).
    """
    from wheelbase.odometry import Encoder, WheelOdometry
    from wheelbase.sim import EncoderOdometry, PerfectState

    spec = scenario.odometry
    if spec.mode == "perfect":
        return PerfectState()
    return EncoderOdometry(
        Encoder(spec.pulses_per_revolution, noise_std=spec.tick_noise_std),
        WheelOdometry(
            robot.wheel_radius, robot.half_track, spec.pulses_per_revolution, method=spec.method
        ),
    )


def _initial_std(spec: Any, default: tuple[float, float, float]) -> tuple[float, float, float]:
    if spec.initial_std is None:
        return default
    x, y, heading = spec.initial_std
    return (x, y, math.radians(heading))


def _kalman_motion(scenario: Scenario, robot: Any) -> Any:
    """The Kalman filters' motion noise (module docstring)."""
    from wheelbase.localization import VelocityMotion

    spec = scenario.localization
    if spec.motion is not None:
        return VelocityMotion(**spec.motion)
    odometry = scenario.odometry
    sigma = odometry.tick_noise_std
    tick_var = sigma**2 + 1.0 / 12.0 if sigma > 0 else 0.0
    wheel_var = (
        tick_var * (2.0 * math.pi * robot.wheel_radius / odometry.pulses_per_revolution) ** 2
    )
    dt = scenario.dt
    return VelocityMotion(
        **_KALMAN_MOTION,
        distance_per_s=wheel_var / (2.0 * dt),  # Δs = (s_l + s_r)/2
        heading_per_s=wheel_var / (2.0 * robot.half_track**2 * dt),  # Δθ = (s_r − s_l)/2b
    )


def build_estimator(scenario: Scenario, robot: Any, world: Any, sensors: Any) -> Any:
    """The estimator the controller reads (module docstring).

    Parameters
    ----------
    scenario : Scenario
        The validated scenario.
    robot : Robot
        The resolved robot.
    world : OccupancyGrid or PolygonWorld
        The map (AMCL's likelihood field and random particles).
    sensors : SensorSuite or None
        :func:`build_sensors` of the same scenario.

    Returns
    -------
    PerfectState, EncoderOdometry, KalmanLocalizer or ParticleLocalizer
    """
    odometry = build_odometry(scenario, robot)
    spec = scenario.localization
    if spec.method == "odometry":
        return odometry
    marks = scenario.sensors.landmarks
    range_std = spec.range_std or (marks.range_std if marks is not None else 0.1)
    bearing_deg = spec.bearing_std_deg or (marks.bearing_std_deg if marks is not None else 3.0)
    if spec.method in ("ekf", "ukf"):
        from wheelbase.localization import EKF, UKF
        from wheelbase.sim import KalmanLocalizer

        options: dict[str, Any] = {
            "motion": _kalman_motion(scenario, robot),
            "range_std": range_std,
            "bearing_std": math.radians(bearing_deg),
        }
        if spec.gate_probability is not None:
            options["gate_probability"] = spec.gate_probability
        if spec.method == "ukf":
            # `is not None`, not truthiness: β = 0 and κ = 0 are values a user may choose
            options.update(
                {
                    k: getattr(spec, k)
                    for k in ("alpha", "beta", "kappa")
                    if getattr(spec, k) is not None
                }
            )
        cls = EKF if spec.method == "ekf" else UKF
        return KalmanLocalizer(
            cls(sensors.landmarks, **options),
            odometry,
            _initial_std(spec, (0.01, 0.01, math.radians(1.0))),
        )
    from wheelbase.localization import AMCL, OdometryMotion
    from wheelbase.sim import ParticleLocalizer

    chosen = {**AMCL_DEFAULTS}
    chosen.update(
        {
            name: getattr(spec, name)
            for name in sorted(scenario.localization.model_fields_set)
            if getattr(spec, name, None) is not None
        }
    )
    motion = OdometryMotion(*(chosen.pop(f"alpha{k}") for k in range(1, 5)))
    global_start = bool(chosen.pop("global_start", False))
    for name in ("method", "initial_std", "range_std", "bearing_std_deg"):
        chosen.pop(name, None)
    if "update_min_a_deg" in chosen:
        chosen["update_min_a"] = math.radians(chosen.pop("update_min_a_deg"))
    lidar = None if sensors is None else sensors.lidar
    amcl = AMCL(
        grid=world_grid(world),
        lidar=lidar,
        landmarks=None if marks is None else sensors.landmarks,
        motion=motion,
        landmark_range_std=range_std,
        landmark_bearing_std=math.radians(bearing_deg),
        # a floor under the landmark likelihood: a false detection cannot wipe out the set
        landmark_z_rand=0.1,
        landmark_max_range=10.0 if marks is None else marks.max_range,
        **chosen,
    )
    return ParticleLocalizer(
        amcl, odometry, _initial_std(spec, (0.02, 0.02, math.radians(1.0))), global_start
    )
