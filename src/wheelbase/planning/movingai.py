"""The Moving AI pathfinding benchmark formats (Sturtevant 2012): ``.map`` grids and ``.scen``
start/goal tables."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path as FilePath

import numpy as np
from numpy.typing import ArrayLike

from wheelbase._validate import count_text, read_text
from wheelbase.errors import DataError, MapError
from wheelbase.limits import MAX_MAP_CELLS
from wheelbase.planning.occupancy import OccupancyGrid

__all__ = ["MovingAIScenario", "read_movingai_map", "read_movingai_scenarios"]

_MOVINGAI_PASSABLE = frozenset(".GS")


def read_movingai_map(
    path: str | FilePath,
    resolution: float = 1.0,
    origin: ArrayLike = (0.0, 0.0),
    *,
    max_cells: int = MAX_MAP_CELLS,
) -> OccupancyGrid:
    """Load a Moving AI benchmark ``.map`` file (Sturtevant 2012).

    ``.``, ``G`` and ``S`` are passable; every other terrain (``@``, ``O``, ``T``, ``W``) is
    blocked. The file's first row (Moving AI y = 0) becomes the highest grid row, so Moving
    AI cell ``(x, y)`` is grid cell ``(height − 1 − y, x)``.

    Parameters
    ----------
    path : str or pathlib.Path
        The ``.map`` file. Text after the ``height`` map rows (e.g. a BibTeX entry) is
        ignored.
    resolution : float
        Cell side [m/cell].
    origin : array_like
        ``(x0, y0)`` [m] of the lower-left corner.
    max_cells : int
        Most cells accepted, checked from the header before the rows are read (default
        :data:`wheelbase.limits.MAX_MAP_CELLS` = 1e8).

    Returns
    -------
    OccupancyGrid
    """
    path = FilePath(path)
    lines = read_text(path, "Moving AI map").splitlines()
    header: dict[str, str] = {}
    row0 = None
    for i, line in enumerate(lines):
        parts = line.split()
        if parts and parts[0] == "map":
            row0 = i + 1
            break
        if len(parts) == 2:
            header[parts[0]] = parts[1]
    if row0 is None or "height" not in header or "width" not in header:
        raise MapError(f"{path}: not a Moving AI map (needs height, width and map lines)")
    height, width = (_dimension(path, name, header[name]) for name in ("height", "width"))
    if height * width > max_cells:
        raise MapError(
            f"{path}: {height} × {width} = {count_text(height * width)} cells: more than "
            "max_cells = "
            f"{max_cells}; raise max_cells (scenarios: resources.max_map_cells) if you mean it"
        )
    rows = lines[row0 : row0 + height]
    if len(rows) < height or any(len(r) < width for r in rows):
        raise MapError(f"{path}: expected {height} rows of {width} characters")
    chars = np.array([list(r[:width]) for r in rows])
    blocked = ~np.isin(chars, list(_MOVINGAI_PASSABLE))
    return OccupancyGrid(np.flipud(blocked), resolution, tuple(np.ravel(origin)[:2]))


def _dimension(path: FilePath, name: str, text: str) -> int:
    if not (text.isascii() and text.isdigit() and len(text) <= 18) or int(text) < 1:
        raise MapError(f"{path}: {name} must be an integer >= 1 [cells] (got {text!r})")
    return int(text)


@dataclass(frozen=True)
class MovingAIScenario:
    """One row of a Moving AI ``.scen`` file.

    Parameters
    ----------
    bucket : int
        Difficulty bucket.
    map_name : str
        Map file name.
    width, height : int
        Map size [cells].
    start, goal : tuple of int
        Moving AI cells ``(x, y)`` (x = column, y = row from the top).
    optimal_length : float
        Optimal octile length [cells] (no corner cutting).
    """

    bucket: int
    map_name: str
    width: int
    height: int
    start: tuple[int, int]
    goal: tuple[int, int]
    optimal_length: float

    def grid_cells(self) -> tuple[tuple[int, int], tuple[int, int]]:
        """Start and goal as grid cells ``(row, col)`` of :func:`read_movingai_map`.

        Returns
        -------
        tuple
            ``((row, col), (row, col))``.
        """
        h = self.height
        return (h - 1 - self.start[1], self.start[0]), (h - 1 - self.goal[1], self.goal[0])


def read_movingai_scenarios(path: str | FilePath) -> list[MovingAIScenario]:
    """Read a Moving AI ``.scen`` file (version 1).

    Parameters
    ----------
    path : str or pathlib.Path
        The scenario file; lines that are not 9 tab- or space-separated fields after the
        version line (e.g. an appended BibTeX entry) end the table.

    Returns
    -------
    list of MovingAIScenario
    """
    path = FilePath(path)
    lines = read_text(FilePath(path), "scenario file").splitlines()
    out = []
    for line in lines[1:]:
        parts = line.split()
        if len(parts) != 9:
            break
        try:
            b, name, w, h, sx, sy, gx, gy, opt = parts
            out.append(
                MovingAIScenario(
                    int(b),
                    name,
                    int(w),
                    int(h),
                    (int(sx), int(sy)),
                    (int(gx), int(gy)),
                    float(opt),
                )
            )
        except ValueError:
            break
    if not out:
        raise DataError(f"{path}: no scenarios found")
    return out
