"""``wheelbase goto`` and ``wheelbase calibrate`` (typer CliRunner on a local app)."""

import json

import pytest
import typer
from typer.testing import CliRunner

from wheelbase.commands.odometry import CALIBRATE_FILES, GOTO_FILES, register
from wheelbase.commands.options import PoseGroup
from wheelbase.errors import ConfigError

app = typer.Typer(cls=PoseGroup)


@app.callback()
def _main() -> None:
    """Test app."""


register(app)
runner = CliRunner()


def test_goto_writes_files_and_metrics(tmp_path):
    out = tmp_path / "run"
    result = runner.invoke(
        app, ["goto", "--goal", "100cm", "100cm", "--goal", "-1,-500mm", "--out", str(out)]
    )
    assert result.exit_code == 0, result.output
    for name in GOTO_FILES:
        assert (out / name).stat().st_size > 0
    metrics = json.loads((out / "metrics.json").read_text())
    goals = metrics["goals"]
    assert [g["goal"] for g in goals] == [[1.0, 1.0], [-1.0, -0.5]]  # cm, mm → m
    for g in goals:
        assert g["true_final_error_m"] < 0.02 and g["odometry_final_error_m"] < 0.015
    header = (out / "log.csv").read_text().splitlines()[0].split(",")
    assert header[:3] == ["robot", "t", "true_x"]
    assert "setpoint_rpm_0" in header and "duty_1" in header
    # No overwrite without --force.
    again = runner.invoke(app, ["goto", "--goal", "1", "1", "--out", str(out)])
    assert again.exit_code != 0 and isinstance(again.exception, FileExistsError)
    forced = runner.invoke(app, ["goto", "--goal", "0.5", "0", "--out", str(out), "--force"])
    assert forced.exit_code == 0, forced.output
    assert json.loads((out / "metrics.json").read_text())["goals"][0]["goal"] == [0.5, 0.0]


def test_goto_no_gif_writes_the_rest(tmp_path):
    # goto always wrote route.gif; the other commands that animate take --gif/--no-gif
    out = tmp_path / "run"
    result = runner.invoke(app, ["goto", "--goal", "0.5,0.5", "--no-gif", "--out", str(out)])
    assert result.exit_code == 0, result.output
    assert not (out / "route.gif").exists()
    assert {p.name for p in out.iterdir()} == set(GOTO_FILES) - {"route.gif"}
    assert "route.gif" not in result.output


@pytest.mark.parametrize(
    ("argv", "match"),
    [
        (["--goal", "nan", "1"], "goal x must be finite"),
        (["--goal", "1"], "goal needs 2 values X,Y"),
        (["--goal", "1", "abc"], "goal y must be a number"),
        (["--goal", "1", "1km"], "goal y must be a number such as 1.5, 1.5m or 150cm"),
        (["--goal", "1", "1", "--bogus", "3"], "No such option: --bogus"),
        (["--goal", "1", "1", "--unit", "cm"], "No such option: --unit"),  # metres, or 100cm
        (["--goal", "1e300", "1"], "within ±1e+10 m"),  # was a LinAlgError
    ],
)
def test_goto_bad_flags_name_the_flag(tmp_path, argv, match):
    from wheelbase.cli import app as wheelbase

    result = runner.invoke(wheelbase, ["goto", *argv, "--out", str(tmp_path / "x")])
    assert result.exit_code == 2
    assert match in result.stderr and len(result.stderr.splitlines()) == 1
    assert not (tmp_path / "x").exists()


@pytest.mark.parametrize(
    ("argv", "match"),
    [
        (["--goal", "1", "1", "--seed", "-1"], "seed must be an integer in [0, "),  # was ValueError
        (["--goal", "1", "1", "--seed", "99999999999999999999"], "seed must be an integer in"),
    ],
)
def test_goto_bad_input(tmp_path, argv, match):
    result = runner.invoke(app, ["goto", *argv, "--out", str(tmp_path / "x")])
    assert result.exit_code != 0
    assert isinstance(result.exception, ConfigError)
    assert match in str(result.exception)


def test_calibrate_negative_seed_is_one_clear_error(tmp_path):
    result = runner.invoke(app, ["calibrate", "--seed", "-1", "--out", str(tmp_path / "x")])
    assert isinstance(result.exception, ConfigError)
    assert "seed must be an integer >= 0" in str(result.exception)


def test_calibrate_writes_metrics(tmp_path):
    out = tmp_path / "cal"
    result = runner.invoke(app, ["calibrate", "--ed", "1.005", "--eb", "1.02", "--out", str(out)])
    assert result.exit_code == 0, result.output
    for name in CALIBRATE_FILES:
        assert (out / name).stat().st_size > 0
    metrics = json.loads((out / "metrics.json").read_text())
    assert metrics["e_max_syst_before_m"] / metrics["e_max_syst_after_m"] >= 10
    assert metrics["track_m"] == pytest.approx(0.408, abs=2e-3)
    assert metrics["scale_right"] / metrics["scale_left"] == pytest.approx(1.005, abs=1e-4)
    bad = runner.invoke(app, ["calibrate", "--ed", "-1", "--out", str(tmp_path / "bad")])
    assert isinstance(bad.exception, ConfigError) and "diameter_ratio" in str(bad.exception)


def test_a_goal_the_robot_starts_on_is_reported_not_a_traceback(tmp_path):
    # found by benchmarks/fuzz.py: KeyError 'final_position_error_estimated_m'
    out = tmp_path / "run"
    result = runner.invoke(
        app, ["goto", "--goal", "0.5", "0.5", "--goal", "1e-300", "1e-300", "--out", str(out),
              "--no-gif"],
    )  # fmt: skip
    assert result.exit_code == 0, result.output
    assert "odometry error n/a (no motion)" in result.output
    goals = json.loads((out / "metrics.json").read_text())["goals"]
    assert goals[0]["odometry_final_error_m"] < 0.015
    assert goals[1]["odometry_final_error_m"] is None
