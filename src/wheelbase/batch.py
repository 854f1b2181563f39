"""Batch runs: many scenarios, or one scenario over many noise seeds, vectorised and in chunks.

The seeds of one scenario run as vectorised batches: the plan is made once and the engine
steps one robot per seed in lockstep (:func:`wheelbase.runner.run_seeds`), as many seeds at a
time as fit a memory budget (:data:`wheelbase.limits.BATCH_MEMORY`, 512 MiB, or
``memory_budget``); only the finished runs' metrics are kept, so memory stays flat however
many seeds there are. Large batches are
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

from wheelbase.errors import ConfigError, WheelbaseError
from wheelbase.limits import MAX_SEEDS

__all__ = ["JOURNAL", "BatchResult", "Journal", "run_batch", "run_chunk"]


def run_chunk(
    scenario: dict[str, Any], seeds: Sequence[int], memory_budget: float | None = None
) -> list[dict[str, Any]]:
    """Run one scenario (given as a dict) over ``seeds`` as vectorised batches.

    Parameters
    ----------
    scenario : dict
        A scenario mapping as accepted by :func:`wheelbase.scenario.load_scenario`.
    seeds : sequence of int
        Noise seeds, one run each.
    memory_budget : float, optional
        Bytes the logs of the seeds run together may take (default
        :data:`wheelbase.limits.BATCH_MEMORY`).

    Returns
    -------
    list of dict
        The metrics of each run with ``name`` and ``seed``, in the order of ``seeds``. When the
        chunk cannot run for a reason wheelbase names (a :class:`~wheelbase.errors.WheelbaseError`:
        an invalid scenario, a start in collision), every row has ``status`` ``"error"`` and the
        error's type and message in ``error``.

    Raises
    ------
    Exception
        Any other exception (a TypeError, a MemoryError: a bug or the machine, not the
        scenario) propagates: it is not a result.
    """
    from wheelbase.runner import run_seeds

    try:
        return run_seeds(scenario, seeds, memory_budget=memory_budget)
    except WheelbaseError as error:  # a batch records every failure of a scenario, goes on
        return _error_rows(scenario.get("name", "scenario"), seeds, error)


_NOT_OUTCOMES = frozenset(
    {"seed", "scenario_index", "planning_time_s", "compile_time_s", "expanded_nodes"}
)
"""Row keys that are not a run's outcome: which seed, and how long the shared plan took."""


def _worker_gave_up(error: BaseException) -> bool:
    """Whether an executor lost the task (a killed process, a broken pool, a Dask worker
    killed too often) rather than the task failing."""
    from concurrent.futures import BrokenExecutor, CancelledError

    if isinstance(error, (BrokenExecutor, CancelledError, WheelbaseError)):
        return True
    return type(error).__name__ in ("KilledWorker", "CommClosedError")


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

    def groups(self) -> list[tuple[int, str, list[dict[str, Any]]]]:
        """The rows of each scenario: (scenario_index, name, rows), in submission order."""
        out: dict[int, tuple[int, str, list[dict[str, Any]]]] = {}
        for row in self.rows:
            index = int(row.get("scenario_index", 0))
            out.setdefault(index, (index, str(row.get("name", "")), []))[2].append(row)
        return list(out.values())

    @staticmethod
    def identical(rows: list[dict[str, Any]]) -> bool:
        """Whether several runs gave the same row (besides seed and timings): a scenario
        without randomness, whose seeds all run the same run.

        Parameters
        ----------
        rows : list of dict
            The rows of one scenario.
        """
        if len(rows) < 2:
            return False

        def outcome(row: dict[str, Any]) -> dict[str, Any]:
            return {k: v for k, v in row.items() if k not in _NOT_OUTCOMES}

        first = outcome(rows[0])
        return all(outcome(row) == first for row in rows[1:])

    def summary(self, rows: list[dict[str, Any]] | None = None) -> dict[str, dict[str, float]]:
        """Mean, median, 90th percentile, min and max of every numeric metric.

        Parameters
        ----------
        rows : list of dict, optional
            The rows to summarise (default: all; one scenario's from :meth:`groups`).
        """
        rows = self.rows if rows is None else rows
        out: dict[str, dict[str, float]] = {}
        keys: list[str] = []
        for row in rows:
            keys.extend(key for key in row if key not in keys and key not in ("seed",))
        for key in keys:
            values = [row.get(key) for row in rows]
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
        statuses = [row.get("status") for row in rows]
        out["success_rate"] = {"mean": statuses.count("arrived") / max(1, len(statuses))}
        return out

    def write(self, folder: str | Path, *, force: bool = False) -> list[Path]:
        """Write ``batch.csv`` and ``batch.json`` (rows, the summary of all runs, and each
        scenario's summary and whether its runs were identical) into ``folder``.

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
            "scenarios": [
                {
                    "scenario_index": index,
                    "name": name,
                    "runs": len(rows),
                    "identical_rows": self.identical(rows),
                    "summary": self.summary(rows),
                }
                for index, name, rows in self.groups()
            ],
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
    memory_budget: float | None = None,
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
        With ``journal``: take the rows already there and run only the missing ones, and
        again those that ended ``error`` (a chunk lost to a killed worker).
    memory_budget : float, optional
        Bytes the logs of the seeds one process runs together may take (default
        :data:`wheelbase.limits.BATCH_MEMORY`, 512 MiB): the seeds of a chunk run in
        vectorised parts that fit it.

    Returns
    -------
    BatchResult
        Rows in submission order (scenario-major, then seed), each with ``scenario_index``.
        A chunk that fails with a :class:`~wheelbase.errors.WheelbaseError`, or whose worker
        gives up, gives rows with ``status`` ``"error"``; the batch goes on. Any other
        exception propagates. On a Dask cluster a chunk whose worker dies is run again
        elsewhere by Dask; its rows are kept once (by position).
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
        missing = [
            seed
            for seed in own
            if book is None
            or (number, seed) not in book.done
            or book.done[(number, seed)].get("status") == "error"  # run it again
        ]
        size = chunk_size
        if size is None:
            quarter = math.ceil(len(missing) / 4)
            size = len(missing) if executor is None else min(256, quarter)
        size = max(size, 1)
        tasks.extend((number, data, missing[i : i + size]) for i in range(0, len(missing), size))

    total = sum(len(own) for _, _, own in plan)
    done = total - sum(len(chunk) for _, _, chunk in tasks)
    if memory_budget is not None:
        from wheelbase._validate import positive

        positive("memory_budget", memory_budget, "bytes")
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
            finished(number, run_chunk(data, chunk, memory_budget))
    else:
        futures = {
            executor.submit(run_chunk, data, chunk, memory_budget): (number, chunk)
            for number, data, chunk in tasks
        }
        for future in as_completed(futures):
            number, chunk = futures[future]
            try:
                rows = future.result()
            except Exception as error:
                if not _worker_gave_up(error):
                    raise  # a bug, not a lost worker: not a row
                rows = _error_rows(resolved[number].name, chunk, error)
            finished(number, rows)
    ordered = [found[(number, seed)] for number, _, own in plan for seed in own]
    return BatchResult(rows=ordered, wall_time_s=time.perf_counter() - start)
