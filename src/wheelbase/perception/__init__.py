"""Perception: what a robot makes of its lidar, a layered costmap and tracks of moving obstacles.

:class:`LayeredCostmap` and :func:`update_costmap` keep Nav2-style costmaps (static layer from
the map, obstacle layer marked from lidar returns and cleared by exact ray tracing, inflation)
for N robots at once; :func:`update_tracker` clusters the returns the map does not explain and
tracks them with constant-velocity Kalman filters; :class:`LocalView` is what a local
controller receives of it. Nothing here reads the world's truth: only scans and the map.
"""

from typing import TYPE_CHECKING

from wheelbase._lazy import attach

if TYPE_CHECKING:  # the names, for type checkers and IDEs; imported on first use
    from wheelbase.perception.clusters import Detections, detect
    from wheelbase.perception.costmap import Costmap, CostmapState, LayeredCostmap, update_costmap
    from wheelbase.perception.costs import FREE, INSCRIBED, LETHAL, UNKNOWN, inflation_cost
    from wheelbase.perception.scoring import TrackErrors, track_errors
    from wheelbase.perception.specs import CostmapSpec, TrackerSpec
    from wheelbase.perception.tracking import TrackerState, Tracks, update_tracker
    from wheelbase.perception.view import LocalView

_EXPORTS = {
    "Costmap": "wheelbase.perception.costmap",
    "CostmapState": "wheelbase.perception.costmap",
    "LayeredCostmap": "wheelbase.perception.costmap",
    "update_costmap": "wheelbase.perception.costmap",
    "FREE": "wheelbase.perception.costs",
    "INSCRIBED": "wheelbase.perception.costs",
    "LETHAL": "wheelbase.perception.costs",
    "UNKNOWN": "wheelbase.perception.costs",
    "inflation_cost": "wheelbase.perception.costs",
    "CostmapSpec": "wheelbase.perception.specs",
    "TrackerSpec": "wheelbase.perception.specs",
    "Detections": "wheelbase.perception.clusters",
    "detect": "wheelbase.perception.clusters",
    "TrackErrors": "wheelbase.perception.scoring",
    "track_errors": "wheelbase.perception.scoring",
    "TrackerState": "wheelbase.perception.tracking",
    "Tracks": "wheelbase.perception.tracking",
    "update_tracker": "wheelbase.perception.tracking",
    "LocalView": "wheelbase.perception.view",
}
__getattr__, __dir__ = attach(__name__, _EXPORTS)

__all__ = [
    "FREE",
    "INSCRIBED",
    "LETHAL",
    "UNKNOWN",
    "Costmap",
    "CostmapSpec",
    "CostmapState",
    "Detections",
    "LayeredCostmap",
    "LocalView",
    "TrackErrors",
    "TrackerSpec",
    "TrackerState",
    "Tracks",
    "detect",
    "inflation_cost",
    "track_errors",
    "update_costmap",
    "update_tracker",
]
