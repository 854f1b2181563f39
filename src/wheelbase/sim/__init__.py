"""The one closed-loop engine: N robots in lockstep → one batched :class:`Log`.

- :mod:`wheelbase.sim.plants`: what moves (kinematic, dynamic, or dynamic on terrain with
  slip and payloads), and its encoder axle;
- :mod:`wheelbase.sim.sensing`: encoders and the estimator the controller reads;
- :mod:`wheelbase.sim.slip_odometry`: encoder odometry that takes out the slip of its torques;
- :mod:`wheelbase.sim.gyrodometry`: encoder odometry whose heading follows the gyro where a
  wheel slips;
- :mod:`wheelbase.sim.sensors`: a lidar and a landmark sensor read at the true poses;
- :mod:`wheelbase.sim.localizers`: EKF, UKF and AMCL fusing the encoders with the sensors;
- :mod:`wheelbase.sim.streams`: counter-based random streams (a step is a function of its
  state);
- :mod:`wheelbase.sim.surroundings`: the world beyond the map (obstacles, agents, a fleet's
  other robots) that steps with the robots and that only the sensors see;
- :mod:`wheelbase.sim.perceiving`: each robot's costmap and tracks from its lidar;
- :mod:`wheelbase.sim.engine`: the step (estimator → controller → limits → rules → plant →
  encoders) and the run;
- :mod:`wheelbase.sim.stuck`: the ``stuck`` rule (commanded to move, not moving);
- :mod:`wheelbase.sim.log`: the record, its statuses, metrics, CSV and plot.
"""

from typing import TYPE_CHECKING

from wheelbase._lazy import attach

if TYPE_CHECKING:  # the names, for type checkers and IDEs; imported on first use
    from wheelbase.sim.drive_train import DriveTrainPlant, run_go_to_goal
    from wheelbase.sim.engine import Arrival, Engine, EngineState, closed_loop
    from wheelbase.sim.gyrodometry import Gyrodometry
    from wheelbase.sim.localizers import KalmanLocalizer, ParticleLocalizer
    from wheelbase.sim.log import STATUSES, Log, status_code
    from wheelbase.sim.perceiving import PerceptionState, PerceptionSuite
    from wheelbase.sim.plants import (
        DynamicPlant,
        KinematicPlant,
        TerrainPlant,
        TerrainState,
        WheelAxle,
    )
    from wheelbase.sim.sensing import EncoderOdometry, PerfectState
    from wheelbase.sim.sensors import Readings, SensorSuite
    from wheelbase.sim.slip_odometry import SlipCompensatedOdometry
    from wheelbase.sim.stuck import Stuck
    from wheelbase.sim.surroundings import Surroundings
    from wheelbase.sim.tracking import track_trajectory, tune_computed_torque

_EXPORTS = {
    "DriveTrainPlant": "wheelbase.sim.drive_train",
    "run_go_to_goal": "wheelbase.sim.drive_train",
    "Arrival": "wheelbase.sim.engine",
    "Engine": "wheelbase.sim.engine",
    "EngineState": "wheelbase.sim.engine",
    "closed_loop": "wheelbase.sim.engine",
    "Gyrodometry": "wheelbase.sim.gyrodometry",
    "KalmanLocalizer": "wheelbase.sim.localizers",
    "ParticleLocalizer": "wheelbase.sim.localizers",
    "STATUSES": "wheelbase.sim.log",
    "Log": "wheelbase.sim.log",
    "status_code": "wheelbase.sim.log",
    "PerceptionState": "wheelbase.sim.perceiving",
    "PerceptionSuite": "wheelbase.sim.perceiving",
    "DynamicPlant": "wheelbase.sim.plants",
    "KinematicPlant": "wheelbase.sim.plants",
    "TerrainPlant": "wheelbase.sim.plants",
    "TerrainState": "wheelbase.sim.plants",
    "WheelAxle": "wheelbase.sim.plants",
    "EncoderOdometry": "wheelbase.sim.sensing",
    "PerfectState": "wheelbase.sim.sensing",
    "Readings": "wheelbase.sim.sensors",
    "SensorSuite": "wheelbase.sim.sensors",
    "SlipCompensatedOdometry": "wheelbase.sim.slip_odometry",
    "Stuck": "wheelbase.sim.stuck",
    "Surroundings": "wheelbase.sim.surroundings",
    "track_trajectory": "wheelbase.sim.tracking",
    "tune_computed_torque": "wheelbase.sim.tracking",
}
__getattr__, __dir__ = attach(__name__, _EXPORTS)

__all__ = [
    "STATUSES",
    "Arrival",
    "DriveTrainPlant",
    "DynamicPlant",
    "EncoderOdometry",
    "Engine",
    "EngineState",
    "Gyrodometry",
    "KalmanLocalizer",
    "KinematicPlant",
    "Log",
    "ParticleLocalizer",
    "PerceptionState",
    "PerceptionSuite",
    "PerfectState",
    "Readings",
    "SensorSuite",
    "SlipCompensatedOdometry",
    "Stuck",
    "Surroundings",
    "TerrainPlant",
    "TerrainState",
    "WheelAxle",
    "closed_loop",
    "run_go_to_goal",
    "status_code",
    "track_trajectory",
    "tune_computed_torque",
]
