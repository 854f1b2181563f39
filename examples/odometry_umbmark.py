"""
UMBmark (Borenstein & Feng 1996) on a simulated robot with E_d = 1.005 and E_b = 1.02
=====================================================================================

Run ``python examples/odometry_umbmark.py``: prints E_max,syst before and after the correction
(one round, as in the paper, and two rounds), the estimated E_d and E_b and the corrected track
and wheel factors, for a robot with 50 mm wheels, a 400 mm track and 4096-tick encoders driving
a 4 m square 5 times each way. ``wheelbase calibrate --out DIR`` does the same and draws it.
"""

from __future__ import annotations

from wheelbase.odometry import calibrate_umbmark


def main() -> None:
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
    main()
