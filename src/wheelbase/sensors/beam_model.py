"""The beam model of a range finder (Thrun, Burgard and Fox, *Probabilistic Robotics*, 2005, §6.3).

A reading z of a beam whose true range is z* (the distance to the first obstacle, or z_max when
nothing is in range) comes from one of four causes, with probabilities that add up to 1:

=========  ==========================================================================
``hit``    the obstacle, seen with Gaussian noise: N(z*, σ_hit²) truncated to [0, z_max]
           (eq. 6.4–6.6);
``short``  an unexpected object in front of it: exponential with rate λ_short truncated to
           [0, z*] (eq. 6.7–6.9);
``max``    a missed return: exactly z_max (eq. 6.10);
``rand``   an unexplained reading: uniform on [0, z_max) (eq. 6.11).
=========  ==========================================================================

The weights carry the names Nav2 gives them (``z_hit``, ``z_short``, ``z_max``, ``z_rand``); the
largest range itself is called ``max_range``. The density of eq. 6.12 is :meth:`BeamModel.pdf`
(its ``max`` term is a point mass of probability ``z_max`` at ``max_range``, left out), and
:meth:`BeamModel.sample` draws readings from the mixture. One
departure from the book, for simulation: a beam with nothing in range (z* >= z_max) cannot be
a hit, so its ``hit`` readings are z_max (no return) rather than Gaussian readings around z_max.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike
from scipy import special

from wheelbase._validate import as_float_array, nonnegative, positive
from wheelbase.errors import ConfigError

__all__ = ["BeamModel"]


@dataclass(frozen=True)
class BeamModel:
    """Mixture weights and parameters of the beam model (module docstring).

    Parameters
    ----------
    z_hit, z_short, z_max, z_rand : float
        Probabilities of the four causes, >= 0, adding up to 1 (within 1e-9). The default is a
        pure Gaussian sensor.
    lambda_short : float
        Rate λ_short of the exponential of unexpected objects [1/m], > 0.

    Examples
    --------
    >>> BeamModel(z_hit=0.8, z_short=0.1, z_max=0.05, z_rand=0.05).z_hit
    0.8
    """

    z_hit: float = 1.0
    z_short: float = 0.0
    z_max: float = 0.0
    z_rand: float = 0.0
    lambda_short: float = 1.0

    def __post_init__(self) -> None:
        names = ("z_hit", "z_short", "z_max", "z_rand")
        weights = [nonnegative(name, getattr(self, name)) for name in names]
        if abs(sum(weights) - 1.0) > 1e-9:
            raise ConfigError(
                f"z_hit + z_short + z_max + z_rand must be 1 (got {sum(weights):g} from "
                f"{', '.join(f'{w:g}' for w in weights)})"
            )
        positive("lambda_short", self.lambda_short, "1/m")

    @property
    def weights(self) -> np.ndarray:
        """``(z_hit, z_short, z_max, z_rand)``."""
        return np.array([self.z_hit, self.z_short, self.z_max, self.z_rand])

    def sample(
        self,
        true_range: ArrayLike,
        sigma_hit: float,
        max_range: float,
        rng: np.random.Generator,
    ) -> np.ndarray:
        """Draw one reading per beam.

        Parameters
        ----------
        true_range : array_like
            True ranges z* [m] in ``[0, max_range]``.
        sigma_hit : float
            Standard deviation σ_hit of a hit [m], >= 0 (0: hits are exact).
        max_range : float
            z_max [m], > 0.
        rng : numpy.random.Generator
            Source of randomness.

        Returns
        -------
        numpy.ndarray
            Readings [m] in ``[0, max_range]``, of the shape of ``true_range``.
        """
        z_true = np.minimum(as_float_array("true_range", true_range), max_range)
        sigma = nonnegative("sigma_hit", sigma_hit, "m")
        limit = positive("max_range", max_range, "m")
        cause = rng.choice(4, size=z_true.shape, p=self.weights)
        u = rng.random(z_true.shape)
        out = np.empty_like(z_true)
        hit = cause == 0
        zt = z_true[hit]
        if sigma > 0.0:
            # inverse-CDF draw of N(z*, σ²) truncated to [0, z_max]
            lo = special.ndtr(-zt / sigma)
            hi = special.ndtr((limit - zt) / sigma)
            z = zt + sigma * special.ndtri(lo + u[hit] * (hi - lo))
            out[hit] = np.clip(z, 0.0, limit)
        else:
            out[hit] = zt
        out[hit & (z_true >= limit)] = limit  # nothing to hit: no return
        short = cause == 1
        lam = self.lambda_short
        # inverse CDF of the exponential truncated to [0, z*]
        out[short] = -np.log1p(-u[short] * -np.expm1(-lam * z_true[short])) / lam
        out[cause == 2] = limit
        rand = cause == 3
        out[rand] = u[rand] * limit
        return out

    def pdf(
        self, reading: ArrayLike, true_range: ArrayLike, sigma_hit: float, max_range: float
    ) -> np.ndarray:
        """Density [1/m] of the continuous part of eq. 6.12 (the ``max`` point mass excluded).

        Parameters
        ----------
        reading : array_like
            Readings z [m].
        true_range : array_like
            True ranges z* [m] in ``(0, max_range)``; broadcast against ``reading``.
        sigma_hit : float
            σ_hit [m], > 0.
        max_range : float
            z_max [m], > 0.

        Returns
        -------
        numpy.ndarray
            p(z | z*) over ``0 <= z < z_max``, 0 outside.
        """
        z = as_float_array("reading", reading)
        zt = as_float_array("true_range", true_range)
        sigma = positive("sigma_hit", sigma_hit, "m")
        limit = positive("max_range", max_range, "m")
        inside = (z >= 0.0) & (z < limit)
        norm = special.ndtr((limit - zt) / sigma) - special.ndtr(-zt / sigma)
        gauss = np.exp(-0.5 * ((z - zt) / sigma) ** 2) / (sigma * math.sqrt(2.0 * math.pi))
        p_hit = gauss / norm
        lam = self.lambda_short
        with np.errstate(divide="ignore", invalid="ignore"):
            eta = np.where(zt > 0.0, 1.0 / -np.expm1(-lam * zt), 0.0)
        p_short = np.where(z <= zt, eta * lam * np.exp(-lam * z), 0.0)
        p_rand = 1.0 / limit
        density = self.z_hit * p_hit + self.z_short * p_short + self.z_rand * p_rand
        return np.where(inside, density, 0.0)
