"""
UMBmark (Borenstein & Feng 1996) on a simulated robot with E_d = 1.005 and E_b = 1.02
=====================================================================================

Run ``python examples/odometry_umbmark.py [OUT_DIR]`` (default ``examples/out``): prints E_max,syst
before and after the correction (one round, as in the paper, and two rounds), the estimated E_d and
E_b and the corrected track and wheel factors, for a robot with 50 mm wheels, a 400 mm track and
4096-tick encoders driving a 4 m square 5 times each way, and draws the one-round calibration into
``OUT_DIR/odometry_umbmark.png`` (the figure of ``wheelbase calibrate``).
"""

from __future__ import annotations

import sys
from pathlib import Path

from wheelbase.commands.odometry import plot_calibration
from wheelbase.odometry import calibrate_umbmark


def main(out_dir: str | Path) -> None:
    """Print the three calibrations and draw the first into ``out_dir``."""
    Path(out_dir).mkdir(parents=True, exist_ok=True)
    plot_calibration(calibrate_umbmark(1.005, 1.02), Path(out_dir) / "odometry_umbmark.png")
    for label, kwargs in (
        ("one round", {}),
        ("two rounds", {"iterations": 2}),
        ("one round, 0.1 % random slip", {"slip_std": 0.001}),
    ):
        cal = calibrate_umbmark(1.005, 1.02, **kwargs)
        c = cal.correction
        print(
            f"{label}: E_max,syst {cal.before.e_max_syst:.4f} m -> {cal.after.e_max_syst:.5f} m "
            f"({cal.reduction:.0f}x); E_d {c.diameter_ratio:.5f}, E_b {c.track_ratio:.5f}, "
            f"track {c.track:.5f} m, c_L {c.scale_left:.6f}, c_R {c.scale_right:.6f}"
        )


if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else Path(__file__).parent / "out")
