"""The ``wheelbase`` command line: a thin layer over the Python API.

Commands
--------
``wheelbase simulate``
    Simulate one kinematic model under constant inputs (one :func:`wheelbase.simulate` call) and
    write ``trajectory.csv``, ``states.png``, ``path.png`` and ``animation.gif``.
``wheelbase kinematics-demo``
    Document 000 §3.2's three wheel-speed cases on one plot and the animation of case 1.
``wheelbase demo`` / ``run`` / ``batch`` / ``schema``
    The closed loop on scenario files (:mod:`wheelbase.commands.run`).

Angles, rates, lengths and poses follow one rule, parsed by :mod:`wheelbase.commands.options`
(angles in degrees unless written ``1.57rad``, rates in rad/s, lengths in metres, poses
``X,Y,HEADING``), converted to SI on entry. Every :class:`~wheelbase.errors.WheelbaseError`,
``FileExistsError``, ``OSError`` of a file or folder and usage error ends the program with one
red line ``error: ...`` on stderr and exit code 2; no traceback. What commands print goes
through :mod:`wheelbase.commands.output`. Sub-commands of other areas live in
:mod:`wheelbase.commands` (each module there has ``register(app)``) and are added here.
"""

from __future__ import annotations

import importlib
import math
import pkgutil
import sys
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Annotated, Any

import numpy as np
import typer
from rich.table import Table
from rich.text import Text

from wheelbase._validate import check_choice, finite, positive
from wheelbase.commands.options import (
    ANGLE_RULE,
    OUT_RULE,
    PoseGroup,
    angle_option,
    out_option,
    pose_option,
    rate_option,
)
from wheelbase.commands.output import console as make_console
from wheelbase.commands.output import plural
from wheelbase.errors import ConfigError, WheelbaseError
from wheelbase.integrate import METHODS, SimResult, simulate

__all__ = ["app"]

MODELS: tuple[str, ...] = (
    "diffdrive",
    "unicycle",
    "twist",
    "bicycle",
    "rear-bicycle",
    "ackermann",
    "mecanum",
    "omni",
)
SIMULATE_FILES: tuple[str, ...] = ("trajectory.csv", "states.png", "path.png", "animation.gif")
DEMO_FILES: tuple[str, ...] = ("paths.png", "states.png", "animation.gif")
DEMO_DIR = "wheelbase-kinematics-demo"


# --------------------------------------------------------------------------- errors
def _error_line(message: str) -> None:
    """One red line on stderr (no markup interpretation, no wrapping)."""
    line = " ".join(str(message).split())
    make_console(stderr=True).print(Text(f"error: {line}", style="red"), soft_wrap=True)


class _OneLineErrors(PoseGroup):
    """Turns usage errors and wheelbase errors of any command into one line and exit code 2.

    A :class:`~wheelbase.commands.options.PoseGroup`: pose flags take ``X Y HEADING`` too.

    Commands raise; this wrapper (the group's ``main``, which both the console script and
    typer's CliRunner call) reports. Other exceptions are bugs and keep their traceback.
    """

    def main(self, *args: Any, standalone_mode: bool = True, **kwargs: Any) -> Any:
        if not standalone_mode:
            return super().main(*args, standalone_mode=False, **kwargs)
        try:
            code = super().main(*args, standalone_mode=False, **kwargs)
        except (WheelbaseError, FileExistsError) as error:
            _error_line(str(error))
            sys.exit(2)
        except OSError as error:  # a folder that cannot be made or a file that cannot be written
            where = f": {error.filename}" if error.filename else ""
            _error_line(f"{error.strerror or error}{where}")
            sys.exit(2)
        except typer.Abort:
            _error_line("aborted")
            sys.exit(1)
        except Exception as error:
            # click's usage errors (typer may vendor click, so match by behaviour, not type).
            if type(error).__name__ == "NoArgsIsHelpError":  # bare `wheelbase`: the help
                typer.echo(error.format_message())
                sys.exit(0)
            if hasattr(error, "format_message") and hasattr(error, "exit_code"):
                hint = ""
                context = getattr(error, "ctx", None)
                if context is not None:
                    hint = f" (see '{context.command_path} --help')"
                _error_line(f"{error.format_message()}{hint}")
                sys.exit(error.exit_code)
            raise
        sys.exit(code if isinstance(code, int) else 0)


app = typer.Typer(
    cls=_OneLineErrors,
    name="wheelbase",
    help=f"Model, simulate, plan for and control wheeled mobile robots. {ANGLE_RULE} {OUT_RULE}",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_show_locals=False,
    rich_markup_mode=None,  # help texts hold units in brackets, e.g. [rad/s]: not markup
)


def _version(value: bool) -> None:
    if value:
        from wheelbase import __version__

        typer.echo(f"wheelbase {__version__}")
        raise typer.Exit()


@app.callback()
def _main(
    version: bool = typer.Option(
        False,
        "--version",
        callback=_version,
        is_eager=True,
        help="Print the version and exit.",
    ),
) -> None:
    """Model, simulate, plan for and control wheeled mobile robots."""


# --------------------------------------------------------------------------- models
@dataclass(frozen=True)
class _Built:
    model: Any
    inputs: tuple[float, ...]
    footprint: tuple[float, float]


@dataclass(frozen=True)
class _Spec:
    options: tuple[str, ...]
    build: Callable[[dict[str, Any]], _Built]


def _need(given: dict[str, Any], name: str, unit: str, model: str) -> float:
    value = given.get(name)
    if value is None:
        flag = "--" + name.replace("_", "-")
        raise ConfigError(f"--model {model} needs {flag} [{unit}]")
    return finite(name, value, unit)


def _default(given: dict[str, Any], name: str, value: float) -> float:
    return value if given.get(name) is None else given[name]


def _build_diffdrive(given: dict[str, Any]) -> _Built:
    from wheelbase.models import DiffDrive

    robot = DiffDrive(_default(given, "wheel_radius", 0.05), _default(given, "half_track", 0.2))
    inputs = (
        _need(given, "left", "rad/s", "diffdrive"),
        _need(given, "right", "rad/s", "diffdrive"),
    )
    # Document 000 §3.2, program 2, draws the robot 0.75 m long and 2d wide.
    return _Built(robot, inputs, (0.75, 2.0 * robot.half_track))


def _build_unicycle(given: dict[str, Any]) -> _Built:
    from wheelbase.models import Unicycle

    inputs = (_need(given, "v", "m/s", "unicycle"), _need(given, "omega", "rad/s", "unicycle"))
    return _Built(Unicycle(), inputs, (0.6, 0.4))


def _build_twist(given: dict[str, Any]) -> _Built:
    from wheelbase.models import BodyTwist

    inputs = tuple(finite(n, _default(given, n, 0.0), u) for n, u in _TWIST_UNITS)
    return _Built(BodyTwist(), inputs, (0.6, 0.4))  # document 000 §3.2, program 1


_TWIST_UNITS = (("u", "m/s"), ("v", "m/s"), ("r", "rad/s"))


def _steering(given: dict[str, Any], model: str) -> tuple[float, float]:
    speed = _need(given, "speed", "m/s", model)
    if given.get("steering") is None:
        raise ConfigError(f"--model {model} needs --steering [deg, or e.g. 0.2rad]")
    return speed, finite("steering", given["steering"], "rad")


def _max_steering(given: dict[str, Any]) -> dict[str, float]:
    if given.get("max_steering") is None:
        return {}
    return {"max_steering": finite("max_steering", given["max_steering"], "rad")}


def _build_bicycle(given: dict[str, Any]) -> _Built:
    from wheelbase.models.bicycle import Bicycle

    wheel_base = _default(given, "wheel_base", 1.0)
    robot = Bicycle(wheel_base, **_max_steering(given))
    return _Built(robot, _steering(given, "bicycle"), (1.4 * wheel_base, 0.4 * wheel_base))


def _build_rear_bicycle(given: dict[str, Any]) -> _Built:
    from wheelbase.models.bicycle import RearWheelBicycle

    wheel_base = _default(given, "wheel_base", 1.0)
    robot = RearWheelBicycle(wheel_base, **_max_steering(given))
    return _Built(robot, _steering(given, "rear-bicycle"), (1.4 * wheel_base, 0.4 * wheel_base))


def _build_ackermann(given: dict[str, Any]) -> _Built:
    from wheelbase.models.bicycle import Ackermann

    wheel_base = _default(given, "wheel_base", 1.0)
    track = _default(given, "track", 0.6)
    robot = Ackermann(wheel_base, track, **_max_steering(given))
    return _Built(robot, _steering(given, "ackermann"), (1.4 * wheel_base, 1.2 * track))


def _holonomic_inputs(robot: Any, given: dict[str, Any]) -> tuple[float, ...]:
    twist = [finite(n, _default(given, n, 0.0), u) for n, u in _TWIST_UNITS]
    return tuple(float(w) for w in robot.inverse(twist))


def _build_mecanum(given: dict[str, Any]) -> _Built:
    from wheelbase.models.wheeled import mecanum4

    half_length = _default(given, "half_length", 0.2)
    half_width = _default(given, "half_width", 0.15)
    robot = mecanum4(_default(given, "wheel_radius", 0.05), half_length, half_width)
    footprint = (2.0 * half_length + 0.1, 2.0 * half_width + 0.1)
    return _Built(robot, _holonomic_inputs(robot, given), footprint)


def _build_omni(given: dict[str, Any]) -> _Built:
    from wheelbase.models.wheeled import omni3

    base_radius = _default(given, "base_radius", 0.2)
    robot = omni3(_default(given, "wheel_radius", 0.05), base_radius)
    side = 2.0 * base_radius + 0.1
    return _Built(robot, _holonomic_inputs(robot, given), (side, side))


_SPECS: dict[str, _Spec] = {
    "diffdrive": _Spec(("wheel_radius", "half_track", "left", "right"), _build_diffdrive),
    "unicycle": _Spec(("v", "omega"), _build_unicycle),
    "twist": _Spec(("u", "v", "r"), _build_twist),
    "bicycle": _Spec(("wheel_base", "speed", "steering", "max_steering"), _build_bicycle),
    "rear-bicycle": _Spec(("wheel_base", "speed", "steering", "max_steering"), _build_rear_bicycle),
    "ackermann": _Spec(
        ("wheel_base", "track", "speed", "steering", "max_steering"), _build_ackermann
    ),
    "mecanum": _Spec(("wheel_radius", "half_length", "half_width", "u", "v", "r"), _build_mecanum),
    "omni": _Spec(("wheel_radius", "base_radius", "u", "v", "r"), _build_omni),
}


def build_model(name: str, given: dict[str, Any]) -> _Built:
    """The model, its constant inputs and a drawing footprint from the command-line options.

    Raises ConfigError for an unknown model, a missing input, or an option that does not apply.
    """
    check_choice("model", name, MODELS)
    spec = _SPECS[name]
    stray = sorted(k for k, v in given.items() if v is not None and k not in spec.options)
    if stray:
        flags = ", ".join("--" + k.replace("_", "-") for k in stray)
        takes = ", ".join("--" + k.replace("_", "-") for k in spec.options)
        raise ConfigError(f"{flags} does not apply to --model {name} (it takes {takes})")
    return spec.build(given)


# --------------------------------------------------------------------------- output
def _path_length(poses: np.ndarray) -> float:
    return float(np.sum(np.hypot(*np.diff(poses[..., :2], axis=0).T)))


def _check_outputs(out: Path, names: Sequence[str], force: bool) -> list[Path]:
    if out.exists() and not out.is_dir():
        raise ConfigError(f"--out {out} is a file, not a folder")
    paths = [out / name for name in names]
    existing = [p.name for p in paths if p.exists()]
    if existing and not force:
        raise FileExistsError(
            f"{out} already holds {', '.join(existing)}; pass --force to replace "
            f"{'it' if len(existing) == 1 else 'them'}"
        )
    return paths


def _summary(result: SimResult, model_name: str, title: str) -> Table:
    x, y, theta = (round(float(v), 9) + 0.0 for v in result.poses[-1])  # no "-0.000000"
    table = Table(title=title, show_header=False)
    table.add_column("quantity", style="bold")
    table.add_column("value", justify="right")
    table.add_row("model", model_name)
    table.add_row("method", result.method)
    table.add_row("steps", str(result.t.size - 1))
    table.add_row("duration", f"{float(result.t[-1]):g} s")
    table.add_row("final x", f"{x:.6f} m")
    table.add_row("final y", f"{y:.6f} m")
    table.add_row("final θ", f"{theta:.6f} rad ({math.degrees(theta):.3f}°)")
    table.add_row("distance travelled", f"{_path_length(result.poses):.6f} m")
    return table


def _write_figures(
    result: SimResult,
    paths: dict[str, Path],
    footprint: tuple[float, float],
    title: str,
    *,
    gif: bool,
) -> None:
    from wheelbase.plot import animate, plot_path, plot_states, save_figure

    fig, _ = plot_states(result)
    fig.suptitle(title)
    save_figure(fig, paths["states.png"], overwrite=True)
    fig, _ = plot_path(result, footprint=footprint)
    fig.suptitle(title)
    save_figure(fig, paths["path.png"], overwrite=True)
    if gif:
        animate(result, paths["animation.gif"], footprint=footprint, overwrite=True, title=title)


# --------------------------------------------------------------------------- simulate
_NUM = {"show_default": False}


@app.command("simulate")
def simulate_command(
    model: str = typer.Option(
        "diffdrive", "--model", "-m", help=f"Kinematic model: {', '.join(MODELS)}."
    ),
    wheel_radius: float | None = typer.Option(
        None, help="Wheel radius [m] (diffdrive, mecanum, omni; default 0.05).", **_NUM
    ),
    half_track: float | None = typer.Option(
        None, help="Half track d, centre to each wheel [m] (diffdrive; default 0.2).", **_NUM
    ),
    left: float | None = typer.Option(None, help="Left wheel speed [rad/s] (diffdrive)."),
    right: float | None = typer.Option(None, help="Right wheel speed [rad/s] (diffdrive)."),
    v: float | None = typer.Option(
        None,
        "--v",
        help="unicycle: forward speed [m/s]; twist, mecanum, omni: lateral speed, left "
        "positive [m/s] (default 0).",
    ),
    omega: Annotated[float | None, rate_option("--omega", "Yaw rate (unicycle).")] = None,
    u: float | None = typer.Option(
        None, "--u", help="Forward speed [m/s] (twist, mecanum, omni; default 0)."
    ),
    r: Annotated[
        float | None, rate_option("--r", "Yaw rate (twist, mecanum, omni; default 0).")
    ] = None,
    wheel_base: float | None = typer.Option(
        None, help="Axle distance [m] (bicycle, rear-bicycle, ackermann; default 1.0)."
    ),
    track: float | None = typer.Option(
        None, help="Front wheel separation [m] (ackermann; default 0.6)."
    ),
    speed: float | None = typer.Option(
        None, help="Speed [m/s]: front wheel (bicycle) or rear axle (rear-bicycle, ackermann)."
    ),
    steering: Annotated[
        float | None,
        angle_option("--steering", "Steering angle (bicycle, rear-bicycle, ackermann)."),
    ] = None,
    max_steering: Annotated[
        float | None,
        angle_option("--max-steering", "Steering stop (bicycle, rear-bicycle, ackermann)."),
    ] = None,
    half_length: float | None = typer.Option(
        None, help="Centre to front/rear axle [m] (mecanum; default 0.2)."
    ),
    half_width: float | None = typer.Option(
        None, help="Centre to left/right wheels [m] (mecanum; default 0.15)."
    ),
    base_radius: float | None = typer.Option(
        None, help="Centre to each wheel [m] (omni; default 0.2)."
    ),
    t_end: float = typer.Option(10.0, help="Duration [s], > 0."),
    dt: float = typer.Option(0.1, help="Time step [s], 0 < dt <= t-end."),
    method: str = typer.Option("rk4", help=f"Integrator: {', '.join(METHODS)}."),
    pose0: Annotated[np.ndarray, pose_option("--pose0", "Initial pose (default 0,0,0):")] = "0,0,0",
    out: Annotated[
        Path, out_option("simulate", "trajectory.csv, states.png, path.png, animation.gif")
    ] = "wheelbase-simulate",
    force: bool = typer.Option(False, "--force", help="Replace existing output files."),
    gif: bool = typer.Option(True, "--gif/--no-gif", help="Write animation.gif."),
    length: float | None = typer.Option(
        None, help="Robot length drawn in the figures [m] (default: per model)."
    ),
    width: float | None = typer.Option(
        None, help="Robot width drawn in the figures [m] (default: per model)."
    ),
) -> None:
    """Simulate a model under constant inputs; write trajectory.csv, states.png, path.png and
    animation.gif to --out.

    Example (document 000 §3.2, case 1): wheelbase simulate --model diffdrive --left 0.8
    --right 0.6 --t-end 100 --dt 0.1 --method euler --pose0 0,0,90 --out DIR
    """
    given = {
        "wheel_radius": wheel_radius,
        "half_track": half_track,
        "left": left,
        "right": right,
        "v": v,
        "omega": omega,
        "u": u,
        "r": r,
        "wheel_base": wheel_base,
        "track": track,
        "speed": speed,
        "steering": steering,
        "max_steering": max_steering,
        "half_length": half_length,
        "half_width": half_width,
        "base_radius": base_radius,
    }
    check_choice("method", method, METHODS)
    built = build_model(model, given)
    start = pose0
    footprint = (
        positive("length", length, "m") if length is not None else built.footprint[0],
        positive("width", width, "m") if width is not None else built.footprint[1],
    )
    names = SIMULATE_FILES if gif else SIMULATE_FILES[:-1]
    paths = dict(zip(names, _check_outputs(Path(out), names, force), strict=True))
    result = simulate(built.model, start, built.inputs, t_end, dt, method)
    Path(out).mkdir(parents=True, exist_ok=True)
    result.to_csv(paths["trajectory.csv"], overwrite=True)
    title = f"{model}, {method}, dt = {dt:g} s"
    _write_figures(result, paths, footprint, title, gif=gif)
    console = make_console()
    console.print(_summary(result, model, "wheelbase simulate"))
    console.print(
        f"wrote {plural(len(paths), 'file')} to {out}/: " + ", ".join(names),
        soft_wrap=True,
        markup=False,
    )


# --------------------------------------------------------------------------- demo
DEMO_CASES: tuple[tuple[float, float], ...] = ((0.8, 0.6), (0.6, 0.6), (0.6, -0.6))
"""Document 000 §3.2's wheel speeds (ω_left, ω_right) [rad/s], figures 3.9–3.11."""


def run_demo(out: str | Path = DEMO_DIR) -> tuple[SimResult, dict[str, Path]]:
    """Document 000 §3.2's kinematics demo: three wheel-speed cases and an animation.

    A differential drive with a = 0.05 m, d = 0.2 m starts at (0, 0, π/2) and runs for 100 s
    with Euler steps of 0.1 s under (ω_L, ω_R) = (0.8, 0.6), (0.6, 0.6) and (0.6, −0.6) rad/s.
    Writes ``paths.png`` (the three paths), ``states.png`` (x, y, θ of the three) and
    ``animation.gif`` (case 1) into ``out``, replacing those three files if they exist (the
    demo owns them) and touching nothing else.

    Parameters
    ----------
    out : str or pathlib.Path
        Output folder; created if missing.

    Returns
    -------
    (SimResult, dict of str to pathlib.Path)
        The batch result of the three cases (poses (T, 3, 3)) and the files written, by name.
    """
    from wheelbase.models import DiffDrive
    from wheelbase.plot import animate, plot_path, plot_states, save_figure

    paths = dict(zip(DEMO_FILES, _check_outputs(Path(out), DEMO_FILES, True), strict=True))
    Path(out).mkdir(parents=True, exist_ok=True)
    robot = DiffDrive(wheel_radius=0.05, half_track=0.2)
    pose0 = np.tile([0.0, 0.0, math.pi / 2], (len(DEMO_CASES), 1))
    batch = simulate(robot, pose0, np.array(DEMO_CASES), t_end=100.0, dt=0.1, method="euler")
    footprint = (0.75, 2 * robot.half_track)  # document 000 §3.2, program 2
    labels = [f"ω = ({left:g}, {right:g}) rad/s" for left, right in DEMO_CASES]
    fig, _ = plot_path(batch, footprint=footprint, every=125, label=labels)
    fig.suptitle("Document 000 §3.2: a = 0.05 m, d = 0.2 m, Euler, dt = 0.1 s, 100 s")
    save_figure(fig, paths["paths.png"], overwrite=True)
    states_fig, state_axes = plot_states(batch, label=labels)
    state_axes[0].legend(loc="best", fontsize="small")
    states_fig.suptitle("Document 000 §3.2: x(t), y(t), θ(t)")
    save_figure(states_fig, paths["states.png"], overwrite=True)
    animate(
        batch.robot(0),
        paths["animation.gif"],
        footprint=footprint,
        overwrite=True,
        title="ω = (0.8, 0.6) rad/s",
    )
    return batch, paths


@app.command("kinematics-demo")
def demo_command(
    out: str = typer.Option(
        DEMO_DIR, help="Output folder; the demo replaces only its own files there."
    ),
) -> None:
    """Run document 000 §3.2's kinematics demo: three wheel-speed cases on one plot [SI units]
    and the animation of case 1."""
    batch, paths = run_demo(out)
    console = make_console()
    table = Table(title="document 000 §3.2, Euler, dt = 0.1 s, 100 s")
    for column in ("ω_L, ω_R [rad/s]", "final x [m]", "final y [m]", "final θ [rad]"):
        table.add_column(Text(column), justify="right")
    for case, pose in zip(DEMO_CASES, batch.poses[-1], strict=True):
        table.add_row(f"{case[0]:g}, {case[1]:g}", *(f"{value:.4f}" for value in pose))
    console.print(table)
    console.print(
        f"wrote {', '.join(str(p) for p in paths.values())}", soft_wrap=True, markup=False
    )


# --------------------------------------------------------------------------- other areas
def _register_area_commands() -> None:
    """Add the commands of :mod:`wheelbase.commands` (each module has ``register(app)``)."""
    import wheelbase.commands as package

    for info in sorted(pkgutil.iter_modules(package.__path__), key=lambda i: i.name):
        module = importlib.import_module(f"{package.__name__}.{info.name}")
        register = getattr(module, "register", None)
        if callable(register):
            register(app)


_register_area_commands()
