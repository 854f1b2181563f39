"""Batch runs: many scenarios, or one scenario over many noise seeds, vectorised and in chunks.

The seeds of one scenario run as one vectorised batch: the plan is made once and the engine
steps one robot per seed in lockstep (:func:`wheelbase.runner.run_seeds`). Large batches are
split into chunks of seeds, each chunk one task on any :class:`concurrent.futures.Executor` —
a local process pool, or a Dask distributed client's executor
(``Client(address).get_executor()``) so that a sweep scales out to a cluster without code
changes. A task receives the scenario as plain data (a dict) and a list of seeds and returns
plain data (a list of dicts), so any executor that can pickle functions and dicts can run it.
Without an executor the chunks run in this process.
"""

from __future__ import annotations

import csv
import json
import math
from collections.abc import Callable, Sequence
from concurrent.futures import Executor, as_completed
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from wheelbase.errors import ConfigError

__all__ = ["BatchResult", "run_batch", "run_chunk"]


def run_chunk(scenario: dict[str, Any], seeds: Sequence[int]) -> list[dict[str, Any]]:
    """Run one scenario (given as a dict) over ``seeds`` as one vectorised batch; never raises.

    Parameters
    ----------
    scenario : dict
        A scenario mapping as accepted by :func:`wheelbase.scenario.load_scenario`.
    seeds : sequence of int
        Noise seeds, one run each.

    Returns
    -------
    list of dict
        The metrics of each run with ``name`` and ``seed``, in the order of ``seeds``. When the
        chunk cannot run (an invalid scenario, a start in collision, or any other exception),
        every row has ``status`` ``"error"`` and the exception's type and message in
        ``error``.
    """
    from wheelbase.runner import run_seeds

    try:
        return run_seeds(scenario, seeds)
    except Exception as error:  # a batch records every failure and goes on
        name = scenario.get("name", "scenario")
        message = f"{type(error).__name__}: {error}"
        return [{"name": name, "seed": int(seed), "status": "error", "error": message}
                for seed in seeds]  # fmt: skip


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
    chunk_size: int | None = None,
    progress: Callable[[int, int], None] | None = None,
) -> BatchResult:
    """Run every scenario (× every seed) as vectorised chunks and collect the metrics.

    Parameters
    ----------
    scenarios : sequence
        Scenarios: :class:`~wheelbase.scenario.Scenario` objects, dicts, paths or bundled names.
    seeds : int, optional
        Run each scenario with noise seeds 0 … seeds − 1 (default: each scenario's own seed).
    executor : concurrent.futures.Executor, optional
        Where to run the chunks (a ``ProcessPoolExecutor``, a Dask client's
        ``get_executor()``, …; it stays open). Default: in this process, one chunk per
        scenario.
    chunk_size : int, optional
        Seeds per chunk, >= 1 (default: all seeds of a scenario without an executor; with one,
        about four chunks per scenario and at most 256 seeds each).
    progress : callable, optional
        ``progress(done, total)`` (runs) after each completed chunk.

    Returns
    -------
    BatchResult
        Rows in submission order (scenario-major, then seed).
    """
    import time

    from wheelbase.scenario import Scenario, load_scenario

    if seeds is not None and (isinstance(seeds, bool) or not isinstance(seeds, int) or seeds < 1):
        raise ConfigError(f"seeds must be an integer >= 1 (got {seeds!r})")
    if chunk_size is not None and (
        isinstance(chunk_size, bool) or not isinstance(chunk_size, int) or chunk_size < 1
    ):
        raise ConfigError(f"chunk_size must be an integer >= 1 (got {chunk_size!r})")
    if not scenarios:
        raise ConfigError("give at least one scenario")
    resolved = [s if isinstance(s, Scenario) else load_scenario(s) for s in scenarios]
    tasks: list[tuple[dict[str, Any], list[int]]] = []
    for scenario in resolved:
        data = scenario.model_dump(mode="json")
        own = list(range(seeds)) if seeds is not None else [scenario.seed]
        size = chunk_size
        if size is None:
            size = len(own) if executor is None else min(256, max(1, math.ceil(len(own) / 4)))
        tasks.extend((data, own[i : i + size]) for i in range(0, len(own), size))

    total = sum(len(chunk) for _, chunk in tasks)
    start = time.perf_counter()
    results: list[list[dict[str, Any]] | None] = [None] * len(tasks)
    done = 0
    if executor is None:
        for index, (data, chunk) in enumerate(tasks):
            results[index] = run_chunk(data, chunk)
            done += len(chunk)
            if progress is not None:
                progress(done, total)
    else:
        futures = {
            executor.submit(run_chunk, data, chunk): index
            for index, (data, chunk) in enumerate(tasks)
        }
        for future in as_completed(futures):
            index = futures[future]
            results[index] = future.result()
            done += len(tasks[index][1])
            if progress is not None:
                progress(done, total)
    rows = [row for chunk in results if chunk is not None for row in chunk]
    return BatchResult(rows=rows, wall_time_s=time.perf_counter() - start)
