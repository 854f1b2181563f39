"""Harness of the local controllers among obstacles they perceive: the cases, not the library.

- :func:`inflated_costmap`: a costmap (Nav2's costs: 254 lethal, 253 inscribed, 252·exp(−k·(d −
  r_in)) out to the inflation radius) from boxes, on the grid geometry of
  :class:`~wheelbase.planning.OccupancyGrid`, made here from the boxes' cells with a distance
  transform (a stand-in for the perception package's, whose layers come from the lidar);
- :func:`local_view`: a perception view of perfect tracks (what a controller's ``perception=``
  takes: ``costmap``, ``tracks`` with position, velocity, covariance, radius, and ``time``);
- :func:`encounter`: one robot (unicycle, Euler steps of ``dt``) following a path among discs
  that move at constant velocity and ignore it, the controller seeing them (or not): the least
  gap [m] between the footprint and any disc or box, and where the robot ended.

Used by ``benchmarks/mppi.py``, ``benchmarks/dwa.py`` and the tests (which put this folder on
``sys.path``). The engine's own perception loop (lidar → costmap → tracker) is the simulator's;
this harness gives the controllers the truth, to test the critics alone.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy.ndimage import distance_transform_edt

from wheelbase.polyline import distance_to_polyline

__all__ = [
    "CASES",
    "Encounter",
    "busy_view",
    "crowd_case",
    "crowd_suite",
    "encounter",
    "footprint_gap",
    "inflated_costmap",
    "local_view",
]


@dataclass(frozen=True)
class _Costmap:
    cost: np.ndarray
    resolution: float
    origin: tuple[float, float]


@dataclass(frozen=True)
class _Tracks:
    position: np.ndarray
    velocity: np.ndarray
    covariance: np.ndarray
    radius: np.ndarray


@dataclass(frozen=True)
class _View:
    costmap: Any
    tracks: Any
    time: float


def inflated_costmap(
    boxes: list[tuple[float, float, float, float]],
    extent: tuple[float, float, float, float],
    resolution: float = 0.05,
    inscribed_radius: float = 0.2,
    inflation_radius: float = 0.55,
    cost_scaling_factor: float = 10.0,
) -> _Costmap:
    """A costmap of axis-aligned boxes (x0, y0, x1, y1) [m] over ``extent`` (x0, y0, x1, y1).

    Parameters
    ----------
    boxes : list of tuple
        Boxes [m]; cells whose centre lies in one are lethal.
    extent : tuple
        The map's rectangle [m].
    resolution : float
        Cell side [m].
    inscribed_radius, inflation_radius : float
        Nav2's inflation radii [m] (defaults: a 0.4 m square robot, Nav2's 0.55 m).
    cost_scaling_factor : float
        Nav2's decay rate [1/m] (default 10).

    Returns
    -------
    object
        With ``cost`` (uint8), ``resolution`` and ``origin``.
    """
    x0, y0, x1, y1 = extent
    cols, rows = round((x1 - x0) / resolution), round((y1 - y0) / resolution)
    cx = x0 + (np.arange(cols) + 0.5) * resolution
    cy = y0 + (np.arange(rows) + 0.5) * resolution
    gx, gy = np.meshgrid(cx, cy)
    lethal = np.zeros((rows, cols), bool)
    for bx0, by0, bx1, by1 in boxes:
        lethal |= (gx >= bx0) & (gx <= bx1) & (gy >= by0) & (gy <= by1)
    d = distance_transform_edt(~lethal) * resolution if lethal.any() else np.full(lethal.shape, 1e9)
    cost = np.where(d <= inflation_radius,
                    252.0 * np.exp(-cost_scaling_factor * (d - inscribed_radius)), 0.0)  # fmt: skip
    cost = np.minimum(cost, 252.0).astype(np.uint8)
    cost[d <= inscribed_radius] = 253
    cost[lethal] = 254
    return _Costmap(cost, resolution, (x0, y0))


def local_view(
    positions: np.ndarray | None,
    velocities: np.ndarray | None,
    radii: np.ndarray | None,
    time: float,
    costmap: Any = None,
    position_std: float = 0.03,
    velocity_std: float = 0.05,
) -> _View:
    """A perception view: perfect tracks (with a small stated covariance) and a costmap.

    Parameters
    ----------
    positions, velocities : numpy.ndarray, shape (J, 2), or None
        Tracks [m], [m/s] (``None``: no tracks).
    radii : numpy.ndarray, shape (J,), or None
        Track radii [m].
    time : float
        The view's time [s].
    costmap : object, optional
        A costmap (:func:`inflated_costmap`).
    position_std, velocity_std : float
        σ of the stated track covariance [m], [m/s].

    Returns
    -------
    object
        With ``costmap``, ``tracks`` and ``time``.
    """
    tracks = None
    if positions is not None:
        n = len(positions)
        cov = np.zeros((n, 4, 4))
        cov[:, [0, 1], [0, 1]] = position_std**2
        cov[:, [2, 3], [2, 3]] = velocity_std**2
        tracks = _Tracks(np.asarray(positions, float), np.asarray(velocities, float), cov,
                         np.asarray(radii, float))  # fmt: skip
    return _View(costmap, tracks, time)


def footprint_gap(pose: np.ndarray, polygon: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Signed distance [m] from points (K, 2) to a convex footprint (V, 2) at ``pose``
    (negative inside)."""
    c, s = math.cos(pose[2]), math.sin(pose[2])
    outline = pose[:2] + polygon @ np.array([[c, s], [-s, c]])
    distance = distance_to_polyline(points, np.vstack([outline, outline[:1]]))
    edges = np.roll(outline, -1, axis=0) - outline
    rel = points[:, None, :] - outline[None]
    inside = np.all(edges[None, :, 0] * rel[..., 1] - edges[None, :, 1] * rel[..., 0] >= 0, axis=1)
    return np.where(inside, -distance, distance)


@dataclass(frozen=True)
class Encounter:
    """What :func:`encounter` measured.

    Attributes
    ----------
    min_gap : float
        Least gap [m] between the footprint and any disc (or box), negative when they overlap.
    poses : numpy.ndarray, shape (T + 1, 3)
        The robot's poses.
    statuses : list of str
        The controller's status at each step.
    distance_to_end : float
        Final distance [m] to the path's last point.
    """

    min_gap: float
    poses: np.ndarray
    statuses: list
    distance_to_end: float


def encounter(
    controller: Any,
    path: Any,
    start: tuple[float, float, float],
    footprint: Any,
    *,
    discs: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None,
    costmap: Any = None,
    boxes: list[tuple[float, float, float, float]] = (),
    perceive: bool = True,
    duration: float = 16.0,
    dt: float = 0.1,
) -> Encounter:
    """Drive a unicycle with ``controller`` along ``path`` among moving discs and boxes.

    Parameters
    ----------
    controller : callable
        ``controller(t, pose, path, perception=view) -> (v, ω)``.
    path : PlannedPath
        The path.
    start : tuple
        Start pose (x [m], y [m], θ [rad]).
    footprint : Footprint
        The robot outline (the gap is measured to it exactly).
    discs : (positions (J, 2), velocities (J, 2), radii (J,)), optional
        Discs moving at constant velocity, blind to the robot.
    costmap : object, optional
        What the controller sees of static obstacles.
    boxes : list of tuple
        The true static boxes (x0, y0, x1, y1) [m] the gap is measured to.
    perceive : bool
        Give the controller the view (tracks of the discs, the costmap), or ``None``.
    duration, dt : float
        Time [s] and step [s].

    Returns
    -------
    Encounter
    """
    pose = np.array(start, dtype=float)
    polygon = np.asarray(footprint.polygon)
    positions, velocities, radii = (np.zeros((0, 2)), np.zeros((0, 2)), np.zeros(0)) if (
        discs is None) else (np.array(discs[0], float), np.array(discs[1], float),
                             np.array(discs[2], float))  # fmt: skip
    box_points = [_box_outline(box) for box in boxes]
    poses, statuses, least = [pose.copy()], [], math.inf
    for k in range(round(duration / dt)):
        t = k * dt
        view = None
        if perceive:
            tracks = (positions, velocities, radii) if len(radii) else (None, None, None)
            view = local_view(*tracks, time=t, costmap=costmap)
        v, w = np.asarray(controller(t, pose, path, perception=view), float).reshape(2)
        statuses.append(getattr(controller, "status", None))
        if len(radii):
            least = min(least, float(np.min(footprint_gap(pose, polygon, positions) - radii)))
        for outline in box_points:
            least = min(least, _polygon_gap(pose, polygon, outline))
        pose = pose + dt * np.array([v * math.cos(pose[2]), v * math.sin(pose[2]), w])
        positions = positions + dt * velocities
        poses.append(pose.copy())
    end = float(np.hypot(*(pose[:2] - np.asarray(path.points)[-1])))
    return Encounter(least, np.array(poses), statuses, end)


def _box_outline(box: tuple[float, float, float, float]) -> np.ndarray:
    x0, y0, x1, y1 = box
    return np.array([[x0, y0], [x1, y0], [x1, y1], [x0, y1]], dtype=float)


def _polygon_gap(pose: np.ndarray, polygon: np.ndarray, box: np.ndarray) -> float:
    """Gap [m] between the footprint and a box: the least over each's vertices of the signed
    distance to the other (exact for convex polygons that do not cross edge to edge without a
    vertex inside, and a sample of the boundary of both besides)."""
    c, s = math.cos(pose[2]), math.sin(pose[2])
    outline = pose[:2] + polygon @ np.array([[c, s], [-s, c]])
    dense = _densify(box)
    robot = _densify(outline)
    a = footprint_gap(pose, polygon, dense)
    b = footprint_gap(np.zeros(3), box, robot)
    return float(min(a.min(), b.min()))


def _densify(polygon: np.ndarray, step: float = 0.01) -> np.ndarray:
    points = []
    for a, b in zip(polygon, np.roll(polygon, -1, axis=0), strict=True):
        n = max(1, math.ceil(float(np.hypot(*(b - a))) / step))
        points.append(a + np.arange(n)[:, None] / n * (b - a))
    return np.concatenate(points)


def busy_view(pose: np.ndarray):
    """A perception view around ``pose``: a 3 × 3 m costmap (0.05 m cells) with a box 1 m
    ahead, and 20 tracks within 3 m walking at 0.5 m/s."""
    x, y = float(pose[0]), float(pose[1])
    costmap = inflated_costmap([(x + 1.0, y - 0.2, x + 1.3, y + 0.1)],
                               (x - 1.5, y - 1.5, x + 1.5, y + 1.5))  # fmt: skip
    rng = np.random.default_rng(5)
    angle = rng.uniform(-np.pi, np.pi, 20)
    where = pose[:2] + rng.uniform(1.0, 3.0, (20, 1)) * np.column_stack(
        [np.cos(angle), np.sin(angle)]
    )
    heading = rng.uniform(-np.pi, np.pi, 20)
    velocity = 0.5 * np.column_stack([np.cos(heading), np.sin(heading)])
    return local_view(where, velocity, np.full(20, 0.3), 0.0, costmap=costmap)


CASES = ("head_on", "crossing", "overtake", "group", "box")
"""The encounters of :func:`crowd_case`."""


def crowd_case(name: str, seed: int) -> dict[str, Any]:
    """One encounter on the 8 m straight path from (0, 0) to (8, 0), drawn from ``seed``.

    - ``head_on``: a disc (r 0.25–0.35 m) coming down the path at 0.4–0.8 m/s, up to 0.2 m off
      it;
    - ``crossing``: a disc crossing the path at 0.5–1.0 m/s from either side, timed to reach it
      where the robot would be at 0.5 m/s (± 1 s);
    - ``overtake``: a slow disc (0.1–0.2 m/s) ahead on the path, going the same way;
    - ``group``: three discs coming from ahead at 0.3–0.6 m/s, spread over ±1 m;
    - ``box``: a 0.4–0.8 m box on the path 2.5–4 m ahead, in the costmap.

    Parameters
    ----------
    name : str
        One of :data:`CASES`.
    seed : int
        Seed of the draw.

    Returns
    -------
    dict
        Keyword arguments of :func:`encounter` (``discs``, ``costmap``, ``boxes``).
    """
    rng = np.random.default_rng([seed, CASES.index(name)])
    if name == "head_on":
        speed, radius = rng.uniform(0.4, 0.8), rng.uniform(0.25, 0.35)
        return {"discs": (np.array([[rng.uniform(5.0, 7.0), rng.uniform(-0.2, 0.2)]]),
                          np.array([[-speed, 0.0]]), np.array([radius]))}  # fmt: skip
    if name == "crossing":
        speed, side = rng.uniform(0.5, 1.0), rng.choice([-1.0, 1.0])
        meet = rng.uniform(2.5, 5.0)  # where it crosses the path [m]
        arrive = meet / 0.5 + rng.uniform(-1.0, 1.0)  # when [s]
        return {"discs": (np.array([[meet, -side * speed * arrive]]),
                          np.array([[0.0, side * speed]]), np.array([0.3]))}  # fmt: skip
    if name == "overtake":
        return {"discs": (np.array([[rng.uniform(1.5, 2.5), 0.0]]),
                          np.array([[rng.uniform(0.1, 0.2), 0.0]]), np.array([0.3]))}  # fmt: skip
    if name == "group":
        y = rng.uniform(-1.0, 1.0, 3)
        x = rng.uniform(5.0, 7.5, 3)
        speed = rng.uniform(0.3, 0.6, 3)
        order = np.argsort(y)
        y = y[order] + np.array([-0.35, 0.0, 0.35])  # keep the discs apart
        return {"discs": (np.column_stack([x, y]), np.column_stack([-speed, np.zeros(3)]),
                          np.full(3, 0.3))}  # fmt: skip
    side = rng.uniform(0.4, 0.8)
    x = rng.uniform(2.5, 4.0)
    box = (x, -side / 2, x + side, side / 2)
    return {"costmap": inflated_costmap([box], (-1.0, -3.0, 9.0, 3.0)), "boxes": [box]}


def crowd_suite(
    make: Any, seeds: int, footprint: Any, duration: float = 30.0, cases: tuple = CASES
) -> dict[str, Any]:
    """The ``cases`` (default all of :data:`CASES`) over ``seeds`` seeds with fresh controllers
    from ``make()``: success (no contact, within 0.2 m of the path's end), the least gap and the
    time used.

    Parameters
    ----------
    make : callable
        ``make(seed)`` -> a controller.
    seeds : int
        Seeds per case.
    footprint : Footprint
        The robot outline.
    duration : float
        Time limit [s] of each encounter.
    cases : tuple of str
        Which encounters.

    Returns
    -------
    dict
        Per case: ``success_rate``, ``collisions``, ``min_gap_m`` (least), ``median_gap_m``,
        ``stops`` (calls that found no collision-free command), ``wall_s``.
    """
    import time

    path_points = np.array([[0.0, 0.0], [8.0, 0.0]])
    from wheelbase.planning import PlannedPath

    path = PlannedPath.from_points(path_points)
    out: dict[str, Any] = {}
    for name in cases:
        gaps, successes, stops, begin = [], 0, 0, time.perf_counter()
        for seed in range(seeds):
            result = encounter(make(seed), path, (0.0, 0.0, 0.0), footprint,
                               duration=duration, **crowd_case(name, seed))  # fmt: skip
            gaps.append(result.min_gap)
            successes += int(result.min_gap > 0.0 and result.distance_to_end <= 0.2)
            stops += sum(status == "all_collide" for status in result.statuses)
        out[name] = {
            "seeds": seeds,
            "success_rate": successes / seeds,
            "collisions": int(sum(gap <= 0.0 for gap in gaps)),
            "min_gap_m": float(np.min(gaps)),
            "median_gap_m": float(np.median(gaps)),
            "stops": int(stops),
            "wall_s": round(time.perf_counter() - begin, 1),
        }
    return out
