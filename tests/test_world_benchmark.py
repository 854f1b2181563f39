"""benchmarks/world.py runs and prints the JSON it promises (no timing asserts)."""

import json
import subprocess
import sys
from pathlib import Path

SCRIPT = Path(__file__).resolve().parents[1] / "benchmarks" / "world.py"


def test_quick_run_prints_every_figure():
    done = subprocess.run([sys.executable, str(SCRIPT), "--quick", "--no-irsim"],
                          capture_output=True, text=True, timeout=600, check=False)  # fmt: skip
    assert done.returncode == 0, done.stderr[-3000:]
    report = json.loads(done.stdout)
    for n in ("20", "50"):
        assert report["one_world"][n]["steps_per_s"] > 0
        assert (
            report["one_world"][n]["steps_per_s_no_lidar"]
            >= report["one_world"][n]["steps_per_s"] * 0.5
        )
        assert report["ratios"][n]["lidar_vs_irsim_lidar"] is None  # ir-sim skipped: no ratio
        assert report["ratios"][n]["lidar_vs_notes_irsim_no_lidar"] > 0
    assert set(report["lockstep"]) == {"straight", "wander", "social_force", "orca"}
    assert report["irsim"] is None and "met_lockstep" in report["targets"]
