"""Planning in static environments: occupancy grids, grid search, curves and Hybrid A*.

Document 000 (path planning of a wheeled mobile robot in a static environment) and
document 002 (smooth path planning with Hybrid A*).
"""

from wheelbase.planning.astar import GridPath, astar, dijkstra
from wheelbase.planning.dubins import dubins_candidates, dubins_length, dubins_path
from wheelbase.planning.footprint import Footprint
from wheelbase.planning.hybrid_astar import HybridAStar
from wheelbase.planning.maps import BUNDLED_MAPS, PlanningScenario, bundled_scenarios, load_map
from wheelbase.planning.movingai import MovingAIScenario, read_movingai_scenarios
from wheelbase.planning.occupancy import OccupancyGrid
from wheelbase.planning.path import CurvePath, Path, PlanningStats
from wheelbase.planning.reeds_shepp import (
    reeds_shepp_candidates,
    reeds_shepp_length,
    reeds_shepp_path,
)
from wheelbase.planning.smoothing import smooth_path
from wheelbase.planning.world import PolygonWorld

__all__ = [
    "BUNDLED_MAPS",
    "CurvePath",
    "Footprint",
    "GridPath",
    "HybridAStar",
    "MovingAIScenario",
    "OccupancyGrid",
    "Path",
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
    "read_movingai_scenarios",
    "reeds_shepp_candidates",
    "reeds_shepp_length",
    "reeds_shepp_path",
    "smooth_path",
]
