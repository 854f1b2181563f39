"""Speed of the dynamics (issue 3): forward steps per second and the §5.3 closed loop.

Run ``python benchmarks/dynamics.py`` (prints JSON). Figures:

- ``single_rk4_steps_per_s``: one RM100, compiled RK4 (:func:`simulate_dynamics`, method rk4,
  every step recorded);
- ``single_rk45_steps_per_s``: one RM100, scipy ``solve_ivp`` RK45, output steps per second;
- ``batch_rk4_robot_steps_per_s``: 10,000 robots, compiled parallel RK4 kernel, final states
  only (robot·steps per second);
- ``closed_loop_s``: the whole §5.3 closed loop (feasible document-000 trajectory, 467.7 s at
  100 Hz, computed-torque PID with a 20 % model error), best of 5; the issue asks < 1 s.
"""

from __future__ import annotations

import json
import os
import platform
import time

import numpy as np

from wheelbase.control.torque import ComputedTorquePID
from wheelbase.dynamics import RM100, _roll_final, simulate_dynamics
from wheelbase.sim import track_trajectory
from wheelbase.trajectory import feasible_trajectory


def best_of(function, repeat: int = 5) -> float:
    function()  # compile / warm up
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        function()
        times.append(time.perf_counter() - start)
    return min(times)


def main() -> dict:
    steps = 100_000
    single = best_of(lambda: simulate_dynamics(RM100, (0.01, 0.012), steps * 0.01, 0.01,
                                               method="rk4"), 3)  # fmt: skip
    rk45_steps = 2_000
    rk45 = best_of(lambda: simulate_dynamics(RM100, (0.01, 0.012), rk45_steps * 0.1, 0.1), 3)
    n_robots, batch_steps = 10_000, 1_000
    rng = np.random.default_rng(0)
    tau = np.ascontiguousarray(rng.uniform(-0.02, 0.02, (n_robots, 2)))

    def batch() -> None:
        states = np.zeros((n_robots, 6))
        _roll_final(states, tau, 0.01, batch_steps, RM100.params, 1)

    batch_time = best_of(batch, 3)
    ref = feasible_trajectory([[0, 0], [10, 10], [20, 0], [30, 0]], (0.1, 0.1))
    model = RM100.with_body(RM100.body.scaled(1.2, 1.2))
    holder = {}

    def closed_loop() -> None:
        holder["run"] = track_trajectory(RM100, ref, ComputedTorquePID(model), dt=0.01)

    loop = best_of(closed_loop)
    return {
        "single_rk4_steps_per_s": steps / single,
        "single_rk45_steps_per_s": rk45_steps / rk45,
        "batch_robots": n_robots,
        "batch_rk4_robot_steps_per_s": n_robots * batch_steps / batch_time,
        "closed_loop_s": loop,
        "closed_loop_steps": int(holder["run"].t.size - 1),
        "closed_loop_metrics": holder["run"].metrics()[0],
        "cpu_count": os.cpu_count(),
        "machine": platform.machine(),
    }


if __name__ == "__main__":
    print(json.dumps(main(), indent=2))
