import json
from concurrent.futures import ThreadPoolExecutor

import numpy as np
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
    with pytest.raises(ConfigError, match=r"seeds must be an integer in \[1, 1000000\]"):
        run_batch([SCENARIO], seeds=0)
    with pytest.raises(ConfigError, match="MAX_SEEDS"):  # not a list of 1e20 seeds
        run_batch([SCENARIO], seeds=10**20)
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


def test_vectorised_seeds_equal_single_runs():
    """One batch of 5 seeds in lockstep: every run equals its single run (poses to 1e-9 m)."""
    from wheelbase.runner import prepare, run, run_seeds

    seeds = [3, 4, 5, 6, 7]
    rows = run_seeds(SCENARIO, seeds)
    prepared = prepare(SCENARIO)
    batch = prepared.engine.run(np.tile(prepared.start, (5, 1)), seeds=np.array(seeds))
    for i, seed in enumerate(seeds):
        single = run({**SCENARIO, "seed": seed})
        np.testing.assert_allclose(batch.robot(i).true_pose, single.log.true_pose, atol=1e-9)
        for key in ("status", "duration_s", "odometry_drift_m", "final_position_error_true_m"):
            assert rows[i][key] == single.metrics[key], key
        assert rows[i]["seed"] == seed


def test_chunks_on_an_executor_equal_one_vectorised_batch():
    here = run_batch([SCENARIO], seeds=5)
    with ThreadPoolExecutor(max_workers=2) as pool:
        chunked = run_batch([SCENARIO], seeds=5, executor=pool, chunk_size=2)
    assert [row["seed"] for row in chunked.rows] == [0, 1, 2, 3, 4]
    timing = ("planning_time_s", "compile_time_s")

    def untimed(rows):
        return [{k: v for k, v in row.items() if k not in timing} for row in rows]

    assert untimed(here.rows) == untimed(chunked.rows)
    with pytest.raises(ConfigError, match="chunk_size"):
        run_batch([SCENARIO], seeds=2, chunk_size=0)


def _untimed(rows):
    return [{k: v for k, v in row.items() if k not in ("planning_time_s", "compile_time_s")}
            for row in rows]  # fmt: skip


def test_an_interrupted_batch_keeps_its_rows_and_resumes(tmp_path):
    journal = tmp_path / "rows.jsonl"
    full = run_batch([SCENARIO], seeds=6)

    def stop_after_first_chunk(done, total):
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        run_batch([SCENARIO], seeds=6, chunk_size=2, journal=journal,
                  progress=stop_after_first_chunk)  # fmt: skip
    lines = journal.read_text().splitlines()
    assert len(lines) == 1 + 2  # the header and the first chunk's rows, on disk already
    with pytest.raises(FileExistsError, match="--resume"):
        run_batch([SCENARIO], seeds=6, journal=journal)
    with pytest.raises(ConfigError, match="another batch"):
        run_batch([SCENARIO], seeds=7, journal=journal, resume=True)
    journal.write_text(journal.read_text() + '{"scenario_index": 0, "se')  # a crash mid-line
    ran = []
    resumed = run_batch([SCENARIO], seeds=6, chunk_size=2, journal=journal, resume=True,
                        progress=lambda done, total: ran.append(done))  # fmt: skip
    assert ran == [4, 6]  # only the four missing runs ran
    assert [row["seed"] for row in resumed.rows] == list(range(6))
    assert _untimed(resumed.rows) == _untimed(full.rows)


def test_a_killed_dask_worker_loses_no_run():
    distributed = pytest.importorskip("dask.distributed")
    import os
    import signal

    with (
        distributed.LocalCluster(
            n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None
        ) as cluster,  # fmt: skip
        distributed.Client(cluster) as client,
    ):
        pids = list(client.run(os.getpid).values())
        killed = []

        def kill_one(done, total):
            if not killed:
                os.kill(pids[0], signal.SIGKILL)  # mid-batch: other chunks are still queued
                killed.append(done)

        result = run_batch([SCENARIO], seeds=8, executor=client.get_executor(), chunk_size=1,
                           progress=kill_one)  # fmt: skip
    assert killed
    assert [row["seed"] for row in result.rows] == list(range(8))  # none lost, none twice
    assert all(row["status"] in ("arrived", "missed_goal") for row in result.rows)


def test_seeds_run_in_chunks_that_fit_the_memory_budget():
    from wheelbase.runner import prepare, run_seeds, seeds_per_chunk

    prepared = prepare(SCENARIO)
    per_chunk = seeds_per_chunk(prepared.engine, prepared.start, 2**20)
    twice = seeds_per_chunk(prepared.engine, prepared.start, 2**21)
    assert twice in (2 * per_chunk, 2 * per_chunk + 1)
    assert seeds_per_chunk(prepared.engine, prepared.start, 1.0) == 1  # at least one
    together = run_seeds(SCENARIO, range(5))
    one_by_one = run_seeds(SCENARIO, range(5), memory_budget=1.0)  # five chunks of one seed
    assert _untimed(together) == _untimed(one_by_one)
    with pytest.raises(ConfigError, match="memory_budget"):
        run_seeds(SCENARIO, range(2), memory_budget=0.0)


def test_resume_runs_again_the_rows_that_ended_in_error(tmp_path):
    journal = tmp_path / "rows.jsonl"
    full = run_batch([SCENARIO], seeds=3, journal=journal)
    lines = journal.read_text().splitlines()
    lost = json.loads(lines[2])  # seed 1, as if its chunk had been lost to a killed worker
    lines[2] = json.dumps({"scenario_index": 0, "name": "short", "seed": lost["seed"],
                           "status": "error", "error": "KilledWorker: ..."})  # fmt: skip
    journal.write_text("\n".join(lines) + "\n")
    ran = []
    resumed = run_batch([SCENARIO], seeds=3, journal=journal, resume=True,
                        progress=lambda done, total: ran.append(done))  # fmt: skip
    assert ran == [3]  # the one error row ran again
    assert _untimed(resumed.rows) == _untimed(full.rows)


def test_only_wheelbase_errors_become_rows(monkeypatch):
    import wheelbase.runner
    from wheelbase.batch import run_chunk
    from wheelbase.errors import PlanningError

    def broken(scenario, seeds, memory_budget=None):
        raise TypeError("a bug")

    def refused(scenario, seeds, memory_budget=None):
        raise PlanningError("start in collision")

    monkeypatch.setattr(wheelbase.runner, "run_seeds", refused)
    rows = run_chunk(SCENARIO, [0, 1])
    assert [row["status"] for row in rows] == ["error", "error"]
    assert rows[0]["error"] == "PlanningError: start in collision"
    monkeypatch.setattr(wheelbase.runner, "run_seeds", broken)
    with pytest.raises(TypeError, match="a bug"):
        run_chunk(SCENARIO, [0, 1])
    with pytest.raises(TypeError, match="a bug"), ThreadPoolExecutor(max_workers=1) as pool:
        run_batch([SCENARIO], seeds=2, executor=pool)  # on an executor too: not a row


def test_identical_rows_say_a_scenario_has_no_randomness():
    quiet = {**SCENARIO, "odometry": {"mode": "perfect"}, "name": "quiet"}
    result = run_batch([quiet, SCENARIO], seeds=3)
    (i, quiet_name, quiet_rows), (j, noisy_name, noisy_rows) = result.groups()
    assert (i, quiet_name, j, noisy_name) == (0, "quiet", 1, "short")
    assert result.identical(quiet_rows) and not result.identical(noisy_rows)
    assert result.summary(noisy_rows)["odometry_drift_m"]["max"] > 0
    assert "odometry_drift_m" not in result.summary(quiet_rows)  # perfect state: no drift
