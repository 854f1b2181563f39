"""
Document 001, Table I: the trajectory model evaluated with Simpson's 1/3 rule, reproduced
=========================================================================================

Run ``python examples/doc001_table1.py [--out doc001_table1.csv] [--overwrite]``: prints the
table (rich), writes it to CSV, one row per initial heading and variable, and draws the four
arcs with the printed end points beside them (``doc001_table1.png``).

What the document gives
-----------------------
Document 001 §IV.B: r = 1 cm, L = 0.8, step H = 0.5, start (0, 0), initial headings 0°, 45°,
90°, 180°; "Actual" vs "Simpson's" x, y and θ (Table I). It gives neither the wheel speeds nor the
duration.

Units. The document mixes cm (r) with a unitless L and unitless positions. We read every length
in metres: r = 0.01 m, L = 0.8 m (half track 0.4 m), x and y in m, θ in degrees at the edge
(radians inside). Only v = r(ω_R + ω_L)/2 and ω = r(ω_R − ω_L)/L matter to the geometry, so
another reading only rescales the wheel speeds.

The inputs we use, and how we found them
----------------------------------------
**No constant-input arc can give the printed "Actual" column.** For an exact arc from heading
θ₀ that turns by Δθ, the chord from start to end points along θ₀ + Δθ/2 (the inscribed-angle
theorem): Δθ = −69.8° requires the end point at bearing −34.9° from heading 0°, but the printed
(9.56, −7.42) lies at −37.8°, far outside the rounding of two decimals (±0.04°). A least-squares
fit of ω_R, ω_L and T of the exact arc to the four printed rows (``fit_exact_arc``,
scipy.optimize.least_squares, 1° of θ weighted like 1 m) indeed leaves position residuals of up
to 0.59 m (turn −69.86°); letting the turn drift to −72.9° still leaves 0.28 m.

The printed column *is* reproduced, to every printed digit of all four rows, by 12 steps of
H = 0.5 s of Euler's method that updates the heading first and then moves along the *new*
heading (θ_{k+1} = θ_k + Hω, x_{k+1} = x_k + Hv·cos θ_{k+1}, …; ``document_actual``): its
chord points along θ₀ + (n + 1)Δθ/(2n), which is −37.81° for n = 12 steps and no other n. Fitting
v and ω of that scheme (``fit_document_actual``) and rounding to wheel speeds in 0.01 rad/s
gives the inputs used throughout:

    ω_L = 222.77 rad/s, ω_R = 206.53 rad/s (document order: u₁ = ω_R, u₂ = ω_L), T = 6 s,
    i.e. v = 2.1465 m/s, ω = −0.203 rad/s (turning radius 10.57 m to the right).

Our table then compares, for each heading, our exact closed-form arc (``method="exact"``,
"actual") with ``simpson``, ``euler``, ``midpoint`` and ``rk4`` at dt = H = 0.5 s, and shows
the document's printed columns and our reconstruction of its "Actual" beside them.

Why our errors differ from the printed ones
-------------------------------------------
- θ: every method integrates θ̇ = ω exactly for constant inputs, so the θ error is 0 (to
  rounding), as the document finds.
- Simpson: for x = ∫ v cos θ(t) dt with θ(t) = θ₀ + ωt exact, f⁗ = ω⁴f, and Simpson's error
  formula gives the end-point error S − I ≈ (h_s⁴/180)·ω⁴·(Δx, Δy) with node spacing h_s, bounded
  by T·h_s⁴·abs(v)·ω⁴/180 per coordinate. Our ``simpson`` puts the nodes at the start, middle and
  end of each step (h_s = H/2): bound T·H⁴·abs(v)·ω⁴/2880 = 4.7e-7 m (7.6e-6 m for nodes every
  H = 0.5 s).
  We measure at most 4.4e-7 m. (For constant inputs ``rk4`` equals ``simpson``: its two middle
  stages coincide and its heading stages are exact.) The printed 0.29–0.49 m are six orders of
  magnitude larger: for smooth motion Simpson's rule would need abs(ω)·h_s ≈ 1.4 rad, a step longer
  than the whole run.
- The printed errors are instead consistent with headings sampled at the wrong time within each
  step. The exact arc advances each step along a chord at the mid-step heading; the printed "Actual"
  (above) moves along each step's end heading, half a step ahead, and so lands 0.36 m, 0.50 m
  from the exact arc, rotated about the start by Δθ/(2n) = −2.9°. The printed "Simpson's" end
  point is rotated by a further −2.3° with the same length to 0.3 %, as if its headings ran about
  0.9 of a step (5.8° of turn per step) ahead. We could not reproduce the printed Simpson column
  exactly; no Simpson quadrature with correct heading nodes produces it. Plain (forward) Euler
  at H, which uses each step's start heading, errs by as much the other way (0.34 m, 0.51 m).
- The printed 180° x line (−9.56, 9.28, error −0.29) is the 0° line with only its first sign
  flipped: rotating the 0° row by 180° gives (−x, −y), so Simpson's x is −9.28 and its error
  +0.29 (the y line, 7.42 → 7.82, +0.40, is right). Rotating the initial
  heading rotates the end point: the 90° row is (−y₀, x₀), the 45° row (x₀ − y₀, x₀ + y₀)/√2, in
  the printed table as in ours.
"""

from __future__ import annotations

import argparse
import csv
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy.optimize import least_squares

from wheelbase import DiffDrive, simulate
from wheelbase.geometry import wrap_angle

__all__ = [
    "HEADINGS_DEG",
    "PRINTED",
    "ROBOT",
    "Row",
    "document_actual",
    "fit_document_actual",
    "fit_exact_arc",
    "main",
    "simpson_error_bound",
    "table1",
]

WHEEL_RADIUS_M = 0.01  # r = 1 cm
TRACK_M = 0.8  # L = 0.8, read in metres
ROBOT = DiffDrive(wheel_radius=WHEEL_RADIUS_M, half_track=TRACK_M / 2)
STEP_S = 0.5  # H
DURATION_S = 6.0  # 12 steps of H: the only step count that reproduces the printed "Actual"
WHEEL_SPEEDS = (222.77, 206.53)  # (left, right) [rad/s]; document 001 orders (right, left)
HEADINGS_DEG = (0.0, 45.0, 90.0, 180.0)
METHOD_COLUMNS = ("simpson", "euler", "midpoint", "rk4")

# Table I as printed: heading [deg] -> (x, y [m], θ [deg]) of "Actual" and of "Simpson's".
# The 180° Simpson x is printed 9.28 (with the 0° row's error −0.29): the rotation says −9.28.
PRINTED: dict[float, dict[str, tuple[float, float, float]]] = {
    0.0: {"actual": (9.56, -7.42, -69.8), "simpson": (9.28, -7.82, -69.8)},
    45.0: {"actual": (12.01, 1.52, -24.8), "simpson": (12.09, 1.03, -24.8)},
    90.0: {"actual": (7.42, 9.56, 20.2), "simpson": (7.82, 9.28, 20.2)},
    180.0: {"actual": (-9.56, 7.42, 110.2), "simpson": (9.28, 7.82, 110.2)},
}
VARIABLES = ("x", "y", "theta")


@dataclass(frozen=True)
class Row:
    """One line of the table: one initial heading and one variable.

    Attributes
    ----------
    heading_deg : float
        Initial heading [deg].
    variable : str
        ``"x"``, ``"y"`` [m] or ``"theta"`` [deg].
    printed_actual, printed_simpson : float
        Document 001's Table I values (as printed).
    document_actual : float
        Our reconstruction of the printed "Actual" (``document_actual``).
    exact : float
        The exact closed-form arc ("actual").
    methods : dict
        Method name -> value at dt = H.
    errors : dict
        Method name -> value minus ``exact`` (θ errors wrapped, in degrees).
    """

    heading_deg: float
    variable: str
    printed_actual: float
    printed_simpson: float
    document_actual: float
    exact: float
    methods: dict[str, float]
    errors: dict[str, float]


def body_speeds(left: float, right: float) -> tuple[float, float]:
    """Forward speed v [m/s] and yaw rate ω [rad/s] of :data:`ROBOT` for wheel speeds [rad/s]."""
    v, omega = ROBOT.body_velocity(left, right)
    return float(v), float(omega)


def document_actual(
    heading_deg: float, v: float, omega: float, step: float = STEP_S, n_steps: int = 12
) -> np.ndarray:
    """End pose (x [m], y [m], θ [deg]) of the scheme that reproduces the printed "Actual".

    Euler's method with the heading updated first: θ_{k+1} = θ_k + hω, then
    x_{k+1} = x_k + h·v·cos θ_{k+1}, y_{k+1} = y_k + h·v·sin θ_{k+1}, from (0, 0, θ₀).
    A reconstruction of how document 001's Table I was computed, not a wheelbase method.
    """
    k = np.arange(1, n_steps + 1)
    theta = math.radians(heading_deg) + k * step * omega
    x = step * v * np.sum(np.cos(theta))
    y = step * v * np.sum(np.sin(theta))
    return np.array([x, y, math.degrees(theta[-1])])


def _printed_residuals(end_pose, metres_per_degree: float = 0.1) -> np.ndarray:
    """Residuals of end poses against the printed "Actual": x, y [m] and θ [deg] scaled."""
    residuals = []
    for heading in HEADINGS_DEG:
        x, y, theta = end_pose(heading)
        px, py, ptheta = PRINTED[heading]["actual"]
        residuals += [x - px, y - py, (theta - ptheta) * metres_per_degree]
    return np.array(residuals)


def fit_document_actual() -> tuple[float, float]:
    """Fit v [m/s] and ω [rad/s] of ``document_actual`` (12 steps of H) to Table I."""
    fit = least_squares(
        lambda p: _printed_residuals(lambda h: document_actual(h, p[0], p[1])),
        x0=[2.0, -0.2],
        xtol=1e-14,
        ftol=1e-14,
    )
    return float(fit.x[0]), float(fit.x[1])


def fit_exact_arc() -> tuple[tuple[float, float, float], float]:
    """Least-squares fit of (ω_L, ω_R [rad/s], T [s]) of the exact arc to the printed "Actual".

    Returns the fitted inputs and the largest residual [m]; the residual stays large because no
    arc has its chord at −37.8° with a −69.8° turn (see the module docstring).
    """

    def end_pose(params, heading):
        left, right, duration = params
        v, omega = body_speeds(left, right)
        theta0 = math.radians(heading)
        theta1 = theta0 + omega * duration
        # The arc in closed form: (v/ω)(sin θ₁ − sin θ₀, cos θ₀ − cos θ₁), ω ≠ 0 here.
        x = v / omega * (math.sin(theta1) - math.sin(theta0))
        y = v / omega * (math.cos(theta0) - math.cos(theta1))
        return x, y, math.degrees(theta1)

    fit = least_squares(
        lambda p: _printed_residuals(lambda h: end_pose(p, h), 1.0),
        x0=[*WHEEL_SPEEDS, DURATION_S],
        x_scale=[10.0, 10.0, 1.0],
    )
    residuals = _printed_residuals(lambda h: end_pose(fit.x, h), 1.0)
    worst = float(np.max(np.abs(np.delete(residuals, np.s_[2::3]))))
    return (float(fit.x[0]), float(fit.x[1]), float(fit.x[2])), worst


def simpson_error_bound(
    v: float, omega: float, duration: float, step: float, node_spacing: float | None = None
) -> float:
    """Simpson's error bound [m] on x or y after ``duration`` s of constant (v, ω).

    |S − I| ≤ T·h_s⁴·max|f⁗|/180 with f = v·cos θ(t), f⁗ = vω⁴cos θ(t), so
    T·h_s⁴·|v|·ω⁴/180. ``node_spacing`` h_s defaults to ``step / 2`` (wheelbase's ``simpson``
    puts nodes at the start, middle and end of each step).
    """
    spacing = step / 2.0 if node_spacing is None else node_spacing
    return duration * spacing**4 * abs(v) * omega**4 / 180.0


def table1(
    wheel_speeds: tuple[float, float] = WHEEL_SPEEDS,
    duration: float = DURATION_S,
    step: float = STEP_S,
) -> list[Row]:
    """Table I with our methods: one :class:`Row` per heading and variable.

    Parameters
    ----------
    wheel_speeds : (float, float)
        (left, right) wheel angular speeds [rad/s], held constant.
    duration : float
        T [s].
    step : float
        H [s], the step of every method.
    """
    v, omega = body_speeds(*wheel_speeds)
    rows = []
    for heading in HEADINGS_DEG:
        pose0 = [0.0, 0.0, math.radians(heading)]
        ends = {
            method: simulate(ROBOT, pose0, wheel_speeds, duration, step, method).poses[-1]
            for method in ("exact", *METHOD_COLUMNS)
        }
        reconstructed = document_actual(heading, v, omega, step, round(duration / step))
        exact = ends["exact"]
        for index, variable in enumerate(VARIABLES):
            document_value = float(reconstructed[index])
            if variable == "theta":  # wrap the reconstruction like the poses
                document_value = math.degrees(wrap_angle(math.radians(document_value)))
            rows.append(
                Row(
                    heading_deg=heading,
                    variable=variable,
                    printed_actual=PRINTED[heading]["actual"][index],
                    printed_simpson=PRINTED[heading]["simpson"][index],
                    document_actual=document_value,
                    exact=_value(exact, index),
                    methods={m: _value(ends[m], index) for m in METHOD_COLUMNS},
                    errors={m: _error(ends[m], exact, index) for m in METHOD_COLUMNS},
                )
            )
    return rows


def _value(pose: np.ndarray, index: int) -> float:
    """Component ``index`` of a pose, θ in degrees."""
    return math.degrees(pose[2]) if index == 2 else float(pose[index])


def _error(pose: np.ndarray, reference: np.ndarray, index: int) -> float:
    """Component ``index`` of ``pose − reference``, θ wrapped and in degrees."""
    difference = pose[index] - reference[index]
    return math.degrees(wrap_angle(difference)) if index == 2 else float(difference)


CSV_HEADER = [
    "heading_deg",
    "variable",
    "unit",
    "printed_actual",
    "printed_simpson",
    "printed_error",
    "document_actual_reconstructed",
    "exact",
    *[f"{name}{suffix}" for name in METHOD_COLUMNS for suffix in ("", "_error")],
]


def write_csv(rows: list[Row], path: Path, *, overwrite: bool = False) -> Path:
    """Write the table to ``path`` (refuses to replace a file unless ``overwrite``)."""
    if path.exists() and not overwrite:
        raise FileExistsError(f"{path} exists; pass --overwrite to replace it")
    with path.open("w", newline="") as handle:
        writer = csv.writer(handle)
        writer.writerow(CSV_HEADER)
        for row in rows:
            cells = [row.heading_deg, row.variable, "deg" if row.variable == "theta" else "m"]
            cells += [row.printed_actual, row.printed_simpson]
            cells += [row.printed_simpson - row.printed_actual, row.document_actual, row.exact]
            for name in METHOD_COLUMNS:
                cells += [row.methods[name], row.errors[name]]
            writer.writerow([repr(float(c)) if isinstance(c, float) else c for c in cells])
    return path


def print_table(rows: list[Row]) -> None:
    """Print the table with rich."""
    from rich.console import Console
    from rich.table import Table

    v, omega = body_speeds(*WHEEL_SPEEDS)
    table = Table(
        title="Document 001, Table I: exact arc vs the integrators (x, y in m; θ in deg)",
        caption=(
            f"r = {WHEEL_RADIUS_M} m, L = {TRACK_M} m, (ω_L, ω_R) = {WHEEL_SPEEDS} rad/s "
            f"(v = {v:.4f} m/s, ω = {omega:.4f} rad/s), T = {DURATION_S:g} s, H = {STEP_S} s. "
            "Errors are method − exact."
        ),
    )
    for header in ("θ₀", "var", "printed actual", "printed Simpson", "doc actual (rebuilt)"):
        table.add_column(header, justify="right")
    table.add_column("exact", justify="right", style="bold")
    for name in METHOD_COLUMNS:
        table.add_column(name, justify="right")
        table.add_column("error", justify="right", style="dim")
    for row in rows:
        first = row.variable == "x"
        cells = [f"{row.heading_deg:g}°" if first else "", row.variable]
        digits = 1 if row.variable == "theta" else 2
        cells += [f"{row.printed_actual:.{digits}f}", f"{row.printed_simpson:.{digits}f}"]
        cells += [f"{row.document_actual:.{digits + 2}f}", f"{row.exact:.6f}"]
        for name in METHOD_COLUMNS:
            cells += [f"{row.methods[name]:.6f}", f"{row.errors[name]:.1e}"]
        table.add_row(*cells, end_section=row.variable == "theta")
    Console().print(table)


def plot_arcs(path: Path, *, overwrite: bool = False) -> Path:
    """Draw the exact arc from each initial heading with the printed "Actual" and "Simpson's"
    end points and our reconstruction of "Actual" (``document_actual``); write ``path`` (PNG).
    """
    import matplotlib

    matplotlib.use("Agg")
    from matplotlib.figure import Figure

    from wheelbase import simulate
    from wheelbase.plot import save_figure

    v, omega = body_speeds(*WHEEL_SPEEDS)
    fig = Figure(figsize=(6.4, 5.2), layout="constrained")
    ax = fig.add_subplot()
    for k, heading in enumerate(HEADINGS_DEG):
        arc = simulate(ROBOT, [0.0, 0.0, math.radians(heading)], WHEEL_SPEEDS, DURATION_S,
                       STEP_S / 20, "exact")  # fmt: skip
        colour = f"C{k}"
        ax.plot(*arc.poses[:, :2].T, color=colour, label=f"exact arc from {heading:g}°")
        printed = PRINTED[heading]
        ax.plot(*printed["actual"][:2], "o", mfc="none", color=colour, ms=9)
        ax.plot(*printed["simpson"][:2], "s", mfc="none", color=colour, ms=7)
        ax.plot(*document_actual(heading, v, omega)[:2], "x", color=colour, ms=8)
    ax.plot([], [], "ko", mfc="none", label='printed "Actual"')
    ax.plot([], [], "ks", mfc="none", label='printed "Simpson\'s"')
    ax.plot([], [], "kx", label="heading-first Euler (reproduces the printed Actual)")
    ax.plot(0, 0, "k+", ms=10)
    ax.set_aspect("equal")
    ax.grid(True, alpha=0.3)
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_title("Document 001, Table I: 6 s at (ω_L, ω_R) = (222.77, 206.53) rad/s")
    ax.legend(fontsize=7, loc="lower left")
    return save_figure(fig, path, overwrite=overwrite)


def main(argv: list[str] | None = None) -> list[Row]:
    """Print Table I, write it to CSV and return its rows."""
    parser = argparse.ArgumentParser(description="Document 001, Table I, reproduced")
    parser.add_argument("--out", type=Path, default=Path("doc001_table1.csv"), help="CSV file")
    parser.add_argument("--overwrite", action="store_true", help="replace an existing CSV")
    args = parser.parse_args(argv)
    rows = table1()
    print_table(rows)
    v, omega = body_speeds(*WHEEL_SPEEDS)
    fitted_v, fitted_omega = fit_document_actual()
    inputs, worst = fit_exact_arc()
    bound = simpson_error_bound(v, omega, DURATION_S, STEP_S)
    worst_simpson = max(abs(r.errors["simpson"]) for r in rows if r.variable != "theta")
    print(
        f"document's 'Actual' = 12 heading-first Euler steps of H: fitted v = {fitted_v:.5f} "
        f"m/s, ω = {fitted_omega:.6f} rad/s (used: v = {v:.5f}, ω = {omega:.6f})"
    )
    print(
        f"best exact arc fit to the printed 'Actual': (ω_L, ω_R, T) = "
        f"({inputs[0]:.2f}, {inputs[1]:.2f}, {inputs[2]:.3f}), residual up to {worst:.2f} m"
    )
    print(f"Simpson: largest position error {worst_simpson:.2e} m <= bound {bound:.2e} m")
    path = write_csv(rows, args.out, overwrite=args.overwrite)
    figure = plot_arcs(args.out.with_suffix(".png"), overwrite=args.overwrite)
    print(f"wrote {path} and {figure}")
    return rows


if __name__ == "__main__":
    main()
