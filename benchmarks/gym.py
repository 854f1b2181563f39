"""Gymnasium speed (issue 17): the native vector env against Gymnasium's SyncVectorEnv.

Run ``python benchmarks/gym.py`` (``--quick`` for a smoke run); prints one JSON object.

``vector_env_steps_per_s``
    :class:`wheelbase.gym.NavigateVectorEnv` with ``--envs`` (256) robots and ``--beams`` (60)
    lidar beams on the walled empty room: environment steps per second (robots × calls / s),
    the best of ``--repeat`` timed blocks of ``--steps`` calls (random actions, autoreset on).
    Target >= 100,000.
``vector_env_steps_per_s_one_thread``
    The same with Numba on one thread (the lidar kernel is parallel): steadier on a shared
    machine.
``sync_vector_env_steps_per_s``
    ``gymnasium.vector.SyncVectorEnv`` over the same number of single
    :class:`wheelbase.gym.NavigateEnv`, same actions, in the same run (blocks of
    ``--sync-steps`` calls).
``sync_vector_env_steps_per_s_one_thread``
    The same on one Numba thread.
``ratio``
    vector / sync; target >= 50. ``ratio_one_thread``: the same on one Numba thread.
``vector_step_breakdown_us``
    Where one call of the vector env goes: the engine step, the footprint collision check, the
    lidar scan and the rest (observations, rewards, autoreset), in microseconds per call.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import time

import gymnasium
import numba
import numpy as np

from wheelbase.gym import NavigateEnv, NavigateVectorEnv
from wheelbase.sensors import Lidar


def timed_blocks(envs, actions: np.ndarray, steps: int, repeats: int) -> list[float]:
    """Seconds of ``repeats`` blocks of ``steps`` calls, after a warm-up block."""
    times = []
    for block in range(repeats + 1):
        start = time.perf_counter()
        for k in range(steps):
            envs.step(actions[k % len(actions)])
        if block:
            times.append(time.perf_counter() - start)
    return times


def breakdown(envs: NavigateVectorEnv, actions: np.ndarray, steps: int) -> dict[str, float]:
    """Microseconds per call spent in the engine, the collision check, the lidar, the rest."""
    task = envs.task
    spent = {"engine_step": 0.0, "collision_check": 0.0, "lidar_scan": 0.0}
    wrapped = {
        "engine_step": (task.engine, "step"),
        "collision_check": (task.grid, "in_collision"),
        "lidar_scan": (task.lidar, "scan"),
    }
    originals = {}
    for key, (owner, name) in wrapped.items():
        original = getattr(owner, name)
        originals[key] = (owner, name, original)

        def timed(*args, _original=original, _key=key, **kwargs):
            start = time.perf_counter()
            try:
                return _original(*args, **kwargs)
            finally:
                spent[_key] += time.perf_counter() - start

        object.__setattr__(owner, name, timed)
    try:
        start = time.perf_counter()
        for k in range(steps):
            envs.step(actions[k % len(actions)])
        total = time.perf_counter() - start
    finally:
        for owner, name, _ in originals.values():
            object.__delattr__(owner, name)
    out = {key: 1e6 * value / steps for key, value in spent.items()}
    out["rest"] = 1e6 * total / steps - sum(out.values())
    out["total"] = 1e6 * total / steps
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="smoke run: 16 envs, few steps")
    parser.add_argument("--envs", type=int, default=256)
    parser.add_argument("--beams", type=int, default=60)
    parser.add_argument("--steps", type=int, default=200, help="calls per timed block (vector)")
    parser.add_argument("--sync-steps", type=int, default=10, help="calls per block (sync)")
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    if args.quick:
        args.envs, args.steps, args.sync_steps, args.repeat = 16, 10, 3, 1
    n = args.envs
    lidar = Lidar(beams=args.beams, max_range=5.0)
    actions = np.random.default_rng(0).uniform(-1.0, 1.0, (64, n, 2)).astype(np.float32)

    vector = NavigateVectorEnv(n, lidar=lidar)
    vector.reset(seed=0)
    sync = gymnasium.vector.SyncVectorEnv([lambda: NavigateEnv(lidar=lidar) for _ in range(n)])
    sync.reset(seed=0)

    threads = numba.get_num_threads()
    vector_times, one_thread_times, sync_times, sync_one_thread_times = [], [], [], []
    for _ in range(args.repeat):  # take turns: a slow spell of a shared machine hits all
        vector_times += timed_blocks(vector, actions, args.steps, 1)
        sync_times += timed_blocks(sync, actions, args.sync_steps, 1)
        numba.set_num_threads(1)
        one_thread_times += timed_blocks(vector, actions, args.steps, 1)
        sync_one_thread_times += timed_blocks(sync, actions, args.sync_steps, 1)
        numba.set_num_threads(threads)
    vector_rate = n * args.steps / min(vector_times)
    sync_rate = n * args.sync_steps / min(sync_times)
    vector_one = n * args.steps / min(one_thread_times)
    sync_one = n * args.sync_steps / min(sync_one_thread_times)
    report = {
        "machine": {
            "platform": platform.platform(),
            "python": platform.python_version(),
            "cpus": os.cpu_count(),
            "numba_threads": threads,
            "load_average_1min": os.getloadavg()[0],
            "gymnasium": gymnasium.__version__,
        },
        "config": {
            "envs": n,
            "beams": args.beams,
            "max_range_m": 5.0,
            "map": "empty 10 m room",
            "steps_per_block": args.steps,
            "sync_steps_per_block": args.sync_steps,
            "repeats": args.repeat,
        },
        "vector_env_steps_per_s": vector_rate,
        "vector_env_steps_per_s_median": n * args.steps / float(np.median(vector_times)),
        "vector_env_steps_per_s_one_thread": vector_one,
        "sync_vector_env_steps_per_s": sync_rate,
        "sync_vector_env_steps_per_s_one_thread": sync_one,
        "ratio": vector_rate / sync_rate,
        "ratio_one_thread": vector_one / sync_one,
        "vector_step_breakdown_us": breakdown(vector, actions, args.steps),
    }
    report["targets"] = {
        "vector_env_steps_per_s >= 100000": vector_rate >= 1e5,
        "ratio >= 50": report["ratio"] >= 50.0,
    }
    print(json.dumps(report, indent=2))


if __name__ == "__main__":
    main()
