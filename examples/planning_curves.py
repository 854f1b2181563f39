"""
Reeds–Shepp and Dubins shortest paths between the same poses, and A* on a Moving AI map
=======================================================================================

Usage::

    python examples/planning_curves.py [OUT_DIR]      # default: examples/out/

Writes ``planning_curves.png``: for four goal poses, the shortest Reeds–Shepp path (forward
blue, reverse red; its word in the legend) and the shortest Dubins path (grey) from the origin
for a 1 m turning radius — the Reeds–Shepp path is never longer. If the Moving AI arena map is
present in ``../shared/data/movingai/``, also ``planning_movingai.png``: the optimal 8-connected
A* path of the scenario with the longest optimal length (checked against the ``.scen`` file).
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

from wheelbase.planning import (
    astar,
    dubins_path,
    read_movingai_map,
    read_movingai_scenarios,
    reeds_shepp_path,
)
from wheelbase.planning.plot import plot_grid, plot_path

GOALS = [(-3.0, 1.0, 0.0), (0.5, 2.0, math.pi), (4.0, -2.0, math.pi / 2), (-1.0, -1.5, -2.5)]
# sphinx-gallery runs the examples without __file__, from their own folder
HERE = Path(__file__).resolve().parent if "__file__" in globals() else Path.cwd()
ARENA = HERE.parents[1] / "shared" / "data" / "movingai" / "arena.map"


def main(out: Path) -> None:
    out.mkdir(parents=True, exist_ok=True)
    fig, axes = plt.subplots(2, 2, figsize=(10, 9))
    for ax, goal in zip(axes.ravel(), GOALS, strict=True):
        rs = reeds_shepp_path((0, 0, 0), goal, 1.0)
        du = dubins_path((0, 0, 0), goal, 1.0)
        d = du.sample(0.02).poses
        ax.plot(
            d[:, 0],
            d[:, 1],
            color="0.6",
            linestyle="--",
            label=f"Dubins {du.word} {du.length:.2f} m",
        )
        plot_path(rs.sample(0.02), ax=ax)
        ax.set_title(f"RS {rs.word}: {rs.length:.2f} m ≤ Dubins {du.length:.2f} m")
        ax.set_aspect("equal")
        ax.legend(fontsize="small")
        print(
            f"goal {np.round(goal, 2)}: RS {rs.word} {rs.length:.3f} m, "
            f"Dubins {du.word} {du.length:.3f} m"
        )
    fig.tight_layout()
    fig.savefig(out / "planning_curves.png", dpi=110)
    plt.close(fig)

    if ARENA.exists():
        grid = read_movingai_map(ARENA)
        scenarios = read_movingai_scenarios(ARENA.with_name("arena.map.scen"))
        sc = max(scenarios, key=lambda s: s.optimal_length)
        start, goal = sc.grid_cells()
        result = astar(grid, start, goal)
        print(f"Moving AI arena: A* {result.length:.8f} vs optimal {sc.optimal_length:.8f}")
        ax = plot_grid(grid)
        ax.plot(result.points[:, 0], result.points[:, 1], color="tab:blue", linewidth=2)
        ax.set_title(f"A* on arena.map: {result.length:.4f} (optimal {sc.optimal_length:.4f})")
        ax.figure.savefig(out / "planning_movingai.png", dpi=110, bbox_inches="tight")
        plt.close(ax.figure)


if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else Path(__file__).parent / "out")
