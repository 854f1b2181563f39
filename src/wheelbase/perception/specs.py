"""The scenario's ``costmap:`` and ``tracker:`` sections: their keys, defaults and checks.

Each spec's fields are exactly the keys of its section; ``from_mapping`` checks a plain dict (a
parsed YAML section) and names the key it rejects (``costmap.inflation_radius must be > 0 m
(got -1)``, ``unknown key costmap.raytrace_range; allowed: ...``). The costmap defaults are
Nav2's (``nav2_costmap_2d``: the inflation layer's ``inflation_radius`` 0.55 m and
``cost_scaling_factor`` 10, the obstacle layer's ``obstacle_max_range`` 2.5 m and
``raytrace_max_range`` 3.0 m, a 3 m × 3 m rolling window, ``track_unknown_space`` false).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields
from typing import Any

import numpy as np

from wheelbase._validate import flag, integer, nonnegative, positive
from wheelbase.errors import ConfigError, InputError
from wheelbase.limits import MAX_COORDINATE, MAX_TRACKS

__all__ = ["CostmapSpec", "TrackerSpec", "check_scan_geometry"]


def check_scan_geometry(sensor_xy: np.ndarray, max_range: float) -> float:
    """Check a scan's sensor positions and range against ``wheelbase.limits.MAX_COORDINATE``
    (1e10 m: farther, cell indices no longer fit an integer) and return ``max_range``.

    Parameters
    ----------
    sensor_xy : numpy.ndarray
        Sensor positions ``(..., 2)`` [m], finite.
    max_range : float
        The lidar's largest range [m].

    Returns
    -------
    float
        ``max_range``, checked: > 0 and <= ``MAX_COORDINATE``.
    """
    reach = float(np.max(np.abs(sensor_xy), initial=0.0))
    if reach > MAX_COORDINATE:
        raise InputError(
            f"sensor positions must be within ±{MAX_COORDINATE:g} m (got one {reach:.3g} m away)"
        )
    max_range = positive("max_range", max_range, "m")
    if max_range > MAX_COORDINATE:
        raise InputError(f"max_range must be <= {MAX_COORDINATE:g} m (got {max_range:.3g} m)")
    return max_range


def _at_most(name: str, value: float, unit: str) -> float:
    """``value`` if it is at most ``MAX_COORDINATE`` (1e10), else ConfigError naming it."""
    if value > MAX_COORDINATE:
        raise ConfigError(f"{name} must be <= {MAX_COORDINATE:g} {unit} (got {value:.3g} {unit})")
    return value


def _checked_mapping(cls: type, section: str, values: object) -> dict[str, Any]:
    """``values`` as a dict of ``cls``'s fields, or ConfigError naming the section and key."""
    if values is None:
        return {}
    if not isinstance(values, dict):
        raise ConfigError(f"{section} must be a mapping of keys (got {type(values).__name__})")
    known = [f.name for f in fields(cls)]
    for key in values:
        if key not in known:
            raise ConfigError(f"unknown key {section}.{key}; allowed: {', '.join(known)}")
    return dict(values)


@dataclass(frozen=True)
class CostmapSpec:
    """The ``costmap:`` keys of a scenario (Nav2's layered costmap; defaults are Nav2's).

    Parameters
    ----------
    inflation_radius : float
        Distance [m] from an obstacle out to which cells get an inflation cost, > 0 and at
        least the robot's inscribed radius (Nav2 default 0.55 m); at most 1000 cells (the
        map's diagonal counts, when shorter).
    cost_scaling_factor : float
        Decay rate k [1/m] of the inflation cost 252·exp(−k (d − r_inscribed)), >= 0 (Nav2
        default 10).
    obstacle_max_range : float
        Lidar returns up to this range [m] mark obstacles, > 0 (Nav2 default 2.5 m).
    obstacle_min_range : float
        Returns nearer than this [m] do not mark, >= 0 and < ``obstacle_max_range``
        (Nav2 default 0).
    raytrace_max_range : float
        Each beam clears the cells it passes up to this range [m], > 0 (Nav2 default 3.0 m).
    raytrace_min_range : float
        Cells nearer than this [m] along a beam are not cleared, >= 0 and <
        ``raytrace_max_range`` (Nav2 default 0).
    window : float
        Side [m] of the square rolling window around the robot given to local controllers,
        > 0, at most ``wheelbase.limits.MAX_MAP_CELLS`` cells (Nav2's local costmap: 3 m ×
        3 m).
    resolution : float or None
        Cell side [m] of the costmap, > 0; None (default) takes the map's.
    track_unknown : bool
        Nav2's ``track_unknown_space``: cells the map marks unknown stay unknown (cost 255)
        until a beam clears them; false (default): the map's own decision (unknown cells are
        occupied unless its loader said otherwise) stands.
    """

    inflation_radius: float = 0.55
    cost_scaling_factor: float = 10.0
    obstacle_max_range: float = 2.5
    obstacle_min_range: float = 0.0
    raytrace_max_range: float = 3.0
    raytrace_min_range: float = 0.0
    window: float = 3.0
    resolution: float | None = None
    track_unknown: bool = False

    def __post_init__(self) -> None:
        checked = {
            "inflation_radius": positive("costmap.inflation_radius", self.inflation_radius, "m"),
            "cost_scaling_factor": nonnegative(
                "costmap.cost_scaling_factor", self.cost_scaling_factor, "1/m"
            ),
            "obstacle_max_range": positive(
                "costmap.obstacle_max_range", self.obstacle_max_range, "m"
            ),
            "obstacle_min_range": nonnegative(
                "costmap.obstacle_min_range", self.obstacle_min_range, "m"
            ),
            "raytrace_max_range": positive(
                "costmap.raytrace_max_range", self.raytrace_max_range, "m"
            ),
            "raytrace_min_range": nonnegative(
                "costmap.raytrace_min_range", self.raytrace_min_range, "m"
            ),
            "window": positive("costmap.window", self.window, "m"),
            "resolution": None
            if self.resolution is None
            else positive("costmap.resolution", self.resolution, "m"),
            "track_unknown": flag("costmap.track_unknown", self.track_unknown),
        }
        for low, high in (("obstacle_min_range", "obstacle_max_range"),
                          ("raytrace_min_range", "raytrace_max_range")):  # fmt: skip
            if checked[low] >= checked[high]:
                raise ConfigError(
                    f"costmap.{low} must be < costmap.{high} = {checked[high]:g} m "
                    f"(got {checked[low]:g} m)"
                )
        for name in ("inflation_radius", "obstacle_max_range", "raytrace_max_range", "window"):
            _at_most(f"costmap.{name}", checked[name], "m")
        for name, value in checked.items():
            object.__setattr__(self, name, value)

    @classmethod
    def from_mapping(cls, values: dict | None) -> CostmapSpec:
        """The spec of a scenario's ``costmap:`` section (a plain dict; None: the defaults).

        Parameters
        ----------
        values : dict or None
            Keys of the section; missing keys take their defaults.

        Returns
        -------
        CostmapSpec

        Raises
        ------
        ConfigError
            Naming the unknown key, or the key whose value is out of range.
        """
        return cls(**_checked_mapping(cls, "costmap", values))


@dataclass(frozen=True)
class TrackerSpec:
    """The ``tracker:`` keys of a scenario: the moving-obstacle tracker
    (:mod:`wheelbase.perception.tracking`).

    Parameters
    ----------
    map_tolerance : float
        A lidar endpoint is explained by the map when the cell holding it is within this
        distance [m] of an occupied map cell, centre to centre; >= 0 (default 0.2 m; keep it
        at least one map cell, since a beam that hits a wall from above or from the right
        ends on the free cell beside it).
    cluster_distance : float
        Consecutive unexplained endpoints (in beam order) closer than this [m] belong to one
        cluster, > 0 (default 0.3 m).
    min_points : int
        Clusters with fewer endpoints are dropped, >= 1 (default 2).
    max_radius : float
        Clusters whose radius estimate exceeds this [m] are not tracked (long unmapped walls
        are left to the costmap), > 0 (default 1.0 m).
    measurement_std : float
        Standard deviation [m] added in quadrature to a cluster's spread for its measurement
        covariance, > 0 (default 0.05 m).
    process_noise : float
        Spectral density q [m²/s³] of the constant-velocity model's white acceleration,
        > 0 (default 0.5).
    initial_speed_std : float
        Standard deviation [m/s] of each velocity component of a new track, > 0 (default
        1.0 m/s: people walk at 0.5–1.5 m/s).
    gate_probability : float
        Probability mass of the χ² (2 degrees of freedom) gate on the Mahalanobis distance of
        a measurement to a track, in (0, 1) (default 0.99: d² <= 9.21).
    hits_to_confirm : int
        A tentative track is confirmed at this many hits in a row from its birth, >= 1
        (default 3).
    misses_to_delete : int
        A confirmed track is deleted after this many misses in a row, >= 1 (default 5);
        a tentative track at its first miss.
    max_tracks : int
        Most tracks kept, in [1, ``wheelbase.limits.MAX_TRACKS`` = 10000]; unmatched
        measurements beyond it start no track (default 64).
    """

    map_tolerance: float = 0.2
    cluster_distance: float = 0.3
    min_points: int = 2
    max_radius: float = 1.0
    measurement_std: float = 0.05
    process_noise: float = 0.5
    initial_speed_std: float = 1.0
    gate_probability: float = 0.99
    hits_to_confirm: int = 3
    misses_to_delete: int = 5
    max_tracks: int = 64

    def __post_init__(self) -> None:
        checked = {
            "map_tolerance": nonnegative("tracker.map_tolerance", self.map_tolerance, "m"),
            "cluster_distance": positive("tracker.cluster_distance", self.cluster_distance, "m"),
            "min_points": integer("tracker.min_points", self.min_points, minimum=1),
            "max_radius": positive("tracker.max_radius", self.max_radius, "m"),
            "measurement_std": positive("tracker.measurement_std", self.measurement_std, "m"),
            "process_noise": positive("tracker.process_noise", self.process_noise, "m²/s³"),
            "initial_speed_std": positive(
                "tracker.initial_speed_std", self.initial_speed_std, "m/s"
            ),
            "gate_probability": positive("tracker.gate_probability", self.gate_probability),
            "hits_to_confirm": integer("tracker.hits_to_confirm", self.hits_to_confirm, 1),
            "misses_to_delete": integer("tracker.misses_to_delete", self.misses_to_delete, 1),
            "max_tracks": integer("tracker.max_tracks", self.max_tracks, 1, MAX_TRACKS),
        }
        if not checked["gate_probability"] < 1.0:
            raise ConfigError(
                f"tracker.gate_probability must be in (0, 1) (got {checked['gate_probability']:g})"
            )
        units = {
            "map_tolerance": "m",
            "cluster_distance": "m",
            "max_radius": "m",
            "measurement_std": "m",
            "process_noise": "m²/s³",
            "initial_speed_std": "m/s",
        }
        for name, unit in units.items():  # fmt: skip
            _at_most(f"tracker.{name}", checked[name], unit)
        for name, value in checked.items():
            object.__setattr__(self, name, value)

    @property
    def gate(self) -> float:
        """The χ² gate on the squared Mahalanobis distance: the ``gate_probability`` quantile
        of χ² with 2 degrees of freedom, −2 ln(1 − p) (closed form for 2 dof)."""
        return -2.0 * math.log1p(-self.gate_probability)

    @classmethod
    def from_mapping(cls, values: dict | None) -> TrackerSpec:
        """The spec of a scenario's ``tracker:`` section (a plain dict; None: the defaults).

        Parameters
        ----------
        values : dict or None
            Keys of the section; missing keys take their defaults.

        Returns
        -------
        TrackerSpec

        Raises
        ------
        ConfigError
            Naming the unknown key, or the key whose value is out of range.
        """
        return cls(**_checked_mapping(cls, "tracker", values))
