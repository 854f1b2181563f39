"""Fan figures of the pose laws 1–6 (issue 5): 128 starts on a 2 m circle, one figure.

Usage::

    python examples/control_fans.py [OUT_DIR]      # default: examples/out/

Writes ``control_fans.png`` — for each law the paths of a unicycle (|v| ≤ 0.5 m/s,
|ω| ≤ 1.5 rad/s) from 16 bearings × 8 headings to the goal at the origin facing +x (blue:
reached within 1 cm and 1°, red: not) — and prints the benchmark table as JSON.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

from matplotlib.figure import Figure

from wheelbase.commands.control import plot_fan
from wheelbase.control.loop import POSE_LAWS, pose_benchmark


def main(out: Path) -> None:
    out.mkdir(parents=True, exist_ok=True)
    table, results = pose_benchmark()
    fig = Figure(figsize=(15, 10), layout="constrained")
    for index, law in enumerate(POSE_LAWS, start=1):
        plot_fan(results[law], title=law.replace("_", " "), ax=fig.add_subplot(2, 3, index))
    fig.savefig(out / "control_fans.png", dpi=100)
    print(json.dumps(table, indent=2))


if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else Path(__file__).parent / "out")
