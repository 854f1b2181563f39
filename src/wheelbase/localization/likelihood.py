"""Measurement likelihoods of the particle filter: Nav2's likelihood field, landmarks.

Likelihood field (Thrun, Burgard and Fox §6.4, as Nav2's ``likelihood_field`` model computes it)
    For a particle, each used beam's end point is looked up in a distance field: d is the
    distance [m] from the end point to the surface of the obstacles (the boundary between free
    and occupied cells), capped at ``max_dist`` (and ``max_dist`` off the map), and

        p_z = z_hit·exp(−d²/(2σ_hit²)) + z_rand/max_range.

    Two departures from Nav2, both found as biases of the closed-loop estimate on the 0.1 m
    warehouse map (``benchmarks/localization_loop.py``):

    - Nav2 tabulates d once per map cell, from the cell's centre. A true return lies on the
      boundary of an occupied cell, which the look-up assigns to the free cell below or left of
      a wall (d = half a cell) but to the occupied cell above or right of one (d = 0): the
      particles were pulled down and left, 2–3 cm. Here the field is tabulated on cells
      ``supersample`` times finer (4 by default, where the map stays under
      :data:`MAX_FIELD_CELLS` fine cells), from each fine cell's centre: the same on every side
      of a wall, and within an eighth of a map cell of the exact distance.
    - The book and Nav2 take d = 0 anywhere inside an obstacle, so a reading that is too long
      costs nothing while one that is too short pushes the particles away from the wall (a
      further centimetre of bias away from the nearest racks). Here d inside an obstacle is
      the distance to its surface too: a return lies on the surface.

    The beams are combined as the book's product Π p_z, or as Nav2's 1 + Σ p_z³ (the sum of
    cubes keeps one unmodelled obstacle from ruling out the right pose). Readings that are
    NaN, negative, or at or beyond ``max_range`` are skipped.

Landmarks
    Each range–bearing measurement of a known landmark multiplies the weight by
    z_hit·N(r − r̂; σ_r)·N(φ − φ̂; σ_φ) + z_rand/(2π·max_range): a Gaussian with a uniform floor
    that bounds what one wrong measurement can do.

Both return log-likelihoods per particle.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numba
import numpy as np
from scipy import ndimage

from wheelbase.geometry import wrap_angle
from wheelbase.planning import OccupancyGrid

__all__ = [
    "MAX_FIELD_CELLS",
    "LikelihoodField",
    "landmark_log_likelihood",
    "likelihood_field",
    "scan_log_likelihood",
    "surface_distance",
]

_TINY = float(np.finfo(np.float64).tiny)  # smallest normal float64, ~2.2e-308

MAX_FIELD_CELLS = 1 << 22
"""Most fine cells of a likelihood field (about 4 million: 32 MB as float64); the default
``supersample`` is the largest of 4, 3, 2, 1 that stays under it."""


@dataclass(frozen=True)
class LikelihoodField:
    """A likelihood field tabulated on fine cells (module docstring).

    Attributes
    ----------
    table : numpy.ndarray, shape (rows·k, cols·k)
        p_z (or log p_z) at the centre of each fine cell; row 0 is the map's bottom edge.
    resolution : float
        Side of a fine cell [m]: the map's resolution / k.
    """

    table: np.ndarray
    resolution: float

    def log(self) -> LikelihoodField:
        """The same field holding log p_z (for the product of the beams); p_z is floored at the
        smallest normal float, so that with ``z_rand = 0`` a far cell's underflowed Gaussian
        gives a very unlikely particle (log ≈ −708), not −inf and then NaN weights."""
        return LikelihoodField(np.log(np.maximum(self.table, _TINY)), self.resolution)


def surface_distance(grid: OccupancyGrid, supersample: int = 1) -> np.ndarray:
    """Distance [m] from the centre of each fine cell to the surface of the obstacles.

    The map is split into cells ``supersample`` times finer; each fine cell's distance is the
    Euclidean distance between its centre and the nearest centre of a fine cell of the other
    kind (free or occupied), less half a fine cell: exactly the distance to the boundary for a
    wall along the grid, on either side of it. Infinite where the map holds only one kind.

    Parameters
    ----------
    grid : OccupancyGrid
        The map.
    supersample : int
        Fine cells per map cell along each axis, >= 1.

    Returns
    -------
    numpy.ndarray, shape (rows·supersample, cols·supersample)
    """
    occupied = grid.occupied
    if supersample > 1:
        occupied = np.repeat(np.repeat(occupied, supersample, 0), supersample, 1)
    if occupied.all() or not occupied.any():
        return np.full(occupied.shape, np.inf)
    outside = ndimage.distance_transform_edt(~occupied)  # free cells: to the nearest occupied
    inside = ndimage.distance_transform_edt(occupied)  # occupied cells: to the nearest free
    cells = np.where(occupied, inside, outside) - 0.5
    return cells * (grid.resolution / supersample)


def likelihood_field(
    grid: OccupancyGrid, z_hit: float, z_rand: float, sigma_hit: float, max_dist: float,
    max_range: float, supersample: int | None = None,
) -> LikelihoodField:  # fmt: skip
    """The likelihood field of ``grid`` (module docstring).

    Parameters
    ----------
    grid : OccupancyGrid
        The map.
    z_hit : float
        Weight of the Gaussian.
    z_rand : float
        Weight of random readings.
    sigma_hit : float
        σ_hit [m].
    max_dist : float
        Cap on the distance [m].
    max_range : float
        Largest range of the lidar [m].
    supersample : int, optional
        Fine cells per map cell along each axis (default: up to 4, see
        :data:`MAX_FIELD_CELLS`).

    Returns
    -------
    LikelihoodField
    """
    if supersample is None:
        cells = grid.occupied.size
        supersample = next((k for k in (4, 3, 2) if cells * k * k <= MAX_FIELD_CELLS), 1)
    d = np.minimum(surface_distance(grid, supersample), max_dist)
    table = z_hit * np.exp(-(d * d) / (2.0 * sigma_hit * sigma_hit)) + z_rand / max_range
    return LikelihoodField(np.ascontiguousarray(table), grid.resolution / supersample)


@numba.njit(cache=True)
def _field_kernel(table, res, x0, y0, outside, particles, mount, bx, by, product, out):
    """Serial on purpose: 120,000 look-ups take 0.5 ms, less than waking threads costs on a
    busy machine (15 ms measured with two threads at a load of 6)."""
    rows, cols = table.shape
    inv = 1.0 / res
    for p in range(particles.shape[0]):
        c = math.cos(particles[p, 2])
        s = math.sin(particles[p, 2])
        sx = particles[p, 0] + c * mount[0] - s * mount[1]
        sy = particles[p, 1] + s * mount[0] + c * mount[1]
        sc = math.cos(particles[p, 2] + mount[2])
        ss = math.sin(particles[p, 2] + mount[2])
        total = 0.0 if product else 1.0
        for b in range(bx.shape[0]):
            ex = (sx + sc * bx[b] - ss * by[b] - x0) * inv
            ey = (sy + ss * bx[b] + sc * by[b] - y0) * inv
            pz = table[int(ey), int(ex)] if 0.0 <= ex < cols and 0.0 <= ey < rows else outside
            if product:
                total += pz  # the table holds log p_z
            else:
                total += pz * pz * pz
        out[p] = total if product else math.log(total)


def scan_log_likelihood(
    field: LikelihoodField,
    grid: OccupancyGrid,
    particles: np.ndarray,
    mount: np.ndarray,
    ranges: np.ndarray,
    angles: np.ndarray,
    outside: float,
    product: bool = False,
) -> np.ndarray:
    """log p of a scan for each particle (module docstring).

    Parameters
    ----------
    field : LikelihoodField
        :func:`likelihood_field` of ``grid`` (its :meth:`~LikelihoodField.log` when
        ``product``).
    grid : OccupancyGrid
        The map (its origin).
    particles : numpy.ndarray, shape (P, 3)
        Particle poses.
    mount : numpy.ndarray, shape (3,)
        Lidar pose in the body frame.
    ranges : numpy.ndarray, shape (B,)
        Used readings [m] (already subsampled and filtered).
    angles : numpy.ndarray, shape (B,)
        Their beam angles [rad] in the sensor frame.
    outside : float
        p_z of an end point off the map (its logarithm when ``product``).
    product : bool
        Combine the beams as the book's product Π p_z instead of Nav2's 1 + Σ p_z³.

    Returns
    -------
    numpy.ndarray, shape (P,)
    """
    out = np.empty(particles.shape[0])
    _field_kernel(
        field.table,
        field.resolution,
        grid.origin[0],
        grid.origin[1],
        outside,
        np.ascontiguousarray(particles),
        np.ascontiguousarray(mount, dtype=np.float64),
        ranges * np.cos(angles),
        ranges * np.sin(angles),
        product,
        out,
    )
    return out


def landmark_log_likelihood(
    particles: np.ndarray,
    landmarks: np.ndarray,
    z: np.ndarray,
    range_std: float,
    bearing_std: float,
    z_hit: float,
    z_rand: float,
    max_range: float,
) -> np.ndarray:
    """log p of landmark measurements for each particle (module docstring).

    Parameters
    ----------
    particles : numpy.ndarray, shape (P, 3)
        Particle poses.
    landmarks : numpy.ndarray, shape (M, 2)
        Positions [m] of the measured landmarks.
    z : numpy.ndarray, shape (M, 2)
        (range [m], bearing [rad]) measured.
    range_std, bearing_std : float
        σ_r [m] and σ_φ [rad].
    z_hit, z_rand : float
        Weights of the Gaussian and of the uniform floor.
    max_range : float
        Range [m] over which the floor is spread.

    Returns
    -------
    numpy.ndarray, shape (P,)
    """
    dx = landmarks[None, :, 0] - particles[:, None, 0]
    dy = landmarks[None, :, 1] - particles[:, None, 1]
    er = (z[None, :, 0] - np.hypot(dx, dy)) / range_std
    eb = wrap_angle(z[None, :, 1] - np.arctan2(dy, dx) + particles[:, None, 2]) / bearing_std
    log_gauss = -0.5 * (er * er + eb * eb) - math.log(2.0 * math.pi * range_std * bearing_std)
    each = math.log(z_hit) + log_gauss  # z_hit > 0 (checked by the filter)
    if z_rand > 0.0:
        each = np.logaddexp(each, math.log(z_rand / (2.0 * math.pi * max_range)))
    return each.sum(axis=1)
