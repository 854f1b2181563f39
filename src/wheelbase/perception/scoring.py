"""Track accuracy against the truth: the metrics ``track_position_rmse_m`` and
``track_velocity_rmse_m_s``.

Association to the truth, at each time on its own: the confirmed tracks and the true obstacles
(e.g. the world's agents) are paired by ``scipy.optimize.linear_sum_assignment`` on the
Euclidean distance between track and true centres, and a pair counts only when that distance is
at most ``gate`` [m] (default 1 m: farther, the track is not of that obstacle). Matched pairs
add their squared position and velocity errors; confirmed tracks left unmatched are false
tracks, true obstacles left unmatched are missed (seen or not: pass only the obstacles the
sensor could see to count misses of visible ones). Errors of several times (or runs) add with
``+``; the RMSE is over all matched pairs.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from wheelbase._validate import as_float_array, positive
from wheelbase.errors import InputError
from wheelbase.perception.tracking import Tracks

__all__ = ["TrackErrors", "track_errors"]


@dataclass(frozen=True)
class TrackErrors:
    """Sums of track errors over matched (track, truth) pairs (module docstring).

    Parameters
    ----------
    position_square_sum : float
        Σ |p̂ − p|² [m²] over matched pairs.
    velocity_square_sum : float
        Σ |v̂ − v|² [m²/s²] over matched pairs.
    matches : int
        Matched pairs.
    false_tracks : int
        Confirmed tracks matched to no true obstacle.
    missed : int
        True obstacles matched to no confirmed track.
    """

    position_square_sum: float = 0.0
    velocity_square_sum: float = 0.0
    matches: int = 0
    false_tracks: int = 0
    missed: int = 0

    def __add__(self, other: TrackErrors) -> TrackErrors:
        if not isinstance(other, TrackErrors):
            return NotImplemented
        return TrackErrors(
            self.position_square_sum + other.position_square_sum,
            self.velocity_square_sum + other.velocity_square_sum,
            self.matches + other.matches,
            self.false_tracks + other.false_tracks,
            self.missed + other.missed,
        )

    @property
    def position_rmse_m(self) -> float:
        """Position RMSE [m] over the matched pairs (NaN without any)."""
        return math.sqrt(self.position_square_sum / self.matches) if self.matches else math.nan

    @property
    def velocity_rmse_m_s(self) -> float:
        """Velocity RMSE [m/s] over the matched pairs (NaN without any)."""
        return math.sqrt(self.velocity_square_sum / self.matches) if self.matches else math.nan


def track_errors(
    tracks: Tracks, position: ArrayLike, velocity: ArrayLike, gate: float = 1.0
) -> TrackErrors:
    """The errors of the confirmed tracks at one time against the true obstacles.

    Parameters
    ----------
    tracks : Tracks
        The tracks (tentative ones are ignored).
    position : array_like, shape (A, 2)
        True centres [m].
    velocity : array_like, shape (A, 2)
        True velocities [m/s].
    gate : float
        Largest distance [m] of a counted pair, > 0.

    Returns
    -------
    TrackErrors
    """
    from scipy.optimize import linear_sum_assignment

    if not isinstance(tracks, Tracks):
        raise InputError(f"tracks must be Tracks (got {type(tracks).__name__})")
    true_p = as_float_array("position", position, 2, min_ndim=2, max_ndim=2)
    true_v = as_float_array("velocity", velocity, 2, min_ndim=2, max_ndim=2)
    if true_v.shape != true_p.shape:
        raise InputError(f"velocity must have the shape of position {true_p.shape}")
    gate = positive("gate", gate, "m")
    est_p = tracks.position[tracks.confirmed]
    est_v = tracks.velocity[tracks.confirmed]
    if est_p.shape[0] == 0 or true_p.shape[0] == 0:
        return TrackErrors(false_tracks=est_p.shape[0], missed=true_p.shape[0])
    distance = np.hypot(*(est_p[:, None, :] - true_p[None, :, :]).transpose(2, 0, 1))
    rows, cols = linear_sum_assignment(distance)
    keep = distance[rows, cols] <= gate
    rows, cols = rows[keep], cols[keep]
    return TrackErrors(
        float(np.sum((est_p[rows] - true_p[cols]) ** 2)),
        float(np.sum((est_v[rows] - true_v[cols]) ** 2)),
        int(rows.size),
        int(est_p.shape[0] - rows.size),
        int(true_p.shape[0] - rows.size),
    )
