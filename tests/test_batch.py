import json
from concurrent.futures import ThreadPoolExecutor

import pytest

from wheelbase.batch import run_batch
from wheelbase.errors import ConfigError

SCENARIO = {
    "name": "short",
    "map": "empty",
    "robot": {"model": "diffdrive"},
    "controller": {"law": "kanayama"},
    "odometry": {"mode": "encoders", "pulses_per_revolution": 512, "tick_noise_std": 1.0},
    "start": [0.0, 0.0, 0.0],
    "goal": [1.5, 0.0, 0.0],
    "trajectory": {"max_speed": 1.0, "max_acceleration": 1.0},
    "goal_tolerance": [0.05, 5.0],
    "dt": 0.02,
    "duration": 30.0,
}


def test_seeds_change_the_noise_and_rows_keep_order(tmp_path):
    with ThreadPoolExecutor(max_workers=2) as pool:
        result = run_batch([SCENARIO], seeds=3, executor=pool)
    assert [row["seed"] for row in result.rows] == [0, 1, 2]
    assert all(row["status"] in ("arrived", "missed_goal") for row in result.rows)
    drifts = {round(row["odometry_drift_m"], 12) for row in result.rows}
    assert len(drifts) == 3  # noise seeds differ
    paths = result.write(tmp_path)
    payload = json.loads(paths[1].read_text())
    assert payload["runs"] == 3 and "odometry_drift_m" in payload["summary"]
    with pytest.raises(FileExistsError, match="--force"):
        result.write(tmp_path)


def test_failed_runs_are_rows_not_crashes():
    bad = {**SCENARIO, "start": [0.0, 0.0, 0.0], "map": "maze", "name": "blocked"}
    with ThreadPoolExecutor(max_workers=1) as pool:
        result = run_batch([bad], executor=pool)
    assert result.rows[0]["status"] == "error" and "start" in result.rows[0]["error"]
    assert result.summary()["success_rate"]["mean"] == 0.0


def test_bad_batch_arguments():
    with pytest.raises(ConfigError, match="seeds must be an integer >= 1"):
        run_batch([SCENARIO], seeds=0)
    with pytest.raises(ConfigError, match="at least one scenario"):
        run_batch([])


def test_dask_local_cluster_runs_a_batch():
    distributed = pytest.importorskip("dask.distributed")
    with (
        distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=False) as cluster,
        distributed.Client(cluster) as client,
    ):
        result = run_batch([SCENARIO], seeds=2, executor=client.get_executor())
    assert [row["status"] for row in result.rows].count("arrived") >= 1
    assert len(result.rows) == 2
