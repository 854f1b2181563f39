"""How good a SLAM result is: relative errors (Kümmerle et al. 2009), absolute trajectory error,
and the agreement of two occupancy maps.

**Relative error** (R. Kümmerle, B. Steder, C. Dornhege, M. Ruhnke, G. Grisetti, C. Stachniss
and A. Kleiner, "On measuring the accuracy of SLAM algorithms", Autonomous Robots 27(4), 2009,
eq. 2): for pose pairs (i, j), δ_ij = X_i⁻¹X_j of the estimate against δ*_ij of the reference;
the translational error of a pair is ‖trans(δ_ij ⊖ δ*_ij)‖ and the rotational |rot(δ_ij ⊖
δ*_ij)|; papers report their means and standard deviations. The benchmark's relations were
checked by hand; where only a reference trajectory exists, :func:`relation_pairs` chooses them:
every scan with the next one at least ``min_distance`` along the reference (local relations)
and, for each scan, the nearest earlier scan at least ``loop_gap_s`` before it whose reference
pose is within ``loop_distance`` and ``loop_angle`` (relations across loops: the robot came
back); where the log's stamps are not times (:func:`~wheelbase.datasets.scans.stamps_advance`:
CSAIL's corrected log holds one stamp for every scan), at least ``loop_gap_m`` along the
reference instead. The figures are then of the same kind as the published ones, not equal in
definition.

**Absolute trajectory error**: the RMS of the position error after the rigid motion that best
aligns the estimate to the truth (least squares, Umeyama 1991 without scale), as the TUM RGB-D
benchmark defines it.

**Map agreement**: of the cells both maps call known (free or occupied), the fraction on which
they agree.
"""

from __future__ import annotations

import math

import numpy as np

from wheelbase.datasets.scans import stamps_advance
from wheelbase.errors import InputError
from wheelbase.geometry import relative_pose, wrap_angle
from wheelbase.planning import OccupancyGrid

__all__ = [
    "absolute_trajectory_error",
    "align_trajectory",
    "map_agreement",
    "relation_pairs",
    "relative_errors",
]


def relation_pairs(
    reference: np.ndarray,
    t: np.ndarray,
    *,
    min_distance: float = 0.5,
    loop_gap_s: float = 30.0,
    loop_distance: float = 1.0,
    loop_angle: float = math.radians(30.0),
    loop_gap_m: float = 10.0,
) -> tuple[np.ndarray, np.ndarray]:
    """Local and loop relations (i, j) chosen from a reference trajectory (module docstring).

    Parameters
    ----------
    reference : numpy.ndarray, shape (N, 3)
        Reference poses.
    t : numpy.ndarray, shape (N,)
        Their times [s].
    min_distance : float
        Local pairs: j is the first scan after i at least this far along the reference [m].
    loop_gap_s : float
        Loop pairs: at least this much time apart [s].
    loop_distance, loop_angle : float
        Loop pairs: reference poses at most this far apart [m] and turned [rad].
    loop_gap_m : float
        Loop pairs where ``t`` are not times: at least this far apart along the reference [m].

    Returns
    -------
    tuple of numpy.ndarray
        ``(local, loops)``, each of shape (P, 2).
    """
    steps = np.hypot(*np.diff(reference[:, :2], axis=0).T)
    along = np.concatenate([[0.0], np.cumsum(steps)])
    j = np.searchsorted(along, along + min_distance)
    keep = j < len(along)
    local = np.column_stack([np.flatnonzero(keep), j[keep]])
    timed = stamps_advance(t)
    loops = []
    for k in range(len(t)):
        if timed:
            earlier = np.flatnonzero(t <= t[k] - loop_gap_s)
        else:
            earlier = np.flatnonzero(along <= along[k] - loop_gap_m)
        if earlier.size == 0:
            continue
        d = np.hypot(*(reference[earlier, :2] - reference[k, :2]).T)
        turn = np.abs(wrap_angle(reference[earlier, 2] - reference[k, 2]))
        ok = (d <= loop_distance) & (turn <= loop_angle)
        if ok.any():
            loops.append((int(earlier[ok][np.argmin(d[ok])]), k))
    return local, np.array(loops, dtype=np.int64).reshape(-1, 2)


def relative_errors(
    estimate: np.ndarray, reference: np.ndarray, pairs: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Translational [m] and rotational [rad] errors of the relations ``pairs`` (Kümmerle).

    Parameters
    ----------
    estimate, reference : numpy.ndarray, shape (N, 3)
        Poses.
    pairs : numpy.ndarray, shape (P, 2)
        Index pairs (i, j).

    Returns
    -------
    tuple of numpy.ndarray
        Shapes (P,), (P,).
    """
    if estimate.shape != reference.shape:
        raise InputError(f"estimate {estimate.shape} and reference {reference.shape} differ")
    if len(pairs) == 0:
        return np.zeros(0), np.zeros(0)
    d_est = relative_pose(estimate[pairs[:, 0]], estimate[pairs[:, 1]])
    d_ref = relative_pose(reference[pairs[:, 0]], reference[pairs[:, 1]])
    e = relative_pose(d_ref, d_est)
    return np.hypot(e[:, 0], e[:, 1]), np.abs(e[:, 2])


def align_trajectory(estimate: np.ndarray, truth: np.ndarray) -> np.ndarray:
    """The estimate moved by the rigid motion that best fits its positions to the truth's.

    Parameters
    ----------
    estimate, truth : numpy.ndarray, shape (N, 3)
        Poses.

    Returns
    -------
    numpy.ndarray, shape (N, 3)
    """
    a, b = estimate[:, :2], truth[:, :2]
    ma, mb = a.mean(0), b.mean(0)
    h = (a - ma).T @ (b - mb)
    u, _, vt = np.linalg.svd(h)
    d = np.sign(np.linalg.det(vt.T @ u.T))
    rot = vt.T @ np.diag([1.0, d]) @ u.T
    angle = math.atan2(rot[1, 0], rot[0, 0])
    xy = (a - ma) @ rot.T + mb
    return np.column_stack([xy, wrap_angle(estimate[:, 2] + angle)])


def absolute_trajectory_error(estimate: np.ndarray, truth: np.ndarray) -> float:
    """RMS position error [m] after :func:`align_trajectory`.

    Parameters
    ----------
    estimate, truth : numpy.ndarray, shape (N, 3)
        Poses.
    """
    aligned = align_trajectory(estimate, truth)
    return float(np.sqrt(np.mean(np.sum((aligned[:, :2] - truth[:, :2]) ** 2, axis=1))))


def map_agreement(estimate: OccupancyGrid, truth: OccupancyGrid) -> tuple[float, int]:
    """Of the cells both maps call known, the fraction where they agree (free/occupied).

    The estimate's cells are looked up at the truth's cell centres (the maps may differ in
    origin and extent, not in resolution).

    Parameters
    ----------
    estimate, truth : OccupancyGrid
        The maps (unknown masks as loaded or built).

    Returns
    -------
    tuple of float and int
        The fraction and the number of cells compared.
    """
    rows, cols = np.indices(truth.shape)
    centres = truth.cell_to_world(np.stack([rows, cols], -1).reshape(-1, 2))
    cells = estimate.world_to_cell(centres)
    inside = estimate.contains(centres)
    ci = np.clip(cells[:, 0], 0, estimate.shape[0] - 1)
    cj = np.clip(cells[:, 1], 0, estimate.shape[1] - 1)
    est_unknown = np.ones(len(centres), bool)
    est_unknown[inside] = (
        estimate.unknown[ci, cj][inside] if estimate.unknown is not None else False
    )
    true_unknown = (truth.unknown.ravel() if truth.unknown is not None
                    else np.zeros(len(centres), bool))  # fmt: skip
    both = ~est_unknown & ~true_unknown
    if not both.any():
        return math.nan, 0
    agree = estimate.occupied[ci, cj][both] == truth.occupied.ravel()[both]
    return float(agree.mean()), int(both.sum())


def lidar_metrics(log, result) -> dict[str, float | int]:
    """The ``metrics.json`` figures of a lidar SLAM run (``relative_*`` against the log's
    reference poses, when it has them: :func:`relation_pairs`, local and loop relations
    together; ``*_local`` and ``*_loops`` apart).

    Parameters
    ----------
    log : ScanLog
        The scans.
    result : SlamResult
        The run.

    Returns
    -------
    dict
    """
    out: dict[str, float | int] = {
        "scans": log.n_scans,
        "keyframes": int(result.keyframes.size),
        "loop_closures": len(result.loops),
        "processing_time_s": result.processing_time_s,
        "real_time_factor": result.real_time_factor,
        "duration_s": result.duration_s,
        "invalid_readings": log.invalid_readings,
        **{k: int(v) for k, v in result.stats.items()},
    }
    if log.reference is not None:
        local, loops = relation_pairs(log.reference, log.t)
        for suffix, pairs in (("", np.vstack([local, loops])), ("_local", local),
                              ("_loops", loops)):  # fmt: skip
            et, er = relative_errors(result.poses, log.reference, pairs)
            ok = et.size > 0
            out[f"relative_translation_error_m{suffix}"] = float(et.mean()) if ok else math.nan
            out[f"relative_translation_error_m{suffix}_std"] = float(et.std()) if ok else math.nan
            out[f"relative_rotation_error_deg{suffix}"] = (
                float(np.degrees(er.mean())) if ok else math.nan
            )
            out[f"relative_rotation_error_deg{suffix}_std"] = (
                float(np.degrees(er.std())) if ok else math.nan
            )
            out[f"relations{suffix}"] = int(et.size)
        out["position_rmse_m"] = absolute_trajectory_error(result.poses, log.reference)
    return out
