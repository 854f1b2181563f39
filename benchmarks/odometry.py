"""Odometry figures (issue 4): speed, drift of each update, real-data errors, go-to-goal, UMBmark.

Run ``python benchmarks/odometry.py`` (add ``--quick`` to skip the 300 s drift drive); prints one
JSON object. The MRCLAM part is skipped (with the reason in the JSON) when
``../shared/data/mrclam`` is absent.
"""

from __future__ import annotations

import json
import platform
import sys
import time
from pathlib import Path

import numpy as np

from wheelbase.control.goal import FIGURE8_GOALS
from wheelbase.datasets.mrclam import MrclamData, load_mrclam
from wheelbase.odometry import (
    DEAD_RECKONING_METHODS,
    WheelOdometry,
    calibrate_umbmark,
    dead_reckoning_errors,
    drift_table,
    yaw_rate_fit,
)
from wheelbase.sim import run_go_to_goal

DATA = Path(__file__).resolve().parents[2] / "shared" / "data" / "mrclam"


def best_of(function, repeats: int = 5) -> float:
    """Shortest wall time [s] of ``repeats`` calls."""
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        function()
        times.append(time.perf_counter() - start)
    return min(times)


def speed() -> dict:
    rng = np.random.default_rng(0)
    out = {}
    for method in DEAD_RECKONING_METHODS:
        odo = WheelOdometry(0.05, 0.15, 1024, method)
        ticks = rng.integers(0, 40, size=(100_000, 2))
        stream = best_of(lambda odo=odo, ticks=ticks: odo.integrate([0, 0, 0], ticks), 3)
        pose = np.zeros(3)

        def per_call(odo=odo, ticks=ticks, pose=pose):
            p = pose
            for k in range(2000):
                p = odo.update(p, ticks[k])

        single = best_of(per_call, 3) / 2000
        batch_ticks = rng.integers(0, 40, size=(10_000, 2))
        poses = np.zeros((10_000, 3))
        batch = best_of(lambda odo=odo, p=poses, t=batch_ticks: odo.update(p, t), 10)
        out[method] = {
            "single_stream_vectorised_updates_per_s": 100_000 / stream,
            "single_stream_per_call_updates_per_s": 1.0 / single,
            "batch_10000_robots_updates_per_s": 10_000 / batch,
            "batch_10000_robots_call_ms": batch * 1e3,
        }
    return out


def drift(quick: bool) -> dict:
    duration = 60.0 if quick else 300.0
    exact = drift_table(duration=duration)
    encoder = drift_table(duration=duration, pulses_per_revolution=1024)

    def table(records):
        return [
            {
                k: r[k]
                for k in (
                    "rate_hz",
                    "method",
                    "final_position_error_m",
                    "max_position_error_m",
                    "final_heading_error_rad",
                    "drift_per_metre",
                )
            }
            for r in records
        ]

    return {
        "drive": f"CurvyDrive(), {duration:g} s, {exact[0]['distance_m']:.1f} m travelled",
        "exact_wheel_angles": table(exact),
        "encoder_1024_ppr": table(encoder),
    }


def mrclam() -> dict:
    odometry = DATA / "Dataset6_Robot1_Odometry.dat"
    truth = DATA / "Dataset6_Robot1_Groundtruth.dat"
    if not (odometry.is_file() and truth.is_file()):
        return {"skipped": f"MRCLAM data not found in {DATA}"}
    data = load_mrclam(odometry, truth)
    records = dead_reckoning_errors(data, horizons=(10.0, 60.0, 300.0), n_starts=8)
    summary = []
    for horizon in (10.0, 60.0, 300.0):
        for method in DEAD_RECKONING_METHODS:
            rows = [r for r in records if r["horizon_s"] == horizon and r["method"] == method]
            pos = np.array([r["position_error_m"] for r in rows])
            summary.append(
                {
                    "horizon_s": horizon,
                    "method": method,
                    "starts": len(rows),
                    "position_error_median_m": float(np.median(pos)),
                    "position_error_max_m": float(pos.max()),
                    "heading_error_median_rad": float(
                        np.median([r["heading_error_rad"] for r in rows])
                    ),
                    "drift_per_metre_median": float(
                        np.median([r["drift_per_metre"] for r in rows])
                    ),
                    "true_heading_position_error_median_m": float(
                        np.median([r["true_heading_position_error_m"] for r in rows])
                    ),
                }
            )
    fit = yaw_rate_fit(data)
    scaled = MrclamData(data.t, data.v, data.omega * fit["scale"], data.true_pose)
    scaled_records = dead_reckoning_errors(scaled, (10.0, 60.0, 300.0), 8, ("exact",))
    scaled_summary = {
        f"{h:g}s": float(
            np.median([r["position_error_m"] for r in scaled_records if r["horizon_s"] == h])
        )
        for h in (10.0, 60.0, 300.0)
    }
    dt = np.diff(data.t)
    gt_rate = np.diff(np.unwrap(data.true_pose[:, 2])) / dt
    gt_distance = float(np.hypot(*np.diff(data.true_pose[:, :2], axis=0).T).sum())
    return {
        "samples": int(data.t.size),
        "duration_s": data.duration,
        "yaw_rate_bias_median_rad_per_s": float(np.median(data.omega[:-1] - gt_rate)),
        "net_turn_odometry_rad": float(np.sum(data.omega[:-1] * dt)),
        "net_turn_truth_rad": float(np.unwrap(data.true_pose[:, 2])[-1] - data.true_pose[0, 2]),
        "distance_odometry_m": float(np.sum(data.v[:-1] * dt)),
        "distance_truth_m": gt_distance,
        "summary": summary,
        "yaw_rate_fit": fit,
        "position_error_median_m_with_yaw_rate_scaled_in_sample": scaled_summary,
        "what_dominates": (
            "heading error: with the true heading the 300 s error falls from "
            f"{summary[-1]['position_error_median_m']:.2f} m to "
            f"{summary[-1]['true_heading_position_error_median_m']:.2f} m; the odometry yaw rate "
            f"over-reports turning (true/odometry scale {fit['scale']:.2f}) and leads the Vicon "
            f"by {fit['lag_s']:.2f} s. The update method changes the error by < 5 cm."
        ),
    }


def go_to_goal() -> dict:
    run_go_to_goal(FIGURE8_GOALS[0])  # warm-up (imports, caches)
    start = time.perf_counter()
    log = run_go_to_goal(FIGURE8_GOALS)  # the four goals as one batch on the engine
    elapsed = time.perf_counter() - start
    return {
        "four_goal_run_s": elapsed,
        "goals": [
            {
                "goal": [float(v) for v in log.goal[i, :2]],
                "status": m["status"],
                "true_final_error_m": m["final_position_error_true_m"],
                "odometry_final_error_m": m["final_position_error_estimated_m"],
                "time_s": m["duration_s"],
            }
            for i, m in enumerate(log.metrics())
        ],
    }


def umbmark() -> dict:
    out = {}
    for label, kwargs in (
        ("ed1.005_eb1.02", {}),
        ("ed1.005_eb1.02_two_rounds", {"iterations": 2}),
        ("ed1.005_eb1.02_slip0.001", {"slip_std": 0.001}),
    ):
        cal = calibrate_umbmark(1.005, 1.02, **kwargs)
        out[label] = {
            "e_max_syst_before_m": cal.before.e_max_syst,
            "e_max_syst_after_m": cal.after.e_max_syst,
            "reduction": cal.reduction,
            "diameter_ratio_estimate": cal.correction.diameter_ratio,
            "track_ratio_estimate": cal.correction.track_ratio,
        }
    return out


def main() -> None:
    quick = "--quick" in sys.argv
    report = {
        "machine": platform.platform(),
        "python": platform.python_version(),
        "speed": speed(),
        "drift": drift(quick),
        "mrclam": mrclam(),
        "go_to_goal": go_to_goal(),
        "umbmark": umbmark(),
    }
    print(json.dumps(report, indent=2))


if __name__ == "__main__":
    main()
