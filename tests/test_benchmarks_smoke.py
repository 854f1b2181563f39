"""The speed benchmark runs and prints the JSON it promises (no timing asserts: see benchmarks/)."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

SCRIPT = Path(__file__).resolve().parents[1] / "benchmarks" / "kinematics.py"
METHODS_TIMED = {"euler", "rk4", "exact"}


@pytest.fixture(scope="module")
def report() -> dict:
    completed = subprocess.run(
        [sys.executable, str(SCRIPT), "--quick"],
        capture_output=True,
        text=True,
        timeout=300,
        check=False,
    )
    assert completed.returncode == 0, completed.stderr
    return json.loads(completed.stdout)


def test_report_has_every_figure(report):
    for key in ("machine", "config", "batch", "single", "numpy_loop", "peer", "ratios", "targets"):
        assert key in report
    assert set(report["batch"]) == set(report["single"]) == METHODS_TIMED
    for record in [*report["batch"].values(), *report["single"].values(), report["numpy_loop"]]:
        assert record["seconds"] > 0 and record["robot_steps_per_s"] > 0
    assert set(report["ratios"]["batch_vs_numpy_loop"]) == METHODS_TIMED
    assert report["config"]["robots"] == 1000


def test_baselines_integrate_the_same_robots(report):
    # The NumPy loop and the peer are Euler on the same robots: same end points to rounding.
    assert report["numpy_loop"]["max_position_difference_to_ours_euler_m"] < 1e-9
    if report["peer"] is None:
        assert report["peer_error"]
    else:
        assert report["peer_error"] is None
        assert report["peer"]["max_position_difference_to_ours_euler_m"] < 1e-9
        assert set(report["ratios"]["batch_vs_peer"]) == METHODS_TIMED
