"""``wheelbase dynamics`` and ``wheelbase track-waypoints`` (document 000 §5.1–§5.3).

``wheelbase dynamics --preset rm100 --torques 0.01 0.012 --t-end 60 --out DIR`` integrates the
forward dynamics under constant wheel torques (left, right) [N·m] and writes ``dynamics.csv``,
``path.png``, ``states.png`` and ``animation.gif``.

``wheelbase track-waypoints --preset rm100 --waypoints "0,0 10,10 20,0 30,0" --peak-velocity 0.1
--out DIR`` builds the trapezoidal trajectory through the waypoints (the feasible variant with
turns in place, or ``--reference document`` for document 000's heading jumps), computes the
inverse dynamics, runs the open loop and (unless ``--no-pid``) the computed-torque PID, and
writes ``reference.csv``, ``tracking.csv``, ``reference.png`` (figures 5.8–5.11),
``tracking.png`` (figures 5.13/5.16), ``animation.gif`` and ``metrics.json`` (keys
``open_loop`` and ``pid``, each the run's :meth:`wheelbase.sim.Log.metrics`:
``tracking_max_position_error_m``, ``tracking_rms_position_error_m``,
``tracking_rms_heading_error_deg``, the wheel torques …); it prints the error table.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from types import SimpleNamespace
from typing import Annotated, Any

import numpy as np
import typer

from wheelbase._io import write_csv
from wheelbase._validate import check_choice, finite, nonnegative, positive
from wheelbase.commands.options import out_option, rate_option
from wheelbase.errors import ConfigError

__all__ = ["DYNAMICS_FILES", "PRESETS", "TRACK_FILES", "parse_waypoints", "register"]

DYNAMICS_FILES: tuple[str, ...] = ("dynamics.csv", "path.png", "states.png", "animation.gif")
TRACK_FILES: tuple[str, ...] = (
    "reference.csv",
    "tracking.csv",
    "reference.png",
    "tracking.png",
    "animation.gif",
    "metrics.json",
)
PRESETS: tuple[str, ...] = ("rm100",)
_FOOTPRINT = (0.66, 0.455)  # RM100 body, document 000 ch. 4


def parse_waypoints(text: str) -> np.ndarray:
    """Parse ``"0,0 10,10 20,0"`` (x,y pairs separated by spaces or ';') into (P, 2) [m].

    Parameters
    ----------
    text : str
        The waypoints.
    """
    pairs = [p for p in str(text).replace(";", " ").split() if p]
    points = []
    for pair in pairs:
        parts = pair.split(",")
        if len(parts) != 2:
            raise ConfigError(f"waypoints must be x,y pairs such as '0,0 10,10' (got {pair!r})")
        try:
            points.append([float(parts[0]), float(parts[1])])
        except ValueError:
            raise ConfigError(f"waypoint {pair!r} is not two numbers") from None
    if len(points) < 2:
        raise ConfigError(f"waypoints need at least two points (got {len(points)})")
    return np.array(points)


def _parse_numbers(text: str, name: str) -> float | tuple[float, ...]:
    try:
        values = tuple(float(v) for v in str(text).replace(",", " ").split())
    except ValueError:
        raise ConfigError(f"{name} must be one or two numbers (got {text!r})") from None
    if len(values) not in (1, 2):
        raise ConfigError(f"{name} must be one or two numbers (got {text!r})")
    return values[0] if len(values) == 1 else values


def _prepare(out: Path, names: tuple[str, ...], force: bool) -> dict[str, Path]:
    """Output paths in ``out``; refuse to overwrite unless ``force``."""
    out = Path(out)
    if out.exists() and not out.is_dir():
        raise ConfigError(f"--out must be a folder (got the file {out})")
    paths = {name: out / name for name in names}
    existing = [p.name for p in paths.values() if p.exists()]
    if existing and not force:
        raise FileExistsError(f"{out} already holds {', '.join(existing)}; pass --force")
    return paths


def _write_csv(path: Path, columns: dict[str, np.ndarray]) -> None:
    write_csv(path, columns, overwrite=True)  # the command checked --force already


def _preset(name: str, unconstrained: bool = False) -> Any:
    from wheelbase.dynamics import RM100

    check_choice("preset", name.lower(), PRESETS)
    robot = RM100
    if unconstrained:
        robot = type(RM100)(RM100.body, RM100.wheel_radius, RM100.half_track, constrained=False)
    return robot


def _save(fig: Any, path: Path) -> None:
    from wheelbase.plot import save_figure

    save_figure(fig, path, overwrite=True)


def register(app: typer.Typer) -> None:
    """Add ``dynamics`` and ``track-waypoints`` to the ``wheelbase`` app.

    Parameters
    ----------
    app : typer.Typer
        The main application (or a test app).
    """

    @app.command("dynamics")
    def dynamics_command(
        out: Annotated[
            Path, out_option("dynamics", ", ".join(DYNAMICS_FILES))
        ] = "wheelbase-dynamics",
        preset: str = typer.Option("rm100", "--preset", help="Robot preset: rm100."),
        torques: tuple[float, float] = typer.Option(
            (0.01, 0.01), "--torques", help="Wheel torques LEFT RIGHT [N·m] (held constant)."
        ),
        t_end: float = typer.Option(60.0, "--t-end", help="Duration [s]."),
        dt: float = typer.Option(0.1, "--dt", help="Output step [s] (step of euler/rk4)."),
        method: str = typer.Option(
            "RK45", "--method", help="RK45, DOP853, Radau, LSODA (solve_ivp), euler or rk4."
        ),
        unconstrained: bool = typer.Option(
            False, "--unconstrained", help="Document 000's 3-DOF model: no no-slip constraint."
        ),
        gif: bool = typer.Option(True, "--gif/--no-gif", help="Write animation.gif."),
        force: bool = typer.Option(False, "--force", help="Overwrite existing files."),
    ) -> None:
        """Forward dynamics from constant wheel torques (document 000 §5.1)."""
        from wheelbase.dynamics import simulate_dynamics
        from wheelbase.plot import animate, plot_path, plot_states

        robot = _preset(preset, unconstrained)
        tau = (finite("torques[0]", torques[0], "N·m"), finite("torques[1]", torques[1], "N·m"))
        paths = _prepare(out, DYNAMICS_FILES, force)
        result = simulate_dynamics(robot, tau, t_end, dt, method=method)
        Path(out).mkdir(parents=True, exist_ok=True)
        _write_csv(paths["dynamics.csv"], result.columns())
        title = f"{preset.upper()}, τ = ({tau[0]:g}, {tau[1]:g}) N·m"
        fig, _ = plot_path(result, footprint=_FOOTPRINT)
        fig.suptitle(title)
        _save(fig, paths["path.png"])
        fig, _ = plot_states(result)
        fig.suptitle(title)
        _save(fig, paths["states.png"])
        if gif:
            animate(result, paths["animation.gif"], footprint=_FOOTPRINT, overwrite=True,
                    title=title)  # fmt: skip
        x, y, psi, u, v, r = result.states[-1]
        typer.echo(
            f"t = {result.t[-1]:g} s: x = {x:.4f} m, y = {y:.4f} m, ψ = {math.degrees(psi):.2f}°, "
            f"u = {u:.4f} m/s, v = {v:.4f} m/s, r = {r:.4f} rad/s"
        )
        written = [p for name, p in paths.items() if gif or name != "animation.gif"]
        typer.echo(f"wrote {', '.join(map(str, written))}")

    @app.command("track-waypoints")
    def track_command(
        out: Annotated[Path, out_option("track-waypoints", ", ".join(TRACK_FILES))] = (
            "wheelbase-track-waypoints"
        ),
        preset: str = typer.Option("rm100", "--preset", help="Robot preset: rm100."),
        waypoints: str = typer.Option(
            "0,0 10,10 20,0 30,0", "--waypoints", help="Waypoints 'x,y x,y ...' [m]."
        ),
        peak_velocity: str = typer.Option(
            "0.1", "--peak-velocity", help="Peak velocity of x and y [m/s]: 'V' or 'VX,VY'."
        ),
        peak_yaw_rate: Annotated[
            float, rate_option("--peak-yaw-rate", "Peak yaw rate of the turns in place")
        ] = 0.2,
        reference_kind: str = typer.Option(
            "feasible",
            "--reference",
            help="feasible (turns in place) or document (heading jumps at the waypoints).",
        ),
        pid: bool = typer.Option(True, "--pid/--no-pid", help="Run the computed-torque PID."),
        tune: bool = typer.Option(False, "--tune", help="Tune the PID by ISE minimisation."),
        bandwidth: float = typer.Option(1.0, "--bandwidth", help="PID pole placement ω [rad/s]."),
        model_error: float = typer.Option(
            0.0, "--model-error", help="Relative error of the controller's mass and inertia [-]."
        ),
        max_torque: float = typer.Option(
            math.inf, "--max-torque", help="Wheel-torque saturation [N·m] (default none)."
        ),
        dt: float = typer.Option(0.01, "--dt", help="Control period [s]."),
        gif: bool = typer.Option(True, "--gif/--no-gif", help="Write animation.gif."),
        force: bool = typer.Option(False, "--force", help="Overwrite existing files."),
    ) -> None:
        """Trapezoidal waypoint trajectory, inverse dynamics, open loop vs computed-torque PID."""
        from rich.table import Table

        from wheelbase.commands.output import console
        from wheelbase.control.torque import ComputedTorquePID, TorqueGains
        from wheelbase.dynamics import inverse_dynamics
        from wheelbase.dynamics_plot import plot_inverse_dynamics, plot_tracking
        from wheelbase.plot import animate
        from wheelbase.sim import track_trajectory, tune_computed_torque
        from wheelbase.trajectory import feasible_trajectory, heading_from_velocity, trapezoidal

        robot = _preset(preset)
        points = parse_waypoints(waypoints)
        vmax = _parse_numbers(peak_velocity, "peak_velocity")
        yaw_rate = peak_yaw_rate
        check_choice("reference", reference_kind, ("feasible", "document"))
        error = nonnegative("model_error", model_error)
        if error >= 1.0:
            raise ConfigError(f"model_error must be < 1 (got {error:g})")
        positive("bandwidth", bandwidth, "rad/s")
        paths = _prepare(out, TRACK_FILES, force)
        if reference_kind == "feasible":
            ref = feasible_trajectory(points, vmax, peak_yaw_rate=yaw_rate, dt=dt)
        else:
            ref = heading_from_velocity(trapezoidal(points, vmax, dt=dt))
        model = robot.with_body(robot.body.scaled(1.0 + error, 1.0 + error))
        inverse = inverse_dynamics(model, ref)
        runs = {"open_loop": track_trajectory(robot, ref, model=model, dt=dt)}
        gains = None
        if pid:
            speed = max(float(np.abs(ref.twist[:, 0]).max()), 1e-3)
            if tune:
                gains = tune_computed_torque(robot, ref, model=model, dt=dt,
                                             max_torque=max_torque)  # fmt: skip
            else:
                gains = TorqueGains.pole_placement(bandwidth, speed=speed)
            controller = ComputedTorquePID(model, gains, max_torque=max_torque)
            runs["pid"] = track_trajectory(robot, ref, controller, dt=dt)
        Path(out).mkdir(parents=True, exist_ok=True)
        columns = {"t": ref.t}
        for k, name in enumerate(("x", "y", "psi", "u", "v", "r", "du", "dv", "dr")):
            columns[name] = ref.reference()[:, k]
        for k, name in enumerate(("Fx", "Fy", "Mz")):
            columns[name] = inverse.force[:, k]
        columns["tau_left"], columns["tau_right"] = inverse.torques.T
        _write_csv(paths["reference.csv"], columns)
        last = runs.get("pid", runs["open_loop"])
        last.to_csv(paths["tracking.csv"], overwrite=True)
        _save(plot_inverse_dynamics(ref, inverse), paths["reference.png"])
        _save(plot_tracking(list(runs.values()), list(runs)), paths["tracking.png"])
        if gif:
            trace = SimpleNamespace(t=last.t, poses=last.true_pose[0])
            animate(trace, paths["animation.gif"], footprint=_FOOTPRINT, overwrite=True,
                    title="pid" if pid else "open_loop")  # fmt: skip
        metrics: dict[str, Any] = {name: run.metrics()[0] for name, run in runs.items()}
        metrics["settings"] = {
            "preset": preset,
            "reference": reference_kind,
            "waypoints_m": points.tolist(),
            "peak_velocity_m_s": vmax,
            "peak_yaw_rate_rad_s": yaw_rate,
            "model_error": error,
            "dt_s": dt,
            "duration_s": ref.duration,
            "half_track_m": robot.half_track,
            "gains": None if gains is None else {"kp": gains.kp, "ki": gains.ki, "kd": gains.kd},
        }
        paths["metrics.json"].write_text(json.dumps(metrics, indent=2) + "\n")
        table = Table(title=f"tracking errors ({reference_kind} reference, {preset})")
        for column in ("run", "max position [m]", "RMS position [m]", "RMS heading [deg]"):
            table.add_column(column, justify="right")
        for name, m in metrics.items():
            if name == "settings":
                continue
            table.add_row(
                name,
                f"{m['tracking_max_position_error_m']:.3g}",
                f"{m['tracking_rms_position_error_m']:.3g}",
                f"{m['tracking_rms_heading_error_deg']:.3g}",
            )
        console().print(table)
        written = [p for name, p in paths.items() if gif or name != "animation.gif"]
        typer.echo(f"wrote {', '.join(map(str, written))}")
