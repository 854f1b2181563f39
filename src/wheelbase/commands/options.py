"""The values typed on the command line: one rule for angles, lengths and poses, one parser each.

The rule (every flag of every command, and every wheelbase file)
----------------------------------------------------------------
- **Angles** (headings, steering angles, tolerances) are in **degrees** unless written with a
  unit: ``90``, ``90deg``, ``90°`` and ``1.5708rad`` are the same heading. Scenario and
  planning-case files use degrees too. The one exception is a format defined elsewhere: the yaw
  of a ROS ``map_server`` YAML's ``origin`` stays in radians, as ROS defines it.
- **Angular rates** are SI, **rad/s**, unless written with a unit (``0.5``, ``0.5rad/s``,
  ``30deg/s``).
- **Lengths** are **metres** unless written with a unit (``1.5``, ``1.5m``, ``150cm``,
  ``1500mm``).
- **Output**: ``--out DIR`` is optional on every command that writes files; its default is
  ``./wheelbase-COMMAND/`` (``wheelbase run``: ``./SCENARIO-NAME/``), created if missing. Files
  already there are kept unless ``--force`` (the two demos replace only their own files).
- A **pose** is ``X,Y,HEADING`` (``--start 1,4,90``); ``--start 1 4 90`` is the same. The values
  after a pose flag are gathered up to the next token that is not a number, so negative numbers
  (``--goal 13.6 9 -90``) are values and the next flag (``--out DIR``) is never swallowed. A
  pose short of values is an error that names the flag. A **point** is ``X,Y`` likewise.

Everything is converted to SI (m, rad, rad/s) on entry; headings are wrapped to (−π, π].

Using it in a command
---------------------
A command of :mod:`wheelbase.commands` declares its options with these factories; the
``wheelbase`` group (:mod:`wheelbase.cli`, a :class:`PoseGroup`; a test app gets the same with
``typer.Typer(cls=PoseGroup)``) gathers the space-separated form for every option made by
:func:`pose_option` and :func:`point_option`::

    from wheelbase.commands.options import angle_option, pose_option

    def command(
        start: Annotated[np.ndarray | None, pose_option("--start", "Start pose.")] = None,
        steering: Annotated[float, angle_option("--steering", "Steering angle.")] = 0.0,
    ) -> None: ...

``start`` then arrives as a float64 array ``(x [m], y [m], θ [rad])`` and ``steering`` in
radians. In Python, :func:`parse_angle`, :func:`parse_rate`, :func:`parse_length` and
:func:`parse_pose` do the same conversions.
"""

from __future__ import annotations

import math
import re
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
import typer
from typer.core import TyperGroup

from wheelbase._validate import finite
from wheelbase._validate import parse_angle as _parse_angle
from wheelbase.errors import ConfigError
from wheelbase.geometry import wrap_angle
from wheelbase.limits import MAX_COORDINATE

__all__ = [
    "ANGLE_RULE",
    "OUT_RULE",
    "POSE_HELP",
    "PoseGroup",
    "VectorParser",
    "angle_option",
    "default_out",
    "gather_vector_values",
    "out_option",
    "parse_angle",
    "parse_length",
    "parse_point",
    "parse_pose",
    "parse_rate",
    "point_option",
    "pose_option",
    "rate_option",
]

ANGLE_RULE = (
    "Angles in degrees unless written 1.57rad; rates in rad/s unless written 30deg/s; lengths "
    "in m unless written 150cm; poses X,Y,HEADING (or X Y HEADING)."
)
"""The rule in one line, for ``wheelbase --help``."""

OUT_RULE = "Files go to --out DIR (default ./wheelbase-COMMAND/; kept unless --force)."
"""The ``--out`` rule in one line, for ``wheelbase --help``."""

POSE_HELP = "x, y [m], heading [deg, or e.g. 1.57rad]"
"""What a pose flag takes, for its help text."""

_LENGTH_UNITS = (("mm", 1e-3), ("cm", 1e-2), ("m", 1.0))
_RATE_UNITS = (("deg/s", math.pi / 180.0), ("°/s", math.pi / 180.0), ("rad/s", 1.0))
_NUMBER = r"[+-]?(?:(?:\d+(?:\.\d*)?|\.\d+)(?:e[+-]?\d+)?|nan|inf(?:inity)?)"
_VALUE = re.compile(rf"{_NUMBER}\s*(?:deg|°|rad|mm|cm|m)?", re.IGNORECASE)


# --------------------------------------------------------------------------- scalars
def parse_angle(text: str | float, name: str = "angle") -> float:
    """An angle typed by a user → radians; a bare number is in degrees.

    Parameters
    ----------
    text : str or float
        ``"90"``, ``"90deg"``, ``"90°"`` or ``"1.57rad"``.
    name : str
        What the angle is, for the error message.

    Returns
    -------
    float
        The angle [rad], not wrapped (a steering stop of 35° stays 35°).

    Raises
    ------
    ConfigError
        If the text is not a finite number with an optional ``deg``/``°``/``rad`` suffix.

    Examples
    --------
    >>> parse_angle("180") == parse_angle("180deg") == parse_angle(f"{math.pi}rad")
    True
    """
    return _parse_angle(text, name, default_unit="deg")


def parse_rate(text: str | float, name: str = "rate") -> float:
    """An angular rate typed by a user → rad/s; a bare number is in rad/s (SI).

    Parameters
    ----------
    text : str or float
        ``"0.5"``, ``"0.5rad/s"`` or ``"30deg/s"`` (``°/s`` too).
    name : str
        What the rate is, for the error message.

    Returns
    -------
    float
        The rate [rad/s].

    Raises
    ------
    ConfigError
        If the text is not a finite number with an optional ``rad/s``/``deg/s`` suffix.

    Examples
    --------
    >>> round(parse_rate("180deg/s"), 12) == round(math.pi, 12), parse_rate("0.5")
    (True, 0.5)
    """
    return _scaled(text, name, _RATE_UNITS, "rad/s", "0.5, 0.5rad/s or 30deg/s")


def parse_length(text: str | float, name: str = "length") -> float:
    """A length typed by a user → metres; a bare number is in metres.

    Parameters
    ----------
    text : str or float
        ``"1.5"``, ``"1.5m"``, ``"150cm"`` or ``"1500mm"``.
    name : str
        What the length is, for the error message.

    Returns
    -------
    float
        The length [m].

    Raises
    ------
    ConfigError
        If the text is not a finite number with an optional ``m``/``cm``/``mm`` suffix.

    Examples
    --------
    >>> parse_length("150cm"), parse_length("-2"), parse_length("5mm")
    (1.5, -2.0, 0.005)
    """
    return _scaled(text, name, _LENGTH_UNITS, "m", "1.5, 1.5m or 150cm")


def _scaled(
    text: str | float, name: str, units: Sequence[tuple[str, float]], si: str, example: str
) -> float:
    raw, scale = str(text).strip().lower(), 1.0
    for suffix, factor in units:
        if raw.endswith(suffix):
            raw, scale = raw[: -len(suffix)].strip(), factor
            break
    try:
        value = float(raw)
    except ValueError:
        raise ConfigError(f"{name} must be a number such as {example} (got {text!r})") from None
    return finite(name, value, si) * scale


# --------------------------------------------------------------------------- poses and points
def parse_pose(
    text: str | Sequence[Any], name: str = "pose", heading_default: float | None = None
) -> np.ndarray:
    """A pose typed by a user, ``"X,Y,HEADING"`` → ``(x [m], y [m], θ [rad])``.

    Parameters
    ----------
    text : str or sequence
        ``"1,4,90"`` (commas or spaces between the values) or the three values.
    name : str
        What the pose is (``"start"``), for the error message.
    heading_default : float or None
        The heading [rad] of a pose given as ``X,Y``; None: the heading is required.

    Returns
    -------
    numpy.ndarray
        Float64 ``(3,)``: x, y [m] within ±``MAX_COORDINATE``, θ [rad] wrapped to (−π, π].

    Raises
    ------
    ConfigError
        If a value is missing, extra or not a number, naming ``name`` and what was given.

    Examples
    --------
    >>> parse_pose("1,-2,180").tolist() == [1.0, -2.0, math.pi]
    True
    """
    return _vector(text, name, ("x", "y", "heading"), heading_default)


def parse_point(text: str | Sequence[Any], name: str = "point") -> np.ndarray:
    """A point typed by a user, ``"X,Y"`` → ``(x [m], y [m])``.

    Parameters
    ----------
    text : str or sequence
        ``"1,4"`` (commas or spaces between the values; ``150cm`` accepted) or the two values.
    name : str
        What the point is (``"goal"``), for the error message.

    Returns
    -------
    numpy.ndarray
        Float64 ``(2,)`` [m], within ±``MAX_COORDINATE``.

    Raises
    ------
    ConfigError
        If a value is missing, extra or not a number.

    Examples
    --------
    >>> parse_point("100cm,-1").tolist()
    [1.0, -1.0]
    """
    return _vector(text, name, ("x", "y"), None)


def _parts(text: str | Sequence[Any]) -> list[str]:
    if isinstance(text, str):
        return [part for part in re.split(r"[,\s]+", text.strip()) if part]
    return [str(part) for part in text]


def _vector(
    text: str | Sequence[Any],
    name: str,
    components: tuple[str, ...],
    heading_default: float | None,
) -> np.ndarray:
    parts = _parts(text)
    allowed = {len(components)}
    if heading_default is not None:
        allowed.add(len(components) - 1)
    if len(parts) not in allowed:
        shape = ",".join(c.upper() for c in components)
        given = ",".join(parts) if parts else "nothing"
        how_many = " or ".join(str(n) for n in sorted(allowed))
        raise ConfigError(
            f"{name} needs {how_many} values {shape} ("
            + ", ".join(_COMPONENT_UNITS[c] for c in components)
            + f"; got {len(parts)}: {given!r})"
        )
    values = [
        parse_angle(part, f"{name} {component}")
        if component == "heading"
        else parse_length(part, f"{name} {component}")
        for part, component in zip(parts, components, strict=False)
    ]
    if len(values) < len(components):
        values.append(float(heading_default))  # type: ignore[arg-type]
    if max(abs(values[0]), abs(values[1])) > MAX_COORDINATE:
        raise ConfigError(
            f"{name} x and y must be within ±{MAX_COORDINATE:g} m, where float64 still resolves "
            f"micrometres (got ({values[0]:g}, {values[1]:g}))"
        )
    if "heading" in components:
        values[2] = float(wrap_angle(values[2]))
    return np.array(values, dtype=np.float64)


_COMPONENT_UNITS = {"x": "x [m]", "y": "y [m]", "heading": "heading [deg, or e.g. 1.57rad]"}


# --------------------------------------------------------------------------- typer options
class VectorParser:
    """The typer ``parser`` of a pose or point flag; the ``wheelbase`` group gathers its values.

    Parameters
    ----------
    flag : str
        The flag, e.g. ``"--start"`` (named in errors).
    size : int
        Values it takes at most: 3 (pose) or 2 (point).
    heading_default : float or None
        Heading [rad] of a pose given as ``X,Y`` (None: required).
    """

    def __init__(self, flag: str, size: int, heading_default: float | None = None) -> None:
        self.flag = flag
        self.size = size
        self.heading_default = heading_default
        self.__name__ = "pose" if size == 3 else "point"  # typer names the type by it

    def __call__(self, value: Any) -> np.ndarray:
        if isinstance(value, np.ndarray):
            return value
        name = self.flag.lstrip("-").replace("-", "_")
        try:
            if self.size == 3:
                return parse_pose(value, name, self.heading_default)
            return parse_point(value, name)
        except ConfigError as error:
            raise typer.BadParameter(str(error)) from None


class _ScalarParser:
    """The typer ``parser`` of an angle or rate flag."""

    def __init__(self, flag: str, parse: Any, kind: str) -> None:
        self.flag = flag
        self.parse = parse
        self.__name__ = kind

    def __call__(self, value: Any) -> float:
        if isinstance(value, float):
            return value
        try:
            return self.parse(value, self.flag.lstrip("-").replace("-", "_"))
        except ConfigError as error:
            raise typer.BadParameter(str(error)) from None


def pose_option(flag: str, help: str, heading_default: float | None = None) -> Any:
    """A typer option taking a pose ``X,Y,HEADING`` (or ``X Y HEADING``) → float64 ``(3,)``.

    Parameters
    ----------
    flag : str
        The flag, e.g. ``"--start"``.
    help : str
        What the pose is; the unit rule is appended.
    heading_default : float or None
        Heading [rad] when only ``X,Y`` is given (None: the heading is required).

    Returns
    -------
    typer.models.OptionInfo
        For ``Annotated[np.ndarray | None, pose_option(...)]``; give the default (a string
        such as ``"0,0,0"``, or None) in the signature.
    """
    shape = POSE_HELP if heading_default is None else POSE_HELP + " (heading optional)"
    return typer.Option(
        flag,
        parser=VectorParser(flag, 3, heading_default),
        metavar="X,Y,HEADING",
        help=f"{help.rstrip('.:')}: {shape}.",
        show_default=False,
    )


def point_option(flag: str, help: str) -> Any:
    """A typer option taking a point ``X,Y`` (or ``X Y``) → float64 ``(2,)`` [m].

    Parameters
    ----------
    flag : str
        The flag, e.g. ``"--goal"``.
    help : str
        What the point is; the unit rule is appended.

    Returns
    -------
    typer.models.OptionInfo
        For ``Annotated[np.ndarray | None, point_option(...)]`` (or ``list[np.ndarray]``).
    """
    return typer.Option(
        flag,
        parser=VectorParser(flag, 2),
        metavar="X,Y",
        help=f"{help.rstrip('.:')}: x, y [m, or e.g. 150cm].",
        show_default=False,
    )


def angle_option(flag: str, help: str) -> Any:
    """A typer option taking an angle → rad (bare number: degrees; ``1.57rad`` accepted).

    Parameters
    ----------
    flag : str
        The flag.
    help : str
        What the angle is; the unit is appended.

    Returns
    -------
    typer.models.OptionInfo
    """
    return typer.Option(
        flag,
        parser=_ScalarParser(flag, parse_angle, "angle"),
        metavar="ANGLE",
        help=f"{help.rstrip('.')} [deg, or e.g. 0.6rad].",
    )


def rate_option(flag: str, help: str) -> Any:
    """A typer option taking an angular rate → rad/s (bare number: rad/s; ``30deg/s`` accepted).

    Parameters
    ----------
    flag : str
        The flag.
    help : str
        What the rate is; the unit is appended.

    Returns
    -------
    typer.models.OptionInfo
    """
    return typer.Option(
        flag,
        parser=_ScalarParser(flag, parse_rate, "rate"),
        metavar="RATE",
        help=f"{help.rstrip('.')} [rad/s, or e.g. 30deg/s].",
    )


def default_out(command: str) -> Path:
    """The default ``--out`` of ``wheelbase COMMAND``: ``./wheelbase-COMMAND/``.

    Parameters
    ----------
    command : str
        The sub-command's name.

    Returns
    -------
    pathlib.Path
    """
    return Path(f"wheelbase-{command}")


def out_option(command: str, files: str = "") -> Any:
    """The ``--out`` option of a command that writes files (the rule: optional, default
    :func:`default_out`; give ``= default_out(COMMAND)`` in the signature).

    Parameters
    ----------
    command : str
        The sub-command's name (named in the help's default).
    files : str
        What it writes there, for the help (e.g. ``"path.csv, path.png, metrics.json"``).

    Returns
    -------
    typer.models.OptionInfo
    """
    what = f" for {files}" if files else ""
    return typer.Option(
        "--out",
        help=f"Output folder{what} (created if missing) [default: ./{default_out(command)}/].",
        show_default=False,
    )


# --------------------------------------------------------------------------- gathering
def _vector_flags(command: Any) -> dict[str, int]:
    """``{flag: size}`` of the options made by :func:`pose_option` and :func:`point_option`."""
    flags = {}
    for param in getattr(command, "params", ()):
        # typer keeps the parser on the parameter's OptionInfo; click wraps it as type.func
        info = getattr(getattr(param, "type_descriptor", None), "parameter_info", None)
        wrapped = getattr(getattr(param, "type", None), "func", None)
        parser = getattr(info, "parser", None) or wrapped
        if isinstance(parser, VectorParser):
            for flag in (*param.opts, *param.secondary_opts):
                flags[flag] = parser.size
    return flags


def _count(token: str) -> int:
    """Number of values in a token such as ``-90``, ``1,4`` or ``north``; 0 for a flag.

    A token that starts with ``-`` is a value only if it is a number (``-90``, ``-1.5e-3``,
    ``-90deg``); any other token is a value (a wrong one is then refused by the parser, which
    names the flag, instead of becoming a stray argument).
    """
    parts = token.split(",")
    if token.startswith("-") and not all(_VALUE.fullmatch(part.strip()) for part in parts):
        return 0
    return len(parts)


def gather_vector_values(command: Any, args: Sequence[str]) -> list[str]:
    """Join the space-separated values of every pose and point flag into one ``X,Y,…`` token.

    ``--goal 13.6 9 -90 --out DIR`` becomes ``--goal 13.6,9,-90 --out DIR``: after a pose flag
    the tokens up to the next flag are taken (a negative number, with or without a unit, is a
    value, not a flag), at most the pose's size, so the next flag is never read as a value.
    ``--goal 0 0 --out DIR`` becomes ``--goal 0,0 --out DIR``, which the pose's parser refuses,
    naming ``--goal``.

    Parameters
    ----------
    command : click command
        The sub-command about to parse ``args``.
    args : sequence of str
        Its arguments.

    Returns
    -------
    list of str
        The arguments with each pose's values in one token.
    """
    flags = _vector_flags(command)
    args = list(args)
    if not flags:
        return args
    out: list[str] = []
    k = 0
    while k < len(args):
        token = args[k]
        out.append(token)
        k += 1
        if token == "--":
            out.extend(args[k:])
            break
        if token not in flags:
            continue
        taken: list[str] = []
        count = 0
        while k < len(args):
            n = _count(args[k])
            if n == 0 or count + n > flags[token]:
                break
            taken.append(args[k])
            count += n
            k += 1
        if taken:
            out.append(",".join(taken))
    return out


class PoseGroup(TyperGroup):
    """A typer group whose sub-commands' pose and point flags take ``X Y HEADING`` as well as
    ``X,Y,HEADING`` (:func:`gather_vector_values` runs before a sub-command parses)."""

    def resolve_command(self, ctx: Any, args: list[str]) -> Any:
        name, command, rest = super().resolve_command(ctx, args)
        return name, command, gather_vector_values(command, rest)
