"""Nav2's cell costs and its inflation formula.

A costmap cell holds a uint8 cost (``nav2_costmap_2d/cost_values.hpp``): 0 free, 253 inscribed
(the robot's inscribed circle centred there touches an obstacle), 254 lethal (an obstacle),
255 unknown. Around each lethal cell the inflation layer writes, at distance d [m] between
cell centres,

* 254 at d = 0, 253 for 0 < d <= r_inscribed,
* ⌊252 · exp(−k · (d − r_inscribed))⌋ for r_inscribed < d <= ``inflation_radius``
  (Nav2's ``InflationLayer::computeCost``; the cast to unsigned char truncates),
* nothing beyond ``inflation_radius``,

and a cell keeps the largest cost any obstacle gives it. Distances compare to the radii to
rounding (1e-9 cells). Nav2 rounds ``inflation_radius`` up to whole cells
(``cellDistance``) and propagates distances by a brushfire from the obstacles; here the
distance is the exact Euclidean one to the nearest lethal cell and the radius is in metres.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike

__all__ = ["FREE", "INSCRIBED", "LETHAL", "UNKNOWN", "inflation_cost", "inflation_table"]

FREE = 0
"""Cost of a free cell."""
INSCRIBED = 253
"""Cost of a cell within the robot's inscribed radius of an obstacle."""
LETHAL = 254
"""Cost of an obstacle cell."""
UNKNOWN = 255
"""Cost of a cell nothing is known about (``track_unknown``)."""

_ROUNDING = 1e-9  # cells: distances this close to a radius count as on it


def inflation_cost(
    distance: ArrayLike,
    inscribed_radius: float,
    cost_scaling_factor: float,
    inflation_radius: float,
    resolution: float = 1.0,
) -> np.ndarray:
    """Nav2's inflation cost at distances from an obstacle (module docstring).

    Parameters
    ----------
    distance : array_like
        Distance d [m] from the cell centre to the obstacle cell's centre, >= 0.
    inscribed_radius : float
        The robot's inscribed radius r_inscribed [m].
    cost_scaling_factor : float
        Decay rate k [1/m].
    inflation_radius : float
        Largest distance [m] that gets a cost.
    resolution : float
        Cell side [m], the unit of the rounding tolerance.

    Returns
    -------
    numpy.ndarray
        uint8 costs of the shape of ``distance``.

    Examples
    --------
    >>> inflation_cost([0.0, 0.1, 0.3, 0.6], 0.2, 10.0, 0.55).tolist()
    [254, 253, 92, 0]
    """
    d = np.asarray(distance, dtype=np.float64)
    tol = _ROUNDING * resolution
    beyond = np.maximum(d - inscribed_radius, 0.0)  # inside, the cost is 253 anyway
    decay = np.floor((INSCRIBED - 1) * np.exp(-cost_scaling_factor * beyond))
    cost = np.where(d <= inflation_radius + tol, np.minimum(decay, INSCRIBED - 1), FREE)
    cost = np.where(d <= inscribed_radius + tol, INSCRIBED, cost)
    return np.where(d <= tol, LETHAL, cost).astype(np.uint8)


def inflation_table(
    resolution: float,
    inscribed_radius: float,
    cost_scaling_factor: float,
    inflation_radius: float,
    max_reach: int | None = None,
) -> np.ndarray:
    """Costs by squared distance in cells: entry ``s`` is :func:`inflation_cost` at
    ``sqrt(s) · resolution``, for ``s`` up to the first squared distance beyond the radius.

    Parameters
    ----------
    resolution : float
        Cell side [m].
    inscribed_radius : float
        The robot's inscribed radius [m].
    cost_scaling_factor : float
        Decay rate k [1/m].
    inflation_radius : float
        Largest distance [m] that gets a cost.
    max_reach : int or None
        Cells beyond which no distance occurs (e.g. the map's diagonal): R is capped there.

    Returns
    -------
    numpy.ndarray
        uint8, length ``(R + 1)²`` with ``R = ⌊inflation_radius / resolution⌋`` cells, so that
        every squared distance at or beyond the table's length costs 0.
    """
    reach = math.floor(min(inflation_radius / resolution + _ROUNDING, 1e18))
    if max_reach is not None:
        reach = min(reach, max_reach)
    squares = np.arange((reach + 1) ** 2, dtype=np.float64)
    return inflation_cost(
        np.sqrt(squares) * resolution, inscribed_radius, cost_scaling_factor, inflation_radius,
        resolution,
    )  # fmt: skip
