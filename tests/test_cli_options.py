"""One rule for angles, lengths and poses on the command line (``wheelbase.commands.options``),
held by every sub-command: a bare angle is in degrees, explicit units are accepted, and a pose
flag takes ``X,Y,HEADING`` or ``X Y HEADING`` with negative numbers, never the next flag."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
import typer
from hypothesis import given
from hypothesis import strategies as st
from typer.testing import CliRunner

from wheelbase.cli import app
from wheelbase.commands.options import (
    VectorParser,
    gather_vector_values,
    parse_angle,
    parse_length,
    parse_point,
    parse_pose,
    parse_rate,
)
from wheelbase.errors import ConfigError
from wheelbase.geometry import wrap_angle

GROUP = typer.main.get_command(app)
RUNNER = CliRunner()


# --------------------------------------------------------------------------- the parsers
def test_scalars_bare_and_with_units():
    assert parse_angle("90") == parse_angle("90deg") == parse_angle("90°") == math.pi / 2
    assert parse_angle("1.5rad") == 1.5 and parse_angle("-45 deg") == -math.pi / 4
    assert parse_rate("0.5") == parse_rate("0.5rad/s") == 0.5
    assert parse_rate("180deg/s") == pytest.approx(math.pi, rel=1e-15)
    assert parse_length("150cm") == 1.5 and parse_length("1500mm") == 1.5
    assert parse_length("-2") == parse_length("-2m") == -2.0
    for parse, bad in ((parse_angle, "north"), (parse_rate, "30deg"), (parse_length, "1km")):
        with pytest.raises(ConfigError, match="must be"):
            parse(bad, "x")
    with pytest.raises(ConfigError, match="finite"):
        parse_angle("nan", "heading")


@given(
    st.floats(-1e6, 1e6, allow_nan=False),
    st.floats(-1e6, 1e6, allow_nan=False),
    st.floats(-720, 720, allow_nan=False),
)
def test_pose_forms_agree_and_the_heading_is_wrapped(x, y, degrees):
    expected = [x, y, float(wrap_angle(math.radians(degrees)))]
    for text in (f"{x!r},{y!r},{degrees!r}", f"{x!r} {y!r} {degrees!r}deg"):
        pose = parse_pose(text, "start")
        assert pose.dtype == np.float64 and pose.shape == (3,)
        np.testing.assert_allclose(pose, expected, rtol=0, atol=1e-12)
    in_radians = parse_pose(f"{x!r},{y!r},{math.radians(degrees)!r}rad", "start")
    np.testing.assert_allclose(in_radians, expected, rtol=0, atol=1e-12)
    assert -math.pi < in_radians[2] <= math.pi


def test_pose_and_point_errors_name_what_is_short():
    with pytest.raises(ConfigError, match=r"goal needs 3 values X,Y,HEADING .*got 2: '0,0'"):
        parse_pose("0,0", "goal")
    with pytest.raises(ConfigError, match="start heading must be an angle"):
        parse_pose("1,2,north", "start")
    with pytest.raises(ConfigError, match=r"goal x and y must be within ±1e\+10 m"):
        parse_point("1e300,0", "goal")
    assert parse_pose("1,2", "start", heading_default=0.5).tolist() == [1.0, 2.0, 0.5]
    assert parse_pose("1,2,180", "start")[2] == math.pi  # (−π, π]: +π, not −π


@pytest.mark.parametrize(
    ("args", "gathered"),
    [
        (["--goal", "13.6", "9", "-90", "--out", "d"], ["--goal", "13.6,9,-90", "--out", "d"]),
        (["--goal", "0", "0", "--out", "d"], ["--goal", "0,0", "--out", "d"]),
        (["--start", "1,4", "-1.5e-3rad", "maze"], ["--start", "1,4,-1.5e-3rad", "maze"]),
        (["--start", "1", "1", "0", "maze"], ["--start", "1,1,0", "maze"]),
        (["--start", "--out", "d"], ["--start", "--out", "d"]),
        (["--", "--start", "1", "2"], ["--", "--start", "1", "2"]),
    ],
)
def test_pose_values_are_gathered_up_to_the_next_flag(args, gathered):
    assert gather_vector_values(GROUP.commands["plan"], args) == gathered


# --------------------------------------------------------------------------- every command
def _parsers(kinds: tuple[str, ...]) -> list[tuple[str, str, object]]:
    """(command, flag, parser) of every option of every sub-command parsed by the shared module."""
    found = []
    for name, command in GROUP.commands.items():
        for param in command.params:
            parser = param.type_descriptor.parameter_info.parser
            if getattr(parser, "__name__", None) in kinds:
                found.append((name, param.opts[0], parser))
    return found


POSES = _parsers(("pose",))
ANGLES = _parsers(("angle",))
RATES = _parsers(("rate",))


def test_every_angle_flag_of_every_command_follows_the_rule():
    # An option whose help speaks of a heading, an angle, a steering angle or a yaw (or says
    # degrees) is parsed by wheelbase.commands.options: a new command cannot read radians.
    shared = {(name, flag) for name, flag, _ in (*POSES, *ANGLES, *RATES)}
    shared |= {(name, flag) for name, flag, _ in _parsers(("point",))}
    words = ("heading", "angle", "steering", "yaw", "[deg")
    not_angles = {
        ("track-waypoints", "--reference"),  # a choice: feasible or document (heading jumps)
        ("plan", "--headings"),  # a count of heading bins
    }
    for name, command in GROUP.commands.items():
        for param in command.params:
            text = f"{param.name} {getattr(param, 'help', '') or ''}".lower()
            if any(word in text for word in words) and (name, param.opts[0]) not in not_angles:
                assert (name, param.opts[0]) in shared, f"wheelbase {name} {param.opts[0]}"
    assert {name for name, _, _ in POSES} >= {"simulate", "control", "plan"}


def _parse(command: str, argv: list[str]) -> dict:
    """The parameters ``wheelbase COMMAND ARGV`` gives its command (parsed, not run)."""
    with GROUP.make_context("wheelbase", [command, *argv]) as ctx:
        _, sub, rest = GROUP.resolve_command(ctx, [command, *argv])
        required = []
        for param in sub.params:
            if param.required and param.param_type_name == "argument":
                required.insert(0, "x")
            elif param.required:
                required += [param.opts[0], "x"]
        with sub.make_context(command, [*required, *rest], parent=ctx) as sub_ctx:
            return dict(sub_ctx.params)


HEADINGS = ["-90", "-90deg", "-90°", f"{-math.pi / 2!r}rad", "270"]


def _case_id(value) -> str:
    """A test id that is the same in every process (a parser's repr holds its address)."""
    return value if isinstance(value, str) else type(value).__name__


@pytest.mark.parametrize(("command", "flag", "parser"), POSES, ids=_case_id)
@pytest.mark.parametrize("heading", HEADINGS)
def test_every_pose_flag_reads_degrees_and_units(command, flag, parser, heading):
    key = flag.lstrip("-").replace("-", "_")
    expected = [1.5, -2.0, -math.pi / 2]
    for argv in ([flag, "1.5", "-2", heading], [flag, f"1.5,-2,{heading}"]):
        pose = _parse(command, argv)[key]
        np.testing.assert_allclose(pose, expected, rtol=0, atol=1e-12)


@pytest.mark.parametrize(("command", "flag", "parser"), ANGLES, ids=_case_id)
def test_every_angle_flag_reads_degrees_and_units(command, flag, parser):
    key = flag.lstrip("-").replace("-", "_")
    for text in ("10", "10deg", f"{math.radians(10)!r}rad"):
        assert _parse(command, [flag, text])[key] == pytest.approx(math.radians(10), rel=1e-15)


@pytest.mark.parametrize(("command", "flag", "parser"), RATES, ids=_case_id)
def test_every_rate_flag_reads_rad_per_second_and_units(command, flag, parser):
    key = flag.lstrip("-").replace("-", "_")
    for text in ("0.5", "0.5rad/s", f"{math.degrees(0.5)!r}deg/s"):
        assert _parse(command, [flag, text])[key] == pytest.approx(0.5, rel=1e-15)


@pytest.mark.parametrize(("command", "flag", "parser"), POSES, ids=_case_id)
def test_a_pose_short_of_values_names_its_flag_and_keeps_the_next_flag(
    command, flag, parser, tmp_path
):
    assert isinstance(parser, VectorParser)
    out = tmp_path / "never"
    result = RUNNER.invoke(app, [command, flag, "0", "0", "--out", str(out)])
    assert result.exit_code == 2
    assert f"'{flag}'" in result.stderr and "needs 3 values X,Y,HEADING" in result.stderr
    assert "Missing option '--out'" not in result.stderr
    assert len(result.stderr.strip().splitlines()) == 1
    assert not out.exists()


def test_the_rule_is_in_the_help():
    top = RUNNER.invoke(app, ["--help"]).stdout
    assert "Angles in degrees unless written 1.57rad" in " ".join(top.split())


# --------------------------------------------------------------------------- --out
def test_out_is_optional_everywhere_with_one_default():
    # --out was required by seven commands and defaulted elsewhere ("out", "wheelbase-batch")
    from wheelbase.commands.options import default_out

    for name, command in GROUP.commands.items():
        outs = [param for param in command.params if "--out" in param.opts]
        if name in ("schema", "scenarios"):
            assert not outs  # they print, they write no file
            continue
        assert len(outs) == 1, name
        assert not outs[0].required, f"wheelbase {name} --out is required"
        if name == "run":  # a report is named after its scenario
            assert outs[0].default is None
        else:
            assert Path(outs[0].default) == default_out(name), name


def test_commands_write_to_their_default_folder(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    result = RUNNER.invoke(app, ["simulate", "--left", "1", "--right", "1", "--t-end", "1",
                                 "--no-gif"])  # fmt: skip
    assert result.exit_code == 0, result.output
    assert (tmp_path / "wheelbase-simulate" / "trajectory.csv").is_file()
    result = RUNNER.invoke(app, ["control", "--start", "1,0,0", "--t-end", "2", "--dt", "0.05"])
    assert result.exit_code == 0, result.output
    assert (tmp_path / "wheelbase-control" / "metrics.json").is_file()
    again = RUNNER.invoke(app, ["control", "--start", "1,0,0", "--t-end", "2", "--dt", "0.05"])
    assert again.exit_code == 2 and "--force" in again.stderr  # kept unless --force
