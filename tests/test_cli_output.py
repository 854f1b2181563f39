"""What the commands print (``wheelbase.commands.output``): piped output keeps names and paths
whole, nothing precedes an error line, counts agree with their nouns, and an OS error is one
line too."""

from __future__ import annotations

import re

import pytest
from typer.testing import CliRunner

from wheelbase.cli import app
from wheelbase.commands.output import PIPED_WIDTH, console, plural

RUNNER = CliRunner()  # its output is not a terminal: the piped case

ONE_RUN = """\
name: one
map: empty
robot: {model: diffdrive}
controller: {law: kanayama}
start: [0.0, 0.0, 0.0]
goal: [1.0, 0.0, 0.0]
dt: 0.05
"""


def test_plural():
    assert [plural(n, "run") for n in (0, 1, 2)] == ["0 runs", "1 run", "2 runs"]
    assert plural(1, "cusp") == "1 cusp" and plural(2, "batch", "batches") == "2 batches"


def test_piped_console_does_not_wrap(capsys):
    output = console()
    assert not output.is_terminal and output.width == PIPED_WIDTH
    long_path = "/" + "/".join(["a-rather-long-folder-name"] * 12)
    output.print(f"wrote {long_path}")
    assert f"wrote {long_path}\n" == capsys.readouterr().out


def test_piped_paths_stay_on_one_line(tmp_path):
    # `wheelbase control ... | cat` printed "wrote" and the path on two lines
    out = tmp_path / ("a-long-output-folder-name-" * 4)
    result = RUNNER.invoke(app, ["control", "--start", "1,0,0", "--t-end", "2", "--dt", "0.05",
                                 "--out", str(out)])  # fmt: skip
    assert result.exit_code == 0, result.output
    assert f"wrote {out}" in result.stdout.splitlines()[-1]


def test_nothing_before_an_error(tmp_path):
    # a progress bar that cannot be erased left a blank line on stdout before the error
    scenario = tmp_path / "blocked.yaml"
    scenario.write_text(
        ONE_RUN.replace("map: empty", "map: maze").replace("[0.0, 0.0", "[0.2, 0.2")
    )
    result = RUNNER.invoke(app, ["run", str(scenario), "--out", str(tmp_path / "r")])
    assert result.exit_code == 2
    assert result.stdout == ""
    assert result.stderr.startswith("error: ") and len(result.stderr.splitlines()) == 1


def test_one_run_is_one_run(tmp_path):
    scenario = tmp_path / "one.yaml"
    scenario.write_text(ONE_RUN)
    result = RUNNER.invoke(app, ["batch", str(scenario), "--out", str(tmp_path / "b")])
    assert result.exit_code == 0, result.output
    assert result.stdout.lstrip().startswith("1 run in "), result.stdout
    assert not re.search(r"(^|\s)1 runs\b", result.stdout)  # ("1.71 runs/s" is a rate)


@pytest.mark.parametrize("command", [["simulate", "--left", "1", "--right", "1", "--no-gif"],
                                     ["calibrate", "--runs", "1"]])  # fmt: skip
def test_an_os_error_is_one_line(tmp_path, command):
    # --out under a file: NotADirectoryError was a traceback
    blocker = tmp_path / "file"
    blocker.write_text("x")
    result = RUNNER.invoke(app, [*command, "--out", str(blocker / "sub")])
    assert result.exit_code == 2, result.output
    assert result.stderr == f"error: Not a directory: {blocker / 'sub'}\n"


@pytest.mark.parametrize(
    "argv",
    [
        ["nosuch"],  # no such command
        ["plan", "--bogus"],  # no such option
        ["batch"],  # missing argument
        ["plan", "--headings", "x"],  # bad value
        ["schema", "extra"],  # extra argument
        ["simulate", "--t-end"],  # option without its value
        ["run", "nosuch"],  # a wheelbase error
        ["control", "--start", "1", "1"],  # a pose short of values
    ],
)
def test_every_error_is_one_lowercase_error_line(argv, tmp_path):
    result = RUNNER.invoke(
        app, [*argv, "--out", str(tmp_path / "o")] if argv[0] == "control" else argv
    )
    assert result.exit_code == 2, result.output
    assert result.stdout == ""
    lines = result.stderr.splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: ") and "Error:" not in lines[0]
