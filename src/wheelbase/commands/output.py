"""What the commands print: one console, one progress bar, one way to count things.

Every command prints through :func:`console`. On a terminal that is rich's console; piped into a
file or another program (not a TTY) no line is wrapped, so names and paths stay whole for
``grep`` and scripts, and no progress bar is drawn (a bar that cannot be erased would leave a
blank line before the result or the error). Counts in messages go through :func:`plural`
("1 run", "2 runs").
"""

from __future__ import annotations

from typing import Any

from rich.console import Console
from rich.progress import Progress

__all__ = ["PIPED_WIDTH", "console", "plural", "progress"]

PIPED_WIDTH = 10_000
"""Columns of the console when the output is not a terminal: wide enough that no table cell or
line of a command is folded (rich's default there is 80)."""


def console(stderr: bool = False) -> Console:
    """The console a command prints to.

    Parameters
    ----------
    stderr : bool
        Print to standard error instead of standard output.

    Returns
    -------
    rich.console.Console
        No highlighting of numbers or paths; when not a terminal, :data:`PIPED_WIDTH` columns
        and no soft wrapping of long lines.
    """
    probe = Console(stderr=stderr)
    if probe.is_terminal:
        return Console(stderr=stderr, highlight=False)
    return Console(stderr=stderr, highlight=False, soft_wrap=True, width=PIPED_WIDTH)


def progress(output: Console, *columns: Any) -> Progress:
    """A transient progress bar on ``output``, drawn only on a terminal.

    Parameters
    ----------
    output : rich.console.Console
        The command's console (:func:`console`).
    *columns : rich.progress.ProgressColumn
        The bar's columns (rich's defaults if none).

    Returns
    -------
    rich.progress.Progress
        Use as a context manager; disabled when ``output`` is not a terminal.
    """
    return Progress(*columns, console=output, transient=True, disable=not output.is_terminal)


def plural(count: int, noun: str, plural_noun: str | None = None) -> str:
    """``"1 run"``, ``"2 runs"``, ``"0 cusps"``: a count and its noun.

    Parameters
    ----------
    count : int
        How many.
    noun : str
        The singular.
    plural_noun : str, optional
        The plural (default ``noun + "s"``).

    Returns
    -------
    str

    Examples
    --------
    >>> plural(1, "cusp"), plural(3, "cusp"), plural(2, "batch", "batches")
    ('1 cusp', '3 cusps', '2 batches')
    """
    word = noun if count == 1 else (plural_noun or f"{noun}s")
    return f"{count} {word}"
