"""
Reproduce document 000 §3.2: the two MATLAB kinematics programs, with plots and animations
==========================================================================================

Document 000 (``000_da8bbdc5a43f14d5.txt``) §3.2 integrates η̇ = J(ψ)·ζ with Euler steps of
dt = 0.1 s from η0 = (0, 0, π/2):

* program 1 commands the body twist ζ = (u, v, r) directly: (0.1, 0.05, 0.3) (its figure 3.6)
  and (0.6, 0, −0.3) (figures 3.7, 3.8), for 10 s, robot drawn 0.6 m × 0.4 m;
* program 2 commands the wheel speeds of a differential drive (a = 0.05 m, d = 0.2 m) through
  ζ = W·ω: (ω1, ω2) = (0.8, 0.6), (0.6, 0.6) and (0.6, −0.6) rad/s (figures 3.9–3.11), for
  100 s, robot drawn 0.75 m × 2d. ω1 is the left wheel, per the comments in its code.

The printed code plots the first row of η three times (``plot(t, eta(1,1:i))`` under the labels
x, y and psi); here x(t), y(t) and ψ(t) are the three rows. Every run is also integrated with
the ``exact`` method (the closed-form arc, exact for constant inputs) and Euler's end-point error
is printed.

Usage::

    python examples/doc000_kinematics.py [OUT_DIR]      # default: examples/out/

It writes, per case, ``doc000_<case>.png`` (path with the footprint + x, y, ψ against t) and
``doc000_<case>.gif`` (the animation), plus ``doc000_twist_paths.png`` and
``doc000_wheel_paths.png`` with the cases of each program on one plot. Files of those names are
replaced; nothing else in OUT_DIR is touched.
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np

from wheelbase import BodyTwist, DiffDrive, SimResult, simulate
from wheelbase.plot import animate, plot_path, plot_result, save_figure

START = (0.0, 0.0, math.pi / 2)  # η0 = (x0, y0, ψ0)
DT = 0.1  # [s]
WHEEL_RADIUS = 0.05  # a [m]
HALF_TRACK = 0.2  # d [m]

TWIST_PROGRAMS: dict[str, tuple[float, float, float]] = {
    "twist_1": (0.1, 0.05, 0.3),  # (u [m/s], v [m/s], r [rad/s]), figure 3.6
    "twist_2": (0.6, 0.0, -0.3),  # figures 3.7 and 3.8
}
TWIST_DURATION = 10.0  # [s]
TWIST_FOOTPRINT = (0.6, 0.4)  # (l, w) [m] of program 1's animation

WHEEL_CASES: dict[str, tuple[float, float]] = {
    "wheels_1": (0.8, 0.6),  # (ω1 = left, ω2 = right) [rad/s], figure 3.9
    "wheels_2": (0.6, 0.6),  # figure 3.10
    "wheels_3": (0.6, -0.6),  # figure 3.11
}
WHEEL_DURATION = 100.0  # [s]
WHEEL_FOOTPRINT = (0.75, 2 * HALF_TRACK)  # (l, w = 2d) [m] of program 2's animation


def robot() -> DiffDrive:
    """Program 2's differential drive (a = 0.05 m, d = 0.2 m)."""
    return DiffDrive(wheel_radius=WHEEL_RADIUS, half_track=HALF_TRACK)


def run_programs(method: str = "euler") -> dict[str, SimResult]:
    """Both programs of §3.2 as batches: ``"twist"`` (2 robots) and ``"wheel"`` (3 robots)."""
    twist_starts = np.tile(START, (len(TWIST_PROGRAMS), 1))
    wheel_starts = np.tile(START, (len(WHEEL_CASES), 1))
    twists = np.array(list(TWIST_PROGRAMS.values()))
    speeds = np.array(list(WHEEL_CASES.values()))
    return {
        "twist": simulate(BodyTwist(), twist_starts, twists, TWIST_DURATION, DT, method),
        "wheel": simulate(robot(), wheel_starts, speeds, WHEEL_DURATION, DT, method),
    }


def split_cases(programs: dict[str, SimResult]) -> dict[str, SimResult]:
    """The five single-robot runs of :func:`run_programs`' batches, by case name."""
    results = {}
    for group, names in (("twist", TWIST_PROGRAMS), ("wheel", WHEEL_CASES)):
        for index, name in enumerate(names):
            results[name] = programs[group].robot(index)
    return results


def run_cases(method: str = "euler") -> dict[str, SimResult]:
    """All five runs of §3.2 with ``method`` (the document uses ``"euler"``), by case name."""
    return split_cases(run_programs(method))


def footprint_of(name: str) -> tuple[float, float]:
    """The robot rectangle (length, width) [m] the document draws for a case."""
    return TWIST_FOOTPRINT if name.startswith("twist") else WHEEL_FOOTPRINT


def describe(name: str) -> str:
    """A short label of a case's inputs, with units."""
    if name in TWIST_PROGRAMS:
        u, v, r = TWIST_PROGRAMS[name]
        return f"(u, v, r) = ({u:g} m/s, {v:g} m/s, {r:g} rad/s)"
    left, right = WHEEL_CASES[name]
    return f"(ω1, ω2) = ({left:g}, {right:g}) rad/s"


def write_figures(programs: dict[str, SimResult], out: Path) -> list[Path]:
    """Write the figures and animations of :func:`run_programs`' batches into ``out``."""
    out.mkdir(parents=True, exist_ok=True)
    written = []
    for name, result in split_cases(programs).items():
        footprint = footprint_of(name)
        title = f"document 000 §3.2, {describe(name)}, Euler dt = {DT:g} s"
        fig = plot_result(result, footprint=footprint, title=title)
        written.append(save_figure(fig, out / f"doc000_{name}.png", overwrite=True))
        written.append(
            animate(
                result,
                out / f"doc000_{name}.gif",
                footprint=footprint,
                overwrite=True,
                title=describe(name),
            )
        )
    for number, (group, names) in enumerate(
        (("twist", TWIST_PROGRAMS), ("wheel", WHEEL_CASES)), start=1
    ):
        first = next(iter(names))
        fig, _ = plot_path(
            programs[group], footprint=footprint_of(first), label=[describe(n) for n in names]
        )
        fig.suptitle(f"document 000 §3.2, program {number}, Euler dt = {DT:g} s")
        written.append(save_figure(fig, out / f"doc000_{group}_paths.png", overwrite=True))
    return written


def error_table(euler: dict[str, SimResult], exact: dict[str, SimResult]) -> list[str]:
    """Lines comparing Euler's end pose with the exact arc's, per case."""
    lines = [
        f"{'case':<10} {'inputs':<46} {'Euler end (x, y, ψ)':<28} "
        f"{'exact end (x, y, ψ)':<28} {'|Δp| [mm]':>9}"
    ]
    for name, result in euler.items():
        a, b = result.poses[-1], exact[name].poses[-1]
        error = 1e3 * float(np.hypot(*(a[:2] - b[:2])))
        lines.append(
            f"{name:<10} {describe(name):<46} "
            f"({a[0]:7.4f}, {a[1]:7.4f}, {a[2]:7.4f})  "
            f"({b[0]:7.4f}, {b[1]:7.4f}, {b[2]:7.4f})  {error:9.3f}"
        )
    return lines


def main(argv: list[str] | None = None) -> int:
    """Run the five cases, print the error table and write the figures."""
    args = sys.argv[1:] if argv is None else argv
    out = Path(args[0]) if args else Path(__file__).resolve().parent / "out"
    programs = run_programs("euler")
    print("\n".join(error_table(split_cases(programs), run_cases("exact"))))
    for path in write_figures(programs, out):
        print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    main()
