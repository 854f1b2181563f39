"""The one closed-loop engine: N robots in lockstep → one batched :class:`Log`.

- :mod:`wheelbase.sim.plants`: what moves (kinematic or dynamic), and its encoder axle;
- :mod:`wheelbase.sim.sensing`: encoders and the estimator the controller reads;
- :mod:`wheelbase.sim.engine`: the step (estimator → controller → limits → rules → plant →
  encoders) and the run;
- :mod:`wheelbase.sim.log`: the record, its statuses, metrics, CSV and plot.
"""

from wheelbase.sim.engine import Arrival, Engine, EngineState, closed_loop
from wheelbase.sim.log import STATUSES, Log, status_code
from wheelbase.sim.plants import DynamicPlant, KinematicPlant, WheelAxle
from wheelbase.sim.sensing import EncoderOdometry, PerfectState

__all__ = [
    "STATUSES",
    "Arrival",
    "DynamicPlant",
    "EncoderOdometry",
    "Engine",
    "EngineState",
    "KinematicPlant",
    "Log",
    "PerfectState",
    "WheelAxle",
    "closed_loop",
    "status_code",
]
