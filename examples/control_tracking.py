"""
Path following and trajectory tracking (issue 5, laws 7–8): error against time and paths
========================================================================================

Usage::

    python examples/control_tracking.py [OUT_DIR]      # default: examples/out/

Writes ``control_tracking_errors.png`` (lateral error against time for every law, plant and
reference of the tracking benchmark) and ``control_cusp_paths.png`` (the three-point-turn path
with reverse section, and the paths the four followers drive on the rear-wheel bicycle, L = 0.5 m,
abs(δ) ≤ 35°), and prints the tracking table as JSON.
"""

from __future__ import annotations

import json
import math
import sys
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from wheelbase.control import SteeringLimits
from wheelbase.control.path import PurePursuit, RearWheelFeedback, SegmentFollower, Stanley
from wheelbase.models import RearWheelBicycle
from wheelbase.sim import closed_loop

# sphinx-gallery runs the examples without __file__, from their own folder
HERE = Path(__file__).resolve().parent if "__file__" in globals() else Path.cwd()
sys.path.insert(0, str(HERE.parent / "benchmarks"))
from control_cases import three_point_turn_path, tracking_benchmark  # noqa: E402


def plot_tracking_errors(traces: dict) -> Figure:
    """Lateral error against time [cm] for every (reference, law, plant) of the tracking run."""
    references = sorted({key[0] for key in traces})
    fig = Figure(figsize=(10.0, 4.0 * len(references)), layout="constrained")
    for row, reference in enumerate(references, start=1):
        ax = fig.add_subplot(len(references), 1, row)
        for (ref, law, plant), (t, lateral) in traces.items():
            if ref == reference:
                ax.plot(t, 100.0 * np.abs(lateral), lw=1, label=f"{law} ({plant})",
                        ls="-" if plant == "unicycle" else "--")  # fmt: skip
        ax.set_yscale("log")
        ax.set_ylim(1e-3, 100)
        ax.axvline(5.0, color="0.5", lw=0.8)
        ax.set_title(reference.replace("_", " "))
        ax.set_ylabel("|lateral error| [cm]")
        ax.set_xlabel("t [s]")
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=7, ncol=2)
    return fig


def main(out: Path) -> None:
    out.mkdir(parents=True, exist_ok=True)
    rows, traces = tracking_benchmark()
    plot_tracking_errors(traces).savefig(out / "control_tracking_errors.png", dpi=100)

    path = three_point_turn_path()
    car = RearWheelBicycle(wheel_base=0.5, max_steering=math.radians(35.0))
    limits = SteeringLimits(math.radians(35.0), max_steering_rate=3.0)
    fig = Figure(figsize=(8, 5), layout="constrained")
    ax = fig.add_subplot()
    points, forward = path.points, path.directions[1:] > 0  # the segment reaching each sample
    for index in range(len(path) - 1):
        ax.plot(points[index : index + 2, 0], points[index : index + 2, 1],
                color="0.7" if forward[index] else "salmon", lw=6)  # fmt: skip
    for cls in (SegmentFollower, PurePursuit, Stanley, RearWheelFeedback):
        law = cls(speed=0.3, output="steering", wheel_base=0.5, limits=limits)
        result = closed_loop(law, car, np.array([0.0, 0.05, 0.0]), path, 40.0, 0.01)
        ax.plot(result.true_pose[0, :, 0], result.true_pose[0, :, 1], lw=1.2, label=cls.__name__)
    ax.set_aspect("equal")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_title("three-point turn (grey forward, red reverse), rear axle of the bicycle")
    ax.legend(fontsize=8)
    ax.grid(True, alpha=0.3)
    fig.savefig(out / "control_cusp_paths.png", dpi=100)
    print(json.dumps(rows, indent=2))


if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else Path(__file__).parent / "out")
