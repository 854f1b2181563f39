"""Tracks of obstacles not on the map: a constant-velocity Kalman filter per track.

Each scan's :func:`~wheelbase.perception.clusters.detect` detections update the tracks of one
robot in :func:`update_tracker`, a pure function of a :class:`TrackerState`:

Prediction
    State x = (x, y, vx, vy) [m, m, m/s, m/s] in the world frame, constant velocity with white
    acceleration of spectral density q (``process_noise``) on each axis (Bar-Shalom, Li and
    Kirubarajan, *Estimation with Applications to Tracking and Navigation*, 2001, §6.2.2):
    F = [[I, Δt I], [0, I]], Q = q [[Δt³/3 I, Δt²/2 I], [Δt²/2 I, Δt I]].
Association
    Global nearest neighbour: the squared Mahalanobis distance d² = νᵀ S⁻¹ ν of every
    detection to every track (ν = z − H x̂, S = H P Hᵀ + R, H picks the position) is gated
    at the χ² (2 dof) quantile of ``gate_probability``; the assignment of detections to
    tracks that pairs the most gated pairs at the least total d² is solved by
    ``scipy.optimize.linear_sum_assignment`` (pairs outside the gate cost more than any
    assignment inside it, and are dropped after).
Update
    Kalman gain K = P Hᵀ S⁻¹, x̂ += K ν, P = (I − K H) P (I − K H)ᵀ + K R Kᵀ (Joseph form). The
    radius is a running mean of the radii of the detections not occluded (over the last 10 at
    most).
Management
    A detection no track takes starts a tentative track at z with velocity 0 and covariance
    blockdiag(R, σ_v² I) with σ_v = ``initial_speed_std``, unless ``max_tracks`` are alive.
    A tentative track is confirmed at ``hits_to_confirm`` hits in a row since its birth and
    deleted at its first miss; a confirmed track is deleted after ``misses_to_delete`` misses
    in a row (it coasts on its prediction until then). Ids are never reused.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from wheelbase._validate import finite, flag
from wheelbase.errors import InputError
from wheelbase.perception.clusters import Detections, detect
from wheelbase.perception.specs import TrackerSpec
from wheelbase.planning import OccupancyGrid

__all__ = ["TrackerState", "Tracks", "update_tracker"]

_RADIUS_MEMORY = 10  # detections the running mean of a radius spans at most
_MAX_TIME = 1e9  # s (31 years): beyond it Δt³ of a prediction nears the float range


def _time(time: float) -> float:
    time = finite("time", time, "s", InputError)
    if abs(time) > _MAX_TIME:
        raise InputError(f"time must be within ±{_MAX_TIME:g} s (got {time:g} s)")
    return time


@dataclass(frozen=True, eq=False)
class Tracks:
    """Tracked obstacles at one time, sorted by id.

    Parameters
    ----------
    ids : numpy.ndarray
        ``(K,)`` int64 track ids (unique within a tracker, never reused).
    position : numpy.ndarray
        ``(K, 2)`` estimated centres (x, y) [m], world frame.
    velocity : numpy.ndarray
        ``(K, 2)`` estimated velocities (vx, vy) [m/s], world frame.
    covariance : numpy.ndarray
        ``(K, 4, 4)`` covariance of (x, y, vx, vy) [m², m²/s, m²/s²].
    radius : numpy.ndarray
        ``(K,)`` radius estimates [m].
    confirmed : numpy.ndarray
        ``(K,)`` bool: confirmed (True) or tentative.
    """

    ids: np.ndarray
    position: np.ndarray
    velocity: np.ndarray
    covariance: np.ndarray
    radius: np.ndarray
    confirmed: np.ndarray

    def __len__(self) -> int:
        return self.ids.shape[0]

    @classmethod
    def empty(cls) -> Tracks:
        """No tracks.

        Returns
        -------
        Tracks
        """
        return cls(np.zeros(0, np.int64), np.zeros((0, 2)), np.zeros((0, 2)),
                   np.zeros((0, 4, 4)), np.zeros(0), np.zeros(0, bool))  # fmt: skip


@dataclass(frozen=True, eq=False)
class TrackerState:
    """One robot's tracker: ``max_tracks`` slots of plain arrays (a slot with id −1 is free).

    Parameters
    ----------
    time : float
        Time [s] of the last update.
    ids : numpy.ndarray
        ``(T,)`` int64 id of each slot's track, −1 for a free slot.
    mean : numpy.ndarray
        ``(T, 4)`` state estimates (x, y, vx, vy).
    covariance : numpy.ndarray
        ``(T, 4, 4)`` their covariances.
    radius : numpy.ndarray
        ``(T,)`` radius estimates [m].
    hits : numpy.ndarray
        ``(T,)`` int64 detections each track has taken.
    misses : numpy.ndarray
        ``(T,)`` int64 updates in a row without one.
    confirmed : numpy.ndarray
        ``(T,)`` bool.
    next_id : int
        The id the next new track gets.
    """

    time: float
    ids: np.ndarray
    mean: np.ndarray
    covariance: np.ndarray
    radius: np.ndarray
    hits: np.ndarray
    misses: np.ndarray
    confirmed: np.ndarray
    next_id: int

    @classmethod
    def initial(cls, spec: TrackerSpec, time: float = 0.0) -> TrackerState:
        """A tracker with no tracks.

        Parameters
        ----------
        spec : TrackerSpec
            The ``tracker:`` keys (``max_tracks`` slots).
        time : float
            Start time [s].

        Returns
        -------
        TrackerState
        """
        if not isinstance(spec, TrackerSpec):
            raise InputError(f"spec must be a TrackerSpec (got {type(spec).__name__})")
        n = spec.max_tracks
        arrays = (np.full(n, -1, np.int64), np.zeros((n, 4)), np.zeros((n, 4, 4)), np.zeros(n),
                  np.zeros(n, np.int64), np.zeros(n, np.int64), np.zeros(n, bool))  # fmt: skip
        for array in arrays:
            array.setflags(write=False)
        return cls(_time(time), *arrays, 0)

    def tracks(self, confirmed_only: bool = False) -> Tracks:
        """The tracks alive, sorted by id.

        Parameters
        ----------
        confirmed_only : bool
            Leave the tentative tracks out.

        Returns
        -------
        Tracks
        """
        alive = self.ids >= 0
        if flag("confirmed_only", confirmed_only):
            alive &= self.confirmed
        slots = np.flatnonzero(alive)
        slots = slots[np.argsort(self.ids[slots], kind="stable")]
        mean = self.mean[slots]
        return Tracks(self.ids[slots], mean[:, :2], mean[:, 2:], self.covariance[slots],
                      self.radius[slots], self.confirmed[slots])  # fmt: skip


def _motion(spec: TrackerSpec, dt: float) -> tuple[np.ndarray, np.ndarray]:
    """F and Q of the constant-velocity model over ``dt`` (module docstring)."""
    f = np.eye(4)
    f[0, 2] = f[1, 3] = dt
    q = np.zeros((4, 4))
    q[0, 0] = q[1, 1] = dt**3 / 3.0
    q[0, 2] = q[1, 3] = q[2, 0] = q[3, 1] = dt**2 / 2.0
    q[2, 2] = q[3, 3] = dt
    return f, spec.process_noise * q


def _associate(
    spec: TrackerSpec, mean: np.ndarray, cov: np.ndarray, found: Detections
) -> tuple[np.ndarray, np.ndarray]:
    """Gated global-nearest-neighbour pairs (track row, detection) (module docstring)."""
    from scipy.optimize import linear_sum_assignment

    if mean.shape[0] == 0 or len(found) == 0:
        return np.zeros(0, np.int64), np.zeros(0, np.int64)
    nu = found.position[None, :, :] - mean[:, None, :2]
    s = cov[:, None, :2, :2] + found.covariance[None, :, :, :]
    det = s[..., 0, 0] * s[..., 1, 1] - s[..., 0, 1] * s[..., 1, 0]
    d2 = (
        s[..., 1, 1] * nu[..., 0] ** 2
        - (s[..., 0, 1] + s[..., 1, 0]) * nu[..., 0] * nu[..., 1]
        + s[..., 0, 0] * nu[..., 1] ** 2
    ) / det
    inside = d2 <= spec.gate
    if not inside.any():
        return np.zeros(0, np.int64), np.zeros(0, np.int64)
    # outside the gate: dearer than every gated assignment together, so the most pairs win
    cost = np.where(inside, d2, spec.gate * (min(d2.shape) + 1.0))
    rows, cols = linear_sum_assignment(cost)
    keep = inside[rows, cols]
    return rows[keep], cols[keep]


def update_tracker(
    spec: TrackerSpec,
    state: TrackerState,
    time: float,
    sensor_pose: ArrayLike,
    beam_angles: ArrayLike,
    ranges: ArrayLike,
    max_range: float,
    grid: OccupancyGrid,
) -> TrackerState:
    """The tracks after one scan (pure: ``state`` is not changed; module docstring).

    Parameters
    ----------
    spec : TrackerSpec
        The ``tracker:`` keys.
    state : TrackerState
        The tracker before the scan.
    time : float
        Time [s] of the scan, >= ``state.time``.
    sensor_pose : array_like, shape (3,)
        The lidar's world pose (x [m], y [m], θ [rad]).
    beam_angles : array_like, shape (K,)
        Beam directions [rad] in the sensor frame, in scan order.
    ranges : array_like, shape (K,)
        Readings [m]: NaN or >= ``max_range`` (or +inf) for no return.
    max_range : float
        The lidar's largest range [m].
    grid : OccupancyGrid
        The map: returns it explains are not tracked.

    Returns
    -------
    TrackerState
    """
    if not isinstance(state, TrackerState):
        raise InputError(f"state must be a TrackerState (got {type(state).__name__})")
    if state.ids.shape != (spec.max_tracks,):
        raise InputError(
            f"state has {state.ids.shape[0]} track slots, spec.max_tracks = {spec.max_tracks}"
        )
    time = _time(time)
    dt = time - state.time
    if dt < 0.0:
        raise InputError(f"time must not go back: {time:g} s after {state.time:g} s")
    found = detect(spec, sensor_pose, beam_angles, ranges, max_range, grid)

    ids, mean, cov = state.ids.copy(), state.mean.copy(), state.covariance.copy()
    radius, hits, misses = state.radius.copy(), state.hits.copy(), state.misses.copy()
    confirmed, next_id = state.confirmed.copy(), state.next_id
    alive = np.flatnonzero(ids >= 0)
    f, q = _motion(spec, dt)
    mean[alive] = mean[alive] @ f.T
    cov[alive] = f @ cov[alive] @ f.T + q

    rows, taken = _associate(spec, mean[alive], cov[alive], found)
    slots = alive[rows]
    if slots.size:
        r = found.covariance[taken]
        s = cov[slots, :2, :2] + r
        gain = cov[slots, :, :2] @ np.linalg.inv(s)  # K = P Hᵀ S⁻¹, (n, 4, 2)
        nu = found.position[taken] - mean[slots, :2]
        mean[slots] += np.einsum("nij,nj->ni", gain, nu)
        keep = np.eye(4) - np.concatenate([gain, np.zeros((slots.size, 4, 2))], axis=2)
        cov[slots] = keep @ cov[slots] @ keep.transpose(0, 2, 1) + gain @ r @ gain.transpose(
            0, 2, 1
        )
        hits[slots] += 1
        misses[slots] = 0
        weight = 1.0 / np.minimum(hits[slots], _RADIUS_MEMORY)
        weight[found.occluded[taken]] = 0.0  # a partly hidden cluster's radius is too small
        radius[slots] += weight * (found.radius[taken] - radius[slots])
        confirmed[slots] |= hits[slots] >= spec.hits_to_confirm
    matched = np.zeros(ids.shape, bool)
    matched[slots] = True
    missed = alive[~matched[alive]]
    misses[missed] += 1
    gone = missed[~confirmed[missed] | (misses[missed] >= spec.misses_to_delete)]
    ids[gone] = -1
    confirmed[gone] = False

    unclaimed = np.ones(len(found), bool)
    unclaimed[taken] = False
    new = np.flatnonzero(unclaimed)
    free = np.flatnonzero(ids < 0)[: new.size]
    new = new[: free.size]
    if free.size:
        ids[free] = next_id + np.arange(free.size)
        next_id += int(free.size)
        mean[free] = np.concatenate([found.position[new], np.zeros((free.size, 2))], axis=1)
        cov[free] = 0.0
        cov[free, :2, :2] = found.covariance[new]
        cov[free, 2, 2] = cov[free, 3, 3] = spec.initial_speed_std**2
        radius[free] = found.radius[new]
        hits[free] = 1
        misses[free] = 0
        confirmed[free] = spec.hits_to_confirm <= 1
    arrays = (ids, mean, cov, radius, hits, misses, confirmed)
    for array in arrays:
        array.setflags(write=False)
    return TrackerState(time, *arrays, next_id)
