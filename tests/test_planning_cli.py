"""``wheelbase plan``: files, metrics, refusal to overwrite, errors; Path.to_csv / plot."""

import csv
import json
import math

import numpy as np
import pytest
import typer
from typer.testing import CliRunner

from wheelbase.commands.plan import register
from wheelbase.errors import ConfigError, PlanningError

app = typer.Typer()


@app.callback()
def _main() -> None:
    """Test app."""


register(app)
runner = CliRunner()
ARGS = ["warehouse", "--start", "6.2", "6", "90", "--goal", "16.9", "14", "-90deg"]
ROBOT = ["--turning-radius", "1.5", "--footprint", "1.6", "1.0", "--rear-axle-to-center", "0.5"]


def test_plan_writes_files_and_metrics(tmp_path):
    result = runner.invoke(app, ["plan", *ARGS, *ROBOT, "--out", str(tmp_path)])
    assert result.exit_code == 0, result.output
    metrics = json.loads((tmp_path / "metrics.json").read_text())
    assert metrics["success"] is True
    assert metrics["length_m"] > math.dist((6.2, 6), (16.9, 14))
    assert metrics["min_clearance_m"] > 0 and metrics["expanded_nodes"] > 0
    assert "length_m" in result.output
    with (tmp_path / "path.csv").open() as handle:
        rows = list(csv.DictReader(handle))
    first, last = rows[0], rows[-1]
    assert (float(first["x_m"]), float(first["y_m"])) == (6.2, 6.0)
    assert float(last["theta_rad"]) == pytest.approx(-math.pi / 2, abs=1e-6)
    assert float(last["s_m"]) == pytest.approx(metrics["length_m"], abs=1e-5)
    assert (tmp_path / "path.png").stat().st_size > 10_000
    again = runner.invoke(app, ["plan", *ARGS, *ROBOT, "--out", str(tmp_path)])
    assert again.exit_code != 0 and isinstance(again.exception, FileExistsError)
    forced = runner.invoke(app, ["plan", *ARGS, *ROBOT, "--out", str(tmp_path), "--force"])
    assert forced.exit_code == 0


def test_plan_no_reverse_and_errors(tmp_path):
    result = runner.invoke(app, ["plan", *ARGS, *ROBOT, "--no-reverse", "--out", str(tmp_path)])
    assert result.exit_code == 0, result.output
    with (tmp_path / "path.csv").open() as handle:
        assert {row["direction"] for row in csv.DictReader(handle)} == {"1"}
    bad = runner.invoke(
        app,
        [
            "plan",
            "warehouse",
            "--start",
            "0.2",
            "0.2",
            "0",
            "--goal",
            "16.9",
            "14",
            "-90",
            *ROBOT,
            "--out",
            str(tmp_path / "x"),
        ],
    )
    assert isinstance(bad.exception, PlanningError) and "start" in str(bad.exception)
    heading = runner.invoke(
        app,
        [
            "plan",
            "warehouse",
            "--start",
            "6.2",
            "6",
            "north",
            "--goal",
            "16.9",
            "14",
            "-90",
            "--out",
            str(tmp_path / "y"),
        ],
    )
    assert isinstance(heading.exception, ConfigError) and "heading" in str(heading.exception)
    unknown = runner.invoke(
        app,
        [
            "plan",
            "nowhere",
            "--start",
            "1",
            "1",
            "0",
            "--goal",
            "2",
            "2",
            "0",
            "--out",
            str(tmp_path / "z"),
        ],
    )
    assert isinstance(unknown.exception, ConfigError) and "map" in str(unknown.exception)


def test_path_plot_and_curve_csv(tmp_path):
    import matplotlib

    matplotlib.use("Agg")
    from wheelbase.planning import Footprint, load_map, reeds_shepp_path

    path = reeds_shepp_path((5.0, 5.0, 0.0), (4.0, 5.0, math.pi), 1.5).sample(0.05)
    ax = path.plot(grid=load_map("maze"), footprint=Footprint.rectangle(0.6, 0.4))
    assert len(ax.lines) >= 2
    written = path.to_csv(tmp_path / "rs.csv")
    data = np.loadtxt(written, delimiter=",", skiprows=1)
    np.testing.assert_allclose(data[:, 1:4], path.poses, atol=1e-6)
    np.testing.assert_array_equal(data[:, 4], path.directions)
