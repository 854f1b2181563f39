"""The simulator's own runs as scan records: the lidar scans of an engine log with its poses."""

from __future__ import annotations

from typing import Any

import numpy as np

from wheelbase.datasets.scans import ScanLog, clean_ranges
from wheelbase.errors import DataError

__all__ = ["scans_from_log"]


def scans_from_log(log: Any, lidar: Any, robot: int = 0, *, source: str = "simulation") -> ScanLog:
    """The scans one robot of a :class:`wheelbase.sim.Log` recorded, as a :class:`ScanLog`.

    ``odometry`` is the robot's estimated pose at each scan (the odometry, when the scenario
    localises by odometry), ``reference`` its true pose (the ground truth); the ranges are
    rounded to float32, as a ROS 2 ``LaserScan`` stores them, so that a bag written from the
    record reads back the same numbers.

    Parameters
    ----------
    log : Log
        An engine log that kept the scans (a scenario with ``sensors.lidar``).
    lidar : Lidar
        The lidar that took them (beam angles, maximum range, mount).
    robot : int
        Which robot.
    source : str
        Name of the record.

    Returns
    -------
    ScanLog

    Raises
    ------
    DataError
        If the log kept no scan of that robot.
    """
    rows = sorted(row for (r, row) in log.scans if r == robot)
    if not rows:
        raise DataError(f"the log kept no lidar scan of robot {robot} (add sensors.lidar)")
    ranges = np.array([log.scans[(robot, row)] for row in rows], dtype=np.float32)
    ranges, invalid = clean_ranges(ranges.astype(np.float64))
    index = np.array(rows)
    return ScanLog(
        t=np.asarray(log.t, dtype=np.float64)[index],
        ranges=ranges,
        angles=np.asarray(lidar.beam_angles, dtype=np.float64),
        max_range=float(lidar.max_range),
        odometry=np.asarray(log.estimated_pose[robot], dtype=np.float64)[index],
        reference=np.asarray(log.true_pose[robot], dtype=np.float64)[index],
        mount=tuple(float(v) for v in lidar.mount),
        invalid_readings=invalid,
        source=source,
    )
