"""Generate the bundled ``cluttered`` map (ROS ``map_server`` YAML + PNG) for the MPPI evaluation.

Run ``python src/wheelbase/data/maps/make_cluttered.py``; the output is deterministic.

The map is 12 × 8 m at 0.05 m/cell with a border wall. Its reference path is the straight line
y = 4 m from x = 1 m to x = 11 m. Three discs of radius 0.5 m sit alternately above and below
it with their edges 0.1 m from the line (centres (3.5, 4.6), (6, 3.4), (8.5, 4.6)), so a robot
of half-width 0.2 m that follows the line exactly collides, while there is room to weave
around them; boxes away from the line add clutter.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from wheelbase.planning import OccupancyGrid, write_ros_yaml

__all__: list[str] = []

HERE = Path(__file__).resolve().parent
RESOLUTION = 0.05
WIDTH, HEIGHT = 12.0, 8.0
DISCS = ((3.5, 4.6, 0.5), (6.0, 3.4, 0.5), (8.5, 4.6, 0.5))
BOXES = ((1.0, 6.5, 2.0, 7.2), (4.5, 0.8, 5.3, 1.8), (7.0, 6.2, 7.6, 7.4), (9.8, 1.0, 11.0, 1.6))


def cluttered() -> np.ndarray:
    """Occupancy array (rows = y, columns = x) of the cluttered map."""
    rows, cols = round(HEIGHT / RESOLUTION), round(WIDTH / RESOLUTION)
    occ = np.zeros((rows, cols), bool)
    occ[0, :] = occ[-1, :] = occ[:, 0] = occ[:, -1] = True
    y, x = (np.mgrid[0:rows, 0:cols] + 0.5) * RESOLUTION
    for cx, cy, radius in DISCS:
        occ |= np.hypot(x - cx, y - cy) <= radius
    for x0, y0, x1, y1 in BOXES:
        occ |= (x >= x0) & (x <= x1) & (y >= y0) & (y <= y1)
    return occ


def main() -> None:
    """Write ``cluttered.yaml`` and ``cluttered.png`` beside this script."""
    grid = OccupancyGrid.from_array(cluttered(), RESOLUTION)
    write_ros_yaml(grid, HERE / "cluttered.yaml", image="cluttered.png")


if __name__ == "__main__":
    main()
