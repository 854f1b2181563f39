"""Tyre–road friction against slip: Pacejka's magic formula fitted to a peak and a sliding value.

The friction coefficient a wheel develops on a hard surface grows with the slip, peaks, and
falls to its sliding value when the wheel spins or locks. Pacejka's magic formula (Pacejka,
*Tyre and Vehicle Dynamics*, 3rd ed. 2012, §4.3, eq. 4.49) with the curvature factor E = 0,

    μ(σ) = D·sin(C·atan(B·σ)),    σ ≥ 0 the magnitude of the slip,

has three coefficients with a meaning: D is the peak μ_p, C the shape factor that sets how far
the curve falls after the peak, B the stiffness factor that sets where the peak lies. Surface
tables give the peak and the sliding (locked-wheel) coefficients (e.g. Wong, *Theory of Ground
Vehicles*, 4th ed. 2008, Table 1.3); :class:`FrictionCurve` solves B and C so that the curve
peaks at μ_p at the slip σ_p and passes through the sliding value μ_s at σ = 1 (full spin or
lock):

    peak:     C·atan(B·σ_p) = π/2          ⇒  B = tan(π/(2C))/σ_p,
    sliding:  D·sin(C·atan(B)) = μ_s       ⇒  one equation in C ∈ [1, 2), solved by bisection.

The slope at zero slip, the longitudinal slip stiffness per newton of load, is B·C·D.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from wheelbase._validate import finite
from wheelbase.errors import ConfigError

__all__ = ["MAX_FRICTION", "FrictionCurve"]

MAX_FRICTION = 3.0
"""Largest friction coefficient accepted (racing slicks on a dry track reach about 1.7)."""


@dataclass(frozen=True)
class FrictionCurve:
    """Friction coefficient against slip: the magic formula through a peak and a sliding value.

    Parameters
    ----------
    peak : float
        Peak friction coefficient μ_p (dimensionless), 0 < μ_p ≤ :data:`MAX_FRICTION`.
    sliding : float
        Sliding (full-slip) coefficient μ_s, 0 < μ_s ≤ μ_p. Equal to the peak: a curve that
        rises monotonically to μ_p (C = 1, with B·σ_p = 3: 95 % of the peak at σ_p).
    peak_slip : float
        Slip σ_p at the peak, 0 < σ_p < 1.

    Attributes
    ----------
    stiffness_factor, shape_factor : float
        Pacejka's B and C (D is ``peak``).

    Raises
    ------
    ConfigError
        Values outside those ranges, or a sliding value too low for the peak slip: with E = 0
        the curve at σ = 1 cannot fall below μ_p·2σ_p/(1 + σ_p²).

    Examples
    --------
    >>> curve = FrictionCurve(peak=0.85, sliding=0.75, peak_slip=0.16)
    >>> round(float(curve.mu(0.16)), 6), round(float(curve.mu(1.0)), 6)
    (0.85, 0.75)
    """

    peak: float
    sliding: float
    peak_slip: float

    def __post_init__(self) -> None:
        peak = finite("peak friction", self.peak)
        if not 0.0 < peak <= MAX_FRICTION:
            raise ConfigError(
                f"peak friction must be in (0, {MAX_FRICTION:g}] (dimensionless) (got {peak:g})"
            )
        sliding = finite("sliding friction", self.sliding)
        if not 0.0 < sliding <= peak:
            raise ConfigError(f"sliding friction must be in (0, peak = {peak:g}] (got {sliding:g})")
        slip = finite("peak_slip", self.peak_slip)
        if not 0.0 < slip < 1.0:
            raise ConfigError(f"peak_slip must be in (0, 1) (got {slip:g})")
        object.__setattr__(self, "peak", peak)
        object.__setattr__(self, "sliding", sliding)
        object.__setattr__(self, "peak_slip", slip)
        b, c = _fit(peak, sliding, slip)
        object.__setattr__(self, "stiffness_factor", b)
        object.__setattr__(self, "shape_factor", c)

    @property
    def coefficients(self) -> tuple[float, float, float]:
        """(B, C, D) of the magic formula."""
        return self.stiffness_factor, self.shape_factor, self.peak  # type: ignore[attr-defined]

    @property
    def slip_stiffness(self) -> float:
        """dμ/dσ at σ = 0, B·C·D (per unit slip)."""
        b, c, d = self.coefficients
        return b * c * d

    def mu(self, slip: ArrayLike) -> np.ndarray:
        """Friction coefficient μ(|σ|) for slips of any sign (the curve is odd in σ).

        Parameters
        ----------
        slip : array_like
            Slip σ (dimensionless); the magnitude is used and the sign kept.
        """
        b, c, d = self.coefficients
        s = np.asarray(slip, dtype=np.float64)
        return np.sign(s) * d * np.sin(c * np.arctan(b * np.abs(s)))


def _fit(peak: float, sliding: float, slip: float) -> tuple[float, float]:
    """(B, C) of the curve through (σ_p, μ_p) at its peak and (1, μ_s)."""
    ratio = sliding / peak
    if ratio >= 1.0 - 1e-12:
        return 3.0 / slip, 1.0
    lowest = 2.0 * slip / (1.0 + slip * slip)  # μ(1)/μ_p as C → 2
    if ratio <= lowest + 1e-9:
        raise ConfigError(
            f"sliding friction {sliding:g} is too low for peak {peak:g} at peak_slip {slip:g}: "
            f"the magic formula reaches at least {peak * lowest:.4g} at full slip; raise "
            "sliding or lower peak_slip"
        )

    def excess(c: float) -> float:  # μ(1)/μ_p − ratio, decreasing in C on [1, 2)
        b = math.tan(math.pi / (2.0 * c)) / slip
        return math.sin(c * math.atan(b)) - ratio

    low, high = 1.0 + 1e-12, 2.0 - 1e-12
    for _ in range(200):  # bisection to machine precision
        mid = 0.5 * (low + high)
        if excess(mid) > 0.0:
            low = mid
        else:
            high = mid
        if high - low < 1e-15:
            break
    c = 0.5 * (low + high)
    return math.tan(math.pi / (2.0 * c)) / slip, c
