"""How a real differential drive differs from the model its odometry assumes.

Systematic errors (Borenstein & Feng 1996, "UMBmark"):

- unequal wheel diameters, E_d = D_R/D_L, with the mean diameter kept at its nominal value
  D_a: D_L = 2·D_a/(E_d + 1), D_R = 2·D_a/(1/E_d + 1);
- a wrong track, E_b = b_actual/b_nominal.

Random errors: the encoder's own (missed/extra ticks, noise: :class:`~wheelbase.odometry.Encoder`)
and wheel slip: over each step each wheel moves the ground by (1 − s)·r·Δφ with s drawn from a
zero-mean Gaussian of standard deviation ``slip_std`` (independent per wheel and per step).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from wheelbase._validate import as_float_array, nonnegative, positive
from wheelbase.errors import ConfigError

__all__ = ["OdometryErrors"]


@dataclass(frozen=True)
class OdometryErrors:
    """Systematic and random differences between a real robot and its nominal model.

    Parameters
    ----------
    diameter_ratio : float
        E_d = D_R/D_L [–], > 0 (1 = equal wheels).
    track_ratio : float
        E_b = b_actual/b_nominal [–], > 0 (1 = the nominal track is right).
    slip_std : float
        Standard deviation [–] of the relative wheel slip per step, in [0, 0.5).

    Examples
    --------
    >>> errors = OdometryErrors(diameter_ratio=1.005, track_ratio=1.02)
    >>> [round(r, 6) for r in errors.wheel_radii(0.05)]
    [0.049875, 0.050125]
    """

    diameter_ratio: float = 1.0
    track_ratio: float = 1.0
    slip_std: float = 0.0

    def __post_init__(self) -> None:
        object.__setattr__(self, "diameter_ratio", positive("diameter_ratio", self.diameter_ratio))
        object.__setattr__(self, "track_ratio", positive("track_ratio", self.track_ratio))
        slip = nonnegative("slip_std", self.slip_std)
        if slip >= 0.5:
            raise ConfigError(f"slip_std must be in [0, 0.5) (got {slip:g})")
        object.__setattr__(self, "slip_std", slip)

    @property
    def scale_factors(self) -> tuple[float, float]:
        """True wheel diameters over the nominal one, (c_L, c_R) = (2/(E_d+1), 2/(1/E_d+1))."""
        ed = self.diameter_ratio
        return 2.0 / (ed + 1.0), 2.0 / (1.0 / ed + 1.0)

    def wheel_radii(self, nominal_radius: float) -> tuple[float, float]:
        """True (left, right) wheel radii [m] for a nominal radius [m] (mean diameter kept)."""
        radius = positive("nominal_radius", nominal_radius, "m")
        left, right = self.scale_factors
        return radius * left, radius * right

    def true_half_track(self, nominal_half_track: float) -> float:
        """True half track [m] = E_b × the nominal one [m]."""
        return self.track_ratio * positive("nominal_half_track", nominal_half_track, "m")

    def ground_increments(
        self,
        wheel_radius: float,
        half_track: float,
        wheel_angles: ArrayLike,
        rng: np.random.Generator | None = None,
    ) -> tuple[np.ndarray, np.ndarray]:
        """True axle distance D_C [m] and heading change φ [rad] for wheel rotations.

        Parameters
        ----------
        wheel_radius : float
            Nominal wheel radius [m].
        half_track : float
            Nominal half track [m].
        wheel_angles : array_like, shape (..., 2)
            Wheel rotations (left, right) [rad] during each step.
        rng : numpy.random.Generator, optional
            Source of the slip draws (needed only when ``slip_std > 0``; default: unseeded).

        Returns
        -------
        tuple of numpy.ndarray
            (D_C, φ) of shape ``(...)``: document 003 eqs. 1–2 with the true radii and track.
        """
        angles = as_float_array("wheel_angles", wheel_angles, 2)
        left_r, right_r = self.wheel_radii(wheel_radius)
        distance = angles * np.array([left_r, right_r])
        if self.slip_std > 0:
            generator = rng if rng is not None else np.random.default_rng()
            distance = distance * (1.0 - generator.normal(0.0, self.slip_std, distance.shape))
        left, right = distance[..., 0], distance[..., 1]
        return 0.5 * (left + right), (right - left) / (2.0 * self.true_half_track(half_track))
