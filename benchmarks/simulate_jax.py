"""simulate(backend="jax") beside a hand-written fused lax.scan Euler loop and the Numba backend.

Prints one JSON object: robot-steps per second for differential-drive robots under constant
wheel speeds, Euler, for ``wheelbase.simulate`` with the ``jax``, ``numba`` and ``numpy``
backends and for a hand-written ``jax.jit`` + ``lax.scan`` Euler loop that keeps the twist in
registers (the target of issue 9: simulate within 2× of it). Best of ``--repeat`` after a
warm-up call. Needs the ``jax`` extra; prints ``{"jax": null, ...}`` without it.

Usage: ``python benchmarks/simulate_jax.py [--robots 10000] [--steps 500] [--repeat 3]``.
"""

from __future__ import annotations

import argparse
import json
import time

import numpy as np

from wheelbase import DiffDrive, simulate


def best(function, repeat: int) -> float:
    function()
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        function()
        times.append(time.perf_counter() - start)
    return min(times)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--robots", type=int, default=10_000)
    parser.add_argument("--steps", type=int, default=500)
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    robot = DiffDrive(0.05, 0.2)
    rng = np.random.default_rng(0)
    poses = np.zeros((args.robots, 3))
    wheels = rng.uniform(-10, 10, (args.robots, 2))
    dt = 0.01
    t_end = dt * args.steps
    work = args.robots * args.steps
    out: dict = {"benchmark": "simulate_jax", "robots": args.robots, "steps": args.steps}

    def run(backend):
        return simulate(
            robot, poses, wheels, t_end, dt, "euler", record_every=args.steps, backend=backend
        )

    for backend in ("numba", "numpy"):
        out[f"{backend}_robot_steps_per_s"] = work / best(lambda b=backend: run(b), args.repeat)
    try:
        import jax
        import jax.numpy as jnp
    except ImportError:
        out["jax"] = None
        print(json.dumps(out, indent=2))
        return
    jax.config.update("jax_enable_x64", True)
    twist = robot.twist(wheels)

    @jax.jit
    def fused(pose, twist):
        def body(p, _):
            c, s = jnp.cos(p[:, 2]), jnp.sin(p[:, 2])
            rate = jnp.stack([c * twist[:, 0], s * twist[:, 0], twist[:, 2]], -1)
            return p + dt * rate, None

        final, _ = jax.lax.scan(body, pose, None, length=args.steps)
        return final

    pose_j, twist_j = jnp.asarray(poses), jnp.asarray(twist)
    fused_s = best(lambda: fused(pose_j, twist_j).block_until_ready(), args.repeat)
    ours_s = best(lambda: run("jax"), args.repeat)
    final = np.asarray(fused(pose_j, twist_j))
    np.testing.assert_allclose(final[:, :2], run("jax").poses[-1, :, :2], atol=1e-9)
    out["jax"] = {
        "version": jax.__version__,
        "device": str(jax.devices()[0]),
        "simulate_robot_steps_per_s": work / ours_s,
        "fused_scan_robot_steps_per_s": work / fused_s,
        "simulate_time_over_fused": ours_s / fused_s,
        "target_ratio": 2.0,
    }
    print(json.dumps(out, indent=2))


if __name__ == "__main__":
    main()
