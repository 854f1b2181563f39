"""The plain record of a recorded or simulated 2-D lidar log, shared by every reader."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from wheelbase.errors import DataError

__all__ = ["ScanLog", "clean_ranges", "stamps_advance"]

ADVANCING_FRACTION = 0.9
"""Least fraction of the steps between a log's sorted time stamps that must be positive for
the stamps to be times: CSAIL's, Freiburg campus's and Örebro's corrected logs hold one stamp
for nearly every scan, the MIT infinite corridor's jumps to 2³² s after its fourth scan."""


def stamps_advance(t: np.ndarray) -> bool:
    """Whether the time stamps ``t`` are times: finite, and at least
    ``ADVANCING_FRACTION`` of the steps between them, sorted, positive (a single scan
    counts as timed).

    Parameters
    ----------
    t : numpy.ndarray, shape (N,)
        The stamps [s].

    Returns
    -------
    bool
    """
    t = np.asarray(t, dtype=np.float64)
    if t.size < 2:
        return True
    steps = np.diff(np.sort(t))
    return bool(np.all(np.isfinite(t)) and np.mean(steps > 0) >= ADVANCING_FRACTION)


@dataclass(frozen=True)
class ScanLog:
    """Lidar scans with the poses logged beside them.

    Attributes
    ----------
    t : numpy.ndarray, shape (N,)
        Scan times [s], non-decreasing; or the log's stamps as recorded where they are not
        times (:attr:`timed` False: the scans are then in the order recorded).
    ranges : numpy.ndarray, shape (N, B)
        Ranges [m]; NaN where a reading was invalid (NaN, inf, negative: counted in
        ``invalid_readings``); readings >= ``max_range`` mean "no return".
    angles : numpy.ndarray, shape (B,)
        Beam directions [rad] in the sensor frame (x forward, y left).
    max_range : float
        Readings at or beyond this [m] are no return: they clear the cells they cross and
        mark none.
    odometry : numpy.ndarray or None, shape (N, 3)
        The robot's odometry pose at each scan (x [m], y [m], θ [rad]), if the log has it.
    reference : numpy.ndarray or None, shape (N, 3)
        A pose logged with each scan that is not odometry: a SLAM solution (the CARMEN
        "corrected" logs) or the ground truth of a simulation; used for evaluation only.
    mount : tuple of float
        The sensor's pose in the robot frame (x [m], y [m], yaw [rad]).
    invalid_readings : int
        Readings replaced by NaN.
    source : str
        Where the log came from (a file name).
    """

    t: np.ndarray
    ranges: np.ndarray
    angles: np.ndarray
    max_range: float
    odometry: np.ndarray | None = None
    reference: np.ndarray | None = None
    mount: tuple[float, float, float] = (0.0, 0.0, 0.0)
    invalid_readings: int = 0
    source: str = ""
    extra: dict = field(default_factory=dict, repr=False)

    def __post_init__(self) -> None:
        n = self.t.shape[0]
        if self.ranges.ndim != 2 or self.ranges.shape[0] != n:
            raise DataError(f"ranges must have shape ({n}, beams) (got {self.ranges.shape})")
        if self.angles.shape != (self.ranges.shape[1],):
            raise DataError(
                f"angles must have shape ({self.ranges.shape[1]},) (got {self.angles.shape})"
            )
        for name in ("odometry", "reference"):
            value = getattr(self, name)
            if value is not None and value.shape != (n, 3):
                raise DataError(f"{name} must have shape ({n}, 3) (got {value.shape})")

    @property
    def n_scans(self) -> int:
        """Number of scans N."""
        return int(self.t.shape[0])

    @property
    def timed(self) -> bool:
        """Whether the time stamps are times (:func:`stamps_advance`)."""
        return stamps_advance(self.t)

    @property
    def duration(self) -> float:
        """Time from the first scan to the last [s]; 0 where the stamps are not times."""
        return float(self.t[-1] - self.t[0]) if self.n_scans and self.timed else 0.0

    def subset(self, index: slice | np.ndarray) -> ScanLog:
        """The scans selected by ``index`` (a slice or an index array).

        Parameters
        ----------
        index : slice or numpy.ndarray
            Which scans.
        """
        pick = lambda a: None if a is None else a[index]  # noqa: E731
        return ScanLog(self.t[index], self.ranges[index], self.angles, self.max_range,
                       pick(self.odometry), pick(self.reference), self.mount,
                       self.invalid_readings, self.source, self.extra)  # fmt: skip


def clean_ranges(ranges: np.ndarray) -> tuple[np.ndarray, int]:
    """Ranges with NaN, ±inf and negative readings replaced by NaN, and how many there were.

    Parameters
    ----------
    ranges : numpy.ndarray
        Raw readings [m].

    Returns
    -------
    tuple of numpy.ndarray and int
    """
    ranges = np.array(ranges, dtype=np.float64)
    with np.errstate(invalid="ignore"):
        bad = ~np.isfinite(ranges) | (ranges < 0.0)
    ranges[bad] = np.nan
    return ranges, int(bad.sum())
