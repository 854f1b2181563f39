import json
import math

import numpy as np
import pytest
import typer
from typer.testing import CliRunner

from wheelbase.commands.control import register
from wheelbase.commands.options import PoseGroup, parse_angle
from wheelbase.control.pose import POSE_LAWS
from wheelbase.errors import ConfigError, InputError

app = typer.Typer(cls=PoseGroup)


@app.callback()
def _main() -> None:
    """Test app."""


register(app)
runner = CliRunner()


def test_angles():
    assert parse_angle("180deg") == pytest.approx(math.pi)
    assert parse_angle("90°") == pytest.approx(0.5 * math.pi)
    assert parse_angle("1.5rad") == 1.5
    assert parse_angle("-0.5rad") == -0.5
    assert parse_angle("-90") == pytest.approx(-0.5 * math.pi)
    with pytest.raises(ConfigError, match="angle"):
        parse_angle("north")


def test_single_run_writes_files_and_refuses_to_overwrite(tmp_path):
    args = ["control", "--law", "polar", "--start", "2", "0", "180",
            "--goal", "0,0,0deg", "--out", str(tmp_path)]  # fmt: skip
    result = runner.invoke(app, args)
    assert result.exit_code == 0, result.output
    assert "arrived" in result.output
    metrics = json.loads((tmp_path / "metrics.json").read_text())
    assert metrics["status"] == "arrived"
    assert metrics["final_position_error_true_m"] <= 0.01
    rows = np.loadtxt(tmp_path / "run.csv", delimiter=",", skiprows=1)
    np.testing.assert_allclose(rows[0, 1:4], [2.0, 0.0, math.pi])
    assert np.all(np.abs(rows[:, 4]) <= 0.5 + 1e-12)
    assert (tmp_path / "run.png").stat().st_size > 1000
    again = runner.invoke(app, args)
    assert again.exit_code != 0
    assert isinstance(again.exception, FileExistsError)
    assert runner.invoke(app, [*args, "--force"]).exit_code == 0


def test_bad_cli_input(tmp_path):
    same = [
        "control",
        "--start",
        "1",
        "1",
        "0",
        "--goal",
        "1",
        "1",
        "90deg",
        "--out",
        str(tmp_path),
    ]
    result = runner.invoke(app, same)
    assert isinstance(result.exception, InputError)
    assert "goal equals the start" in str(result.exception)
    result = runner.invoke(app, ["control", "--law", "magic", "--start", "1", "1", "0",
                                 "--out", str(tmp_path)])  # fmt: skip
    assert isinstance(result.exception, ConfigError)
    assert "unknown law 'magic'" in str(result.exception)
    assert str(result.exception).endswith(", ".join(map(repr, (*POSE_LAWS, "mppi"))))
    result = runner.invoke(app, ["control", "--out", str(tmp_path)])
    assert isinstance(result.exception, ConfigError)
    assert "--start" in str(result.exception)


def test_step_count_is_bounded(tmp_path):
    # --dt 1e-300 looped for 5e300 steps (found by tests/test_fuzz.py): one clear error instead
    result = runner.invoke(app, ["control", "--start", "1", "1", "0", "--dt", "1e-300",
                                 "--t-end", "5", "--out", str(tmp_path / "o")])  # fmt: skip
    assert isinstance(result.exception, ConfigError)
    assert "t_end / dt = 5e+300 steps: more than max_steps" in str(result.exception)


def test_goal_beyond_1e10_m_is_refused(tmp_path):
    # a goal 1e300 m away overflowed the metrics (found by the fuzz suite's explore run)
    result = runner.invoke(app, ["control", "--start", "1", "1", "0", "--goal", "0", "1e300",
                                 "0", "--out", str(tmp_path / "o")])  # fmt: skip
    assert result.exit_code == 2  # a flag's error: usage error naming --goal
    assert "'--goal': goal x and y must be within ±1e+10 m" in result.output


def test_help_lists_every_law():
    from wheelbase.cli import app as wheelbase

    text = " ".join(runner.invoke(wheelbase, ["control", "--help"]).stdout.split())
    assert f"Control law: {', '.join((*POSE_LAWS, 'mppi'))}" in text
