"""The ``wheelbase`` command line: files and numbers match the Python API; bad input is one line."""

import csv
import math
import os
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from PIL import Image
from typer.testing import CliRunner

import wheelbase
from wheelbase import BodyTwist, ConfigError, DiffDrive, Unicycle, simulate
from wheelbase.cli import DEMO_FILES, app
from wheelbase.commands.options import parse_angle
from wheelbase.models import Ackermann, Bicycle, RearWheelBicycle

RUNNER = CliRunner()
DOC000 = [
    "simulate",
    "--model", "diffdrive",
    "--wheel-radius", "0.05",
    "--half-track", "0.2",
    "--left", "0.8",
    "--right", "0.6",
    "--t-end", "100",
    "--dt", "0.1",
    "--method", "euler",
    "--pose0", "0", "0", "90deg",
]  # fmt: skip


def run(*args: str):
    return RUNNER.invoke(app, [str(a) for a in args])


def read_csv(path: Path) -> tuple[list[str], np.ndarray]:
    with path.open() as handle:
        rows = list(csv.reader(handle))
    return rows[0], np.array(rows[1:], dtype=float)


def assert_one_line_error(result, *fragments: str) -> None:
    assert result.exit_code == 2, result.output
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1, result.stderr
    assert lines[0].startswith("error: ")
    assert "Traceback" not in result.output
    for fragment in fragments:
        assert fragment in lines[0]


# --------------------------------------------------------------------------- simulate
def test_simulate_document_000_case_1_writes_the_files(tmp_path):
    out = tmp_path / "run"
    result = run(*DOC000, "--out", out)
    assert result.exit_code == 0, result.output
    for name in ("trajectory.csv", "states.png", "path.png", "animation.gif"):
        assert (out / name).stat().st_size > 0
    assert (out / "path.png").read_bytes()[:4] == b"\x89PNG"
    with Image.open(out / "animation.gif") as gif:
        assert 2 <= gif.n_frames <= 150
    assert (out / "animation.gif").stat().st_size < 2_000_000

    header, data = read_csv(out / "trajectory.csv")
    assert header == ["t", "x", "y", "theta", "omega_left", "omega_right"]
    expected = simulate(DiffDrive(0.05, 0.2), [0, 0, math.pi / 2], (0.8, 0.6), 100, 0.1, "euler")
    np.testing.assert_array_equal(data[:, 0], expected.t)
    np.testing.assert_array_equal(data[:, 1:4], expected.poses)
    np.testing.assert_array_equal(data[:, 4:], expected.inputs)

    # The summary reports the final pose, the distance (v·t = 0.035 m/s · 100 s) and the run.
    x, y, theta = expected.poses[-1]
    for text in (f"{x:.6f}", f"{y:.6f}", f"{theta:.6f}", "3.500000 m", "euler", "1000", "100 s"):
        assert text in result.stdout
    assert str(out) in result.stdout


@pytest.mark.parametrize("heading", ["90deg", "90°", "90", "1.5707963267948966rad"])
def test_pose0_heading_units(tmp_path, heading):
    result = run(
        "simulate", "--left", "1", "--right", "0.5", "--t-end", "1", "--pose0", "1", "-2",
        heading, "--no-gif", "--out", tmp_path,
    )  # fmt: skip
    assert result.exit_code == 0, result.output
    _, data = read_csv(tmp_path / "trajectory.csv")
    np.testing.assert_allclose(data[0, 1:4], [1.0, -2.0, math.pi / 2], atol=1e-15)
    assert not (tmp_path / "animation.gif").exists()


def test_parse_angle():
    assert parse_angle("180deg") == pytest.approx(math.pi)
    assert parse_angle("-45 deg") == pytest.approx(-math.pi / 4)
    assert parse_angle("0.5rad") == 0.5
    assert parse_angle(" -45 ") == pytest.approx(-math.pi / 4)  # a bare angle is in degrees
    for bad in ("abc", "deg", "nan", "infdeg", ""):
        with pytest.raises(ConfigError, match="angle"):
            parse_angle(bad, "angle")


@pytest.mark.parametrize(
    ("args", "model", "inputs", "columns"),
    [
        (["--model", "unicycle", "--v", "0.5", "--omega", "0.2"], Unicycle(), (0.5, 0.2),
         ["v", "omega"]),
        (["--model", "twist", "--u", "0.1", "--v", "0.05", "--r", "0.3"], BodyTwist(),
         (0.1, 0.05, 0.3), ["u", "v", "r"]),
        (["--model", "twist", "--r", "0.3"], BodyTwist(), (0.0, 0.0, 0.3), ["u", "v", "r"]),
    ],
)  # fmt: skip
def test_other_models_match_the_python_call(tmp_path, args, model, inputs, columns):
    result = run(
        "simulate", *args, "--t-end", "10", "--method", "rk4", "--no-gif", "--out", tmp_path
    )
    assert result.exit_code == 0, result.output
    header, data = read_csv(tmp_path / "trajectory.csv")
    assert header == ["t", "x", "y", "theta", *columns]
    expected = simulate(model, [0, 0, 0], inputs, 10.0, 0.1, "rk4")
    np.testing.assert_array_equal(data[:, 1:4], expected.poses)


def test_steered_models(tmp_path):
    cases = [
        ("bicycle", [], Bicycle(1.0)),
        ("rear-bicycle", [], RearWheelBicycle(1.0)),
        ("ackermann", ["--track", "0.5", "--wheel-base", "1.2"], Ackermann(1.2, 0.5)),
    ]
    for name, extra, model in cases:
        out = tmp_path / name
        result = run(
            "simulate", "--model", name, "--speed", "1", "--steering", "10deg", *extra,
            "--t-end", "5", "--no-gif", "--out", out,
        )  # fmt: skip
        assert result.exit_code == 0, result.output
        header, data = read_csv(out / "trajectory.csv")
        assert header[4:] == ["speed", "steering"]
        np.testing.assert_allclose(data[0, 5], math.radians(10), rtol=1e-15)
        expected = simulate(model, [0, 0, 0], (1.0, math.radians(10)), 5.0, 0.1, "rk4")
        np.testing.assert_allclose(data[:, 1:4], expected.poses, atol=1e-15)
    result = run("simulate", "--model", "bicycle", "--speed", "1", "--steering", "100deg",
                 "--out", tmp_path / "bad")  # fmt: skip
    assert_one_line_error(result, "steering")


def test_holonomic_bases_drive_sideways(tmp_path):
    for name in ("mecanum", "omni"):
        out = tmp_path / name
        result = run("simulate", "--model", name, "--v", "0.2", "--t-end", "10", "--no-gif",
                     "--out", out)  # fmt: skip
        assert result.exit_code == 0, result.output
        _, data = read_csv(out / "trajectory.csv")
        # Pure lateral body speed from heading 0: straight along +y at 0.2 m/s.
        np.testing.assert_allclose(data[-1, 1:4], [0.0, 2.0, 0.0], atol=1e-12)


def test_refuses_to_overwrite_unless_forced(tmp_path):
    args = ["simulate", "--left", "1", "--right", "0.5", "--t-end", "1", "--no-gif"]
    assert run(*args, "--out", tmp_path).exit_code == 0
    csv_path = tmp_path / "trajectory.csv"
    csv_path.write_text("mine")
    result = run(*args, "--left", "2", "--out", tmp_path)
    assert_one_line_error(result, "--force", "trajectory.csv")
    assert csv_path.read_text() == "mine"
    result = run(*args, "--out", tmp_path, "--force")
    assert result.exit_code == 0, result.output
    assert csv_path.read_text().startswith("t,x,y,theta")


def test_out_must_be_a_folder(tmp_path):
    target = tmp_path / "file.txt"
    target.write_text("x")
    result = run("simulate", "--left", "1", "--right", "1", "--out", target)
    assert_one_line_error(result, "not a folder")


@pytest.mark.parametrize(
    ("args", "fragment"),
    [
        (["--wheel-radius", "-0.05", "--left", "1", "--right", "1"], "wheel_radius must be > 0"),
        (["--half-track", "0", "--left", "1", "--right", "1"], "half_track must be > 0"),
        (["--left", "1", "--right", "1", "--dt", "5", "--t-end", "1"], "dt must be <= t_end"),
        (["--left", "1", "--right", "1", "--dt", "-0.1"], "dt must be > 0"),
        (["--left", "1", "--right", "1", "--t-end", "nan"], "t_end must be finite"),
        (["--left", "nan", "--right", "1"], "left must be finite"),
        (["--left", "1", "--right", "1", "--pose0", "0", "inf", "0"], "pose0 y"),
        (["--left", "1", "--right", "1", "--pose0", "0", "0", "north"], "pose0 heading"),
        (["--model", "tank", "--left", "1"], "unknown model 'tank'"),
        (["--left", "1", "--right", "1", "--method", "leapfrog"], "unknown method 'leapfrog'"),
        (["--left", "1"], "needs --right"),
        (["--model", "unicycle", "--v", "1", "--omega", "0", "--left", "1"], "--left"),
        (["--left", "one", "--right", "1"], "--left"),
        (["--left", "1", "--right", "1", "--length", "-1"], "length must be > 0"),
    ],
)
def test_bad_input_is_one_red_line_and_exit_2(tmp_path, args, fragment):
    out = tmp_path / "never"
    result = run("simulate", *args, "--out", out)
    assert_one_line_error(result, fragment)
    assert not out.exists()  # nothing written on error


# --------------------------------------------------------------------------- demo
def test_demo_writes_its_files_and_reruns(tmp_path):
    out = tmp_path / "demo"
    out.mkdir()
    (out / "notes.txt").write_text("user file")
    first = run("kinematics-demo", "--out", out)
    assert first.exit_code == 0, first.output
    for name in DEMO_FILES:
        assert (out / name).stat().st_size > 0
    assert (out / "animation.gif").stat().st_size < 2_000_000
    assert "2.5206" in first.stdout and "3.0000" in first.stdout  # case 1 x, case 2 y
    second = run("kinematics-demo", "--out", out)  # a previous demo's files do not stop it
    assert second.exit_code == 0, second.output
    assert sorted(p.name for p in out.iterdir()) == sorted([*DEMO_FILES, "notes.txt"])
    assert (out / "notes.txt").read_text() == "user file"


# --------------------------------------------------------------------------- help/version
def test_version_and_help():
    result = run("--version")
    assert result.exit_code == 0 and result.stdout.strip() == f"wheelbase {wheelbase.__version__}"
    top = run("--help")
    assert top.exit_code == 0 and "simulate" in top.stdout and "demo" in top.stdout
    help_text = run("simulate", "--help").stdout
    for unit in ("[m]", "[rad/s]", "[m/s]", "[s]", "[deg", "X,Y,HEADING"):
        assert unit in help_text
    assert run("kinematics-demo", "--help").exit_code == 0
    bare = run()
    assert bare.exit_code == 0 and "Usage" in bare.stdout


def test_console_script_runs(tmp_path):
    script = Path(sys.executable).with_name("wheelbase")
    command = str(script) if script.exists() else shutil.which("wheelbase")
    if command is None:
        pytest.skip("the wheelbase console script is not installed (pip install -e .)")
    ok = subprocess.run(
        [command, *DOC000[:-4], "--t-end", "2", "--no-gif", "--out", str(tmp_path)],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert ok.returncode == 0, ok.stderr
    assert (tmp_path / "trajectory.csv").exists() and (tmp_path / "path.png").exists()
    bad = subprocess.run(
        [command, "simulate", "--wheel-radius", "-1", "--left", "1", "--right", "1",
         "--out", str(tmp_path / "x")],
        capture_output=True,
        text=True,
        timeout=120,
    )  # fmt: skip
    assert bad.returncode == 2
    assert bad.stderr.strip() == "error: wheel_radius must be > 0 m (got -1)"
    assert "Traceback" not in bad.stdout + bad.stderr


def test_python_m_wheelbase_is_the_command_line(tmp_path):
    # benchmarks/closed_loop.py falls back to it where the console script is not on PATH
    environment = {**os.environ, "PYTHONPATH": str(Path(wheelbase.__file__).parents[1])}
    ok = subprocess.run([sys.executable, "-m", "wheelbase", "--version"], capture_output=True,
                        text=True, timeout=120, env=environment)  # fmt: skip
    assert ok.returncode == 0, ok.stderr
    assert ok.stdout.strip() == f"wheelbase {wheelbase.__version__}"
    bad = subprocess.run([sys.executable, "-m", "wheelbase", "simulate", "--left", "x"],
                         capture_output=True, text=True, timeout=120, env=environment)  # fmt: skip
    assert bad.returncode == 2 and "Traceback" not in bad.stderr
    assert "(see 'wheelbase simulate --help')" in bad.stderr
