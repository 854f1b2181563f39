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
import hashlib
import json
import math
from collections.abc import Callable, Sequence
from concurrent.futures import Executor, as_completed
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from wheelbase.errors import ConfigError
from wheelbase.limits import MAX_SEEDS

__all__ = ["JOURNAL", "BatchResult", "Journal", "run_batch", "run_chunk"]


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
        return _error_rows(scenario.get("name", "scenario"), seeds, error)


def _error_rows(name: str, seeds: Sequence[int], error: Exception) -> list[dict[str, Any]]:
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


JOURNAL = "rows.jsonl"
"""File (JSON lines) where a batch appends every finished chunk's rows as it finishes."""


class Journal:
    """Rows of a batch on disk as they finish, so that an interrupted batch can resume.

    The first line records the batch (a fingerprint of its scenarios and seeds); each further
    line is one finished row, written and flushed as its chunk completes, so a Ctrl-C or a
    crash loses at most the chunks still running. Resuming reads the rows back (a torn last
    line from a crash is ignored) and refuses a journal written for another batch.

    Parameters
    ----------
    path : str or Path
        The journal file.
    fingerprint : str
        What identifies the batch (:func:`run_batch` hashes the resolved scenarios and seeds).
    resume : bool
        Continue the journal that is there (default: refuse to replace an existing one).
    """

    def __init__(self, path: str | Path, fingerprint: str, *, resume: bool = False) -> None:
        self.path = Path(path)
        self.done: dict[tuple[int, int], dict[str, Any]] = {}
        if self.path.exists():
            if not resume:
                raise FileExistsError(
                    f"{self.path} exists (an earlier batch): use --resume to finish it or "
                    "--force to start again"
                )
            self._read(fingerprint)
        else:
            self.path.parent.mkdir(parents=True, exist_ok=True)
            self.path.write_text(json.dumps({"batch": fingerprint}) + "\n")

    def _read(self, fingerprint: str) -> None:
        lines = self.path.read_text().splitlines()
        try:
            header = json.loads(lines[0]) if lines else {}
        except json.JSONDecodeError:
            header = {}
        if header.get("batch") != fingerprint:
            raise ConfigError(
                f"{self.path} was written for another batch (other scenarios or seeds): "
                "resume with the same arguments, or start again with --force"
            )
        for line in lines[1:]:
            try:
                row = json.loads(line)
            except json.JSONDecodeError:  # the line a crash cut short: that run runs again
                continue
            self.done[(int(row["scenario_index"]), int(row["seed"]))] = row

    def append(self, rows: list[dict[str, Any]]) -> None:
        """Write finished rows and flush them to disk.

        Parameters
        ----------
        rows : list of dict
            Rows with ``scenario_index`` and ``seed``.
        """
        with self.path.open("a") as handle:
            for row in rows:
                handle.write(json.dumps(row, default=_plain) + "\n")
            handle.flush()
        for row in rows:
            self.done[(int(row["scenario_index"]), int(row["seed"]))] = row


def _plain(value: Any) -> Any:
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, np.ndarray):
        return value.tolist()
    raise TypeError(f"cannot write {type(value).__name__} to JSON")


def run_batch(
    scenarios: Sequence[Any],
    *,
    seeds: int | None = None,
    executor: Executor | None = None,
    chunk_size: int | None = None,
    progress: Callable[[int, int], None] | None = None,
    journal: str | Path | None = None,
    resume: bool = False,
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
    journal : str or Path, optional
        Append every finished row to this JSON-lines file as its chunk finishes
        (:class:`Journal`): an interrupted batch keeps what it finished.
    resume : bool
        With ``journal``: take the rows already there and run only the missing ones.

    Returns
    -------
    BatchResult
        Rows in submission order (scenario-major, then seed), each with ``scenario_index``.
        A chunk that raises (a run in error) gives rows with ``status`` ``"error"``; the batch
        goes on. On a Dask cluster a chunk whose worker dies is run again elsewhere by Dask;
        its rows are kept once (by position).
    """
    import time

    from wheelbase.scenario import Scenario, load_scenario

    if seeds is not None and (
        isinstance(seeds, bool) or not isinstance(seeds, int) or not 1 <= seeds <= MAX_SEEDS
    ):
        raise ConfigError(
            f"seeds must be an integer in [1, {MAX_SEEDS}] (wheelbase.limits.MAX_SEEDS; "
            f"got {seeds!r})"
        )
    if chunk_size is not None and (
        isinstance(chunk_size, bool) or not isinstance(chunk_size, int) or chunk_size < 1
    ):
        raise ConfigError(f"chunk_size must be an integer >= 1 (got {chunk_size!r})")
    if not scenarios:
        raise ConfigError("give at least one scenario")
    resolved = [s if isinstance(s, Scenario) else load_scenario(s) for s in scenarios]
    plan: list[tuple[int, dict[str, Any], list[int]]] = []
    for number, scenario in enumerate(resolved):
        data = scenario.model_dump(mode="json")
        own = list(range(seeds)) if seeds is not None else [scenario.seed]
        plan.append((number, data, own))
    book = None
    if journal is not None:
        fingerprint = hashlib.sha256(
            json.dumps([[data, own] for _, data, own in plan], sort_keys=True).encode()
        ).hexdigest()
        book = Journal(journal, fingerprint, resume=resume)
    tasks: list[tuple[int, dict[str, Any], list[int]]] = []
    for number, data, own in plan:
        missing = [seed for seed in own if book is None or (number, seed) not in book.done]
        size = chunk_size
        if size is None:
            quarter = math.ceil(len(missing) / 4)
            size = len(missing) if executor is None else min(256, quarter)
        size = max(size, 1)
        tasks.extend((number, data, missing[i : i + size]) for i in range(0, len(missing), size))

    total = sum(len(own) for _, _, own in plan)
    done = total - sum(len(chunk) for _, _, chunk in tasks)
    start = time.perf_counter()

    def finished(number: int, rows: list[dict[str, Any]]) -> None:
        nonlocal done
        rows = [{"scenario_index": number, **row} for row in rows]
        if book is not None:
            book.append(rows)
        for row in rows:
            found[(number, int(row["seed"]))] = row
        done += len(rows)
        if progress is not None:
            progress(done, total)

    found: dict[tuple[int, int], dict[str, Any]] = dict(book.done) if book is not None else {}
    if executor is None:
        for number, data, chunk in tasks:
            finished(number, run_chunk(data, chunk))
    else:
        futures = {
            executor.submit(run_chunk, data, chunk): (number, chunk)
            for number, data, chunk in tasks
        }
        for future in as_completed(futures):
            number, chunk = futures[future]
            try:
                rows = future.result()
            except Exception as error:  # the worker gave up (killed too often, broken pool)
                rows = _error_rows(resolved[number].name, chunk, error)
            finished(number, rows)
    ordered = [found[(number, seed)] for number, _, own in plan for seed in own]
    return BatchResult(rows=ordered, wall_time_s=time.perf_counter() - start)
