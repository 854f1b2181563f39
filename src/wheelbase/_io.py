"""Writing result tables (private): one CSV writer for every result and command."""

from __future__ import annotations

import csv
from collections.abc import Mapping
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike

__all__ = ["write_csv"]


def write_csv(
    path: str | Path, columns: Mapping[str, ArrayLike], *, overwrite: bool = False
) -> Path:
    """Write named columns of equal length to a CSV file, refusing to replace a file.

    Integer columns are written as integers, others with ``repr`` (round-trip exact floats).

    Parameters
    ----------
    path : str or Path
        Output file.
    columns : mapping of str to array_like
        Column name → values (1-D, all the same length).
    overwrite : bool
        Replace an existing file (default: raise FileExistsError).
    """
    path = Path(path)
    if path.exists() and not overwrite:
        raise FileExistsError(f"{path} exists; pass overwrite=True to replace it")
    arrays = [np.asarray(values) for values in columns.values()]
    cells = [
        [str(int(v)) for v in a] if np.issubdtype(a.dtype, np.integer)
        else [repr(float(v)) for v in a]
        for a in arrays
    ]  # fmt: skip
    with path.open("w", newline="") as handle:
        writer = csv.writer(handle)
        writer.writerow(list(columns))
        writer.writerows(zip(*cells, strict=True))
    return path
