"""MPPI figures of issue 9: controller rate per backend, tracking beside the path followers,
clearance on the bundled cluttered map.

Prints one JSON object:

- ``cpu_hz_2000x56``: controller calls per second (one MPPI iteration, 2,000 samples × 56
  steps, dt 0.05 s) per backend — ``numpy``, ``numba`` (all Numba threads), ``numba_1_thread``,
  ``jax`` (CPU, float32) and ``jax_float64`` where JAX is installed — with the default critics
  (path, path alignment, follow, goal, obstacles through the distance field with a 0.4 × 0.4 m
  footprint, prefer-forward, effort, rate) on the cluttered map; ``pytorch_mppi`` (goal and
  distance-field obstacle costs only) where PyTorch and pytorch_mppi are installed, else null;
- ``tracking``: the figure-eight of issue 5 (x = 1.1 + 0.7 sin(2πt/30), y = 0.9 + 0.7 sin(4πt/30),
  as a path) and the three-point-turn path with two cusps, on the unicycle and the rear-wheel
  bicycle (L = 0.05 m on the figure-eight, 0.5 m on the cusp path, |δ| <= 35°): RMS and max
  distance to the path after 5 s, final distance to its end and reversals, for MPPI (numba,
  500 × 30, dt 0.05 s, σ = (0.15 m/s, 0.4 rad/s or rad), |v| <= 0.35 / 0.3 m/s, stopping within
  1 cm and 0.1 rad of the end), pure pursuit and rear-wheel feedback at the mean
  reference speed (0.22 / 0.3 m/s), all in this run (the figure-eight is closed: its end is its
  start, so also see ``path_length_driven_m``);
- ``clearance``: the cluttered map's straight reference through three discs whose edges are
  0.1 m from it: pure pursuit (0.4 m/s) collides; MPPI (numba, 400 × 30, dt 0.1 s) over
  ``--seeds`` noise seeds: success = no collision, footprint clearance >= 0.1 m all along and
  the end of the path reached within 0.2 m.

- ``gpu_hz_2000x56``, ``gpu_hz_100000x56``, ``gpu_hz_1000000x56``: the jax backend (float32)
  where JAX sees a GPU (install ``jax[cuda12]``), else ``null`` with the reason in ``gpu``.

- ``parking``: the bundled parking scenario (4.5 m car) driven by MPPI over
  ``--parking-seeds`` seeds (none with ``--quick``): statuses, final errors, path deviation.

- ``default_backend``: what ``MPPI(...)`` picks without ``backend=`` (the fast one, as
  ``MPPI.from_gains``); ``cpu_hz_2000x56`` also holds ``numba_with_view`` and
  ``numpy_with_view``: the same call with a perception view (a 3 × 3 m costmap of 0.05 m cells
  with a box, 20 tracks within 3 m);
- ``crowd``: MPPI (numba, 1,000 × 56) on the encounters of ``benchmarks/crowd_cases.py``
  (a disc head-on, one crossing, one to overtake, a group of three, a box in the costmap) over
  ``--crowd-seeds`` seeds (``--quick``: the head-on disc, one seed), seeing perfect tracks:
  success rate (no contact and the path's end reached), collisions, least and median gap,
  stops.

Usage: ``python benchmarks/mppi.py [--quick] [--seeds N] [--parking-seeds N] [--crowd-seeds N]``
(``--quick``: 5 seeds, 5 timed calls).
"""

from __future__ import annotations

import argparse
import json
import math
import os
import platform
import time
from importlib import resources
from pathlib import Path

import numba
import numpy as np

from control_cases import figure_eight_reference, three_point_turn_path
from crowd_cases import busy_view, crowd_suite
from wheelbase.control import (
    MPPI,
    PurePursuit,
    RearWheelFeedback,
    SteeringLimits,
    VelocityLimits,
)
from wheelbase.models import RearWheelBicycle, Unicycle
from wheelbase.planning import Footprint, PlannedPath, load_map
from wheelbase.sim import closed_loop

LIMITS = VelocityLimits(max_speed=0.5, max_yaw_rate=1.5)
ROBOT = Footprint.rectangle(0.4, 0.4)
STRAIGHT = PlannedPath.from_points([[1.0, 4.0], [11.0, 4.0]])


def cluttered():
    return load_map(Path(str(resources.files("wheelbase") / "data" / "maps" / "cluttered.yaml")))


def rate(backend: str, grid, calls: int, samples: int = 2000, view=None, **options) -> float:
    mppi = MPPI(Unicycle(), 56, 0.05, samples, (0.2, 0.5), 0.03, None, LIMITS, seed=0,
                backend=backend, grid=grid, footprint=ROBOT, max_sample_steps=samples * 56,
                **options)  # fmt: skip
    pose = np.array([2.4, 3.9, 0.1])
    for _ in range(3):  # compile / warm up
        mppi.plan(pose, STRAIGHT, perception=view)
    best = np.inf
    for _ in range(3):
        begin = time.perf_counter()
        for _ in range(calls):
            mppi.plan(pose, STRAIGHT, perception=view)
        best = min(best, (time.perf_counter() - begin) / calls)
    return 1.0 / best


def speed(grid, calls: int) -> dict:
    out: dict = {}
    out["numpy"] = rate("numpy", grid, max(1, calls // 10))
    out["numba"] = rate("numba", grid, calls)
    threads = numba.get_num_threads()
    numba.set_num_threads(1)
    out["numba_1_thread"] = rate("numba", grid, calls)
    numba.set_num_threads(threads)
    view = busy_view(np.array([2.4, 3.9, 0.1]))
    out["numba_with_view"] = rate("numba", grid, calls, view=view)
    out["numpy_with_view"] = rate("numpy", grid, max(1, calls // 10), view=view)
    try:
        import jax  # noqa: F401

        out["jax"] = rate("jax", grid, max(1, calls // 4))
        out["jax_float64"] = rate("jax", grid, max(1, calls // 4), jax_float64=True)
    except ImportError as error:
        out["jax"] = None
        out["jax_error"] = str(error)
    out["pytorch_mppi"] = peer_rate(grid, max(1, calls // 10))
    return out


def peer_rate(grid, calls: int, samples: int = 2000, device: str = "cpu"):
    """Calls per second of ``pytorch_mppi.MPPI.command`` on the same problem size (unicycle,
    56 steps of 0.05 s) with a goal cost and the map's distance-field obstacle cost (lighter
    than our default critics), or ``None`` where PyTorch or pytorch_mppi is not installed."""
    try:
        import torch
        from pytorch_mppi import MPPI as TorchMPPI
    except ImportError:
        return None
    field = torch.tensor(grid.distance_field, dtype=torch.float32, device=device)
    rows, cols = field.shape
    x0, y0 = (float(v) for v in grid.origin)
    res, goal = float(grid.resolution), torch.tensor([11.0, 4.0], device=device)

    def dynamics(state, action):
        x, y, th = state[:, 0], state[:, 1], state[:, 2]
        v, w = action[:, 0], action[:, 1]
        return torch.stack([x + 0.05 * v * torch.cos(th), y + 0.05 * v * torch.sin(th),
                            th + 0.05 * w], dim=1)  # fmt: skip

    def running_cost(state, action):
        col = ((state[:, 0] - x0) / res).long().clamp(0, cols - 1)
        row = ((state[:, 1] - y0) / res).long().clamp(0, rows - 1)
        clear = field[row, col] - 0.283
        obstacle = torch.where(clear <= 0.0, 1e6, 20.0 * torch.clamp(0.4 - clear, min=0.0) ** 2)
        return torch.linalg.norm(state[:, :2] - goal, dim=1) + obstacle

    low, high = torch.tensor([-0.5, -1.5]), torch.tensor([0.5, 1.5])
    controller = TorchMPPI(dynamics, running_cost, 3, torch.diag(torch.tensor([0.04, 0.25])),
                           num_samples=samples, horizon=56, device=device, lambda_=0.03,
                           u_min=low, u_max=high)  # fmt: skip
    state = torch.tensor([2.4, 3.9, 0.1])
    for _ in range(3):
        controller.command(state)
    best = np.inf
    for _ in range(3):
        begin = time.perf_counter()
        for _ in range(calls):
            controller.command(state)
        best = min(best, (time.perf_counter() - begin) / calls)
    return 1.0 / best


def gpu(grid, calls: int) -> dict:
    """``gpu_hz_{2000,100000,1000000}x56`` with the jax backend (float32, noise drawn on the
    device) where JAX sees a GPU; ``null`` and the reason otherwise."""
    sizes = (2_000, 100_000, 1_000_000)
    keys = [f"gpu_hz_{n}x56" for n in sizes]
    try:
        import jax
    except ImportError:
        return dict.fromkeys(keys) | {"gpu": "none: JAX is not installed"}
    if jax.default_backend() == "cpu":
        return dict.fromkeys(keys) | {"gpu": "none: JAX sees only the CPU"}
    out = {key: rate("jax", grid, calls, samples=n) for key, n in zip(keys, sizes, strict=True)}
    return out | {"gpu": str(jax.devices()[0]), "target_gpu_hz": [2000.0, 1000.0, 300.0]}


def errors(result, path) -> dict:
    distance = path.distance(result.true_pose[0, :, :2])[result.t >= 5.0]
    end = np.hypot(*(result.true_pose[0, -1, :2] - path.points[-1]))
    return {
        "rms_lateral_error_m": float(np.sqrt(np.mean(distance**2))),
        "max_lateral_error_m": float(np.max(distance)),
        "final_distance_to_path_end_m": float(end),
    }


def tracking() -> list[dict]:
    eight = PlannedPath.from_points(figure_eight_reference(30.0, 0.01).poses[::20, :2])
    cusp = three_point_turn_path()
    cases = (
        ("figure_eight", eight, (1.1, 0.8, 0.0), eight.length / 30.0, 0.35, 36.0, 0.05),
        ("cusp_path", cusp, (0.0, 0.05, 0.0), 0.3, 0.3, 40.0, 0.5),
    )
    rows = []
    for reference, path, start, v, v_mppi, t_end, wheel_base in cases:
        steer = math.radians(35.0)
        bike = RearWheelBicycle(wheel_base=wheel_base, max_steering=steer)
        plants = (
            ("unicycle", Unicycle(), {"limits": LIMITS}, VelocityLimits(v_mppi, 1.5), (0.15, 0.4)),
            (
                "bicycle",
                bike,
                {"output": "steering", "wheel_base": wheel_base,
                 "limits": SteeringLimits(steer, max_steering_rate=3.0)},
                SteeringLimits(steer, max_speed=v_mppi),
                (0.15, 0.4),
            ),
        )  # fmt: skip
        for plant, model, options, mppi_limits, noise in plants:
            laws = {
                "pure_pursuit": PurePursuit(speed=v, **options),
                "rear_wheel_feedback": RearWheelFeedback(speed=v, **options),
                "mppi": MPPI(model, 30, 0.05, 500, noise, 0.03, None, mppi_limits,
                             backend="numba", goal_tolerance=(0.01, 0.1)),
            }  # fmt: skip
            for law_name, law in laws.items():
                begin = time.perf_counter()
                result = closed_loop(law, model, start, path, t_end, 0.05)
                rows.append(
                    {"reference": reference, "plant": plant, "law": law_name}
                    | errors(result, path)
                    | {
                        "reversals": int(result.metrics()[0]["reversals"]),
                        "path_length_driven_m": float(result.metrics()[0]["distance_travelled_m"]),
                        "reference_length_m": path.length,
                        "runtime_s": time.perf_counter() - begin,
                    }
                )
    return rows


def clearance(grid, seeds: int) -> dict:
    start = np.array([1.0, 4.0, 0.0])
    pp = closed_loop(PurePursuit(speed=0.4, limits=LIMITS), Unicycle(), start, STRAIGHT,
                         26.0, 0.1)  # fmt: skip
    pp_clear = grid.footprint_clearance(ROBOT, pp.true_pose[0])
    minima, successes, times = [], 0, []
    for seed in range(seeds):
        mppi = MPPI(Unicycle(), 30, 0.1, 400, (0.2, 0.5), 0.03, None, LIMITS, seed=seed,
                    backend="numba", grid=grid, footprint=ROBOT)  # fmt: skip
        result = closed_loop(mppi, Unicycle(), start, STRAIGHT, 30.0, 0.1)
        poses = result.true_pose[0]
        low = float(grid.footprint_clearance(ROBOT, poses).min())
        reached = np.hypot(*(poses[-1, :2] - STRAIGHT.points[-1])) < 0.2
        arrive = np.flatnonzero(np.hypot(*(poses[:, :2] - STRAIGHT.points[-1]).T) < 0.2)
        times.append(float(result.t[arrive[0]]) if arrive.size else float("nan"))
        minima.append(low)
        successes += int(low >= 0.1 and reached and not grid.in_collision(ROBOT, poses).any())
    return {
        "stated_clearance_m": 0.1,
        "pure_pursuit_collides": bool(grid.in_collision(ROBOT, pp.true_pose[0]).any()),
        "pure_pursuit_min_clearance_m": float(pp_clear.min()),
        "mppi_seeds": seeds,
        "mppi_success_rate": successes / seeds,
        "mppi_min_clearance_m": float(np.min(minima)),
        "mppi_median_min_clearance_m": float(np.median(minima)),
        "mppi_median_time_to_end_s": float(np.nanmedian(times)),
    }


def parking(seeds: int) -> dict:
    """The bundled ``parking`` scenario (4.5 × 1.8 m car, one cusp, reverse into a bay)
    driven by MPPI (1,000 × 56, Numba) over noise seeds instead of rear-wheel feedback."""
    from wheelbase.runner import run
    from wheelbase.scenario import load_scenario

    base = load_scenario("parking")
    rows = []
    for seed in range(seeds):
        controller = {"law": "mppi", "gains": {"samples": 1000, "max_speed": 1.5, "seed": seed}}
        scenario = base.model_validate(base.model_dump() | {"controller": controller})
        begin = time.perf_counter()
        metrics = run(scenario).metrics
        rows.append(
            {
                "status": metrics["status"],
                "final_position_error_m": metrics["final_position_error_true_m"],
                "path_deviation_max_m": metrics["path_deviation_max_m"],
                "min_clearance_m": metrics["min_clearance_m"],
                "duration_s": metrics["duration_s"],
                "wall_time_s": time.perf_counter() - begin,
            }
        )
    arrived = sum(row["status"] == "arrived" for row in rows)
    return {"seeds": seeds, "arrived": arrived, "runs": rows}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="5 seeds, 5 timed calls")
    parser.add_argument("--seeds", type=int, default=50, help="noise seeds of the clearance run")
    parser.add_argument("--parking-seeds", type=int, default=4, help="seeds of the parking run")
    parser.add_argument("--crowd-seeds", type=int, default=10, help="seeds of each encounter")
    args = parser.parse_args()
    seeds = 5 if args.quick else args.seeds
    calls = 5 if args.quick else 50
    grid = cluttered()
    out = {
        "machine": {
            "cpus": os.cpu_count(),
            "numba_threads": numba.get_num_threads(),
            "load_average_1min": os.getloadavg()[0],
            "python": platform.python_version(),
        },
        "config": {"samples": 2000, "horizon_steps": 56, "dt_s": 0.05, "map": "cluttered"},
    }
    out["cpu_hz_2000x56"] = speed(grid, calls)
    out["target_cpu_hz"] = 200.0
    out |= gpu(grid, calls)
    out["tracking"] = tracking()
    out["clearance"] = clearance(grid, seeds)
    out["parking"] = parking(0 if args.quick else args.parking_seeds)
    out["default_backend"] = MPPI(Unicycle(), 10, 0.05, 16, 0.2, 0.1, None, LIMITS).backend

    def crowd_mppi(seed: int) -> MPPI:
        return MPPI.from_gains(Unicycle(), samples=1000, footprint=ROBOT, seed=seed)

    if args.quick:  # one encounter, one seed: a smoke run
        out["crowd"] = crowd_suite(crowd_mppi, 1, ROBOT, cases=("head_on",))
    else:
        out["crowd"] = crowd_suite(crowd_mppi, args.crowd_seeds, ROBOT)
    print(json.dumps(out, indent=2))


if __name__ == "__main__":
    main()
