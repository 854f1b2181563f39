"""Planning in static environments: occupancy grids, grid search, curves and Hybrid A*.

Document 000 (path planning of a wheeled mobile robot in a static environment) and
document 002 (smooth path planning with Hybrid A*).
"""

from typing import TYPE_CHECKING

from wheelbase._lazy import attach

# ``astar`` is both a submodule and a function: importing the submodule (as any user of it
# does) would bind the package attribute to the module, so the function is bound here, eagerly.
from wheelbase.planning.astar import GridPath, astar, dijkstra

if TYPE_CHECKING:  # the names, for type checkers and IDEs; imported on first use
    from wheelbase.planning.dubins import dubins_candidates, dubins_length, dubins_path
    from wheelbase.planning.footprint import Footprint
    from wheelbase.planning.hybrid_astar import HybridAStar
    from wheelbase.planning.map_io import read_image, read_ros_yaml, write_ros_yaml
    from wheelbase.planning.maps import (
        BUNDLED_MAPS,
        PlanningScenario,
        bundled_scenarios,
        load_map,
        load_world,
    )
    from wheelbase.planning.movingai import (
        MovingAIScenario,
        read_movingai_map,
        read_movingai_scenarios,
    )
    from wheelbase.planning.occupancy import OccupancyGrid
    from wheelbase.planning.path import CurvePath, PlannedPath, PlanningStats
    from wheelbase.planning.reeds_shepp import (
        reeds_shepp_candidates,
        reeds_shepp_length,
        reeds_shepp_path,
    )
    from wheelbase.planning.smoothing import smooth_path
    from wheelbase.planning.world import PolygonWorld

_EXPORTS = {
    "dubins_candidates": "wheelbase.planning.dubins",
    "dubins_length": "wheelbase.planning.dubins",
    "dubins_path": "wheelbase.planning.dubins",
    "Footprint": "wheelbase.planning.footprint",
    "HybridAStar": "wheelbase.planning.hybrid_astar",
    "BUNDLED_MAPS": "wheelbase.planning.maps",
    "PlanningScenario": "wheelbase.planning.maps",
    "bundled_scenarios": "wheelbase.planning.maps",
    "load_map": "wheelbase.planning.maps",
    "load_world": "wheelbase.planning.maps",
    "read_image": "wheelbase.planning.map_io",
    "read_ros_yaml": "wheelbase.planning.map_io",
    "write_ros_yaml": "wheelbase.planning.map_io",
    "MovingAIScenario": "wheelbase.planning.movingai",
    "read_movingai_map": "wheelbase.planning.movingai",
    "read_movingai_scenarios": "wheelbase.planning.movingai",
    "OccupancyGrid": "wheelbase.planning.occupancy",
    "CurvePath": "wheelbase.planning.path",
    "PlannedPath": "wheelbase.planning.path",
    "PlanningStats": "wheelbase.planning.path",
    "reeds_shepp_candidates": "wheelbase.planning.reeds_shepp",
    "reeds_shepp_length": "wheelbase.planning.reeds_shepp",
    "reeds_shepp_path": "wheelbase.planning.reeds_shepp",
    "smooth_path": "wheelbase.planning.smoothing",
    "PolygonWorld": "wheelbase.planning.world",
}
__getattr__, __dir__ = attach(__name__, _EXPORTS)

__all__ = [
    "BUNDLED_MAPS",
    "CurvePath",
    "Footprint",
    "GridPath",
    "HybridAStar",
    "MovingAIScenario",
    "OccupancyGrid",
    "PlannedPath",
    "PlanningScenario",
    "PlanningStats",
    "PolygonWorld",
    "astar",
    "bundled_scenarios",
    "dijkstra",
    "dubins_candidates",
    "dubins_length",
    "dubins_path",
    "load_map",
    "load_world",
    "read_image",
    "read_movingai_map",
    "read_movingai_scenarios",
    "read_ros_yaml",
    "reeds_shepp_candidates",
    "reeds_shepp_length",
    "reeds_shepp_path",
    "smooth_path",
    "write_ros_yaml",
]
