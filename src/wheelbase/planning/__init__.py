"""Planning in static environments: occupancy grids, grid search, curves and Hybrid A*.

Document 000 (path planning of a wheeled mobile robot in a static environment) and
document 002 (smooth path planning with Hybrid A*).
"""

from wheelbase.planning.astar import GridPath, astar, dijkstra
from wheelbase.planning.grid import (
    Footprint,
    MovingAIScenario,
    OccupancyGrid,
    read_movingai_scenarios,
)

__all__ = [
    "Footprint",
    "GridPath",
    "MovingAIScenario",
    "OccupancyGrid",
    "astar",
    "dijkstra",
    "read_movingai_scenarios",
]
