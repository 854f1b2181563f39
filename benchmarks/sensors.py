"""Sensing and localisation speed (issue 14): lidar rays per second, AMCL updates per second.

Run ``python benchmarks/sensors.py`` (``--quick`` for a smoke run); prints one JSON object.

``lidar_rays_per_s``
    :meth:`wheelbase.sensors.Lidar.scan` (ray marching on the gap field, Numba, all cores) for
    2,000 random free poses × 360 beams, 8 m range, on the bundled ``warehouse`` map and on the
    turtlebot3 map of ``../shared/data/maps`` (skipped, with the reason, when absent). Target
    >= 20 M rays/s.
``lidar_rays_per_s_one_thread``
    The same on one Numba thread: the figure per core, steadier on a shared machine.
``numpy_rays_per_s`` / ``exact_rays_per_s``
    The same scans with the vectorised NumPy march and with the exact Amanatides–Woo traversal,
    in the same run; ``fast_vs_exact_max_m`` is the largest difference to the exact ranges.
``amcl_updates_per_s``
    :meth:`wheelbase.localization.AMCL.update` with 2,000 particles (KLD limits pinned) and a
    360-beam scan subsampled to 60, on the warehouse: motion, likelihood field, KLD bound,
    low-variance resampling. Target >= 500. Also for Nav2's sum of cubes and for the beam model.
``global_localization``
    Global localisation on the maze (20 seeds): particles spread over the free
    space, a robot wandering 12 m; the fraction whose estimate is within 0.2 m for good within
    10 m of travel (target >= 0.95), and the distances (``--quick``: one seed). ``kidnapped``:
    10 robots tracked for 4 m from a known pose, then carried to another corridor
    (``amcl_trials.kidnapped_run``); the fraction whose estimate is within
    0.2 m for good within 30 s (ticks of 0.1 s) and the times. ``kidnapped_anywhere``: the
    same, each carried to a random pose of the maze instead.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import time
import warnings
from pathlib import Path

import numba
import numpy as np

from wheelbase.planning import OccupancyGrid, load_map
from wheelbase.sensors import Lidar

MAPS = Path(__file__).resolve().parents[2] / "shared" / "data" / "maps"


def best_of(function, repeats: int) -> float:
    """Shortest wall time [s] of ``repeats`` calls after one warm-up call."""
    function()
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        function()
        times.append(time.perf_counter() - start)
    return min(times)


def free_poses(grid: OccupancyGrid, n: int, rng: np.random.Generator) -> np.ndarray:
    """``n`` poses uniformly over the free cells, random headings."""
    free = np.argwhere(~grid.occupied)
    cells = free[rng.integers(len(free), size=n)]
    xy = grid.cell_to_world(cells) + rng.uniform(-0.5, 0.5, (n, 2)) * grid.resolution
    return np.column_stack([xy, rng.uniform(-np.pi, np.pi, n)])


def lidar_maps() -> tuple[dict[str, OccupancyGrid], dict[str, str]]:
    maps = {"warehouse": load_map("warehouse")}
    skipped = {}
    path = MAPS / "turtlebot3_world.yaml"
    if path.is_file():
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # the YAML names map.pgm; the loader finds the .pgm
            maps["turtlebot3_world"] = load_map(path)
    else:
        skipped["turtlebot3_world"] = f"not found: {path}"
    return maps, skipped


def lidar(quick: bool) -> dict:
    poses_n = 200 if quick else 2000
    repeats = 1 if quick else 5
    lidar = Lidar(beams=360, max_range=8.0)
    maps, skipped = lidar_maps()
    out: dict = {
        "config": {"poses": poses_n, "beams": 360, "max_range_m": 8.0, "repeats": repeats},
        "lidar_rays_per_s": {},
        "lidar_rays_per_s_one_thread": {},
        "numpy_rays_per_s": {},
        "exact_rays_per_s": {},
        "fast_vs_exact_max_m": {},
        "skipped": skipped,
    }
    rays = poses_n * lidar.beams
    for name, grid in maps.items():
        poses = free_poses(grid, poses_n, np.random.default_rng(0))
        results = {}
        for method, key in (
            ("fast", "lidar_rays_per_s"),
            ("numpy", "numpy_rays_per_s"),
            ("exact", "exact_rays_per_s"),
        ):

            def call(method=method, grid=grid, poses=poses, results=results):
                results[method] = lidar.scan(grid, poses, noise=False, method=method)

            out[key][name] = rays / best_of(call, repeats)
            if method == "fast":
                threads = numba.get_num_threads()
                numba.set_num_threads(1)
                out["lidar_rays_per_s_one_thread"][name] = rays / best_of(call, repeats)
                numba.set_num_threads(threads)
        out["fast_vs_exact_max_m"][name] = float(np.max(np.abs(results["fast"] - results["exact"])))
    return out


def amcl_speed(quick: bool) -> dict:
    from wheelbase.localization import AMCL

    grid = load_map("warehouse")
    lidar = Lidar(beams=360, max_range=10.0, range_std=0.02)
    rng = np.random.default_rng(0)
    truth = np.array([3.0, 2.0, 0.3])
    scan = lidar.scan(grid, truth, rng)
    out = {"config": {"particles": 2000, "beams": 60, "map": "warehouse"}}
    for key, options in (
        ("amcl_updates_per_s", {}),
        ("amcl_cubes_updates_per_s", {"beam_combination": "cubes"}),
        ("amcl_beam_model_updates_per_s", {"sensor_model": "beam"}),
    ):
        amcl = AMCL(grid=grid, lidar=lidar, min_particles=2000, max_particles=2000, **options)
        state = amcl.initial_state(truth, np.diag([0.3, 0.3, 0.1]) ** 2, (0, 0, 0), rng)
        holder = {"state": state}

        def call(amcl=amcl, holder=holder):
            holder["state"], _ = amcl.update(holder["state"], (0, 0, 0), rng, scan=scan, force=True)

        calls = 5 if quick else 50
        out[key] = calls / best_of(lambda call=call, calls=calls: [call() for _ in range(calls)], 3)
    return out


def global_localization(quick: bool) -> dict:
    from amcl_trials import kidnapped_run, noisy_odometry, run_amcl, wander
    from wheelbase.localization import AMCL, GLOBAL_LOCALIZATION

    grid = load_map("maze")
    lidar = Lidar(beams=360, max_range=30.0, range_std=0.02)
    amcl = AMCL(grid=grid, lidar=lidar, **GLOBAL_LOCALIZATION)
    distances = []
    start = time.perf_counter()
    for seed in range(1 if quick else 20):
        rng = np.random.default_rng(seed)
        truth = wander(grid, 12.0, rng)
        odometry = noisy_odometry(truth, rng)
        run = run_amcl(amcl, lidar, truth, odometry, amcl.global_state(odometry[0], rng), rng)
        distances.append(run.converged_after(0.2))
    distances = np.array(distances)
    return {
        "options": GLOBAL_LOCALIZATION,
        "lidar": {"beams": 360, "max_range_m": 30.0, "range_std_m": 0.02},
        "seeds": int(distances.size),
        "converged_within_10m": float(np.mean(distances <= 10.0)),
        "convergence_distance_m": [
            None if not np.isfinite(d) else round(float(d), 2) for d in distances
        ],
        "seconds": time.perf_counter() - start,
        "kidnapped": kidnapped(amcl, lidar, 1 if quick else 10, kidnapped_run),
        "kidnapped_anywhere": kidnapped(amcl, lidar, 1 if quick else 10, kidnapped_run, True),
    }


def kidnapped(amcl, lidar, seeds: int, kidnapped_run, anywhere: bool = False) -> dict:
    """Seconds to recover (0.2 m for good) after a kidnapping, over ``seeds`` routes: carried
    to (15, 14, π) (the function's default), or ``anywhere``: to a random pose more than 0.6 m
    from the walls (``amcl_trials.clear_pose``, seed 1000 + the route's)."""
    from amcl_trials import clear_pose

    start = time.perf_counter()
    seconds, poses = [], []
    for seed in range(seeds):
        options = {}
        if anywhere:
            pose = clear_pose(amcl.grid, 1000 + seed)
            options["teleport"] = pose
            poses.append([round(float(v), 2) for v in pose])
        run = kidnapped_run(amcl, lidar, seed, **options)[1]
        seconds.append(run.converged_at_tick(0.2) * 0.1)
    seconds = np.array(seconds)
    return {
        "seeds": seeds,
        **({"teleported_to": poses} if anywhere else {}),
        "recovered_within_30s": float(np.mean(seconds <= 30.0)),
        "recovered_after_s": [None if not np.isfinite(t) else round(float(t), 1) for t in seconds],
        "seconds": time.perf_counter() - start,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="smoke run: small sizes, one repeat")
    parser.add_argument(
        "--no-global", action="store_true", help="skip the global-localisation runs (minutes)"
    )
    args = parser.parse_args()
    report = {
        "machine": {
            "platform": platform.platform(),
            "python": platform.python_version(),
            "cpus": os.cpu_count(),
            "numba_threads": numba.get_num_threads(),
            "load_average_1min": os.getloadavg()[0],
        },
        "lidar": lidar(args.quick),
        "amcl": amcl_speed(args.quick),
    }
    if not args.no_global:
        report["global_localization"] = global_localization(args.quick)
    rays = report["lidar"]["lidar_rays_per_s"]
    report["targets"] = {
        "lidar_rays_per_s >= 20e6": {name: value >= 20e6 for name, value in rays.items()},
        "amcl_updates_per_s >= 500": report["amcl"]["amcl_updates_per_s"] >= 500,
        "global_localization >= 0.95": (
            report["global_localization"]["converged_within_10m"] >= 0.95
            if "global_localization" in report
            else None
        ),
    }
    print(json.dumps(report, indent=2))


if __name__ == "__main__":
    main()
