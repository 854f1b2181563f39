"""A scenario's ground and loads resolved to objects (for :mod:`wheelbase.runner`).

- :func:`payload_timeline`: the payload from t = 0 and its changes at the goals;
- :func:`controller_model`: the controller's model of the robot (``controller.model_payload``);
- :func:`build_terrain`: the ``terrain`` section on the map's rectangle
  (:class:`~wheelbase.terrain.TerrainMap`);
- :func:`build_plant`: the true robot on its ground, payload changes included
  (:class:`~wheelbase.sim.TerrainPlant`);
- :func:`wrap_controller`: the controller's model schedule, slope feed-forward and traction
  control;
- :func:`compensate_slip`: the encoder odometry that takes out its torques' slip;
- :func:`gyrodometry`: the heading from the IMU's gyro where the wheels slip;
- :func:`build_stuck`: the ``stuck`` rule of a scenario with terrain.

Decisions where the scenario is silent: a payload changes when the reference trajectory comes to
rest at the goal that carries the change (the robot is there, within its tracking error); the
terrain raster has the map's cells (a ``map: empty`` field's 5 cm) unless
``terrain.resolution`` says otherwise; without a ``terrain`` section a robot with a payload
rolls without slipping on a floor without rolling resistance, which is the existing dynamic
model with the payload's body; the adaptive computed torque lets its force F_0 drift at 1 N/√s
on graded terrain (the pull of a slope changes with the grade and the heading) and keeps it
constant on level ground (:func:`adaptive_defaults`).
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any

import numpy as np

from wheelbase.errors import ConfigError, ScenarioError
from wheelbase.inertial import Payload, with_payload
from wheelbase.scenario import Scenario

__all__ = [
    "adaptive_defaults",
    "build_contacts",
    "build_plant",
    "build_stuck",
    "build_terrain",
    "compensate_slip",
    "controller_model",
    "ground_active",
    "gyrodometry",
    "payload_timeline",
    "surface_of",
    "terrain_metrics",
    "wrap_controller",
]

_FLOOR = "floor"  # the ground of a payload without terrain: rolling, no resistance


def ground_active(scenario: Scenario) -> bool:
    """Whether the run needs the terrain plant (a terrain, a payload or a payload change)."""
    return scenario.plant == "dynamic" and (
        scenario.terrain is not None
        or scenario.robot.payload is not None
        or scenario.goal_payloads is not None
    )


def adaptive_defaults(scenario: Scenario) -> dict[str, float]:
    """Gains of ``adaptive_computed_torque`` that depend on the ground (module docstring).

    Parameters
    ----------
    scenario : Scenario
        The scenario.
    """
    terrain = scenario.terrain
    graded = terrain is not None and any(region.grade_percent > 0 for region in terrain.regions)
    return {"force_drift": 1.0} if graded else {}


def _payload(spec: Any) -> Payload | None:
    if spec is None or spec.mass == 0.0:
        return None
    return Payload(spec.mass, tuple(spec.position), spec.inertia, spec.height)


def _check_on_robot(payload: Payload | None, robot: Any, where: str) -> None:
    if payload is None:
        return
    try:
        payload.check_footprint(*robot.footprint, robot.center_offset)
    except ConfigError as error:
        raise ScenarioError(f"{where}: {error}") from None


def payload_timeline(
    scenario: Scenario, robot: Any, reference: Any = None, goals: list | None = None
) -> list[tuple[float, Payload | None]]:
    """[(t [s], payload from then on)], starting at t = 0 with ``robot.payload``.

    Parameters
    ----------
    scenario : Scenario
        The scenario.
    robot : Robot
        The resolved robot (its footprint bounds the payload's position).
    reference : PoseTrajectory, optional
        The reference trajectory (when the robot reaches each goal); needed for goal changes.
    goals : list of numpy.ndarray, optional
        The goal poses [m, m, rad].
    """
    first = _payload(scenario.robot.payload)
    _check_on_robot(first, robot, "robot.payload.position")
    timeline: list[tuple[float, Payload | None]] = [(0.0, first)]
    if scenario.goal_payloads is None or reference is None:
        return timeline
    times = _arrival_times(reference, goals, 0.5 * scenario.goal_tolerance[0])
    for index, (spec, time) in enumerate(zip(scenario.goal_payloads, times, strict=True)):
        if spec is None:
            continue
        payload = _payload(spec)
        _check_on_robot(payload, robot, f"goal_payloads[{index}].position")
        timeline.append((time, payload))
    return timeline


def _arrival_times(reference: Any, goals: list, tolerance: float) -> list[float]:
    """When the reference comes to rest at each goal, in order [s]."""
    poses, t = reference.poses, reference.t
    speed = np.abs(reference.twist[:, 0]) + np.abs(reference.twist[:, 2])
    times, start = [], 0
    for goal in goals:
        distance = np.hypot(poses[start:, 0] - goal[0], poses[start:, 1] - goal[1])
        near = np.flatnonzero((distance <= max(tolerance, 1e-6)) & (speed[start:] < 1e-9))
        k = start + (int(near[0]) if near.size else int(np.argmin(distance)))
        times.append(float(t[k]))
        start = k
    return times


def _dynamics_with(robot: Any, payload: Payload | None) -> Any:
    base = robot.dynamics
    return base.with_body(with_payload(base.body, payload))


def controller_model(scenario: Scenario, robot: Any) -> Any:
    """The controller's model at t = 0: the robot with the payload it believes it carries.

    Parameters
    ----------
    scenario : Scenario
        The scenario.
    robot : Robot
        The resolved robot (``robot.dynamics`` without payload).
    """
    belief = scenario.controller.model_payload
    if belief is True:
        payload = _payload(scenario.robot.payload)
    elif belief is False:
        payload = None
    else:
        payload = _payload(belief)
        _check_on_robot(payload, robot, "controller.model_payload.position")
    return _dynamics_with(robot, payload)


def build_contacts(scenario: Scenario) -> Any:
    """The robot's :class:`~wheelbase.terrain.WheelContacts` (RM100's, with the set fields).

    Parameters
    ----------
    scenario : Scenario
        The scenario.
    """
    from wheelbase.terrain.contact import RM100_CONTACTS

    spec = scenario.robot.contacts
    if spec is None:
        return RM100_CONTACTS
    values = {k: v for k, v in spec.model_dump().items() if v is not None}
    if "casters" in values:
        values["casters"] = tuple(tuple(c) for c in values["casters"])
    try:
        return dataclasses.replace(RM100_CONTACTS, **values)
    except ConfigError as error:
        raise ScenarioError(f"robot.contacts: {error}") from None


def surface_of(spec: Any, where: str) -> Any:
    """A :class:`~wheelbase.terrain.Surface` from a name or a ``SurfaceSpec``.

    Parameters
    ----------
    spec : str or SurfaceSpec
        The scenario's surface.
    where : str
        Its key, for errors.
    """
    from wheelbase.terrain.soil import Soil
    from wheelbase.terrain.surfaces import SURFACES, Surface

    if isinstance(spec, str):
        return SURFACES[spec]
    try:
        soil = None
        if spec.soil is not None:
            s = spec.soil
            soil = Soil(s.n, s.k_c * 1e3, s.k_phi * 1e3, s.cohesion * 1e3,
                        math.radians(s.friction_angle_deg), s.shear_modulus, "given")  # fmt: skip
        if spec.like is not None and soil is None:
            values = {
                key: value
                for key, value in (
                    ("peak", spec.peak_friction),
                    ("sliding", spec.sliding_friction),
                    ("peak_slip", spec.peak_slip),
                    ("rolling_resistance", spec.rolling_resistance),
                )
                if value is not None
            }
            return SURFACES[spec.like].with_values(**values)
        if soil is not None:
            return Surface(f"{spec.like or 'soil'}*", soil=soil)
        from wheelbase.terrain.friction import FrictionCurve

        curve = FrictionCurve(spec.peak_friction, spec.sliding_friction, spec.peak_slip)
        return Surface("given", curve, spec.rolling_resistance or 0.0)
    except ConfigError as error:
        raise ScenarioError(f"{where}: {error}") from None


def build_terrain(scenario: Scenario, grid: Any) -> Any:
    """The scenario's :class:`~wheelbase.terrain.TerrainMap` over the map's rectangle.

    Parameters
    ----------
    scenario : Scenario
        The scenario.
    grid : OccupancyGrid or PolygonWorld
        The map (its rectangle and cell size).
    """
    from wheelbase.terrain.map import Region, TerrainMap
    from wheelbase.terrain.surfaces import SURFACES

    spec = scenario.terrain
    if spec is None:
        floor = SURFACES["dry_concrete"].with_values(rolling_resistance=0.0)
        return TerrainMap.uniform(dataclasses.replace(floor, name=_FLOOR))
    default = surface_of(spec.surface, "terrain.surface")
    regions = []
    for index, region in enumerate(spec.regions):
        surface = surface_of(region.surface, f"terrain.regions[{index}].surface")
        try:
            regions.append(Region(np.array(region.polygon), surface, region.grade_percent / 100,
                                  math.radians(region.uphill_deg)))  # fmt: skip
        except ConfigError as error:
            raise ScenarioError(f"terrain.regions[{index}]: {error}") from None
    from wheelbase.planning.world import PolygonWorld

    cells = grid.grid if isinstance(grid, PolygonWorld) else grid  # a world's raster
    x0, y0 = cells.origin
    rows, cols = cells.occupied.shape
    resolution = spec.resolution or cells.resolution
    bounds = (x0, y0, x0 + cols * cells.resolution, y0 + rows * cells.resolution)
    base = None
    if spec.raster is not None:
        base = _raster(spec.raster, cells, scenario.resources.max_map_cells)
    try:
        return TerrainMap.from_regions(
            default, regions, bounds=bounds, resolution=resolution,
            max_cells=scenario.resources.max_map_cells, base=base,
        )  # fmt: skip
    except ConfigError as error:
        raise ScenarioError(f"terrain: {error}") from None


def _raster(spec: Any, cells: Any, max_cells: int) -> Any:
    """The ``terrain.raster`` image as a :class:`~wheelbase.terrain.TerrainMap` (flat)."""
    from wheelbase.errors import DataError, MapError
    from wheelbase.planning.map_io import _read_gray
    from wheelbase.terrain.map import TerrainMap

    try:
        gray = _read_gray(spec.image, max_cells)
    except (DataError, MapError) as error:
        raise ScenarioError(f"terrain.raster.image: {error}") from None
    levels = np.unique(gray.astype(np.int64))
    missing = [int(level) for level in levels if int(level) not in spec.legend]
    if missing:
        raise ScenarioError(
            f"terrain.raster.legend: grey level {missing[0]} of the image has no surface "
            f"(levels in the image: {', '.join(map(str, levels[:12]))})"
        )
    keys = sorted(spec.legend)
    surfaces = [surface_of(spec.legend[k], f"terrain.raster.legend.{k}") for k in keys]
    lookup = np.zeros(256, np.int32)
    lookup[keys] = np.arange(len(keys))
    codes = lookup[np.flipud(gray).astype(np.int64)]  # image row 0 is the top
    origin = spec.origin if spec.origin is not None else cells.origin
    try:
        return TerrainMap(tuple(surfaces), codes, np.zeros((*codes.shape, 2)),
                          spec.resolution or cells.resolution, origin)  # fmt: skip
    except ConfigError as error:
        raise ScenarioError(f"terrain.raster: {error}") from None


def build_plant(
    scenario: Scenario,
    robot: Any,
    terrain: Any,
    axle: Any,
    timeline: list[tuple[float, Payload | None]],
) -> Any:
    """The true robot on its ground, as a :class:`~wheelbase.sim.TerrainPlant`.

    Parameters
    ----------
    scenario : Scenario
        The scenario.
    robot : Robot
        The resolved robot (``robot.dynamics`` without payload).
    terrain : TerrainMap
        The ground.
    axle : WheelAxle
        The encoder axle.
    timeline : list of (float, Payload or None)
        :func:`payload_timeline`.
    """
    from wheelbase.sim import TerrainPlant
    from wheelbase.terrain.dynamics import TerrainDynamics

    contacts = build_contacts(scenario)
    spec = scenario.terrain
    slip = spec.slip if spec is not None else False
    slip_speed = spec.slip_speed if spec is not None else 0.05

    def model(payload: Payload | None) -> Any:
        dynamics = _dynamics_with(robot, payload)
        local = contacts
        if payload is not None and payload.height is not None:
            m, mp = robot.dynamics.body.mass, payload.mass
            height = (m * contacts.cg_height + mp * payload.height) / (m + mp)
            local = dataclasses.replace(contacts, cg_height=height)
        try:
            return TerrainDynamics(dynamics, terrain, local, slip=slip, slip_speed=slip_speed)
        except ConfigError as error:
            raise ScenarioError(f"terrain: {error}") from None

    first, *later = timeline
    changes = tuple((time, model(payload)) for time, payload in later)
    return TerrainPlant(model(first[1]), axle, changes)


def wrap_controller(
    scenario: Scenario,
    controller: Any,
    robot: Any,
    timeline: list[tuple[float, Payload | None]],
    terrain: Any = None,
) -> Any:
    """The controller with the payload changes it knows of, the slope feed-forward and
    traction control.

    Parameters
    ----------
    scenario : Scenario
        The scenario.
    controller : object
        The torque controller.
    robot : Robot
        The resolved robot (``robot.dynamics`` without payload).
    timeline : list of (float, Payload or None)
        :func:`payload_timeline`.
    terrain : TerrainMap, optional
        The floor the robot knows (the slope feed-forward, traction control's
        ``friction: map``).
    """
    from wheelbase.control.schedule import ModelSchedule
    from wheelbase.control.traction import TractionControl

    if (
        scenario.controller.model_payload is True
        and len(timeline) > 1
        and hasattr(controller, "model")
    ):
        changes = [(time, _dynamics_with(robot, payload)) for time, payload in timeline[1:]]
        controller = ModelSchedule(controller, changes)
    feedforward = scenario.controller.slope_feedforward
    if feedforward is not False:
        from wheelbase.control.slope import SlopeFeedForward

        if terrain is None:
            raise ScenarioError("controller.slope_feedforward needs a terrain section")
        model = getattr(controller, "model", None) or controller_model(scenario, robot)
        rolling = feedforward is not True and feedforward.rolling_resistance
        controller = SlopeFeedForward(
            controller, model, terrain, rolling_resistance=rolling,
            contacts=build_contacts(scenario),
        )  # fmt: skip
    spec = scenario.controller.traction_control
    if spec is not None:
        contacts = build_contacts(scenario)
        model = getattr(controller, "model", None) or controller_model(scenario, robot)
        try:
            controller = TractionControl(
                controller, model, friction=spec.friction, margin=spec.margin,
                drive_load_share=contacts.drive_load_share,
                wheel_inertia=contacts.wheel_inertia,
                terrain=terrain if spec.friction == "map" else None,
                initial_friction=spec.initial_friction, slow_down=spec.slow_down,
                hold_integrators=spec.hold_integrators, reference_share=spec.reference_share,
                rolling_resistance=spec.rolling_resistance, casters=contacts.casters,
                imu=spec.friction == "estimate" and scenario.sensors.imu is not None,
            )  # fmt: skip
        except ConfigError as error:
            raise ScenarioError(f"controller.traction_control: {error}") from None
    return controller


def compensate_slip(scenario: Scenario, estimator: Any, robot: Any, terrain: Any) -> Any:
    """The estimator with ``odometry.slip_compensation`` applied (unchanged without it).

    Parameters
    ----------
    scenario : Scenario
        The scenario.
    estimator : object
        The estimator :func:`wheelbase.scenario_sensors.build_estimator` made.
    robot : Robot
        The resolved robot (``robot.dynamics`` without payload).
    terrain : TerrainMap
        The floor the robot knows.
    """
    if not scenario.odometry.slip_compensation:
        return estimator
    from wheelbase.sim.sensing import EncoderOdometry
    from wheelbase.sim.slip_odometry import SlipCompensatedOdometry

    if type(estimator) is not EncoderOdometry:
        raise ScenarioError(
            "odometry.slip_compensation needs odometry.mode: encoders and localization: odometry"
        )
    try:
        return SlipCompensatedOdometry(
            estimator.encoder, estimator.odometry, controller_model(scenario, robot),
            build_contacts(scenario), terrain,
        )  # fmt: skip
    except ConfigError as error:
        raise ScenarioError(f"odometry.slip_compensation: {error}") from None


def gyrodometry(scenario: Scenario, estimator: Any, imu: Any) -> Any:
    """The estimator with ``odometry.gyro`` applied (unchanged without it): its heading the
    IMU's gyro where the wheels slip (:class:`~wheelbase.sim.gyrodometry.Gyrodometry`).

    Parameters
    ----------
    scenario : Scenario
        The scenario.
    estimator : object
        The encoder odometry (after :func:`compensate_slip`).
    imu : Imu or None
        The robot's IMU (``sensors.imu``).
    """
    if not scenario.odometry.gyro:
        return estimator
    from wheelbase.sim.gyrodometry import Gyrodometry
    from wheelbase.sim.sensing import EncoderOdometry

    if imu is None:
        raise ScenarioError("odometry.gyro reads the IMU's gyro: give sensors.imu")
    if not isinstance(estimator, EncoderOdometry) or scenario.localization.method != "odometry":
        raise ScenarioError(
            "odometry.gyro needs odometry.mode: encoders and localization: odometry"
        )
    return Gyrodometry(estimator, imu)


def build_stuck(scenario: Scenario) -> Any:
    """The ``stuck`` rule of a scenario with terrain (None without).

    Parameters
    ----------
    scenario : Scenario
        The scenario.
    """
    if scenario.terrain is None:
        return None
    from wheelbase.sim.stuck import Stuck

    return Stuck(time=scenario.terrain.stuck_time, distance=max(0.1, scenario.goal_tolerance[0]))


def terrain_metrics(log: Any) -> dict[str, float]:
    """What the ground did to a robot's run (robot 0 of ``log``): largest slip ratio and
    sinkage, and the energy budget [J] — the work of the wheel torques, what slip, rolling
    resistance and soil dissipated, the work done against gravity. Empty for a run without a
    terrain plant.

    Parameters
    ----------
    log : Log
        One robot's record.
    """
    extras = log.extras
    if "slip_left" not in extras:
        return {}
    n = int(log.length[0])

    def spent(name: str) -> float:
        values = extras[name][0, :n]
        return float(values[-1] - values[0])

    slip = np.abs(np.concatenate([extras["slip_left"][0, :n], extras["slip_right"][0, :n]]))
    sink = np.concatenate([extras["sinkage_left"][0, :n], extras["sinkage_right"][0, :n]])
    return {
        "max_slip": float(slip.max()),
        "max_sinkage_m": float(sink.max()),
        "energy_wheels_j": spent("energy_work_wheels"),
        "energy_slip_j": spent("energy_dissipated_slip"),
        "energy_rolling_j": spent("energy_dissipated_rolling"),
        "energy_soil_j": spent("energy_dissipated_soil"),
        "energy_gravity_j": -spent("energy_work_gravity"),
    }
