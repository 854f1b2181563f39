"""
Document 003 Fig. 8: go-to-goal to the four quadrants through the whole loop
============================================================================

Run ``python examples/odometry_figure8.py [OUT_DIR]`` (default ``examples/out/``).

The robot starts at the origin facing +x and drives to (100, 100), (−100, 100), (−100, −100)
and (100, −100), read as centimetres (the document gives no unit; its prototype is a table-top
robot). Assumed robot (:class:`~wheelbase.control.goal.DriveTrain`): 35 mm wheel radius,
150 mm track, 12 V gear-motors (``gearmotor_12v`` preset), 1440-tick encoders on 16-bit
counters, a 100 Hz PI speed loop (the microcontroller) and the law at 20 Hz (the
microprocessor), K_p = 2 1/s, cruise 0.2 m/s slowing within 0.3 m, stop within 1 cm.

Two robots: one exactly as modelled, one whose wheels differ by 1 % (E_d = 1.01) and whose
track is 3 % wider than the odometry thinks (E_b = 1.03). For each goal the true final error
(real pose vs goal) and the odometry final error (estimate vs goal) are printed; the routes
go to ``odometry_figure8.png`` (solid: true path, dashed: odometry estimate).
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt

from wheelbase.control.goal import FIGURE8_GOALS, DriveTrain
from wheelbase.odometry import OdometryErrors
from wheelbase.sim import run_go_to_goal


def main(out_dir: Path) -> None:
    robots = {
        "as modelled": DriveTrain(),
        "E_d = 1.01, E_b = 1.03": DriveTrain(errors=OdometryErrors(1.01, 1.03)),
    }
    fig, axes = plt.subplots(1, 2, figsize=(12, 6))
    for ax, (name, drive) in zip(axes, robots.items(), strict=True):
        start = time.perf_counter()
        log = run_go_to_goal(FIGURE8_GOALS, drive=drive)  # the four goals as one batch
        elapsed = time.perf_counter() - start
        print(f"robot {name} ({elapsed:.2f} s for the four runs)")
        for index, m in enumerate(log.metrics()):
            colour = f"C{index}"
            n, goal = int(log.length[index]), log.goal[index, :2]
            print(
                f"  goal ({goal[0]:+.0f}, {goal[1]:+.0f}) m: {m['status']}, true final error "
                f"{m['final_position_error_true_m'] * 100:.2f} cm, odometry final error "
                f"{m['final_position_error_estimated_m'] * 100:.2f} cm, {m['duration_s']:.1f} s"
            )
            ax.plot(*log.true_pose[index, :n, :2].T, color=colour, lw=2)
            ax.plot(*log.estimated_pose[index, :n, :2].T, "--", color=colour, lw=1)
            ax.plot(*goal, "*", ms=12, color=colour)
        ax.plot(0, 0, "ko")
        ax.set_aspect("equal")
        ax.grid(True, alpha=0.3)
        ax.set_xlabel("x [m]")
        ax.set_ylabel("y [m]")
        ax.set_title(f"Go-to-goal, robot {name}\n(solid: true, dashed: odometry)")
    fig.tight_layout()
    out_dir.mkdir(parents=True, exist_ok=True)
    path = out_dir / "odometry_figure8.png"
    fig.savefig(path, dpi=100)
    print(f"wrote {path}")


if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else Path(__file__).parent / "out")
