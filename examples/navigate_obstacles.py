"""
Obstacles the map does not show (issue 22): the four bundled scenarios, animated
================================================================================

Usage::

    python examples/navigate_obstacles.py [OUT_DIR]      # default: examples/out/

Runs the bundled scenarios ``unexpected_boxes`` (boxes dropped on the planned route),
``crowd_crossing`` (20 walkers that do not avoid the robot), ``doorway_blocked`` (a box closes
the only door: the run ends ``blocked`` after Nav2's recoveries) and ``corridor_swap`` (two
robots swap the ends of a 1.2 m corridor with one passing bay) exactly as
``wheelbase run NAME`` does, and writes for each ``NAME.png`` (the map, what was not on it, the
replanned paths and the path driven) and ``NAME.gif`` (the run: walkers, boxes, lidar beams,
tracks and plans). Prints each run's status and contact figures as JSON.
"""

from __future__ import annotations

import json
import shutil
import sys
import tempfile
from pathlib import Path

import wheelbase
from wheelbase.report import write_report

SCENARIOS = ("unexpected_boxes", "crowd_crossing", "doorway_blocked", "corridor_swap")
"""The bundled scenarios of the obstacles issue."""

SHOWN = ("status", "duration_s", "collision", "collision_at_fault", "min_obstacle_distance_m",
         "replans", "recoveries")  # fmt: skip
"""The metrics printed for each run."""


def main(out: Path) -> dict:
    out.mkdir(parents=True, exist_ok=True)
    figures = {}
    for name in SCENARIOS:
        result = wheelbase.run(name)
        with tempfile.TemporaryDirectory() as folder:
            write_report(result, Path(folder) / name)
            shutil.copyfile(Path(folder) / name / "map.png", out / f"{name}.png")
            shutil.copyfile(Path(folder) / name / "animation.gif", out / f"{name}.gif")
        figures[name] = {key: result.metrics.get(key) for key in SHOWN}
    print(json.dumps(figures, indent=2, default=str))
    return figures


if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else Path(__file__).parent / "out")
