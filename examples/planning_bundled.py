"""
Hybrid A* on every bundled map (document 002's smooth path planning)
=====================================================================

Usage::

    python examples/planning_bundled.py [OUT_DIR]      # default: examples/out/

For each bundled scenario (parking lot, narrow-corridor U-turn, maze with a turning-in-place
RM100-sized robot, warehouse) it plans with :class:`wheelbase.planning.HybridAStar`, prints
length, cusps, planning time and expanded nodes, and writes ``planning_<scenario>.png`` (map,
footprints along the path, forward/reverse colouring, cusps, start and goal arrows) and
``planning_<scenario>.csv``. Files of those names are replaced; nothing else is touched.
"""

from __future__ import annotations

import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt

from wheelbase.planning import Footprint, HybridAStar, bundled_scenarios, load_map
from wheelbase.planning.plot import plot_path


def main(out: Path) -> None:
    out.mkdir(parents=True, exist_ok=True)
    for sc in bundled_scenarios():
        grid = load_map(sc.map_name)
        footprint = Footprint.rectangle(*sc.footprint, sc.rear_axle_to_center)
        planner = HybridAStar(grid, footprint, sc.turning_radius)
        path = planner.plan(sc.start, sc.goal)
        print(
            f"{sc.map_name:15s} {sc.name:24s} success={path.success} length={path.length:6.2f} m "
            f"cusps={path.cusps} time={path.stats.planning_time_s * 1e3:6.1f} ms "
            f"expanded={path.stats.expanded_nodes}"
        )
        ax = plot_path(path, grid=grid, footprint=footprint, footprint_every=1.5)
        ax.set_title(f"{sc.map_name}: {sc.name} ({path.length:.1f} m, {path.cusps} cusps)")
        ax.figure.savefig(out / f"planning_{sc.name}.png", dpi=110, bbox_inches="tight")
        plt.close(ax.figure)
        path.to_csv(out / f"planning_{sc.name}.csv")


if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else Path(__file__).parent / "out")
