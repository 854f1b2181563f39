"""
MPPI on the bundled cluttered map (issue 9): clearance where pure pursuit collides
==================================================================================

Usage::

    python examples/mppi_cluttered.py [OUT_DIR]      # default: examples/out/

Writes ``mppi_cluttered.png``: the map, the straight reference path whose neighbouring discs
come within 0.1 m of it, the path pure pursuit drives (footprints where it collides in red), the
paths MPPI drives for five noise seeds, and a thin fan of sampled rollouts at a few instants of
the first run. Prints the minimum footprint clearance of each run as JSON.
"""

from __future__ import annotations

import json
import sys
from importlib import resources
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from wheelbase.control import MPPI, PurePursuit, VelocityLimits
from wheelbase.models import Unicycle
from wheelbase.planning import Footprint, PlannedPath, load_map
from wheelbase.sim import closed_loop


def main(out: Path) -> None:
    out.mkdir(parents=True, exist_ok=True)
    grid = load_map(Path(str(resources.files("wheelbase") / "data" / "maps" / "cluttered.yaml")))
    robot = Footprint.rectangle(0.4, 0.4)
    limits = VelocityLimits(max_speed=0.5, max_yaw_rate=1.5)
    path = PlannedPath.from_points([[1.0, 4.0], [11.0, 4.0]])
    start = np.array([1.0, 4.0, 0.0])

    fig = Figure(figsize=(10, 7), layout="constrained")
    ax = fig.add_subplot()
    ax.imshow(grid.occupied, origin="lower", extent=grid.extent, cmap="Greys", alpha=0.8)
    ax.plot(*path.points.T, "k--", lw=1, label="reference path")

    pursuit = closed_loop(PurePursuit(speed=0.4, limits=limits), Unicycle(), start, path,
                              26.0, 0.1)  # fmt: skip
    poses = pursuit.true_pose[0]
    hits = grid.in_collision(robot, poses)
    ax.plot(poses[:, 0], poses[:, 1], color="tab:red", lw=1.5, label="pure pursuit")
    for pose in poses[hits][::8]:
        c, s = np.cos(pose[2]), np.sin(pose[2])
        corners = robot.polygon @ np.array([[c, s], [-s, c]]) + pose[:2]
        ax.fill(*corners.T, color="tab:red", alpha=0.25, lw=0)
    clearances = {"pure_pursuit": float(grid.footprint_clearance(robot, poses).min())}

    for seed in range(5):
        mppi = MPPI(Unicycle(), 30, 0.1, 400, (0.2, 0.5), 0.03, None, limits, seed=seed,
                    backend="numba", grid=grid, footprint=robot)  # fmt: skip
        if seed == 0:  # record a fan of sampled rollouts at a few instants
            fans = []
            plant = Unicycle()
            pose = start.copy()
            for k in range(300):
                command = mppi(0.1 * k, pose, path)
                if k % 50 == 25:
                    plan = mppi.last_plan
                    fans.append(mppi.predict(plan, plan.samples[::20]))
                twist = plant.twist(command)
                pose = pose + 0.1 * np.array(
                    [twist[0] * np.cos(pose[2]), twist[0] * np.sin(pose[2]), twist[2]]
                )
            for fan in fans:
                for rollout in fan:
                    ax.plot(rollout[:, 0], rollout[:, 1], color="tab:blue", lw=0.3, alpha=0.5)
            mppi.reset()
        result = closed_loop(mppi, Unicycle(), start, path, 30.0, 0.1)
        poses = result.true_pose[0]
        label = "MPPI (5 seeds)" if seed == 0 else None
        ax.plot(poses[:, 0], poses[:, 1], color="tab:green", lw=1.2, label=label)
        clearances[f"mppi_seed_{seed}"] = float(grid.footprint_clearance(robot, poses).min())

    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_aspect("equal")
    ax.legend(loc="upper right")
    ax.set_title("MPPI keeps clearance where pure pursuit collides (0.4 × 0.4 m robot)")
    fig.savefig(out / "mppi_cluttered.png", dpi=100)
    print(json.dumps({"min_footprint_clearance_m": clearances}, indent=2))


if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else Path(__file__).parent / "out")
