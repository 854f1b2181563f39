"""One entry point for recorded lidar data: the reader chosen by the file."""

from __future__ import annotations

from pathlib import Path

from wheelbase.datasets.scans import ScanLog
from wheelbase.errors import DataError

__all__ = ["LIDAR_SUFFIXES", "read_scans"]

LIDAR_SUFFIXES: tuple[str, ...] = (".log", ".clf", ".gz", ".db3", ".mcap")
"""Suffixes :func:`read_scans` knows: CARMEN logs (gzipped or not) and ROS 2 bags."""


def read_scans(path: str | Path, **options: object) -> ScanLog:
    """Read a lidar log: a CARMEN log (``.log``, ``.clf``, ``.gz``) or a ROS 2 bag (a ``.db3``
    or ``.mcap`` file, or a bag folder with ``metadata.yaml``).

    Parameters
    ----------
    path : str or Path
        The file or bag folder.
    **options
        Passed to the reader (:func:`~wheelbase.datasets.carmen.read_carmen`,
        :func:`~wheelbase.datasets.rosbag.read_bag`).

    Returns
    -------
    ScanLog
    """
    path = Path(path)
    if (path.is_dir() and (path / "metadata.yaml").is_file()) or path.suffix in (".db3", ".mcap"):
        from wheelbase.datasets.rosbag import read_bag

        return read_bag(path, **options)  # type: ignore[arg-type]
    if path.suffix in (".log", ".clf", ".gz"):
        from wheelbase.datasets.carmen import read_carmen

        return read_carmen(path, **options)  # type: ignore[arg-type]
    if not path.exists():
        raise DataError(f"lidar log not found: {path}")
    raise DataError(
        f"{path}: unknown lidar log; expected a CARMEN log ({', '.join(LIDAR_SUFFIXES[:3])}), a "
        "ROS 2 bag (.db3, .mcap, or a folder with metadata.yaml), or an MRCLAM folder"
    )
