"""The NumPy backend of :class:`wheelbase.control.MPPI` (private): the reference the compiled
backends are held to (same costs to rounding on the same noise).

Rollouts take the Euler step of :func:`wheelbase.integrate.integrate_step` through the model's
body twist; the critics are those of :mod:`wheelbase.control.mppi_critics` and
:mod:`wheelbase.control.obstacle_critics`, vectorised over samples and steps.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from wheelbase.control.mppi_bounds import KIND_HOLONOMIC, KIND_VELOCITY, clip_commands
from wheelbase.control.obstacle_critics import (
    HOLD_STEP,
    PerceptionArrays,
    costmap_costs,
    track_costs,
)
from wheelbase.geometry import wrap_angle
from wheelbase.integrate import integrate_step

__all__ = ["contact_steps", "numpy_costs", "rollout"]


def rollout(mppi: Any, pose: np.ndarray, controls: np.ndarray) -> np.ndarray:
    """Poses ``(N, T + 1, 3)`` of command sequences ``(N, T, m)`` from ``pose`` (Euler steps of
    the controller's ``dt`` through its model's body twist).

    Parameters
    ----------
    mppi : MPPI
        The controller (its model, command names and step).
    pose : numpy.ndarray, shape (3,)
        Start pose.
    controls : numpy.ndarray, shape (N, T, m)
        Commands.

    Returns
    -------
    numpy.ndarray
    """
    from wheelbase.control.base import command_to_inputs

    n, steps = controls.shape[:2]
    twist = mppi.model.twist(command_to_inputs(controls, mppi.command_names, mppi.model))
    poses = np.empty((n, steps + 1, 3))
    poses[:, 0] = pose
    for t in range(steps):
        z = twist[:, t]
        poses[:, t + 1] = integrate_step(poses[:, t], z, z, z, mppi.dt, "euler")
    return poses


def numpy_costs(
    mppi: Any,
    pose: np.ndarray,
    mean: np.ndarray,
    lo: np.ndarray,
    hi: np.ndarray,
    scale: np.ndarray,
    window: np.ndarray,
    info: np.ndarray,
    last: np.ndarray,
    w: np.ndarray,
    noise: np.ndarray,
    mp: np.ndarray,
    seen: PerceptionArrays,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Costs ``(K,)``, sampled commands ``(K, T, m)`` and first contacts ``(K,)`` of one MPPI
    iteration.

    Parameters
    ----------
    mppi : MPPI
        The controller (read only).
    pose : numpy.ndarray, shape (3,)
        (0, 0, θ): the robot, positions relative to it.
    mean : numpy.ndarray, shape (T, m)
        The warm-started sequence.
    lo, hi : numpy.ndarray, shape (m,)
        This call's bounds.
    scale : numpy.ndarray, shape (m,)
        The limits ū that normalise effort and rate.
    window, info : numpy.ndarray
        The path window and its scalars (:meth:`~wheelbase.control.local_path.PathWindow.window`).
    last : numpy.ndarray, shape (m,)
        The last command sent.
    w : numpy.ndarray
        :meth:`~wheelbase.control.MPPICritics.vector`, switched for this call.
    noise : numpy.ndarray, shape (K, T, m)
        Perturbations ε.
    mp : numpy.ndarray, shape (4,)
        The map's (x0, y0, resolution, enabled), origin relative to the robot.
    seen : PerceptionArrays
        The costmap and tracks, relative to the robot.

    Returns
    -------
    costs, controls : numpy.ndarray
    first_contact : numpy.ndarray of int, shape (K,)
        Each sample's first colliding step, T where it never collides (as
        :func:`contact_steps`).
    """
    c = mppi.critics
    controls = clip_commands(mppi._kind, mean[None] + noise, lo, hi)
    poses = rollout(mppi, pose, controls)
    after = poses[:, 1:]
    steps = mppi.horizon_steps
    cost = np.zeros(mppi.samples)
    goal_mode = info[0] > 0.5
    checked = np.arange(c.path_stride - 1, steps, c.path_stride)
    if checked.size:
        pts = after[:, checked]
        d2 = (pts[..., 0, None] - window[:, 0]) ** 2 + (pts[..., 1, None] - window[:, 1]) ** 2
        nearest = np.argmin(d2, axis=-1)
        dmin = np.take_along_axis(d2, nearest[..., None], -1)[..., 0]
        err = wrap_angle(pts[..., 2] - window[nearest, 2])
        cost += w[0] * np.sum(np.sqrt(dmin), axis=1) / checked.size
        cost += w[1] * np.sum(err * err, axis=1) / checked.size
    if not goal_mode:
        end = after[:, -1]
        d2 = (end[:, 0, None] - window[:, 0]) ** 2 + (end[:, 1, None] - window[:, 1]) ** 2
        cost += c.follow * (window[-1, 3] - window[np.argmin(d2, axis=-1), 3])
    else:
        dist = np.hypot(after[..., 0] - info[1], after[..., 1] - info[2])
        cost += c.goal * np.sum(dist, axis=1) / steps
        cost += c.goal_heading * np.abs(wrap_angle(after[:, -1, 2] - info[3]))
    hit, clearance, costmap_soft, track_soft = _obstacles(mppi, after, info, mp, seen, w[14])
    if clearance is not None:
        gap = np.where(clearance > 0.0, np.maximum(c.inflation - clearance, 0.0), 0.0)
        cost += w[5] * np.sum(gap * gap, axis=1) / steps
    if costmap_soft is not None:
        cost += w[12] * np.sum(costmap_soft, axis=1) / steps
    if track_soft is not None:
        cost += w[13] * np.sum(track_soft, axis=1) / steps
    cost += np.where(hit.any(axis=1), w[11], 0.0)
    v = controls[..., 0]
    cost += c.prefer_forward * np.sum(np.maximum(-info[4] * v, 0.0), axis=1) * mppi.dt
    cost += c.effort * np.sum((controls / scale) ** 2, axis=(1, 2)) / steps
    previous = np.concatenate(
        [np.broadcast_to(last, (mppi.samples, 1, mppi.nu)), controls[:, :-1]], 1
    )
    cost += c.rate * np.sum(((controls - previous) / scale) ** 2, axis=(1, 2)) / steps
    if mppi._kind in (KIND_VELOCITY, KIND_HOLONOMIC):
        cost += c.twirl * np.sum(np.abs(controls[..., -1]), axis=1) / (steps * scale[-1])
    return cost, controls, _first(hit)


def contact_steps(
    mppi: Any,
    pose: np.ndarray,
    controls: np.ndarray,
    info: np.ndarray,
    mp: np.ndarray,
    seen: PerceptionArrays,
) -> np.ndarray:
    """The first step of each sequence at which its rollout collides: the static map, the
    costmap or a track (the lethal rules of :func:`numpy_costs`); T where it never does.

    Parameters
    ----------
    mppi : MPPI
        The controller (read only).
    pose : numpy.ndarray, shape (3,)
        (0, 0, θ): the robot, positions relative to it.
    controls : numpy.ndarray, shape (N, T, m)
        Command sequences.
    info : numpy.ndarray
        The path window's scalars (its slot 6: the collision relief).
    mp : numpy.ndarray, shape (4,)
        The map's (x0, y0, resolution, enabled), origin relative to the robot.
    seen : PerceptionArrays
        The costmap and tracks, relative to the robot.

    Returns
    -------
    numpy.ndarray of int, shape (N,)
        Index (0-based, the pose after step k + 1) of the first collision, T if none.
    """
    after = rollout(mppi, pose, controls)[:, 1:]
    return _first(_obstacles(mppi, after, info, mp, seen, mppi.critics.dynamic_inflation)[0])


def _first(hit: np.ndarray) -> np.ndarray:
    """The first True step of each row of ``hit`` (N, T); T where none is."""
    return np.where(hit.any(axis=1), np.argmax(hit, axis=1), hit.shape[1])


def _obstacles(
    mppi: Any,
    after: np.ndarray,
    info: np.ndarray,
    mp: np.ndarray,
    seen: PerceptionArrays,
    dynamic_inflation: float,
) -> tuple[np.ndarray, np.ndarray | None, np.ndarray | None, np.ndarray | None]:
    """What the static map, the costmap and the tracks say of rollout poses ``(N, T, 3)``:
    whether each step collides ``(N, T)``, and the map's clearance ``(N, T)``, the costmap's
    soft costs ``(N, T)`` and the tracks' ``(N, T + H)`` (``None`` for what is not there)."""
    steps = after.shape[1]
    hit = np.zeros(after.shape[:2], bool)
    clearance = costmap_soft = track_soft = None
    if mppi._field.enabled:
        clearance, map_hit = mppi._field.clearance(after, info[6], mp)
        hit |= map_hit
    if seen.has_costmap:
        costmap_soft, costmap_hit = costmap_costs(after, seen.cost, seen.near, seen.geometry,
                                              seen.polygon)  # fmt: skip
        hit |= costmap_hit
    if seen.has_tracks:
        track_soft, track_hit = track_costs(after, seen.table, seen.relief, seen.disks,
                                            dynamic_inflation, HOLD_STEP / mppi.dt)  # fmt: skip
        hit |= track_hit[:, :steps]  # the held rows are never lethal
    return hit, clearance, costmap_soft, track_soft
