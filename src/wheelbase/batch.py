"""Batch runs: many scenarios, or one scenario over many noise seeds, on any executor.

:func:`run_batch` submits one closed-loop run per (scenario, seed) to a
:class:`concurrent.futures.Executor` — a local process pool by default, or a Dask distributed
client's executor (``Client(address).get_executor()``) so that a sweep scales out to a cluster
without code changes — and gathers the metrics of every run into a :class:`BatchResult` table.
Each task receives the scenario as plain data (a dict) and returns plain data (a dict), so any
executor that can pickle functions and dicts can run it.
"""

from __future__ import annotations

import csv
import json
import math
from collections.abc import Callable, Sequence
from concurrent.futures import Executor, ProcessPoolExecutor, as_completed
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from wheelbase.errors import ConfigError, WheelbaseError

__all__ = ["BatchResult", "run_batch", "run_metrics"]


def run_metrics(scenario: dict[str, Any]) -> dict[str, Any]:
    """Run one scenario (given as a dict) and return its metrics; never raises.

    Parameters
    ----------
    scenario : dict
        A scenario mapping as accepted by :func:`wheelbase.scenario.load_scenario`.

    Returns
    -------
    dict
        The run's metrics with ``name`` and ``seed``; a failed run has ``status`` ``"error"``
        and the message in ``error``.
    """
    from wheelbase.runner import run

    label = {"name": scenario.get("name", "scenario"), "seed": scenario.get("seed", 0)}
    try:
        result = run(scenario)
    except WheelbaseError as error:
        return {**label, "status": "error", "error": str(error)}
    return {**label, **result.metrics}


@dataclass(frozen=True)
class BatchResult:
    """Metrics of every run of a batch, in submission order.

    Attributes
    ----------
    rows : list of dict
        One dict of metrics per run.
    wall_time_s : float
        Wall-clock time of the whole batch [s].
    """

    rows: list[dict[str, Any]]
    wall_time_s: float

    @property
    def runs_per_second(self) -> float:
        """Completed runs per wall-clock second."""
        return len(self.rows) / self.wall_time_s if self.wall_time_s > 0 else math.inf

    def summary(self) -> dict[str, dict[str, float]]:
        """Mean, median, 90th percentile, min and max of every numeric metric."""
        out: dict[str, dict[str, float]] = {}
        keys = [key for key in self.rows[0] if key != "seed"] if self.rows else []
        for key in keys:
            values = [row.get(key) for row in self.rows]
            numbers = np.array(
                [
                    float(v)
                    for v in values
                    if isinstance(v, (int, float)) and not isinstance(v, bool)
                ]
            )
            numbers = numbers[np.isfinite(numbers)]
            if numbers.size == 0:
                continue
            out[key] = {
                "mean": float(np.mean(numbers)),
                "p50": float(np.percentile(numbers, 50)),
                "p90": float(np.percentile(numbers, 90)),
                "min": float(np.min(numbers)),
                "max": float(np.max(numbers)),
            }
        statuses = [row.get("status") for row in self.rows]
        out["success_rate"] = {"mean": statuses.count("arrived") / max(1, len(statuses))}
        return out

    def write(self, folder: str | Path, *, force: bool = False) -> list[Path]:
        """Write ``batch.csv`` and ``batch.json`` (rows + summary) into ``folder``.

        Parameters
        ----------
        folder : str or Path
            Output folder (created).
        force : bool
            Overwrite existing files (default: raise FileExistsError).
        """
        folder = Path(folder)
        folder.mkdir(parents=True, exist_ok=True)
        paths = [folder / "batch.csv", folder / "batch.json"]
        existing = [path for path in paths if path.exists()]
        if existing and not force:
            raise FileExistsError(f"{existing[0]} exists; use --force to overwrite")
        keys: list[str] = []
        for row in self.rows:
            keys.extend(key for key in row if key not in keys)
        with paths[0].open("w", newline="") as handle:
            writer = csv.DictWriter(handle, fieldnames=keys)
            writer.writeheader()
            writer.writerows(self.rows)
        payload = {
            "runs": len(self.rows),
            "wall_time_s": self.wall_time_s,
            "runs_per_second": self.runs_per_second,
            "summary": self.summary(),
            "rows": self.rows,
        }
        paths[1].write_text(json.dumps(payload, indent=2, default=float))
        return paths


def run_batch(
    scenarios: Sequence[Any],
    *,
    seeds: int | None = None,
    executor: Executor | None = None,
    workers: int = 2,
    progress: Callable[[int, int], None] | None = None,
) -> BatchResult:
    """Run every scenario (× every seed) on an executor and collect the metrics.

    Parameters
    ----------
    scenarios : sequence
        Scenarios: :class:`~wheelbase.scenario.Scenario` objects, dicts, paths or bundled names.
    seeds : int, optional
        Run each scenario with noise seeds 0 … seeds − 1 (default: each scenario's own seed).
    executor : concurrent.futures.Executor, optional
        Where to run (default: a ``ProcessPoolExecutor`` with ``workers`` processes, shut down at
        the end; an executor you pass stays open).
    workers : int
        Processes of the default pool, >= 1.
    progress : callable, optional
        ``progress(done, total)`` after each completed run.

    Returns
    -------
    BatchResult
        Rows in submission order (scenario-major, then seed).
    """
    import time

    from wheelbase.scenario import Scenario, load_scenario

    if isinstance(workers, bool) or not isinstance(workers, int) or workers < 1:
        raise ConfigError(f"workers must be an integer >= 1 (got {workers!r})")
    if seeds is not None and (isinstance(seeds, bool) or not isinstance(seeds, int) or seeds < 1):
        raise ConfigError(f"seeds must be an integer >= 1 (got {seeds!r})")
    if not scenarios:
        raise ConfigError("give at least one scenario")
    resolved = [s if isinstance(s, Scenario) else load_scenario(s) for s in scenarios]
    tasks = []
    for scenario in resolved:
        data = scenario.model_dump(mode="json")
        for seed in range(seeds) if seeds is not None else [scenario.seed]:
            tasks.append({**data, "seed": seed})

    own = executor is None
    pool = ProcessPoolExecutor(max_workers=workers) if own else executor
    start = time.perf_counter()
    rows: list[dict[str, Any] | None] = [None] * len(tasks)
    try:
        futures = {pool.submit(run_metrics, task): index for index, task in enumerate(tasks)}
        for done, future in enumerate(as_completed(futures), start=1):
            rows[futures[future]] = future.result()
            if progress is not None:
                progress(done, len(tasks))
    finally:
        if own:
            pool.shutdown()
    return BatchResult(
        rows=[row for row in rows if row is not None], wall_time_s=time.perf_counter() - start
    )
