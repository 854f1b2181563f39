"""``wheelbase goto`` and ``wheelbase calibrate``: document 003's go-to-goal loop and UMBmark.

``wheelbase goto --goal 1,1 [--goal -1,1 ...] --out DIR`` drives the simulated robot of
:class:`~wheelbase.control.goal.DriveTrain` to each goal through the full loop (set-points in
RPM → PI speed loop → PWM → motor → encoder ticks → odometry) and writes ``routes.png``,
``log.csv``, ``route.gif`` (unless ``--no-gif``) and ``metrics.json``. Goals are in metres
like every length on the command line, or written with their unit (document 003 Fig. 8's
``--goal 100cm,100cm``; :mod:`wheelbase.commands.options`); everything written is in metres.

``wheelbase calibrate --ed 1.005 --eb 1.02 --out DIR`` runs UMBmark on a robot with those errors
and writes ``before_after.png`` and ``metrics.json`` (E_max,syst before/after and the
corrections).
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from types import SimpleNamespace
from typing import Annotated, Any

import numpy as np
import typer

from wheelbase._validate import integer
from wheelbase.commands.options import out_option, point_option
from wheelbase.errors import ConfigError

__all__ = ["CALIBRATE_FILES", "GOTO_FILES", "plot_calibration", "register"]

GOTO_FILES: tuple[str, ...] = ("routes.png", "log.csv", "route.gif", "metrics.json")
"""What ``wheelbase goto`` writes: ``log.csv`` is the engine's long format (a ``robot`` column,
one robot per goal, with the speed loop's set-points, measured speeds and duty)."""
CALIBRATE_FILES: tuple[str, ...] = ("before_after.png", "metrics.json")


def _prepare(out: Path, names: tuple[str, ...], force: bool) -> dict[str, Path]:
    """Output paths in ``out``; refuse to overwrite unless ``force``."""
    out = Path(out)
    if out.exists() and not out.is_dir():
        raise ConfigError(f"--out must be a folder (got the file {out})")
    paths = {name: out / name for name in names}
    existing = [str(p) for p in paths.values() if p.exists()]
    if existing and not force:
        raise FileExistsError(f"{', '.join(existing)} exists; pass --force to overwrite")
    out.mkdir(parents=True, exist_ok=True)
    return paths


def _plot_routes(log: Any, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6.5, 6.0))
    for index in range(log.n_robots):
        colour = f"C{index % 10}"
        n, goal = int(log.length[index]), log.goal[index, :2]
        ax.plot(*log.true_pose[index, :n, :2].T, color=colour, lw=2,
                label=f"goal ({goal[0]:g}, {goal[1]:g}) m")  # fmt: skip
        ax.plot(*log.estimated_pose[index, :n, :2].T, color=colour, lw=1, ls="--")
        ax.plot(*goal, marker="*", ms=12, color=colour)
    ax.plot(0, 0, "ko")
    ax.plot([], [], "k--", lw=1, label="odometry estimate")
    ax.set_aspect("equal")
    ax.grid(True, alpha=0.3)
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_title("Go-to-goal through speed loop, motors, encoders and odometry")
    ax.legend(fontsize=8, loc="best")
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)


def _animate(log: Any, path: Path, overwrite: bool) -> None:
    from wheelbase.plot import animate

    # every robot's poses (T, N, 3); a robot that has arrived stays where it stopped
    result = SimpleNamespace(t=log.t, poses=np.swapaxes(log.true_pose, 0, 1))
    animate(result, path, footprint=(0.2, 0.17), overwrite=overwrite, max_frames=60, title="goto")


def plot_calibration(cal: Any, path: Path) -> None:
    """Draw a UMBmark calibration (true paths before and after, return errors) into ``path``.

    Parameters
    ----------
    cal : wheelbase.odometry.calibration.UMBmarkCalibration
        What :func:`wheelbase.odometry.calibrate_umbmark` returns.
    path : pathlib.Path
        PNG file (replaced if it exists).
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (left, right) = plt.subplots(1, 2, figsize=(11, 5))
    for name, result, style in (("before", cal.before, "-"), ("after", cal.after, ":")):
        for paths, colour in ((result.paths_cw, "tab:red"), (result.paths_ccw, "tab:blue")):
            for k, run in enumerate(paths):
                label = f"{'cw' if colour == 'tab:red' else 'ccw'} {name}" if k == 0 else None
                left.plot(*run[:, :2].T, style, color=colour, lw=1, alpha=0.7, label=label)
    left.set_aspect("equal")
    left.grid(True, alpha=0.3)
    left.set_xlabel("x [m]")
    left.set_ylabel("y [m]")
    left.set_title("True paths of the square test")
    left.legend(fontsize=8)
    for name, result, marker in (("before", cal.before, "o"), ("after", cal.after, "^")):
        for errors, cg, colour, tag in (
            (result.errors_cw, result.cg_cw, "tab:red", "cw"),
            (result.errors_ccw, result.cg_ccw, "tab:blue", "ccw"),
        ):
            right.scatter(*errors.T, marker=marker, color=colour, alpha=0.6, label=f"{tag} {name}")
            right.plot(*cg, marker="x", ms=12, mew=2, color=colour)
    right.axhline(0, color="k", lw=0.5)
    right.axvline(0, color="k", lw=0.5)
    right.set_aspect("equal", adjustable="datalim")
    right.grid(True, alpha=0.3)
    right.set_xlabel("return error x [m]")
    right.set_ylabel("return error y [m]")
    right.set_title(
        f"E_max,syst {cal.before.e_max_syst:.3f} m → {cal.after.e_max_syst:.4f} m "
        f"({cal.reduction:.0f}×)"
    )
    right.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)


def register(app: typer.Typer) -> None:
    """Add ``goto`` and ``calibrate`` to the ``wheelbase`` app.

    Parameters
    ----------
    app : typer.Typer
        The main application (or a test app).
    """

    @app.command()
    def goto(
        out: Annotated[Path, out_option("goto", ", ".join(GOTO_FILES))] = "wheelbase-goto",
        goal: Annotated[
            list[np.ndarray] | None,
            point_option(
                "--goal",
                "A goal (repeat for several; default: document 003 Fig. 8's (1, 1), (-1, 1), "
                "(-1, -1), (1, -1) m)",
            ),
        ] = None,
        ed: float = typer.Option(1.0, "--ed", help="Real wheel-diameter ratio E_d = D_R/D_L [-]."),
        eb: float = typer.Option(1.0, "--eb", help="Real/nominal track ratio E_b [-]."),
        method: str = typer.Option(
            "exact", "--method", help="Odometry update: euler (doc 003), midpoint or exact."
        ),
        seed: int = typer.Option(0, "--seed", help="Seed of the random encoder errors."),
        gif: bool = typer.Option(True, "--gif/--no-gif", help="Write route.gif."),
        force: bool = typer.Option(False, "--force", help="Overwrite existing files."),
    ) -> None:
        """Drive to goals with document 003's go-to-goal loop; write routes, log, GIF, metrics."""
        from wheelbase.control.goal import FIGURE8_GOALS, DriveTrain
        from wheelbase.odometry.error_model import OdometryErrors
        from wheelbase.sim import run_go_to_goal

        goals = [tuple(g) for g in goal] if goal else list(FIGURE8_GOALS)
        seed = integer("seed", seed, minimum=0, maximum=2**63 - 1)  # the engine's int64 seeds
        drive = DriveTrain(errors=OdometryErrors(ed, eb), odometry_method=method)
        names = GOTO_FILES if gif else tuple(n for n in GOTO_FILES if n != "route.gif")
        paths = _prepare(out, names, force)
        log = run_go_to_goal(goals, drive=drive, seed=seed)  # every goal, one robot each
        _plot_routes(log, paths["routes.png"])
        log.to_csv(paths["log.csv"], overwrite=True)
        if gif:
            _animate(log, paths["route.gif"], overwrite=True)
        metrics = {
            "goals": [
                {
                    "goal": [float(log.goal[i, 0]), float(log.goal[i, 1])],
                    "status": row["status"],
                    # a goal the robot starts on leaves no motion to measure: None
                    "true_final_error_m": row.get("final_position_error_true_m"),
                    "odometry_final_error_m": row.get("final_position_error_estimated_m"),
                    "odometry_drift_m": row.get("odometry_drift_m"),
                    "time_s": row["duration_s"],
                }
                for i, row in enumerate(log.metrics())
            ],
            "robot": {
                "wheel_radius_m": drive.model.wheel_radius,
                "half_track_m": drive.model.half_track,
                "pulses_per_revolution": drive.encoder.pulses_per_revolution,
                "diameter_ratio": ed,
                "track_ratio": eb,
                "odometry_method": method,
            },
        }
        paths["metrics.json"].write_text(json.dumps(metrics, indent=2) + "\n")
        for entry in metrics["goals"]:
            x, y = entry["goal"]
            true_error, odometry_error = (
                "n/a (no motion)" if value is None else f"{value:.4f} m"
                for value in (entry["true_final_error_m"], entry["odometry_final_error_m"])
            )
            typer.echo(
                f"goal ({x:g}, {y:g}) m: true error {true_error}, odometry error {odometry_error}"
            )
        typer.echo(f"wrote {', '.join(str(p) for p in paths.values())}")

    @app.command()
    def calibrate(
        out: Annotated[
            Path, out_option("calibrate", ", ".join(CALIBRATE_FILES))
        ] = "wheelbase-calibrate",
        ed: float = typer.Option(1.005, "--ed", help="Injected wheel-diameter ratio E_d [-]."),
        eb: float = typer.Option(1.02, "--eb", help="Injected track ratio E_b [-]."),
        side: float = typer.Option(4.0, "--side", help="Side of the square [m]."),
        runs: int = typer.Option(5, "--runs", help="Runs in each direction."),
        slip: float = typer.Option(0.0, "--slip", help="Random wheel slip per segment [-]."),
        iterations: int = typer.Option(1, "--iterations", help="Test-and-correct rounds."),
        seed: int = typer.Option(0, "--seed", help="Seed of the random errors."),
        force: bool = typer.Option(False, "--force", help="Overwrite existing files."),
    ) -> None:
        """UMBmark: square test with injected E_d, E_b; corrections; test again."""
        from wheelbase.odometry.calibration import calibrate_umbmark

        cal = calibrate_umbmark(
            ed, eb, side=side, runs=runs, slip_std=slip, iterations=iterations, seed=seed
        )
        paths = _prepare(out, CALIBRATE_FILES, force)
        plot_calibration(cal, paths["before_after.png"])
        corr = cal.correction
        metrics = {
            "e_max_syst_before_m": cal.before.e_max_syst,
            "e_max_syst_after_m": cal.after.e_max_syst,
            "reduction": cal.reduction,
            "track_m": corr.track,
            "scale_left": corr.scale_left,
            "scale_right": corr.scale_right,
            "diameter_ratio_estimate": corr.diameter_ratio,
            "track_ratio_estimate": corr.track_ratio,
            "alpha_rad": corr.alpha,
            "beta_rad": corr.beta,
        }
        if not all(math.isfinite(v) for v in metrics.values()):
            raise ConfigError("the calibration produced non-finite figures")
        paths["metrics.json"].write_text(json.dumps(metrics, indent=2) + "\n")
        typer.echo(
            f"E_max,syst {cal.before.e_max_syst:.4f} m -> {cal.after.e_max_syst:.5f} m "
            f"({cal.reduction:.1f}x); track {corr.track:.5f} m, scale left {corr.scale_left:.6f}, "
            f"right {corr.scale_right:.6f}"
        )
        typer.echo(f"wrote {', '.join(str(p) for p in paths.values())}")
