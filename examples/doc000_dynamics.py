"""
Document 000 chapter 5 with the RM100: forward, inverse, open loop vs computed-torque PID
=========================================================================================

Usage::

    python examples/doc000_dynamics.py [OUT_DIR]      # default: examples/out/

Writes

- ``doc000_forward_cases.png`` — figures 5.2–5.5: the four torque cases, 60 s, with the
  no-slip constraint (top) and document 000's unconstrained 3-DOF model (bottom);
- ``doc000_inverse_document.png`` / ``doc000_inverse_feasible.png`` — figures 5.8–5.11 for the
  §5.2 waypoints with the heading of the velocity (jumps at the waypoints) and for the feasible
  variant with turns in place;
- ``doc000_open_loop.png`` — figure 5.13: the inverse-dynamics torques fed open loop;
- ``doc000_pid.png`` — figure 5.16: the computed-torque PID, exact model and 20 % model error;

and prints the error table (max/RMS position error, RMS heading error) as JSON.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

from matplotlib.figure import Figure

from wheelbase.control.torque import ComputedTorquePID
from wheelbase.dynamics import RM100, inverse_dynamics, simulate_dynamics
from wheelbase.dynamics_plot import plot_inverse_dynamics, plot_tracking
from wheelbase.sim import track_trajectory
from wheelbase.trajectory import feasible_trajectory, heading_from_velocity, trapezoidal

CASES = [(0.01, 0.01), (0.01, 0.012), (0.01, 0.0), (0.01, -0.01)]
WAYPOINTS = [[0, 0], [10, 10], [20, 0], [30, 0]]


def forward_cases(out: Path) -> None:
    free = type(RM100)(RM100.body, RM100.wheel_radius, RM100.half_track, constrained=False)
    fig = Figure(figsize=(16, 8), layout="constrained")
    for row, (robot, name) in enumerate(((RM100, "no slip"), (free, "unconstrained"))):
        for col, tau in enumerate(CASES):
            result = simulate_dynamics(robot, tau, t_end=60.0, dt=0.1)
            ax = fig.add_subplot(2, 4, 4 * row + col + 1)
            ax.plot(result.poses[:, 0], result.poses[:, 1], "b-")
            ax.plot(0, 0, "go")
            ax.set_title(f"case {col + 1}: τ = {tau} N·m, {name}", fontsize=9)
            ax.set_xlabel("x [m]")
            ax.set_ylabel("y [m]")
            ax.set_aspect("equal", adjustable="datalim")
            ax.grid(True, alpha=0.3)
    fig.savefig(out / "doc000_forward_cases.png", dpi=100)


def main(out: Path) -> None:
    out.mkdir(parents=True, exist_ok=True)
    forward_cases(out)
    document = heading_from_velocity(trapezoidal(WAYPOINTS, (0.1, 0.1), dt=0.01))
    feasible = feasible_trajectory(WAYPOINTS, (0.1, 0.1), dt=0.01)
    for name, ref in (("document", document), ("feasible", feasible)):
        fig = plot_inverse_dynamics(ref, inverse_dynamics(RM100, ref))
        fig.savefig(out / f"doc000_inverse_{name}.png", dpi=100)
    wrong = RM100.with_body(RM100.body.scaled(1.2, 1.2))
    runs = {
        "open loop, document heading": track_trajectory(RM100, document),
        "open loop, feasible": track_trajectory(RM100, feasible),
        "open loop, feasible, 20 % model error": track_trajectory(RM100, feasible, model=wrong),
        "PID, feasible": track_trajectory(RM100, feasible, ComputedTorquePID(RM100)),
        "PID, feasible, 20 % model error": track_trajectory(
            RM100, feasible, ComputedTorquePID(wrong)
        ),
    }
    names = list(runs)
    plot_tracking([runs[n] for n in names[:3]], names[:3]).savefig(
        out / "doc000_open_loop.png", dpi=100
    )
    plot_tracking([runs[n] for n in names[3:]], names[3:]).savefig(out / "doc000_pid.png", dpi=100)
    print(json.dumps({name: run.metrics()[0] for name, run in runs.items()}, indent=2))


if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else Path(__file__).parent / "out")
