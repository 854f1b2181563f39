"""
Fan figures of the pose laws 1–6 (issue 5): 128 starts on a 2 m circle, one figure
==================================================================================

Usage::

    python examples/control_fans.py [OUT_DIR]      # default: examples/out/

Writes ``control_fans.png`` — for each law the paths of a unicycle (abs(v) ≤ 0.5 m/s,
abs(ω) ≤ 1.5 rad/s) from 16 bearings × 8 headings to the goal at the origin facing +x (blue:
reached within 1 cm and 1°, red: not) — and prints the benchmark table as JSON.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from wheelbase.control import POSE_LAWS
from wheelbase.sim import Log, status_code

# sphinx-gallery runs the examples without __file__, from their own folder
HERE = Path(__file__).resolve().parent if "__file__" in globals() else Path.cwd()
sys.path.insert(0, str(HERE.parent / "benchmarks"))
from control_cases import pose_benchmark  # noqa: E402


def plot_fan(log: Log, title: str, ax) -> None:
    """Every robot's path on one plot: arrived in blue, the others in red."""
    ok = log.status == status_code("arrived")
    for i in range(log.n_robots):
        xy = log.true_pose[i, : log.length[i], :2]
        ax.plot(xy[:, 0], xy[:, 1], lw=0.7, color="tab:blue" if ok[i] else "tab:red", alpha=0.7)
    starts = log.true_pose[:, 0]
    ax.quiver(starts[:, 0], starts[:, 1], np.cos(starts[:, 2]), np.sin(starts[:, 2]),
              scale=25, width=0.003, color="0.3")  # fmt: skip
    ax.plot(0.0, 0.0, "k*", ms=12, zorder=5)
    ax.set_aspect("equal")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_title(f"{title} — {int(ok.sum())}/{ok.size} reached")
    ax.grid(True, alpha=0.3)


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
