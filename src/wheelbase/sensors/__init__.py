"""Simulated sensors: a lidar on occupancy grids and a range–bearing landmark sensor.

:class:`Lidar` casts a fan of beams on an :class:`~wheelbase.planning.OccupancyGrid` for a batch
of poses (an exact grid traversal and a fast distance-field march that agree to rounding) and
adds the beam model of Thrun, Burgard and Fox (§6.3); :class:`LandmarkSensor` measures range and
bearing to identified landmarks with noise, missed detections and clutter.
"""

from wheelbase.sensors.beam_model import BeamModel
from wheelbase.sensors.landmarks import LandmarkObservations, LandmarkSensor, range_bearing
from wheelbase.sensors.lidar import Lidar
from wheelbase.sensors.raycast import RAY_METHODS, cast_rays, gap_field, scan_rays

__all__ = [
    "RAY_METHODS",
    "BeamModel",
    "LandmarkObservations",
    "LandmarkSensor",
    "Lidar",
    "cast_rays",
    "gap_field",
    "range_bearing",
    "scan_rays",
]
