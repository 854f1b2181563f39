"""Simulated sensors: a lidar on occupancy grids, a range–bearing landmark sensor and an IMU.

:class:`Lidar` casts a fan of beams on an :class:`~wheelbase.planning.OccupancyGrid` for a batch
of poses (an exact grid traversal and a fast distance-field march that agree to rounding) and
adds the beam model of Thrun, Burgard and Fox (§6.3); :class:`LandmarkSensor` measures range and
bearing to identified landmarks with noise, missed detections and clutter; :class:`Imu` reads
the yaw rate and the horizontal specific force of the body with a MEMS IMU's white noise and
bias.
"""

from typing import TYPE_CHECKING

from wheelbase._lazy import attach

if TYPE_CHECKING:  # the names, for type checkers and IDEs; imported on first use
    from wheelbase.sensors.beam_model import BeamModel
    from wheelbase.sensors.imu import Imu
    from wheelbase.sensors.landmarks import LandmarkObservations, LandmarkSensor, range_bearing
    from wheelbase.sensors.lidar import Lidar
    from wheelbase.sensors.raycast import RAY_METHODS, cast_rays, gap_field, scan_rays

_EXPORTS = {
    "BeamModel": "wheelbase.sensors.beam_model",
    "Imu": "wheelbase.sensors.imu",
    "LandmarkObservations": "wheelbase.sensors.landmarks",
    "LandmarkSensor": "wheelbase.sensors.landmarks",
    "range_bearing": "wheelbase.sensors.landmarks",
    "Lidar": "wheelbase.sensors.lidar",
    "RAY_METHODS": "wheelbase.sensors.raycast",
    "cast_rays": "wheelbase.sensors.raycast",
    "gap_field": "wheelbase.sensors.raycast",
    "scan_rays": "wheelbase.sensors.raycast",
}
__getattr__, __dir__ = attach(__name__, _EXPORTS)

__all__ = [
    "RAY_METHODS",
    "BeamModel",
    "Imu",
    "LandmarkObservations",
    "LandmarkSensor",
    "Lidar",
    "cast_rays",
    "gap_field",
    "range_bearing",
    "scan_rays",
]
