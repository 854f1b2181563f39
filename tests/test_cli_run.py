"""`wheelbase demo | run | batch | schema | scenarios` as a user runs them."""

import json

import pytest
from typer.testing import CliRunner

from wheelbase.cli import app

runner = CliRunner()

SHORT = """\
name: short
map: empty
robot: {model: diffdrive}
controller: {law: kanayama}
start: [0.0, 0.0, 0.0]
goal: [1.0, 0.5, 0.0]
trajectory: {max_speed: 1.0, max_acceleration: 1.0}
dt: 0.02
"""


def invoke(*args):
    return runner.invoke(app, [str(a) for a in args])


def one_line_error(result, fragment):
    assert result.exit_code == 2, result.output
    assert "Traceback" not in result.output
    lines = [line for line in result.output.splitlines() if line.strip()]
    assert len(lines) == 1 and lines[0].startswith("error: "), result.output
    assert fragment in lines[0], lines[0]


@pytest.fixture
def scenario_file(tmp_path):
    path = tmp_path / "short.yaml"
    path.write_text(SHORT)
    return path


def test_run_writes_a_report_and_refuses_to_overwrite(scenario_file, tmp_path):
    out = tmp_path / "report"
    result = invoke("run", scenario_file, "--out", out, "--no-gif")
    assert result.exit_code == 0, result.output
    metrics = json.loads((out / "metrics.json").read_text())
    assert metrics["status"] == "arrived"
    assert {p.name for p in out.iterdir()} >= {"log.csv", "scenario.yaml", "map.png"}
    assert "arrived" in result.output and "report written to" in result.output
    before = (out / "metrics.json").read_text()
    again = invoke("run", scenario_file, "--out", out, "--no-gif")
    one_line_error(again, "use --force")
    assert (out / "metrics.json").read_text() == before
    assert invoke("run", scenario_file, "--out", out, "--no-gif", "--force").exit_code == 0


def test_demo_runs_the_bundled_scenario_twice(tmp_path):
    out = tmp_path / "demo"
    first = invoke("demo", "--out", out, "--no-gif")
    assert first.exit_code == 0, first.output
    metrics = json.loads((out / "metrics.json").read_text())
    assert metrics["status"] == "arrived" and metrics["cusps"] >= 1  # it reverses into the bay
    assert metrics["tracking_max_position_error_m"] < 0.05
    assert "wheel_energy_j" in metrics
    assert invoke("demo", "--out", out, "--no-gif").exit_code == 0  # the demo owns its folder


def test_schema_is_json_schema_with_the_sections():
    result = invoke("schema")
    assert result.exit_code == 0
    schema = json.loads(result.output)
    for key in ("map", "robot", "plant", "planner", "trajectory", "controller", "odometry"):
        assert key in schema["properties"]
    assert schema["properties"]["robot"]["$ref"].endswith("RobotSpec")


def test_scenarios_lists_the_bundled_ones():
    result = invoke("scenarios")
    assert result.exit_code == 0
    for name in ("demo", "parking", "warehouse_route", "doc000_waypoints", "doc003_goals"):
        assert name in result.output


def test_batch_over_seeds(scenario_file, tmp_path):
    out = tmp_path / "batch"
    result = invoke("batch", scenario_file, "--seeds", 2, "--workers", 1, "--out", out)
    assert result.exit_code == 0, result.output
    rows = json.loads((out / "batch.json").read_text())["rows"]
    assert [row["seed"] for row in rows] == [0, 1]
    assert "success rate" in result.output
    assert len((out / "rows.jsonl").read_text().splitlines()) == 1 + 2  # written as they finish
    again = invoke("batch", scenario_file, "--seeds", 2, "--out", out)
    assert again.exit_code == 2 and "--resume" in again.output
    resumed = invoke("batch", scenario_file, "--seeds", 2, "--out", out, "--resume")
    assert resumed.exit_code == 0, resumed.output  # nothing missing: nothing runs again
    assert json.loads((out / "batch.json").read_text())["rows"] == rows
    fresh = invoke("batch", scenario_file, "--seeds", 3, "--out", out, "--force")
    assert fresh.exit_code == 0, fresh.output
    assert len(json.loads((out / "batch.json").read_text())["rows"]) == 3


@pytest.mark.parametrize(
    ("content", "fragment"),
    [
        ("start: [0, 0\n", "malformed YAML at line"),
        ("- 1\n- 2\n", "a scenario must be a mapping"),
        (SHORT.replace("dt: 0.02", "dt: fast"), "dt: Input should be a valid number"),
        (SHORT + "speed: 3\n", "speed: unknown key"),
        (SHORT.replace("law: kanayama", "law: kanayama, gains: {k_x: -2}"), "k_x must be > 0"),
        (SHORT.replace("map: empty", "map: nowhere.yaml"), "map:"),
        (SHORT.replace("goal: [1.0, 0.5, 0.0]", "goal: [1.0, 0.5]"), "goals.0"),
    ],
)
def test_bad_scenarios_are_one_line_errors(tmp_path, content, fragment):
    path = tmp_path / "bad.yaml"
    path.write_text(content)
    out = tmp_path / "out"
    one_line_error(invoke("run", path, "--out", out), fragment)
    assert not (out / "log.csv").exists()


def test_missing_file_and_not_a_map(tmp_path):
    one_line_error(invoke("run", tmp_path / "nope.yaml"), "no such file")
    image = tmp_path / "notamap.png"
    image.write_bytes(b"this is not an image")
    path = tmp_path / "s.yaml"
    path.write_text(SHORT.replace("map: empty", f"map: {image}"))
    one_line_error(invoke("run", path, "--out", tmp_path / "o"), "map:")


def test_start_in_an_obstacle_writes_a_failed_partial_report(tmp_path):
    path = tmp_path / "blocked.yaml"
    path.write_text(SHORT.replace("map: empty", "map: warehouse").replace(
        "start: [0.0, 0.0, 0.0]", "start: [4.6, 8.0, 0.0]"))  # fmt: skip
    out = tmp_path / "out"
    one_line_error(invoke("run", path, "--out", out), "start (4.6, 8, 0 deg)")
    metrics = json.loads((out / "metrics.json").read_text())
    assert metrics["status"] == "failed" and "obstacle" in metrics["error"]
    assert not (out / "log.csv").exists()


def test_control_law_mppi_runs_on_a_map(tmp_path):
    out = tmp_path / "mppi"
    result = invoke(
        "control", "--law", "mppi", "--map", "cluttered", "--start", "1", "4", "0deg",
        "--goal", "5", "4", "0deg", "--out", out,
    )  # fmt: skip
    assert result.exit_code == 0, result.output
    metrics = json.loads((out / "metrics.json").read_text())
    assert metrics["status"] == "arrived" and metrics["min_clearance_m"] > 0.05
    assert (out / "animation.gif").exists()


NOISY = (
    SHORT.replace("name: short", "name: noisy")
    + """\
odometry: {tick_noise_std: 0.5}
sensors: {landmarks: {positions: [[0.5, 1.0], [1.5, -0.5]], max_range: 5.0}}
localization: {method: ekf}
"""
)


def test_batch_tables_one_scenario_each_and_says_when_seeds_change_nothing(tmp_path):
    short, noisy = tmp_path / "short.yaml", tmp_path / "noisy.yaml"
    short.write_text(SHORT)
    noisy.write_text(NOISY)
    out = tmp_path / "batch"
    result = invoke("batch", short, noisy, "--seeds", 3, "--out", out, "--memory-mb", 64)
    assert result.exit_code == 0, result.output
    text = result.output
    assert "short: 3 runs" in text and "noisy: 3 runs" in text  # never averaged together
    assert "short: the 3 seeds gave identical runs: the scenario has no randomness" in text
    assert "noisy: the 3 seeds" not in text
    noisy_table = text[text.index("noisy: 3 runs") :]
    assert "localization_rms_error_m" in noisy_table  # a filter's batch shows its error
    payload = json.loads((out / "batch.json").read_text())
    groups = {group["name"]: group for group in payload["scenarios"]}
    assert groups["short"]["identical_rows"] and not groups["noisy"]["identical_rows"]
    assert groups["noisy"]["runs"] == 3 and "localization_rms_error_m" in groups["noisy"]["summary"]
    one_line_error(invoke("batch", short, "--out", tmp_path / "b", "--memory-mb", -1), "memory-mb")
