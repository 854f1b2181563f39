"""benchmarks/parking.py: the generated cases are valid queries and the quick run reports them."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np

BENCHMARKS = Path(__file__).resolve().parents[1] / "benchmarks"


def test_every_generated_case_has_free_ends_inside_its_world():
    sys.path.insert(0, str(BENCHMARKS))
    try:
        import parking
    finally:
        sys.path.remove(str(BENCHMARKS))
    cases = parking.cases()
    assert len(cases) == 54 and len({c.name for c in cases}) == 54
    for case in cases:
        ends = np.array([case.start, case.goal])
        assert case.world.contains(ends[:, :2]).all(), case.name
        assert not case.world.in_collision(case.footprint, ends).any(), case.name


def test_quick_run_prints_its_json():
    completed = subprocess.run(
        [sys.executable, str(BENCHMARKS / "parking.py"), "--quick", "--check-spacing", "0.05"],
        capture_output=True,
        text=True,
        timeout=300,
        check=False,
    )
    assert completed.returncode == 0, completed.stderr
    report = json.loads(completed.stdout)
    assert report["summary"]["cases"] == 4
    assert {r["case"] for r in report["cases"]} == set(
        ("parallel_130_curb_in", "perpendicular_0.8_6.5_back_out", "angled_60_in", "lot_0")
    )
    for row in report["cases"]:
        assert row["success"] and row["collisions_independent"] == 0, row
