"""What a local controller sees of its perception, scored: the costmap critic and the
dynamic-obstacle critic shared by MPPI and DWA (one implementation, a Numba and a NumPy twin).

The perception is any object with the attributes of :class:`wheelbase.perception.LocalView`
(duck typed, so that ``control`` does not depend on how it was made):
``costmap.cost`` (uint8 (rows, cols)), ``costmap.resolution`` [m], ``costmap.origin`` (x0, y0)
[m] on the grid geometry of :class:`~wheelbase.planning.OccupancyGrid` (row 0 the lowest y,
column 0 the lowest x, origin the lower-left corner of cell (0, 0)); ``tracks.position`` (J, 2)
[m], ``tracks.velocity`` (J, 2) [m/s], ``tracks.covariance`` (J, 4, 4) of (x, y, v_x, v_y) or
``None``, ``tracks.radius`` (J,) [m] and, if present, ``tracks.confirmed`` (J,) (only confirmed
tracks are predicted: a tentative one may be a spurious cluster, and the costmap marks it
anyway); ``time`` [s], when the view was taken. Either part may be ``None``.

**Costmap critic** (after Nav2's ``CostCritic``; costs 0 free, 1–252 inflated, 253 inscribed,
254 lethal, 255 unknown). At every rollout step, with c the cost of the cell under the robot's
reference point:

- the soft cost is c/252 (1 for 253–255: unknown space is passable but dear, as Nav2 scores it
  when it tracks unknown space), 0 off the costmap (a rolling window knows nothing there; the
  static map's critic guards the map's edge);
- the step collides when c = 254, or c = 253 (the footprint's inscribed circle touches an
  obstacle: the costmap's inscribed radius must be the robot's, as in Nav2), or when any cell
  that the footprint's outline passes through is lethal. The outline is traversed exactly (every
  cell an edge enters, through the crossings of the grid lines) only where a lethal cell lies
  within the footprint's circumscribed radius + a cell diagonal of the centre cell (the *gate*,
  from the lethal cells' distance transform), so a free rollout costs one look-up a step. A
  lethal cell gets inside the outline only by crossing it, which a step shorter than a cell does
  not skip.

When the robot already stands on a 253 cell without its outline touching a lethal one (the
inscribed rule is conservative for a non-round footprint), the inscribed rule is off for that
call, so the robot can drive out; an outline that truly overlaps a lethal cell keeps every
rollout lethal: a safe stop.

**Dynamic-obstacle critic.** Each track is predicted at constant velocity, its uncertainty
growing with the horizon: at τ seconds past the view's time the mean is p + v·τ and the position
covariance is the constant-velocity propagation of the track's covariance plus white
acceleration noise of spectral density q (Bar-Shalom, Li & Kirubarajan, *Estimation with
Applications to Tracking and Navigation*, 2001, §6.2.2):

    P_pp(τ) = P_pp + τ·(P_pv + P_vp) + τ²·P_vv + (q·τ³/3)·I,     σ(τ) = √λ_max(P_pp(τ)),

q = :data:`ACCELERATION_NOISE` = 0.03 m²/s³ by default (a walker's unmodelled acceleration: σ
grows to 0.18 m in 1.5 s, 0.52 m in 3 s and 1.05 m in 4.8 s, of the order of the displacement
errors of constant-velocity pedestrian prediction, about 1 m after 4.8 s on the ETH/UCY data:
Schöller, Aravantinos, Lay & Knoll, IEEE RA-L 5(2), 2020). Rollout step k (the pose after
k + 1 steps of dt, τ_k = (t − view time) + (k + 1)·dt) is compared with the prediction at
τ_k — time-indexed, so a walker that crosses the path before the robot gets there costs
nothing. With d the least over the
footprint's covering disks of |disk centre − mean| − disk radius − track radius:

- the step collides at contact, d <= 0 (with a relief as for the costmap: a track already in
  contact now collides only where it gets 1 cm deeper);
- the soft cost is Σ_tracks g² for d < z = r_dyn + κ·σ(τ_k), with g = r_dyn·(z − max(d, 0))/z
  + max(−d, 0): zero beyond the inflation distance r_dyn past the uncertainty, r_dyn at contact,
  plus the depth of the overlap inside it (which only the held checks below can reach), so a
  rollout nearer the predicted path of a track always pays more. The scaling by z keeps an
  uncertain prediction from costing more than a sure one: it widens the zone, not the price
  (unscaled, a walker predicted 8 s ahead, σ 2.3 m, cost 40 times a sure contact, and in a crowd
  of 20 wandering walkers MPPI stood still). κ (``sigma_scale``) = 1 by default.
- each track's g² is weighted by its *certainty* (:func:`certainty`), the chance
  1 − exp(−ρ²/(2κ²σ²)) that the track lies within ρ = footprint reach + track radius + r_dyn of
  its predicted mean: 1 for a sure prediction, ρ²/(2κ²σ²) for a vague one. A widened zone alone
  still priced a vague prediction at up to half a sure contact over metres of floor, and the
  robot froze (the *freezing robot problem*: Trautman & Krause, "Unfreezing the robot", IROS
  2010): in ``crowd_crossing`` it stood 8 s while the nearest walker was 3-5 m away, its
  standing still costing 3.3 against 34 for driving on at 1 m/s, all of it the held checks of
  walkers predicted 5-8 s ahead (σ 1.5-2.7 m). Weighted, the same call costs 0.04 against 0.7.

A horizon of a few seconds is myopic about a walker coming straight at the robot: a rollout
that slows down pushes the contact past its end and looks safe, and the robot stops in the
walker's way (measured: a disc coming head-on at 0.5 m/s then runs into a stopped robot). So the
rollout's final pose is also *held* (the robot stopped there) for ``hold_time`` seconds more
(:data:`HOLD_TIME` = 5 s, checked every :data:`HOLD_STEP` = 0.25 s: a walker at 0.5 m/s
moves 0.125 m between checks) and scored against the
predictions at those times, with the soft cost only (each check weighted as the HOLD_STEP/dt
rollout steps it stands for): standing in the predicted way of a track
costs (the idea of the braking inevitable-collision-state test of Fraichard & Asama, "Inevitable
collision states", Advanced Robotics 18(10), 2004), but is not lethal, since the robot need not
stay there (a lethal hold stopped DWA in the walker's way: its arcs could not leave the line
within one window). There the soft distance is not clamped at contact (d < 0 costs more than
d = 0), so a held pose deeper in a track's way always pays more.

Tracks that cannot come within reach of the robot over the horizon (its top speed × τ + the
footprint's radius) are dropped before the kernels run.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numba
import numpy as np

from wheelbase.errors import InputError
from wheelbase.limits import MAX_COORDINATE

__all__ = [
    "ACCELERATION_NOISE",
    "EVADE_TIME",
    "HOLD_STEP",
    "HOLD_TIME",
    "INSCRIBED",
    "LETHAL",
    "MAX_INFLATED",
    "MAX_PATH_OCCUPANCY",
    "REACH_SLACK",
    "UNKNOWN",
    "PerceptionArrays",
    "PerceptionInputs",
    "certainty",
    "costmap_check",
    "costmap_cost_at",
    "costmap_costs",
    "disk_reach",
    "evasion_choice",
    "path_blocked",
    "predict_tracks",
    "reachable_tracks",
    "read_costmap",
    "read_tracks",
    "struck_step",
    "track_cost_at",
    "track_costs",
    "track_terms",
]

MAX_INFLATED, INSCRIBED, LETHAL, UNKNOWN = 252, 253, 254, 255
"""Nav2's cell costs: the highest inflated cost, inscribed, lethal, unknown (0 is free)."""

ACCELERATION_NOISE = 0.03
"""Default q [m²/s³] of the tracks' white-acceleration prediction noise (module docstring)."""

HOLD_TIME = 5.0
"""Default time [s] a rollout's final pose is held against the predicted tracks."""

HOLD_STEP = 0.25
"""Spacing [s] of the checks of the held final pose."""

MAX_VIEW_AGE = 3600.0
"""Most seconds a view may be older than the call (the prediction is then meaningless)."""

MAX_TRACK_SPEED = 1000.0
"""Largest track speed component [m/s] a view may give."""

CONTACT_RELIEF = 0.01
"""How much deeper [m] a rollout must get into what it already touches to count as colliding."""


# --------------------------------------------------------------------------- reading the view
def read_costmap(costmap: Any) -> tuple[np.ndarray, float, np.ndarray]:
    """The cost array, resolution and origin of a costmap-like object, checked.

    Parameters
    ----------
    costmap : object
        With ``cost`` (uint8 (rows, cols)), ``resolution`` [m] and ``origin`` (x0, y0) [m].

    Returns
    -------
    cost : numpy.ndarray of uint8, shape (rows, cols), C-contiguous
    resolution : float
    origin : numpy.ndarray, shape (2,)
    """
    try:
        cost, resolution, origin = costmap.cost, costmap.resolution, costmap.origin
    except AttributeError as error:
        raise InputError(
            f"perception.costmap needs cost, resolution and origin (got {type(costmap).__name__}"
            f" without {error.name!r})"
        ) from None
    array = np.asarray(cost)
    if array.ndim != 2 or array.size == 0 or array.dtype != np.uint8:
        raise InputError(
            "perception.costmap.cost must be a non-empty uint8 array (rows, cols) of costs 0-255 "
            f"(got dtype {array.dtype}, shape {array.shape})"
        )
    try:
        res = float(resolution)
    except (TypeError, ValueError):
        res = math.nan
    if not (math.isfinite(res) and res > 0.0):
        raise InputError(f"perception.costmap.resolution must be > 0 m (got {resolution!r})")
    try:
        xy = np.asarray(origin, dtype=np.float64).reshape(-1)
    except (TypeError, ValueError):
        xy = np.zeros(0)
    if xy.size < 2 or not np.all(np.abs(xy[:2]) <= MAX_COORDINATE):
        raise InputError(
            f"perception.costmap.origin must be (x0, y0) [m] within ±{MAX_COORDINATE:g} m (got "
            f"{origin!r})"
        )
    return np.ascontiguousarray(array), res, xy[:2].copy()


def read_tracks(tracks: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Position, velocity, covariance and radius of the (confirmed) tracks, checked.

    Parameters
    ----------
    tracks : object
        With ``position`` (J, 2) [m], ``velocity`` (J, 2) [m/s], ``covariance`` (J, 4, 4) or
        ``None``, ``radius`` (J,) [m] and optionally ``confirmed`` (J,).

    Returns
    -------
    position, velocity : numpy.ndarray, shape (J', 2)
    covariance : numpy.ndarray, shape (J', 4, 4)
        Zero where the tracks give none.
    radius : numpy.ndarray, shape (J',)
        J' = the confirmed tracks.
    """
    try:
        position, velocity, radius = tracks.position, tracks.velocity, tracks.radius
    except AttributeError as error:
        raise InputError(
            f"perception.tracks needs position, velocity and radius (got "
            f"{type(tracks).__name__} without {error.name!r})"
        ) from None
    position = _finite_array("perception.tracks.position", position, (-1, 2))
    count = position.shape[0]
    velocity = _finite_array("perception.tracks.velocity", velocity, (count, 2), MAX_TRACK_SPEED)
    radius = _finite_array("perception.tracks.radius", radius, (count,))
    if np.any(radius < 0.0):
        raise InputError(f"perception.tracks.radius must be >= 0 m (got {radius.min():g})")
    covariance = getattr(tracks, "covariance", None)
    if covariance is None:
        covariance = np.zeros((count, 4, 4))
    else:
        covariance = _finite_array("perception.tracks.covariance", covariance, (count, 4, 4))
    confirmed = getattr(tracks, "confirmed", None)
    if confirmed is not None:
        keep = np.asarray(confirmed, dtype=bool).reshape(-1)
        if keep.shape != (count,):
            raise InputError(
                f"perception.tracks.confirmed must have shape ({count},) (got {keep.shape})"
            )
        position, velocity, covariance, radius = (
            position[keep],
            velocity[keep],
            covariance[keep],
            radius[keep],
        )
    return position, velocity, covariance, radius


def _finite_array(
    name: str, value: Any, shape: tuple[int, ...], limit: float = MAX_COORDINATE
) -> np.ndarray:
    try:
        array = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise InputError(f"{name} must be numeric (got {type(value).__name__})") from None
    if array.size == 0 and shape[0] in (-1, 0):
        array = array.reshape((0, *shape[1:]))
    wanted = tuple(array.shape[0] if s == -1 else s for s in shape) if array.ndim else shape
    if array.shape != wanted:
        text = ", ".join("J" if s == -1 else str(s) for s in shape)
        raise InputError(f"{name} must have shape ({text}) (got {array.shape})")
    if not np.all(np.isfinite(array)):
        raise InputError(f"{name} must be finite (got NaN or inf)")
    if not np.all(np.abs(array) <= limit):
        raise InputError(f"{name} must be within ±{limit:g} (got {np.max(np.abs(array)):.3g})")
    return array


# --------------------------------------------------------------------------- prediction
def predict_tracks(
    position: np.ndarray,
    velocity: np.ndarray,
    covariance: np.ndarray,
    times: np.ndarray,
    acceleration_noise: float = ACCELERATION_NOISE,
) -> tuple[np.ndarray, np.ndarray]:
    """Constant-velocity prediction of tracks with growing uncertainty (module docstring).

    Parameters
    ----------
    position, velocity : numpy.ndarray, shape (J, 2)
        Track positions [m] and velocities [m/s] at the view's time.
    covariance : numpy.ndarray, shape (J, 4, 4)
        Covariance of (x, y, v_x, v_y) [m², m²/s, m²/s²].
    times : numpy.ndarray, shape (T,)
        τ [s] past the view's time, >= 0.
    acceleration_noise : float
        q [m²/s³], >= 0.

    Returns
    -------
    mean : numpy.ndarray, shape (T, J, 2)
        Predicted positions [m].
    sigma : numpy.ndarray, shape (T, J)
        √λ_max of the predicted position covariance [m].

    Examples
    --------
    >>> mean, sigma = predict_tracks(np.zeros((1, 2)), np.array([[1.0, 0.0]]),
    ...                              np.zeros((1, 4, 4)), np.array([0.0, 3.0]), 0.03)
    >>> mean[1, 0].tolist(), round(float(sigma[1, 0]), 3)
    ([3.0, 0.0], 0.52)
    """
    tau = np.ascontiguousarray(times, dtype=np.float64).reshape(-1)
    position = np.ascontiguousarray(position, dtype=np.float64)
    mean = np.empty((tau.shape[0], position.shape[0], 2))
    sigma = np.empty((tau.shape[0], position.shape[0]))
    _predict(position, np.ascontiguousarray(velocity, dtype=np.float64),
             np.ascontiguousarray(covariance, dtype=np.float64), tau,
             float(acceleration_noise), mean, sigma)  # fmt: skip
    return mean, sigma


@numba.njit(cache=True)
def _predict(position, velocity, covariance, tau, noise, mean, sigma):
    """:func:`predict_tracks` into ``mean`` (T, J, 2) and ``sigma`` (T, J) (compiled: it runs
    every control call over the horizon's 60-odd times and every track)."""
    for t in range(tau.shape[0]):
        dt = tau[t]
        grown = noise * dt * dt * dt / 3.0
        for j in range(position.shape[0]):
            p = covariance[j]
            mean[t, j, 0] = position[j, 0] + dt * velocity[j, 0]
            mean[t, j, 1] = position[j, 1] + dt * velocity[j, 1]
            a = p[0, 0] + dt * (p[0, 2] + p[0, 2]) + dt * dt * p[2, 2] + grown
            d = p[1, 1] + dt * (p[1, 3] + p[1, 3]) + dt * dt * p[3, 3] + grown
            upper = p[0, 1] + dt * (p[0, 3] + p[1, 2]) + dt * dt * p[2, 3]
            lower = p[1, 0] + dt * (p[1, 2] + p[0, 3]) + dt * dt * p[3, 2]
            b = 0.5 * (upper + lower)
            top = 0.5 * (a + d) + math.sqrt(max(0.25 * (a - d) ** 2 + b * b, 0.0))
            sigma[t, j] = math.sqrt(max(top, 0.0))


# --------------------------------------------------------------------------- per-call arrays
@dataclass(frozen=True)
class PerceptionArrays:
    """The kernels' inputs for one call, positions relative to the robot.

    Attributes
    ----------
    cost : numpy.ndarray of uint8, shape (rows, cols)
        The costmap ((1, 1) zeros without one).
    near : numpy.ndarray of uint8, shape (rows, cols)
        The outline gate: 1 where a lethal cell lies within reach of the footprint's outline.
    geometry : numpy.ndarray, shape (5,)
        (x0 [m], y0 [m] of the costmap's origin relative to the robot, resolution [m],
        costmap on 0/1, inscribed rule on 0/1).
    polygon : numpy.ndarray, shape (V, 2)
        The footprint's outline [m] in the body frame ((0, 2) for a point robot).
    table : numpy.ndarray, shape (T + H, J, 4)
        Per rollout step (then per check of the held final pose) and track: predicted (x, y)
        [m] relative to the robot, track radius [m], κ·σ [m].
    relief : numpy.ndarray, shape (J,)
        Contact threshold [m] of each track (0, or deeper than now for one already touched).
    disks : numpy.ndarray, shape (D, 3)
        The footprint's covering disks (x, y, radius) [m] for the tracks.
    order : numpy.ndarray of int64, shape (T + H, J)
        Per row of ``table``, the tracks a rollout pose of that row can reach first (in
        increasing index), then the others.
    counts : numpy.ndarray of int64, shape (T + H,)
        How many of each row of ``order`` are reachable: a pose after k steps lies within
        v̄·t_k of the robot, so a track farther than that plus the disks' reach, its radius,
        κσ and r_dyn can neither touch nor cost (:func:`track_cost_at` skips it anyway), and
        the kernels do not even test it.
    """

    cost: np.ndarray
    near: np.ndarray
    geometry: np.ndarray
    polygon: np.ndarray
    table: np.ndarray
    relief: np.ndarray
    disks: np.ndarray
    order: np.ndarray
    counts: np.ndarray

    @property
    def has_costmap(self) -> bool:
        """Whether a costmap is scored."""
        return bool(self.geometry[3] > 0.5)

    @property
    def has_tracks(self) -> bool:
        """Whether any track is scored."""
        return self.table.shape[1] > 0


class PerceptionInputs:
    """Turns a perception view into :class:`PerceptionArrays` for one controller.

    Holds the controller's footprint and prediction parameters, and the outline gate of the
    last costmap seen (recomputed when the costs change).

    Parameters
    ----------
    footprint : Footprint or None
        The robot outline (``None``: a point).
    disks : numpy.ndarray, shape (D, 3)
        Covering disks of the footprint (x, y, radius) [m] for the tracks.
    inflation : float
        r_dyn [m] of the dynamic-obstacle critic (tracks farther cannot cost).
    sigma_scale : float
        κ, >= 0.
    acceleration_noise : float
        q [m²/s³], >= 0.
    hold_time : float
        Time [s] the final pose is held against the tracks, >= 0.
    """

    def __init__(
        self,
        footprint: Any,
        disks: np.ndarray,
        inflation: float,
        sigma_scale: float,
        acceleration_noise: float,
        hold_time: float = HOLD_TIME,
    ) -> None:
        if footprint is None:
            self.polygon = np.zeros((0, 2))
            self.radius = 0.0
        else:
            self.polygon = np.ascontiguousarray(footprint.polygon, dtype=np.float64)
            self.radius = float(footprint.max_radius)
        self.disks = np.ascontiguousarray(disks, dtype=np.float64)
        self.inflation = inflation
        self.sigma_scale = sigma_scale
        self.acceleration_noise = acceleration_noise
        self.hold_checks = math.ceil(hold_time / HOLD_STEP - 1e-9)
        self._gate: tuple[np.ndarray, float, np.ndarray] | None = None

    def empty(self) -> PerceptionArrays:
        """The arrays of a call without perception (both critics off)."""
        zeros = np.zeros((1, 1), np.uint8)
        return PerceptionArrays(zeros, zeros, np.array([0.0, 0.0, 1.0, 0.0, 0.0]),
                                self.polygon, np.zeros((1, 0, 4)), np.zeros(0), self.disks,
                                np.zeros((1, 0), np.int64), np.zeros(1, np.int64))  # fmt: skip

    def arrays(
        self, perception: Any, pose: np.ndarray, t: float | None, times: np.ndarray, speed: float
    ) -> PerceptionArrays:
        """The arrays for one call.

        Parameters
        ----------
        perception : LocalView-like or None
            See the module docstring.
        pose : numpy.ndarray, shape (3,)
            The robot's pose (x [m], y [m], θ [rad]).
        t : float or None
            The controller's time [s]; the tracks are predicted from the view's ``time`` to
            ``t + times`` (``None``: from the view's time).
        times : numpy.ndarray, shape (T,)
            Times [s] of the rollout steps after now.
        speed : float
            The robot's top speed [m/s] (reach of the rollouts).

        Returns
        -------
        PerceptionArrays
        """
        if perception is None:
            return self.empty()
        empty = self.empty()
        costmap = getattr(perception, "costmap", None)
        tracks = getattr(perception, "tracks", None)
        cost, near, geometry = empty.cost, empty.near, empty.geometry
        if costmap is not None:
            cost, res, origin = read_costmap(costmap)
            near = self._near(cost, res)
            geometry = np.array([origin[0] - pose[0], origin[1] - pose[1], res, 1.0, 1.0])
            here = np.array([[0.0, 0.0, pose[2]]])
            _soft, hit = costmap_check(here, cost, near, geometry, self.polygon)
            if hit[0]:
                geometry[4] = 0.0
                _soft, hit = costmap_check(here, cost, near, geometry, self.polygon)
                if hit[0]:
                    geometry[4] = 1.0  # truly overlapping: every rollout collides, a safe stop
        table, relief, order, counts = empty.table, empty.relief, empty.order, empty.counts
        if tracks is not None:
            table, relief = self._tracks(perception, tracks, pose, t, times, speed)
            order, counts = reachable_tracks(table, times, speed, self.disks, self.inflation)
        return PerceptionArrays(cost, near, geometry, self.polygon, table, relief, self.disks,
                                order, counts)  # fmt: skip

    def _near(self, cost: np.ndarray, res: float) -> np.ndarray:
        if self._gate is not None and self._gate[1] == res and np.array_equal(self._gate[0], cost):
            return self._gate[2]
        near = np.zeros(cost.shape, np.uint8)
        if self.polygon.shape[0] > 0:
            near_lethal(cost, res, self.radius + math.sqrt(2.0) * res, near)
        self._gate = (cost.copy(), res, near)
        return near

    def _tracks(self, perception, tracks, pose, t, times, speed):
        position, velocity, covariance, radius = read_tracks(tracks)
        lag = 0.0
        view_time = getattr(perception, "time", None)
        if t is not None and view_time is not None:
            try:
                stamp = float(view_time)
            except (TypeError, ValueError):
                stamp = math.nan
            if not math.isfinite(stamp):
                raise InputError(f"perception.time must be a finite time [s] (got {view_time!r})")
            lag = max(float(t) - stamp, 0.0)
            if not lag <= MAX_VIEW_AGE:
                raise InputError(
                    f"perception.time must be at most {MAX_VIEW_AGE:g} s before the call's t = "
                    f"{float(t):g} s (got {view_time!r})"
                )
        times = np.asarray(times, dtype=np.float64)
        held = times[-1] + HOLD_STEP * np.arange(1, self.hold_checks + 1)
        ahead = np.concatenate([[0.0], times, held])
        mean, sigma = predict_tracks(position, velocity, covariance, lag + ahead,
                                     self.acceleration_noise)  # fmt: skip
        mean = mean - pose[:2]
        sigma = self.sigma_scale * sigma
        # Drop the tracks that cannot come within reach over the horizon.
        moved = speed * np.minimum(ahead, times[-1])[:, None]
        gap = np.hypot(mean[..., 0], mean[..., 1]) - radius[None] - sigma
        keep = np.any(gap < self.radius + moved + self.inflation, axis=0)
        mean, sigma, radius = mean[:, keep], sigma[:, keep], radius[keep]
        table = np.empty((len(ahead) - 1, int(keep.sum()), 4))
        table[..., :2] = mean[1:]
        table[..., 2] = radius[None]
        table[..., 3] = sigma[1:]
        # Relief: a track touched now collides only where a rollout gets deeper.
        now = np.empty((1, table.shape[1], 4))
        now[0, :, :2], now[0, :, 2], now[0, :, 3] = mean[0], radius, 0.0
        here = np.array([[[0.0, 0.0, pose[2]]]])
        distance = _track_distances(here, now, self.disks)[0, 0]  # (J,)
        relief = np.where(distance <= 0.0, distance - CONTACT_RELIEF, 0.0)
        return np.ascontiguousarray(table), relief


EVADE_TIME = 0.1
"""Least time [s] a command must stay clear, when every command collides, to be driven instead
of a stop (and it must stay clear longer than standing still would)."""


def evasion_choice(
    first: np.ndarray, standing: int, costs: np.ndarray, dt: float, struck: int | None
) -> int | None:
    """When every command collides: the one that stays clear longest (the cheapest of those),
    if it stays clear for :data:`EVADE_TIME` and longer than standing still would, or as long
    as standing still where a track strikes it then; else None (a stop). A walker
    that does not avoid the robot strikes a stopped one: where standing still is struck sooner
    than some command, that command is the way out (MPPI's and DWA's rule); where it is struck
    as soon as every command (a walker already at the robot's side, coming on faster than any
    command withdraws), the cheapest of them, whose cost counts the depth of the overlap, hurts
    least (measured in ``crowd_crossing`` with 50 walkers: the stop there was struck).

    Parameters
    ----------
    first : numpy.ndarray of int, shape (S,)
        Each command's first colliding step.
    standing : int
        The first colliding step of standing still.
    costs : numpy.ndarray, shape (S,)
        The commands' costs.
    dt : float
        Step [s].
    struck : int or None
        The first step at which standing still touches a track (:func:`struck_step`; None
        where it never does): only then does a tie with standing still drive.

    Returns
    -------
    int or None
    """
    latest = int(first.max())
    tie = struck is not None and latest == standing == struck
    if not tie and (latest <= standing or latest * dt < EVADE_TIME - 1e-9):
        return None
    candidates = np.flatnonzero(first == latest)
    return int(candidates[np.argmin(costs[candidates])])


def struck_step(seen: PerceptionArrays, heading: float, steps: int) -> int | None:
    """The first of ``steps`` rollout steps at which a robot standing still touches a predicted
    track (the relief of :class:`PerceptionArrays` applies), or None: what
    :func:`evasion_choice` needs to tell a walker coming on from a wall the robot stands in.

    Parameters
    ----------
    seen : PerceptionArrays
        The call's arrays.
    heading : float
        θ [rad] of the robot.
    steps : int
        Rollout steps (the table's first ``steps`` rows).

    Returns
    -------
    int or None
    """
    if seen.table.shape[1] == 0:
        return None
    poses = np.zeros((1, steps, 3))
    poses[..., 2] = heading
    table = seen.table[:steps]
    hits = np.flatnonzero(np.any(_track_distances(poses, table, seen.disks)[0] <= seen.relief, -1))
    return int(hits[0]) if hits.size else None


REACH_SLACK = 1.0e-6
"""Slack [m] on the reachable-track bound, against the rounding of the compiled rollouts."""


def reachable_tracks(
    table: np.ndarray, times: np.ndarray, speed: float, disks: np.ndarray, inflation: float
) -> tuple[np.ndarray, np.ndarray]:
    """The tracks each row of a prediction table can reach (:class:`PerceptionArrays`'
    ``order`` and ``counts``).

    Parameters
    ----------
    table : numpy.ndarray, shape (T + H, J, 4)
        Predicted tracks relative to the robot (x, y, radius, κσ) [m].
    times : numpy.ndarray, shape (T,)
        Times [s] of the rollout steps after now; the H held rows are at the final pose.
    speed : float
        v̄ [m/s], the fastest a rollout moves: after t_k a pose lies within v̄·t_k.
    disks : numpy.ndarray, shape (D, 3)
        The footprint's covering disks (x, y, radius) [m].
    inflation : float
        r_dyn [m].

    Returns
    -------
    order, counts : numpy.ndarray of int64
    """
    rows = table.shape[0]
    steps = times.shape[0]
    moved = speed * np.concatenate([times, np.full(rows - steps, times[-1])])
    far = disk_reach(disks) + table[..., 2] + table[..., 3] + inflation
    gap = np.hypot(table[..., 0], table[..., 1]) - moved[:, None]
    reachable = gap < far + REACH_SLACK
    # stable: the reachable tracks keep their index order, so the sums do not change
    order = np.argsort(~reachable, axis=1, kind="stable").astype(np.int64)
    return np.ascontiguousarray(order), reachable.sum(axis=1).astype(np.int64)


MAX_PATH_OCCUPANCY = 0.07
"""Share of the path window's poses that may collide before the path critics are switched off
for a call (Nav2 MPPI's ``max_path_occupancy_ratio``)."""


def path_blocked(
    window: np.ndarray, field: Any, geometry: np.ndarray, seen: PerceptionArrays
) -> bool:
    """Whether more than :data:`MAX_PATH_OCCUPANCY` of the path window's poses put the footprint
    in collision with the static map or the costmap: a path that cuts through obstacles must
    not pull the robot onto them (the controllers then switch their path critics off).

    Parameters
    ----------
    window : numpy.ndarray, shape (M, 4)
        The path window (x, y, heading, arc), relative to the robot.
    field : FootprintField
        The static map and footprint disks.
    geometry : numpy.ndarray, shape (4,)
        The map's geometry, origin relative to the robot.
    seen : PerceptionArrays
        The costmap.

    Returns
    -------
    bool
    """
    collided = np.zeros(window.shape[0], bool)
    if field.enabled:
        collided |= field.clearance(window[:, :3], geometry=geometry)[1]
    if seen.has_costmap:
        collided |= costmap_check(window[:, :3], seen.cost, seen.near, seen.geometry,
                                  seen.polygon)[1]  # fmt: skip
    return bool(np.mean(collided) > MAX_PATH_OCCUPANCY)


# --------------------------------------------------------------------------- Numba twins
@numba.njit(cache=True, inline="always")
def _lethal_cell(cost, row, col):
    rows, cols = cost.shape
    if row < 0 or row >= rows or col < 0 or col >= cols:
        return False
    return cost[row, col] == LETHAL


@numba.njit(cache=True, inline="always")
def _segment_hits_lethal(cost, ax, ay, bx, by):
    """Whether a segment (in cell units: x = column, y = row) passes through a lethal cell:
    the cells of its ends and, at every crossing of a grid line, the two cells it separates."""
    if _lethal_cell(cost, math.floor(ay), math.floor(ax)):
        return True
    if _lethal_cell(cost, math.floor(by), math.floor(bx)):
        return True
    dx, dy = bx - ax, by - ay
    if dx != 0.0:
        for k in range(math.floor(min(ax, bx)) + 1, math.floor(max(ax, bx)) + 1):
            row = math.floor(ay + (k - ax) / dx * dy)
            if _lethal_cell(cost, row, k - 1) or _lethal_cell(cost, row, k):
                return True
    if dy != 0.0:
        for k in range(math.floor(min(ay, by)) + 1, math.floor(max(ay, by)) + 1):
            col = math.floor(ax + (k - ay) / dy * dx)
            if _lethal_cell(cost, k - 1, col) or _lethal_cell(cost, k, col):
                return True
    return False


@numba.njit(cache=True, inline="always")
def costmap_cost_at(x, y, c, s, cost, near, geometry, polygon):
    """Soft cost (0–1) and collision of one pose on the costmap (module docstring).

    ``(x, y)`` [m] in the frame of ``geometry``'s origin, ``(c, s)`` = (cos θ, sin θ)."""
    x0, y0, res = geometry[0], geometry[1], geometry[2]
    inscribed = geometry[4] > 0.5
    inv = 1.0 / res
    fx, fy = (x - x0) * inv, (y - y0) * inv
    col, row = math.floor(fx), math.floor(fy)
    rows, cols = cost.shape
    if row < 0 or row >= rows or col < 0 or col >= cols:
        return 0.0, False
    value = cost[row, col]
    soft = 1.0 if value > MAX_INFLATED else value / MAX_INFLATED
    hit = value == LETHAL or (inscribed and value == INSCRIBED)
    n = polygon.shape[0]
    if not hit and n > 0 and near[row, col]:
        for i in range(n):
            j = i + 1 if i + 1 < n else 0
            ax = fx + (c * polygon[i, 0] - s * polygon[i, 1]) * inv
            ay = fy + (s * polygon[i, 0] + c * polygon[i, 1]) * inv
            bx = fx + (c * polygon[j, 0] - s * polygon[j, 1]) * inv
            by = fy + (s * polygon[j, 0] + c * polygon[j, 1]) * inv
            if _segment_hits_lethal(cost, ax, ay, bx, by):
                hit = True
                break
    return soft, hit


@numba.njit(cache=True)
def track_terms(table, disks, inflation):
    """The pose-independent parts of :func:`track_cost_at`, once per call: for each row of the
    prediction table and track, the squared distance [m²] beyond which the track can neither
    touch nor cost ((reach + radius + κσ + r_dyn)², reach from :func:`disk_reach`) and the
    weight :func:`certainty` of its soft cost. Shape (T + H, J, 2)."""
    reach = disk_reach(disks)
    terms = np.empty((table.shape[0], table.shape[1], 2))
    for step in range(table.shape[0]):
        for j in range(table.shape[1]):
            far = reach + table[step, j, 2] + table[step, j, 3] + inflation
            terms[step, j, 0] = far * far
            terms[step, j, 1] = certainty(reach + table[step, j, 2] + inflation, table[step, j, 3])
    return terms


@numba.njit(cache=True, inline="always")
def track_cost_at(x, y, c, s, step, table, relief, disks, inflation, held, terms, order, counts):
    """Soft cost Σ_j gap² [m²] and contact of one pose at rollout step ``step`` against the
    predicted tracks (module docstring); a step past the rollout's is a check of the held final
    pose. ``terms`` are the call's :func:`track_terms`: a track farther than its bound there
    can neither touch nor cost, and is skipped; only the ``counts[step]`` first tracks of
    ``order[step]`` are tested at all (:func:`reachable_tracks`)."""
    total = 0.0
    hit = False
    for slot in range(counts[step]):
        j = order[step, slot]
        mx, my = table[step, j, 0], table[step, j, 1]
        if (x - mx) * (x - mx) + (y - my) * (y - my) >= terms[step, j, 0]:
            continue
        least = 1.0e300
        for k in range(disks.shape[0]):
            px = x + c * disks[k, 0] - s * disks[k, 1]
            py = y + s * disks[k, 0] + c * disks[k, 1]
            dx, dy = px - mx, py - my  # sqrt, not hypot: no overflow within the map
            d = math.sqrt(dx * dx + dy * dy) - disks[k, 2] - table[step, j, 2]
            least = min(least, d)
        if least <= relief[j] and step < held:
            hit = True
        spread = table[step, j, 3]  # κσ
        zone = inflation + spread
        if least < zone:
            # r_dyn at contact whatever σ, and the depth of the overlap on top inside it
            gap = inflation * (zone - max(least, 0.0)) / zone + max(-least, 0.0)
            total += terms[step, j, 1] * gap * gap
    return total, hit


@numba.njit(cache=True)
def certainty(zone, spread):
    """The chance 1 − exp(−ρ² / (2 (κσ)²)) that a track whose position is N(mean, (κσ)² I) lies
    within ρ = ``zone`` [m] of its mean (the Rayleigh distribution's CDF): 1 for a sure
    prediction, → ρ²/(2κ²σ²) for a vague one. ``spread`` is κσ [m]; the soft cost of a track is
    weighted by it (module docstring)."""
    if spread <= 0.0:
        return 1.0
    return -math.expm1(-0.5 * (zone / spread) ** 2)


@numba.njit(cache=True)
def near_lethal(cost, res, limit, near):
    """Mark in ``near`` (uint8, zeroed, the shape of ``cost``) the cells whose centre lies within
    ``limit`` [m] of a lethal cell's centre (the outline gate of the module docstring): the
    thresholded Euclidean distance transform of the lethal cells (|Δ| = √(Δrow² + Δcol²)·res,
    as ``scipy.ndimage.distance_transform_edt`` measures it, which it replaces: 0.8 ms a
    132 × 132 window there, tens of µs here).

    Only lethal cells with a non-lethal 4-neighbour (or on the edge) paint their disc: the
    lethal cell nearest a free cell always is one (a step from it towards the free cell would
    otherwise reach a nearer lethal cell), and lethal cells themselves are near."""
    rows, cols = cost.shape
    reach = int(limit / res) + 1
    for row in range(rows):
        for col in range(cols):
            if cost[row, col] != LETHAL:
                continue
            near[row, col] = 1
            if (
                0 < row < rows - 1 and 0 < col < cols - 1
                and cost[row - 1, col] == LETHAL and cost[row + 1, col] == LETHAL
                and cost[row, col - 1] == LETHAL and cost[row, col + 1] == LETHAL
            ):  # fmt: skip
                continue
            for dr in range(-reach, reach + 1):
                r = row + dr
                if r < 0 or r >= rows:
                    continue
                for dc in range(-reach, reach + 1):
                    c = col + dc
                    if 0 <= c < cols and math.sqrt(float(dr * dr + dc * dc)) * res <= limit:
                        near[r, c] = 1


@numba.njit(cache=True)
def disk_reach(disks):
    """The largest |centre| + radius [m] of the disks ``(D, 3)``."""
    reach = 0.0
    for k in range(disks.shape[0]):
        reach = max(reach, math.hypot(disks[k, 0], disks[k, 1]) + disks[k, 2])
    return reach


@numba.njit(cache=True)
def _costmap_poses(poses, cost, near, geometry, polygon, soft, hit):
    for i in range(poses.shape[0]):
        c, s = math.cos(poses[i, 2]), math.sin(poses[i, 2])
        soft[i], hit[i] = costmap_cost_at(poses[i, 0], poses[i, 1], c, s, cost, near, geometry,
                                          polygon)  # fmt: skip


def costmap_check(
    poses: np.ndarray,
    cost: np.ndarray,
    near: np.ndarray,
    geometry: np.ndarray,
    polygon: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """:func:`costmap_cost_at` over poses ``(P, 3)`` (compiled: a few poses or a path window;
    :func:`costmap_costs` is the vectorised NumPy twin).

    Parameters
    ----------
    poses : numpy.ndarray, shape (P, 3)
        Poses in the frame of ``geometry``'s origin.
    cost, near, geometry, polygon : numpy.ndarray
        As for :func:`costmap_costs`.

    Returns
    -------
    soft : numpy.ndarray, shape (P,)
    collided : numpy.ndarray of bool, shape (P,)
    """
    poses = np.ascontiguousarray(poses, dtype=np.float64).reshape(-1, 3)
    soft, hit = np.empty(poses.shape[0]), np.empty(poses.shape[0], np.bool_)
    _costmap_poses(poses, cost, near, geometry, polygon, soft, hit)
    return soft, hit


# --------------------------------------------------------------------------- NumPy twins
def costmap_costs(
    poses: np.ndarray,
    cost: np.ndarray,
    near: np.ndarray,
    geometry: np.ndarray,
    polygon: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """Soft cost (0–1) and collision of poses on the costmap (vectorised twin of
    :func:`costmap_cost_at`).

    Parameters
    ----------
    poses : numpy.ndarray, shape (..., 3)
        Poses (x [m], y [m], θ [rad]) in the frame of ``geometry``'s origin.
    cost, near : numpy.ndarray of uint8, shape (rows, cols)
        Costs and the outline gate (:class:`PerceptionArrays`).
    geometry : numpy.ndarray, shape (5,)
        As :attr:`PerceptionArrays.geometry`.
    polygon : numpy.ndarray, shape (V, 2)
        The footprint outline in the body frame ((0, 2): a point).

    Returns
    -------
    soft : numpy.ndarray, shape (...)
    collided : numpy.ndarray of bool, shape (...)
    """
    x0, y0, res = geometry[0], geometry[1], geometry[2]
    inv = 1.0 / res
    fx, fy = (poses[..., 0] - x0) * inv, (poses[..., 1] - y0) * inv
    col, row = np.floor(fx).astype(np.int64), np.floor(fy).astype(np.int64)
    rows, cols = cost.shape
    inside = (row >= 0) & (row < rows) & (col >= 0) & (col < cols)
    r, q = np.clip(row, 0, rows - 1), np.clip(col, 0, cols - 1)
    value = np.where(inside, cost[r, q], 0).astype(np.int64)
    soft = np.where(value > MAX_INFLATED, 1.0, value / MAX_INFLATED)
    hit = (value == LETHAL) | ((geometry[4] > 0.5) & (value == INSCRIBED))
    if polygon.shape[0] == 0:
        return soft, hit
    check = inside & ~hit & (near[r, q] > 0)
    if np.any(check):
        theta = poses[..., 2][check]
        c, s = np.cos(theta)[:, None], np.sin(theta)[:, None]
        px = fx[check][:, None] + (c * polygon[:, 0] - s * polygon[:, 1]) * inv  # (P, V)
        py = fy[check][:, None] + (s * polygon[:, 0] + c * polygon[:, 1]) * inv
        ax, ay = px, py
        bx, by = np.roll(px, -1, axis=1), np.roll(py, -1, axis=1)
        hit[check] = _segments_hit_lethal(cost, ax, ay, bx, by).any(axis=1)
    return soft, hit


def _segments_hit_lethal(cost, ax, ay, bx, by):
    """Vectorised :func:`_segment_hits_lethal` over arrays of segments (cell units)."""
    rows, cols = cost.shape

    def lethal(row, col):
        inside = (row >= 0) & (row < rows) & (col >= 0) & (col < cols)
        values = cost[np.clip(row, 0, rows - 1), np.clip(col, 0, cols - 1)]
        return inside & (values == LETHAL)

    hits = lethal(np.floor(ay).astype(np.int64), np.floor(ax).astype(np.int64))
    hits |= lethal(np.floor(by).astype(np.int64), np.floor(bx).astype(np.int64))
    for (a, b, c, d), along_x in (((ax, bx, ay, by), True), ((ay, by, ax, bx), False)):
        delta, other = b - a, d - c
        first = np.floor(np.minimum(a, b)) + 1.0
        count = (np.floor(np.maximum(a, b)) + 1.0 - first).astype(np.int64)
        most = int(count.max(initial=0))
        for step in range(most):
            k = first + step
            valid = (step < count) & (delta != 0.0)
            with np.errstate(divide="ignore", invalid="ignore"):
                cross = np.floor(c + (k - a) / delta * other)
            cross = np.where(valid, cross, -1).astype(np.int64)
            line = k.astype(np.int64)
            if along_x:  # a vertical grid line: column k - 1 | k, at row `cross`
                found = lethal(cross, line - 1) | lethal(cross, line)
            else:  # a horizontal one: row k - 1 | k, at column `cross`
                found = lethal(line - 1, cross) | lethal(line, cross)
            hits |= valid & found
    return hits


def _track_distances(poses: np.ndarray, table: np.ndarray, disks: np.ndarray) -> np.ndarray:
    """d (N, T, J) [m]: the least over the disks of |centre − mean| − disk radius − track
    radius, poses (N, T, 3) against table (T, J, 4)."""
    c, s = np.cos(poses[..., 2])[..., None], np.sin(poses[..., 2])[..., None]
    px = poses[..., 0][..., None] + c * disks[:, 0] - s * disks[:, 1]  # (N, T, D)
    py = poses[..., 1][..., None] + s * disks[:, 0] + c * disks[:, 1]
    dx = px[..., :, None] - table[None, :, None, :, 0]  # (N, T, D, J)
    dy = py[..., :, None] - table[None, :, None, :, 1]
    d = np.hypot(dx, dy) - disks[:, 2][None, None, :, None] - table[None, :, None, :, 2]
    return d.min(axis=2) if d.shape[2] else np.full(d.shape[:2] + d.shape[3:], 1e300)


def track_costs(
    poses: np.ndarray,
    table: np.ndarray,
    relief: np.ndarray,
    disks: np.ndarray,
    inflation: float,
    hold_weight: float = 1.0,
) -> tuple[np.ndarray, np.ndarray]:
    """Soft cost Σ_j gap² [m²] and contact of rollout poses against the predicted tracks
    (vectorised twin of :func:`track_cost_at`).

    Parameters
    ----------
    poses : numpy.ndarray, shape (N, T, 3)
        Rollout poses after steps 1..T, relative to the robot's position.
    table : numpy.ndarray, shape (T + H, J, 4)
        As :attr:`PerceptionArrays.table`: its last H rows are checked against the final
        pose, held.
    relief : numpy.ndarray, shape (J,)
        Contact thresholds [m].
    disks : numpy.ndarray, shape (D, 3)
        The footprint's covering disks.
    inflation : float
        r_dyn [m].
    hold_weight : float
        Factor of the held checks' soft cost (:data:`HOLD_STEP` / dt: each stands for that
        many rollout steps).

    Returns
    -------
    soft : numpy.ndarray, shape (N, T + H)
    collided : numpy.ndarray of bool, shape (N, T + H)
    """
    if table.shape[1] == 0:
        zeros = np.zeros((poses.shape[0], table.shape[0]))
        return zeros, zeros.astype(bool)
    steps = poses.shape[1]
    held = table.shape[0] - steps
    poses = np.concatenate([poses, np.repeat(poses[:, -1:], held, axis=1)], axis=1)
    d = _track_distances(poses, table, disks)
    collided = np.any(d <= relief, axis=-1)
    collided[:, steps:] = False  # the held pose is scored, never lethal
    spread = table[None, ..., 3]
    zone = inflation + spread
    inside = inflation * (zone - np.maximum(d, 0.0)) / zone + np.maximum(-d, 0.0)
    gap = np.where(d < zone, inside, 0.0)
    reach = np.max(np.hypot(disks[:, 0], disks[:, 1]) + disks[:, 2]) if disks.shape[0] else 0.0
    rho = reach + table[None, ..., 2] + inflation
    with np.errstate(divide="ignore"):
        sure = np.where(spread > 0.0, -np.expm1(-0.5 * (rho / spread) ** 2), 1.0)
    soft = np.sum(sure * gap * gap, axis=-1)
    soft[:, steps:] *= hold_weight
    return soft, collided
