"""Speed of wheelbase's kinematic integration (issue 2, "Speed"); prints one JSON object.

Measured in one run, on the same differential-drive robots (wheel radius 0.05 m, half track
0.2 m, constant random wheel speeds in ±10 rad/s, random headings, dt = 0.01 s):

- ``batch``: :func:`wheelbase.simulate` (backend ``numba``) on ``--robots`` robots for
  ``--steps`` steps, methods ``euler``, ``rk4`` and ``exact``, keeping only the first and last
  poses (``record_every=steps``);
- ``single``: the same for one robot over ``--single-steps`` steps;
- ``numpy_loop``: the baseline, a plain vectorised NumPy Euler loop over the same robots
  (per step: v and ω from the wheel speeds, x += v cos θ dt, y += v sin θ dt, θ += ω dt);
- ``peer``: roboticstoolbox-python's ``DiffSteer.step`` (Euler, one robot, one Python call per
  step), or ``null`` with ``peer_error`` saying why when it cannot be imported.

The first call of each method compiles (or loads the Numba cache): every timing is taken after
a warm-up call, as the best of ``--repeat`` runs (5 × that for one robot). Figures are
robot-steps per second; ratios are ours / baseline (targets: batch ≥ 2× the NumPy loop, per
robot-step ≥ 1,000× the peer).

Run ``python benchmarks/kinematics.py`` (about 40 s on 2 cores) or ``--quick`` (seconds).
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import sys
import time
from collections.abc import Callable
from typing import Any

import numba
import numpy as np

from wheelbase import DiffDrive, simulate

WHEEL_RADIUS_M = 0.05
HALF_TRACK_M = 0.2
DT_S = 0.01
WHEEL_SPEED_MAX_RAD_S = 10.0
METHODS_TIMED = ("euler", "rk4", "exact")
BATCH_TARGET = 2.0
PEER_TARGET = 1000.0


def make_robots(n_robots: int, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """Initial poses (N, 3) and constant wheel speeds (N, 2) = (left, right) [rad/s]."""
    rng = np.random.default_rng(seed)
    pose0 = np.zeros((n_robots, 3))
    pose0[:, :2] = rng.uniform(-5.0, 5.0, (n_robots, 2))
    pose0[:, 2] = rng.uniform(-np.pi, np.pi, n_robots)
    wheels = rng.uniform(-WHEEL_SPEED_MAX_RAD_S, WHEEL_SPEED_MAX_RAD_S, (n_robots, 2))
    return pose0, wheels


def best_time(function: Callable[[], Any], repeat: int) -> tuple[float, Any]:
    """Best wall time [s] of ``repeat`` calls, and the last result."""
    best, result = np.inf, None
    for _ in range(repeat):
        start = time.perf_counter()
        result = function()
        best = min(best, time.perf_counter() - start)
    return best, result


def figure(seconds: float, robot_steps: int) -> dict[str, float]:
    """A timing as a JSON record."""
    return {"seconds": seconds, "robot_steps_per_s": robot_steps / seconds}


def time_ours(pose0: np.ndarray, wheels: np.ndarray, steps: int, repeat: int) -> dict[str, Any]:
    """Time :func:`wheelbase.simulate` for each method in :data:`METHODS_TIMED`.

    The methods take turns (round robin) so that a slow spell of a shared machine does not fall
    on one method only; each keeps its best time.
    """
    robot = DiffDrive(wheel_radius=WHEEL_RADIUS_M, half_track=HALF_TRACK_M)
    n_robots = 1 if pose0.ndim == 1 else pose0.shape[0]

    def run(method: str) -> np.ndarray:
        result = simulate(
            robot,
            pose0,
            wheels,
            t_end=steps * DT_S,
            dt=DT_S,
            method=method,
            record_every=steps,
            backend="numba",
        )
        return result.poses[-1]

    best = dict.fromkeys(METHODS_TIMED, np.inf)
    finals = {method: run(method) for method in METHODS_TIMED}  # warm-up: compile, threads
    for _ in range(repeat):
        for method in METHODS_TIMED:
            seconds, finals[method] = best_time(lambda m=method: run(m), 1)
            best[method] = min(best[method], seconds)
    return {
        method: figure(best[method], n_robots * steps) | {"_final": finals[method]}
        for method in METHODS_TIMED
    }


def numpy_euler_loop(pose0: np.ndarray, wheels: np.ndarray, steps: int) -> np.ndarray:
    """The baseline: a plain vectorised NumPy Euler loop (document 002 eq. 6/7)."""
    a, d = WHEEL_RADIUS_M, HALF_TRACK_M
    x, y, theta = (pose0[:, i].copy() for i in range(3))
    left, right = wheels[:, 0], wheels[:, 1]
    for _ in range(steps):
        v = 0.5 * a * (left + right)
        omega = 0.5 * a * (right - left) / d
        x += v * np.cos(theta) * DT_S
        y += v * np.sin(theta) * DT_S
        theta += omega * DT_S
    return np.stack([x, y, theta], -1)


def time_peer(pose0: np.ndarray, wheels: np.ndarray, steps: int, repeat: int) -> dict[str, Any]:
    """Time roboticstoolbox-python's ``DiffSteer.step`` on one robot (raises if unavailable)."""
    import roboticstoolbox
    from roboticstoolbox.mobile import DiffSteer

    # DiffSteer's inputs are the wheel rim speeds (v_L, v_R) [m/s] and W is the track [m].
    rim_speeds = WHEEL_RADIUS_M * np.asarray(wheels, dtype=float)

    def run() -> np.ndarray:
        vehicle = DiffSteer(W=2.0 * HALF_TRACK_M, dt=DT_S, x0=np.array(pose0, dtype=float))
        for _ in range(steps):
            vehicle.step(rim_speeds, animate=False)
        return np.array(vehicle.x, dtype=float)

    run()
    seconds, final = best_time(run, repeat)
    return {
        "package": "roboticstoolbox-python",
        "version": roboticstoolbox.__version__,
        "api": "roboticstoolbox.mobile.DiffSteer(W, dt, x0).step((v_L, v_R), animate=False)",
        "steps": steps,
        **figure(seconds, steps),
        "_final": final,
    }


def main(argv: list[str] | None = None) -> dict[str, Any]:
    """Run the benchmark, print the JSON object and return it."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--robots", type=int, default=100_000, help="robots in the batch")
    parser.add_argument("--steps", type=int, default=1_000, help="steps of the batch")
    parser.add_argument("--single-steps", type=int, default=100_000, help="steps of one robot")
    parser.add_argument("--peer-steps", type=int, default=20_000, help="steps of the peer")
    parser.add_argument("--repeat", type=int, default=5, help="timings per figure (best kept)")
    parser.add_argument("--quick", action="store_true", help="small sizes for a smoke run")
    args = parser.parse_args(argv)
    if args.quick:
        args.robots, args.steps, args.single_steps, args.peer_steps = 1_000, 50, 2_000, 200
        args.repeat = 1
    for name in ("robots", "steps", "single_steps", "peer_steps", "repeat"):
        if getattr(args, name) < 1:
            parser.error(f"--{name.replace('_', '-')} must be >= 1")

    pose0, wheels = make_robots(args.robots)
    batch = time_ours(pose0, wheels, args.steps, args.repeat)
    # One robot is a ~1 ms call, easily delayed by a scheduler tick on a busy machine: the best
    # of more repeats.
    single = time_ours(pose0[0], wheels[0], args.single_steps, 5 * args.repeat)
    numpy_loop_result = numpy_euler_loop(pose0, wheels, 1)  # warm-up
    seconds, numpy_loop_result = best_time(
        lambda: numpy_euler_loop(pose0, wheels, args.steps), max(1, args.repeat // 2)
    )
    numpy_loop = figure(seconds, args.robots * args.steps)
    # The baseline integrates the same robots: its end poses equal our Euler's to rounding.
    ours_euler = batch["euler"]["_final"]
    numpy_loop["max_position_difference_to_ours_euler_m"] = float(
        np.max(np.abs(ours_euler[:, :2] - numpy_loop_result[:, :2]))
    )

    peer: dict[str, Any] | None
    peer_error = None
    try:
        peer = time_peer(pose0[0], wheels[0], args.peer_steps, args.repeat)
    except Exception as error:  # any import or API failure of the optional peer
        peer, peer_error = None, f"{type(error).__name__}: {error}"
    if peer is not None:
        check = time_ours(pose0[0], wheels[0], args.peer_steps, 1)["euler"]["_final"]
        peer["max_position_difference_to_ours_euler_m"] = float(
            np.max(np.abs(check[:2] - peer.pop("_final")[:2]))
        )

    ratios: dict[str, Any] = {
        "batch_vs_numpy_loop": {
            m: batch[m]["robot_steps_per_s"] / numpy_loop["robot_steps_per_s"]
            for m in METHODS_TIMED
        }
    }
    if peer is not None:
        rate = peer["robot_steps_per_s"]
        ratios["batch_vs_peer"] = {m: batch[m]["robot_steps_per_s"] / rate for m in METHODS_TIMED}
        ratios["single_vs_peer"] = {m: single[m]["robot_steps_per_s"] / rate for m in METHODS_TIMED}
    targets = {
        "batch_vs_numpy_loop": BATCH_TARGET,
        "per_robot_step_vs_peer": PEER_TARGET,
        "batch_met": all(r >= BATCH_TARGET for r in ratios["batch_vs_numpy_loop"].values()),
        "peer_met": None
        if peer is None
        else all(r >= PEER_TARGET for r in ratios["batch_vs_peer"].values()),
    }
    for records in (batch, single):
        for record in records.values():
            record.pop("_final")

    report = {
        "benchmark": "kinematics",
        "machine": {
            "python": platform.python_version(),
            "numpy": np.__version__,
            "numba": numba.__version__,
            "cpu_count": os.cpu_count(),
            "numba_threads": numba.get_num_threads(),
            "processor": platform.machine(),
        },
        "config": {
            "robots": args.robots,
            "steps": args.steps,
            "single_steps": args.single_steps,
            "peer_steps": args.peer_steps,
            "repeat": args.repeat,
            "dt_s": DT_S,
            "wheel_radius_m": WHEEL_RADIUS_M,
            "half_track_m": HALF_TRACK_M,
        },
        "batch": batch,
        "single": single,
        "numpy_loop": numpy_loop,
        "peer": peer,
        "peer_error": peer_error,
        "ratios": ratios,
        "targets": targets,
    }
    json.dump(report, sys.stdout, indent=2)
    sys.stdout.write("\n")
    return report


if __name__ == "__main__":
    main()
