"""The figures the README quotes, printed by this script instead of typed by hand.

- ``integrators``: end-pose error (norm of the x, y, θ difference) of :func:`wheelbase.simulate`
  against a ``DOP853`` reference (rtol = atol = 1e-13) on a differential drive (r = 0.05 m,
  b = 0.2 m) with time-varying wheel speeds ω_L = 0.5 + 0.3 sin 1.3t, ω_R = 0.9 cos 0.7t + 0.2t
  [rad/s] from (0.1, 0.2, 0.3) over 4 s, at dt = 0.1, 0.05 and 0.025 s, and the measured order
  (slope of log error against log dt). Deterministic: ``tests/test_readme.py`` checks that the
  README's table holds these numbers.
- ``demo``: wall seconds of ``wheelbase demo --out DIR`` in a fresh process, ``cold`` (an empty
  Numba cache: every kernel compiles, as the very first run after installing) and ``warm``
  (cache filled), each with and without the GIF (``--no-gif``); the median of ``--repeat``
  warm runs. Machine-dependent: the README says on which machine.

Usage: ``python benchmarks/readme_figures.py [--markdown] [--no-demo] [--repeat 3]``; prints one
JSON object, or with ``--markdown`` the README's tables.
"""

from __future__ import annotations

import argparse
import functools
import json
import os
import platform
import statistics
import subprocess
import sys
import tempfile
import time

import numpy as np
from scipy.integrate import solve_ivp

from wheelbase import DiffDrive, simulate
from wheelbase.geometry import wrap_angle

STEPS = (0.1, 0.05, 0.025)
METHOD_ROWS = {
    "euler": "`euler` (doc 002 eq. 6)",
    "midpoint": "`midpoint` (doc 002 eq. 8)",
    "exact": "`exact` (arc of the mid-step twist)",
    "rk4": "`rk4`",
    "simpson": "`simpson` (doc 001)",
}
ROBOT = DiffDrive(wheel_radius=0.05, half_track=0.2)
START = (0.1, 0.2, 0.3)
DURATION = 4.0


def wheel_speeds(t: float) -> np.ndarray:
    """ω_L, ω_R [rad/s] at time t [s]."""
    return np.array([0.5 + 0.3 * np.sin(1.3 * t), 0.9 * np.cos(0.7 * t) + 0.2 * t])


@functools.cache
def reference_end_pose() -> np.ndarray:
    """The end pose by DOP853 at rtol = atol = 1e-13."""
    return solve_ivp(
        lambda t, pose: ROBOT.derivative(pose, wheel_speeds(t)),
        (0.0, DURATION),
        list(START),
        rtol=1e-13,
        atol=1e-13,
        method="DOP853",
    ).y[:, -1]


def end_error(method: str, dt: float) -> float:
    """Norm of the end-pose difference to the DOP853 reference (heading difference wrapped)."""
    reference = reference_end_pose()
    result = simulate(ROBOT, list(START), wheel_speeds, t_end=DURATION, dt=dt, method=method)
    diff = result.poses[-1] - reference
    diff[2] = wrap_angle(diff[2])
    return float(np.linalg.norm(diff))


def integrators() -> dict:
    """Errors per method and step, and the measured order of each method."""
    out = {}
    for method in METHOD_ROWS:
        errors = [end_error(method, dt) for dt in STEPS]
        order = float(np.polyfit(np.log(STEPS), np.log(errors), 1)[0])
        out[method] = {"errors": dict(zip(map(str, STEPS), errors, strict=True)), "order": order}
    return out


def _demo_seconds(gif: bool, cache: str) -> float:
    # this interpreter's wheelbase (the console script may belong to another install)
    argv = [sys.executable, "-m", "wheelbase"]
    with tempfile.TemporaryDirectory() as folder:
        argv += ["demo", "--out", os.path.join(folder, "demo"), "--gif" if gif else "--no-gif"]
        environment = {**os.environ, "NUMBA_CACHE_DIR": cache}
        start = time.perf_counter()
        subprocess.run(argv, capture_output=True, check=True, env=environment)
        return time.perf_counter() - start


def demo(repeat: int) -> dict:
    """Cold (fresh Numba cache) and warm seconds of ``wheelbase demo``, with and without GIF."""
    out: dict = {}
    for gif in (False, True):
        key = "with_gif" if gif else "without_gif"
        with tempfile.TemporaryDirectory() as cache:
            cold = _demo_seconds(gif, cache)
            warm = [_demo_seconds(gif, cache) for _ in range(repeat)]
        out[key] = {"cold_s": cold, "warm_s": statistics.median(warm)}
    out["machine"] = f"{platform.processor() or platform.machine()}, {os.cpu_count()} CPUs"
    return out


def markdown(figures: dict) -> str:
    """The README's integrator table (and demo sentence when timed)."""
    lines = [
        "| method | dt = 0.1 s | 0.05 s | 0.025 s | measured order |",
        "| --- | --- | --- | --- | --- |",
    ]
    for method, label in METHOD_ROWS.items():
        row = figures["integrators"][method]
        cells = [f"{row['errors'][str(dt)]:.1e}".replace("e-0", "e-") for dt in STEPS]
        lines.append(f"| {label} | {' | '.join(cells)} | {row['order']:.2f} |")
    if "demo" in figures:
        d = figures["demo"]
        lines.append("")
        lines.append(
            f"`wheelbase demo`: {d['without_gif']['warm_s']:.1f} s without the GIF "
            f"({d['with_gif']['warm_s']:.1f} s with it), {d['without_gif']['cold_s']:.0f} s the "
            f"very first time ({d['with_gif']['cold_s']:.0f} s with the GIF), when Numba compiles "
            f"and caches its kernels ({d['machine']})."
        )
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--markdown", action="store_true", help="print the README's tables")
    parser.add_argument("--no-demo", action="store_true", help="integrators only (seconds)")
    parser.add_argument("--repeat", type=int, default=3, help="warm demo runs (median)")
    args = parser.parse_args()
    figures: dict = {"integrators": integrators()}
    if not args.no_demo:
        figures["demo"] = demo(args.repeat)
    print(markdown(figures) if args.markdown else json.dumps(figures, indent=1))


if __name__ == "__main__":
    main()
