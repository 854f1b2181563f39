"""A simulated 2-D lidar: a fan of beams cast on an occupancy grid, with the beam noise model.

The sensor sits at ``mount`` (x forward [m], y left [m], yaw [rad]) in the robot's body frame.
Its beams are evenly spaced over ``fov`` and centred on the sensor's x axis: for a full circle
(``fov = 2π``) beam k points at ``−π + 2πk/beams``, otherwise the first and last beams lie on the
edges of the field of view, ``−fov/2 + k·fov/(beams − 1)``, as most planar lidars report them.

A scan is the ray cast of :mod:`wheelbase.sensors.raycast` (``fast`` by default) followed by
the beam model of :mod:`wheelbase.sensors.beam_model` with σ_hit = ``range_std``. Readings
shorter than ``min_range`` are reported as NaN (inside the blind zone a lidar has no valid
return); a beam with nothing within ``max_range`` reads ``max_range``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike

from wheelbase._validate import as_float_array, as_rng, integer, nonnegative, positive
from wheelbase.errors import ConfigError
from wheelbase.limits import MAX_BEAMS
from wheelbase.planning import OccupancyGrid, PolygonWorld
from wheelbase.sensors.beam_model import BeamModel
from wheelbase.sensors.raycast import scan_rays

__all__ = ["Lidar"]


@dataclass(frozen=True)
class Lidar:
    """A planar scanning range finder (module docstring).

    Parameters
    ----------
    beams : int
        Number of beams per scan, >= 1.
    fov : float
        Field of view [rad], in (0, 2π].
    max_range : float
        Largest range [m], > 0; beams with no obstacle in range read this.
    min_range : float
        Smallest valid range [m], in [0, max_range); shorter readings are NaN.
    range_std : float
        Standard deviation of a hit σ_hit [m], >= 0.
    mount : tuple of float
        Sensor pose (x [m], y [m], yaw [rad]) in the robot's body frame.
    beam_model : BeamModel
        Mixture of hit, short, max and random readings; the default is Gaussian hits only.

    Examples
    --------
    >>> from wheelbase.planning import OccupancyGrid, PolygonWorld
    >>> room = OccupancyGrid.from_array(np.pad(np.zeros((8, 8), bool), 1, constant_values=True),
    ...                                 0.5)
    >>> Lidar(beams=4, max_range=10.0).scan(room, [2.5, 2.5, 0.0], noise=False).tolist()
    [2.0, 2.0, 2.0, 2.0]
    """

    beams: int = 360
    fov: float = 2.0 * math.pi
    max_range: float = 8.0
    min_range: float = 0.0
    range_std: float = 0.0
    mount: tuple[float, float, float] = (0.0, 0.0, 0.0)
    beam_model: BeamModel = field(default_factory=BeamModel)

    def __post_init__(self) -> None:
        if isinstance(self.beams, bool) or not isinstance(self.beams, int | np.integer):
            raise ConfigError(f"beams must be an integer >= 1 (got {self.beams!r})")
        integer("beams", self.beams, minimum=1, maximum=MAX_BEAMS)
        fov = positive("fov", self.fov, "rad")
        if fov > 2.0 * math.pi + 1e-12:
            raise ConfigError(f"fov must be in (0, 2π] rad (got {fov:g})")
        max_range = positive("max_range", self.max_range, "m")
        min_range = nonnegative("min_range", self.min_range, "m")
        if min_range >= max_range:
            raise ConfigError(
                f"min_range must be < max_range = {max_range:g} m (got {min_range:g} m)"
            )
        range_std = nonnegative("range_std", self.range_std, "m")
        mount = as_float_array("mount", self.mount, 3, max_ndim=1)
        # the checked numbers are kept, not what was given ("8" or numpy scalars)
        for name, value in (("beams", int(self.beams)), ("fov", fov), ("max_range", max_range),
                            ("min_range", min_range), ("range_std", range_std),
                            ("mount", tuple(float(v) for v in mount))):  # fmt: skip
            object.__setattr__(self, name, value)
        if not isinstance(self.beam_model, BeamModel):
            raise ConfigError(
                f"beam_model must be a BeamModel (got {type(self.beam_model).__name__})"
            )

    @property
    def beam_angles(self) -> np.ndarray:
        """Beam directions [rad] in the sensor frame, shape ``(beams,)``."""
        if self.fov >= 2.0 * math.pi - 1e-12:
            return -math.pi + 2.0 * math.pi * np.arange(self.beams) / self.beams
        if self.beams == 1:
            return np.zeros(1)
        return np.linspace(-self.fov / 2.0, self.fov / 2.0, self.beams)

    def sensor_poses(self, poses: ArrayLike) -> np.ndarray:
        """World poses of the sensor for robot poses.

        Parameters
        ----------
        poses : array_like, shape (..., 3)
            Robot poses (x [m], y [m], θ [rad]).

        Returns
        -------
        numpy.ndarray, shape (..., 3)
        """
        from wheelbase.geometry import compose

        return compose(as_float_array("poses", poses, 3), np.asarray(self.mount))

    def scan(
        self,
        grid: OccupancyGrid | PolygonWorld,
        poses: ArrayLike,
        rng: np.random.Generator | int | None = None,
        *,
        noise: bool = True,
        method: str = "fast",
    ) -> np.ndarray:
        """Simulated scans from one robot pose or a batch.

        Parameters
        ----------
        grid : OccupancyGrid or PolygonWorld
            The map (a polygon world: its raster, see :func:`~wheelbase.sensors.scan_rays`).
        poses : array_like, shape (3,) or (N, 3)
            Robot poses (x [m], y [m], θ [rad]).
        rng : numpy.random.Generator, int or None
            Randomness of the noise (a generator, a seed, or None for fresh entropy).
        noise : bool
            Apply the beam model; False gives the true ranges.
        method : {"fast", "exact", "numpy"}
            Ray-casting method (:mod:`wheelbase.sensors.raycast`).

        Returns
        -------
        numpy.ndarray, shape (beams,) or (N, beams)
            Ranges [m] in ``[min_range, max_range]``, NaN below ``min_range``.
        """
        poses = as_float_array("poses", poses, 3, min_ndim=1, max_ndim=2)
        sensor = self.sensor_poses(poses.reshape(-1, 3))
        ranges = scan_rays(
            grid, sensor[:, :2], sensor[:, 2], self.beam_angles, self.max_range, method
        )
        ranges = self.readings(ranges, rng, noise=noise)
        return ranges.reshape(*poses.shape[:-1], self.beams)

    def readings(
        self, true_ranges: ArrayLike, rng: np.random.Generator | int | None = None, *,
        noise: bool = True,
    ) -> np.ndarray:  # fmt: skip
        """What the lidar reports for true ranges: the beam model's noise, then NaN in the
        blind zone below ``min_range`` (the second half of :meth:`scan`).

        Parameters
        ----------
        true_ranges : array_like, shape (..., beams)
            Ray-cast ranges [m] in ``[0, max_range]``.
        rng : numpy.random.Generator, int or None
            Randomness of the noise.
        noise : bool
            Apply the beam model; False keeps the true ranges.

        Returns
        -------
        numpy.ndarray
            Readings [m], of the shape of ``true_ranges`` (a new array).
        """
        ranges = np.array(true_ranges, dtype=np.float64)
        if noise and (self.range_std > 0.0 or self.beam_model.z_hit < 1.0):
            ranges = self.beam_model.sample(ranges, self.range_std, self.max_range, as_rng(rng))
        if self.min_range > 0.0:
            ranges[ranges < self.min_range] = np.nan
        return ranges

    def endpoints(self, poses: ArrayLike, ranges: ArrayLike) -> np.ndarray:
        """World points ``(x, y)`` [m] at the end of each beam.

        Parameters
        ----------
        poses : array_like, shape (..., 3)
            Robot poses.
        ranges : array_like, shape (..., beams)
            Ranges [m] of those poses' scans (NaN stays NaN).

        Returns
        -------
        numpy.ndarray, shape (..., beams, 2)
        """
        sensor = self.sensor_poses(poses)
        ranges = np.asarray(ranges, dtype=np.float64)
        angle = sensor[..., 2, None] + self.beam_angles
        return np.stack(
            [
                sensor[..., 0, None] + ranges * np.cos(angle),
                sensor[..., 1, None] + ranges * np.sin(angle),
            ],
            -1,
        )
