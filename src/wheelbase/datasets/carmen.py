"""CARMEN log files (``.log``, ``.clf``, gzipped or not): laser scans with their poses.

The Carnegie Mellon Robot Navigation Toolkit's text logs (Montemerlo, Roy and Thrun, IROS 2003)
hold one message per line. Read here:

``FLASER n r₁ … rₙ x y θ odom_x odom_y odom_θ ipc_time host logger_time``
    The front laser of the old format: n readings over 180° (a SICK LMS), the first at −90°,
    spaced 180°/n (1° for n = 180, 0.5° for 360), the pose of the laser and the robot's
    odometry. CARMEN's SICK driver reports "no return" as its maximum, 81.83 m: readings at or
    beyond ``max_range`` (81.0 m by default) are no return.
``ROBOTLASER1``
    The newer format, ``ROBOTLASER1 type start fov resolution max_range accuracy
    remission_mode n r₁ … rₙ m e₁ … eₘ laser_x laser_y laser_θ robot_x robot_y robot_θ tv rv
    forward side turn ipc_time host logger_time``: its own beam geometry and maximum range,
    and the laser and robot poses (the mount is the laser pose in the robot's frame, from the
    first scan).
``ODOM x y θ tv rv accel ipc_time host logger_time``
    Counted; the scans carry their odometry pose already.

The scan's own pose (``x y θ`` of FLASER, the laser pose of ROBOTLASER1) is returned as the
``reference``: in the Freiburg "corrected" logs it is a SLAM solution, not odometry.
Other messages (``PARAM``, ``NEFF``, ``RLASER``, ``TRUEPOS``, …) are counted and skipped.
"""

from __future__ import annotations

import gzip
import math
from pathlib import Path

import numpy as np

from wheelbase._validate import positive
from wheelbase.datasets.scans import ScanLog, clean_ranges, stamps_advance
from wheelbase.errors import DataError
from wheelbase.geometry import relative_pose, wrap_angle

__all__ = ["FLASER_NO_RETURN_M", "read_carmen"]

FLASER_NO_RETURN_M = 81.0
"""Readings of an old-format FLASER at or beyond this [m] are no return (SICK: 81.83 m)."""

_MAX_BEAMS = 100_000


def _lines(path: Path) -> list[str]:
    if not path.is_file():
        raise DataError(f"CARMEN log not found: {path}")
    try:
        raw = path.read_bytes()
        if raw[:2] == b"\x1f\x8b":
            raw = gzip.decompress(raw)
        return raw.decode("utf-8", errors="replace").splitlines()
    except (OSError, EOFError, gzip.BadGzipFile) as exc:
        raise DataError(f"cannot read CARMEN log {path}: {exc}") from None


def _floats(path: Path, number: int, tokens: list[str], start: int, count: int) -> np.ndarray:
    if start + count > len(tokens):
        raise DataError(
            f"{path}:{number}: {tokens[0]} is cut short (needs {start + count} fields, "
            f"has {len(tokens)})"
        )
    try:
        return np.array(tokens[start : start + count], dtype=np.float64)
    except ValueError:
        raise DataError(f"{path}:{number}: {tokens[0]} holds a non-number") from None


def _count(path: Path, number: int, tokens: list[str], at: int) -> int:
    value = _floats(path, number, tokens, at, 1)[0]
    if not (math.isfinite(value) and value == int(value) and 0 < value <= _MAX_BEAMS):
        raise DataError(
            f"{path}:{number}: {tokens[0]} beam count must be an integer in [1, {_MAX_BEAMS}] "
            f"(got {tokens[at]!r})"
        )
    return int(value)


def read_carmen(path: str | Path, *, max_range: float = FLASER_NO_RETURN_M) -> ScanLog:
    """Read the laser scans of a CARMEN log (module docstring).

    Parameters
    ----------
    path : str or Path
        ``.log`` or ``.clf`` file, gzipped or not (detected by its first bytes).
    max_range : float
        For FLASER lines: readings at or beyond this are no return [m], > 0. ROBOTLASER1
        lines carry their own.

    Returns
    -------
    ScanLog
        Times from the logger time stamp; ``odometry`` and ``reference`` as logged; NaN,
        inf and negative readings replaced by NaN and counted (``invalid_readings``);
        ``extra`` holds ``skipped_messages`` (lines of other types) and ``odom_messages``.

    Raises
    ------
    DataError
        A missing or unreadable file, a malformed line (named), scans of different beam
        counts or geometry, or a log without a single scan.
    """
    path = Path(path)
    max_range = positive("max_range", max_range, "m")
    times, scans, refs, odoms = [], [], [], []
    geometry: tuple[float, float, int, float] | None = None
    mount = None
    skipped = odom_lines = 0
    for number, line in enumerate(_lines(path), start=1):
        tokens = line.split()
        if not tokens or tokens[0].startswith("#"):
            continue
        tag = tokens[0]
        if tag == "FLASER":
            n = _count(path, number, tokens, 1)
            values = _floats(path, number, tokens, 2, n + 6)
            stamp = _floats(path, number, tokens, n + 10, 1) if len(tokens) > n + 10 else None
            if stamp is None:
                stamp = _floats(path, number, tokens, n + 8, 1)
            shape = (-math.pi / 2.0, math.pi / n, n, max_range)
            ranges, pose, odom = values[:n], values[n : n + 3], values[n + 3 : n + 6]
        elif tag == "ROBOTLASER1":
            head = _floats(path, number, tokens, 2, 5)  # start, fov, resolution, max, accuracy
            n = _count(path, number, tokens, 8)
            ranges = _floats(path, number, tokens, 9, n)
            m_at = 9 + n
            m = int(_floats(path, number, tokens, m_at, 1)[0])
            if not 0 <= m <= _MAX_BEAMS:
                raise DataError(f"{path}:{number}: ROBOTLASER1 remission count {m} invalid")
            rest = _floats(path, number, tokens, m_at + 1 + m, 11)
            stamp = _floats(path, number, tokens, m_at + 1 + m + 13, 1)
            pose, odom = rest[0:3], rest[3:6]
            if not (head[3] > 0 and math.isfinite(head[3])):
                raise DataError(f"{path}:{number}: maximum range must be > 0 (got {head[3]})")
            shape = (float(head[0]), float(head[2]), n, float(head[3]))
            if mount is None and np.all(np.isfinite(rest[:6])):
                mount = tuple(relative_pose(odom, pose).tolist())
        elif tag == "ODOM":
            odom_lines += 1
            continue
        else:
            skipped += 1
            continue
        if geometry is None:
            geometry = shape
        elif shape[2] != geometry[2] or not np.allclose(shape, geometry, rtol=0, atol=1e-9):
            raise DataError(
                f"{path}:{number}: scan geometry {shape} differs from the first scan's "
                f"{geometry} (one laser per log)"
            )
        if not (np.all(np.isfinite(pose)) and np.all(np.isfinite(odom))):
            raise DataError(f"{path}:{number}: {tag} pose holds NaN or inf")
        times.append(float(stamp[0]))
        scans.append(ranges)
        refs.append(pose)
        odoms.append(odom)
    if geometry is None:
        raise DataError(
            f"{path}: no laser scan (no FLASER or ROBOTLASER1 line; {skipped + odom_lines} "
            "other lines)"
        )
    start, step, n, sensor_max = geometry
    ranges, invalid = clean_ranges(np.array(scans))
    t = np.array(times)
    if not np.all(np.isfinite(t)):
        raise DataError(f"{path}: a scan's time stamp is NaN or inf")
    # messages a logger wrote slightly out of order are put in time order, but stamps that
    # are not times (one stamp for every scan, a jump to 2³² s) leave the order recorded
    order = np.argsort(t, kind="stable") if stamps_advance(t) else np.arange(t.size)
    reference = np.array(refs)[order]
    reference[:, 2] = wrap_angle(reference[:, 2])
    odometry = np.array(odoms)[order]
    odometry[:, 2] = wrap_angle(odometry[:, 2])
    return ScanLog(
        t=t[order],
        ranges=ranges[order],
        angles=start + step * np.arange(n),
        max_range=sensor_max,
        odometry=odometry,
        reference=reference,
        mount=mount or (0.0, 0.0, 0.0),
        invalid_readings=invalid,
        source=path.name,
        extra={"skipped_messages": skipped, "odom_messages": odom_lines},
    )
