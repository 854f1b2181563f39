"""``wheelbase demo``, ``run``, ``batch`` and ``schema``: the closed loop from scenario files."""

from __future__ import annotations

import json
import time
from pathlib import Path

import typer
from rich.console import Console
from rich.markup import escape
from rich.progress import BarColumn, TextColumn, TimeRemainingColumn
from rich.table import Table

from wheelbase.commands.output import console as make_console
from wheelbase.commands.output import plural
from wheelbase.commands.output import progress as progress_bar
from wheelbase.errors import WheelbaseError

__all__ = ["DEMO_SCENARIO", "register"]

MAX_WORKERS = 1024
"""Most local worker processes ``wheelbase batch --workers`` starts (far above any machine's
cores; a typo of 1e20 was an OverflowError)."""

DEMO_SCENARIO = "demo"
DEMO_DIR = "wheelbase-demo"

SUMMARY_KEYS = (
    ("status", "status", "{}"),
    ("planning_time_s", "planning time [s]", "{:.3f}"),
    ("path_length_m", "path length [m]", "{:.2f}"),
    ("cusps", "cusps", "{}"),
    ("duration_s", "run time (simulated) [s]", "{:.1f}"),
    ("tracking_rms_position_error_m", "tracking RMS error [m]", "{:.4f}"),
    ("tracking_max_position_error_m", "tracking max error [m]", "{:.4f}"),
    ("final_position_error_true_m", "final error, true [m]", "{:.4f}"),
    ("final_position_error_estimated_m", "final error, estimated [m]", "{:.4f}"),
    ("odometry_drift_m", "odometry drift [m]", "{:.4f}"),
    ("localization_rms_error_m", "localisation RMS error [m]", "{:.4f}"),
    ("localization_max_error_m", "localisation max error [m]", "{:.4f}"),
    ("localization_final_error_m", "localisation final error [m]", "{:.4f}"),
    ("arrival_delay_s", "arrived after the reference by [s]", "{:.1f}"),
    ("min_clearance_m", "min clearance [m]", "{:.3f}"),
    ("wheel_energy_j", "wheel energy [J]", "{:.1f}"),
)


def _summary(metrics: dict, title: str) -> Table:
    table = Table(title=title)
    table.add_column("metric")
    table.add_column("value", justify="right")
    for key, label, form in SUMMARY_KEYS:
        if metrics.get(key) is not None:
            table.add_row(escape(label), form.format(metrics[key]))
    return table


def _run_and_report(
    source, out: Path, *, force: bool, gif: bool, console: Console, mcap: bool = False
) -> dict:
    from wheelbase.report import write_report
    from wheelbase.runner import run
    from wheelbase.scenario import load_scenario

    scenario = load_scenario(source)
    if not force:
        from wheelbase.report import MCAP_FILE, REPORT_FILES

        for name in (*REPORT_FILES, MCAP_FILE) if mcap else REPORT_FILES:
            if (out / name).exists():
                raise FileExistsError(
                    f"{out / name} exists: a report is already there (use --force)"
                )
    if mcap:
        from wheelbase.mcap_export import require_foxglove

        require_foxglove()  # before the run: a missing extra should not cost a run
    started = time.perf_counter()
    with progress_bar(
        console,
        TextColumn("[progress.description]{task.description}"),
        BarColumn(),
        TextColumn("{task.completed:.0f}/{task.total:.0f} s simulated"),
        TimeRemainingColumn(),
    ) as bar:
        task = bar.add_task(f"running {scenario.name}", total=None, visible=False)

        def progress(t: float, end: float) -> None:
            # Only runs that take more than a second get a bar.
            if time.perf_counter() - started > 1.0:
                bar.update(task, completed=t, total=max(end, t), visible=True)

        try:
            result = run(scenario, progress=progress)
        except WheelbaseError as error:
            _write_failure(out, scenario, error, force=force)
            raise
    written = write_report(result, out, force=force, gif=gif, mcap=mcap)
    console.print(
        _summary(result.metrics, f"{scenario.name} ({time.perf_counter() - started:.1f} s)")
    )
    console.print(
        f"report written to {out.resolve()}/ ({plural(len(written), 'file')})", markup=False
    )
    return result.metrics


def _write_failure(out: Path, scenario, error: Exception, *, force: bool) -> None:
    """A partial report marked as failed: metrics.json with the error, and the scenario."""
    path = out / "metrics.json"
    if path.exists() and not force:
        return
    out.mkdir(parents=True, exist_ok=True)
    payload = {"name": scenario.name, "status": "failed", "error": str(error)}
    path.write_text(json.dumps(payload, indent=2) + "\n")
    (out / "scenario.yaml").write_text(scenario.to_yaml())


def register(app: typer.Typer) -> None:
    """Add ``demo``, ``run``, ``batch`` and ``schema`` to the ``wheelbase`` app.

    Parameters
    ----------
    app : typer.Typer
        The main application.
    """

    @app.command("demo")
    def demo_command(
        out: Path = typer.Option(
            Path(DEMO_DIR), help="Report folder; the demo replaces its own previous report there."
        ),
        gif: bool = typer.Option(True, help="Render animation.gif."),
    ) -> None:
        """Run the bundled demo: the RM100 reverse-parks into a warehouse bay (Hybrid A*,
        dynamic plant, computed-torque tracking, encoder odometry) and writes a report."""
        console = make_console()
        _run_and_report(DEMO_SCENARIO, out, force=True, gif=gif, console=console)

    @app.command("run")
    def run_command(
        scenario: str = typer.Argument(..., help="Scenario YAML file or bundled scenario name."),
        out: Path = typer.Option(None, help="Report folder [default: ./<scenario name>/]."),
        force: bool = typer.Option(False, help="Overwrite an existing report."),
        gif: bool = typer.Option(True, help="Render animation.gif."),
        mcap: bool = typer.Option(
            False, help="Also write run.mcap for Foxglove (needs the 'foxglove' extra)."
        ),
    ) -> None:
        """Run a closed-loop scenario and write its report (metrics.json, log.csv,
        scenario.yaml, PNG figures, animation.gif, and run.mcap with --mcap)."""
        from wheelbase.scenario import load_scenario

        name = load_scenario(scenario).name
        target = out if out is not None else Path(name)
        _run_and_report(scenario, target, force=force, gif=gif, console=make_console(), mcap=mcap)

    @app.command("schema")
    def schema_command() -> None:
        """Print the JSON Schema of scenario files (for editors that validate YAML)."""
        from wheelbase.scenario import scenario_json_schema

        typer.echo(json.dumps(scenario_json_schema(), indent=2))

    @app.command("scenarios")
    def scenarios_command() -> None:
        """List the bundled scenarios (usable by name with `wheelbase run NAME`)."""
        from wheelbase.scenario import bundled_scenarios, load_scenario

        table = Table(title="bundled scenarios")
        table.add_column("name", no_wrap=True)
        for column in ("map", "robot", "plant", "law", "goals"):
            table.add_column(column, overflow="fold")
        for name, path in bundled_scenarios().items():
            s = load_scenario(path)
            robot = s.robot.preset or s.robot.model
            table.add_row(name, s.map, robot, s.plant, s.controller.law, str(len(s.goals)))
        make_console().print(table)

    @app.command("batch")
    def batch_command(
        scenarios: list[str] = typer.Argument(..., help="Scenario files or bundled names."),
        seeds: int = typer.Option(None, help="Run each scenario with noise seeds 0..N-1."),
        workers: int = typer.Option(
            1, help="Local worker processes; 1 runs the seeds as one vectorised batch here."
        ),
        chunk_size: int = typer.Option(
            None, help="Seeds per task on a process pool or Dask (default: about 4 per scenario)."
        ),
        scheduler: str = typer.Option(
            None, help="Dask scheduler address (needs the 'dask' extra): run on that cluster."
        ),
        out: Path = typer.Option(
            Path("wheelbase-batch"), help="Folder for rows.jsonl (as runs finish), batch.csv/json."
        ),
        force: bool = typer.Option(False, help="Overwrite an existing batch table."),
        resume: bool = typer.Option(
            False,
            help="Finish the batch in --out: run only the seeds missing from rows.jsonl (and "
            "again those that ended in error).",
        ),
        memory_mb: float = typer.Option(
            None,
            "--memory-mb",
            help="Memory [MiB] the logs of the seeds one process runs together may take "
            "(default 512): more seeds run in smaller vectorised parts.",
        ),
    ) -> None:
        """Run many scenarios (or one over many seeds) as vectorised batches; write one table.

        The seeds of a scenario run in lockstep in one process; --workers N splits them into
        chunks over N local processes, --scheduler over a Dask cluster. Every finished chunk's
        rows go to OUT/rows.jsonl at once: after a Ctrl-C or a crash, --resume runs the rest.
        """
        from concurrent.futures import ProcessPoolExecutor

        from wheelbase.batch import JOURNAL, run_batch

        if not 1 <= workers <= MAX_WORKERS:
            raise WheelbaseError(f"--workers must be in [1, {MAX_WORKERS}] (got {workers})")
        if resume and force:
            raise WheelbaseError("--resume finishes the batch in --out; --force starts it again")
        if memory_mb is not None and not 0 < memory_mb < float("inf"):
            raise WheelbaseError(f"--memory-mb must be > 0 MiB (got {memory_mb:g})")
        for name in ("batch.csv", "batch.json", JOURNAL):
            if (out / name).exists() and not (force or resume):
                raise FileExistsError(
                    f"{out / name} exists; use --resume to finish that batch or --force to "
                    "start again"
                )
        if force and (out / JOURNAL).exists():
            (out / JOURNAL).unlink()
        console = make_console()
        executor = None
        client = None
        if scheduler:
            try:
                from dask.distributed import Client
            except ImportError:
                raise WheelbaseError(
                    "--scheduler needs Dask: pip install 'wheelbase[dask]'"
                ) from None
            client = Client(scheduler)
            executor = client.get_executor()
        elif workers > 1:
            executor = ProcessPoolExecutor(max_workers=workers)
        try:
            with progress_bar(console) as bar:
                task = bar.add_task("runs", total=None)
                result = run_batch(
                    scenarios,
                    seeds=seeds,
                    executor=executor,
                    chunk_size=chunk_size,
                    progress=lambda done, total: bar.update(task, completed=done, total=total),
                    journal=out / JOURNAL,
                    resume=resume,
                    memory_budget=None if memory_mb is None else memory_mb * 2**20,
                )
        finally:
            if client is not None:
                client.close()
            elif executor is not None:
                executor.shutdown()
        result.write(out, force=force or resume)
        console.print(
            f"{plural(len(result.rows), 'run')} in {result.wall_time_s:.1f} s "
            f"({result.runs_per_second:.2f} runs/s)",
            markup=False,
        )
        for _, name, rows in result.groups():  # one table per scenario: never averaged across
            summary = result.summary(rows)
            table = Table(title=f"{name}: {plural(len(rows), 'run')}")
            for column in ("metric", "mean", "p50", "p90", "max"):
                table.add_column(column, justify="right" if column != "metric" else "left")
            for key, _, form in SUMMARY_KEYS[1:]:
                if key in summary:
                    stats = summary[key]
                    values = (form.format(stats[s]) for s in ("mean", "p50", "p90", "max"))
                    table.add_row(key, *values)
            table.add_row("success rate", f"{summary['success_rate']['mean']:.0%}", "", "", "")
            console.print(table)
            if result.identical(rows):
                console.print(
                    f"{name}: the {len(rows)} seeds gave identical runs: the scenario has no "
                    "randomness (give it encoder noise, odometry.tick_noise_std, or noisy "
                    "sensors)",
                    markup=False,
                )
        console.print(f"wrote {out / 'batch.csv'} and {out / 'batch.json'}", markup=False)
