"""Ground surfaces: a friction curve and rolling resistance for hard ground, soil for soft ground.

Every coefficient of :data:`SURFACES` has its source:

============  ======  =======  ========  =======  ==========================================
surface       μ_p     μ_s      σ_p       c_rr     source
============  ======  =======  ========  =======  ==========================================
dry_concrete  0.85    0.75     0.16      0.013    μ: Wong, *Theory of Ground Vehicles* (4th
                                                  ed. 2008), ch. 1, table of average
                                                  coefficients of road adhesion, "asphalt
                                                  and concrete (dry)": peak 0.8–0.9 (mid
                                                  value), sliding 0.75. σ_p: the peak of
                                                  Burckhardt's dry-concrete curve
                                                  (c₁ = 1.1973, c₂ = 25.168, c₃ = 0.5373;
                                                  Kiencke and Nielsen, *Automotive Control
                                                  Systems*, 2005, §7.2): ln(c₁c₂/c₃)/c₂.
                                                  c_rr: Wong ch. 1, rolling-resistance
                                                  coefficients, car tyres on concrete
wet_concrete  0.80    0.70     0.13      0.013    μ: Wong, "concrete (wet)"; σ_p: peak of
                                                  Burckhardt's wet-asphalt curve (0.857,
                                                  33.822, 0.347) — Burckhardt has no wet
                                                  concrete; c_rr as dry
ice           0.10    0.07     0.06      0.013    μ: Wong, "ice"; σ_p: peak of Burckhardt's
                                                  snow curve (0.1946, 94.129, 0.0646), since
                                                  his ice curve (c₃ = 0) has no peak; c_rr as
                                                  on concrete (tyre hysteresis)
grass         0.24    0.20     0.20      0.10     μ_s: Noon, *Engineering Analysis of
                                                  Vehicular Accidents* (1994), "wet, grassy
                                                  field" 0.20; μ_p = μ_s × 0.55/0.45, Wong's
                                                  peak/sliding ratio of a wet earth road;
                                                  σ_p: chosen (no source found); c_rr: the
                                                  low end of Wong's "field" 0.1–0.35
============  ======  =======  ========  =======  ==========================================

The soft surfaces ``dry_sand``, ``sandy_loam`` and ``clay`` are the soils of
:data:`wheelbase.terrain.soil.SOILS` (Wong's Table 2.3): their traction is the soil's shear
(Janosi–Hanamoto) and their resistance its compaction (Bekker), so they have no friction curve
and no separate rolling resistance.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from wheelbase._validate import finite
from wheelbase.errors import ConfigError
from wheelbase.terrain.friction import FrictionCurve
from wheelbase.terrain.soil import SOILS, Soil

__all__ = ["SURFACES", "SURFACE_ROW", "Surface", "burckhardt_peak_slip"]

SURFACE_ROW = 12
"""Length of a surface's row in the compiled plant's table (:meth:`Surface.row`)."""


def burckhardt_peak_slip(c1: float, c2: float, c3: float) -> float:
    """Slip at the peak of Burckhardt's curve μ(s) = c₁(1 − e^(−c₂s)) − c₃s: ln(c₁c₂/c₃)/c₂.

    Parameters
    ----------
    c1, c2, c3 : float
        Burckhardt's coefficients (c₃ > 0: a curve with a peak).
    """
    return math.log(c1 * c2 / c3) / c2


@dataclass(frozen=True)
class Surface:
    """A ground surface: hard (friction curve + rolling resistance) or soft (a soil).

    Parameters
    ----------
    name : str
        Its name.
    friction : FrictionCurve or None
        μ against slip on hard ground (None on soil).
    rolling_resistance : float
        Coefficient c_rr (dimensionless, 0 ≤ c_rr < 1): a moment c_rr·N·a opposing each
        wheel's spin, a force c_rr·N opposing each caster's travel.
    soil : Soil or None
        Bekker/Janosi parameters of soft ground (None on hard ground).

    Raises
    ------
    ConfigError
        Neither or both of ``friction`` and ``soil``, or c_rr out of range.
    """

    name: str
    friction: FrictionCurve | None = None
    rolling_resistance: float = 0.0
    soil: Soil | None = None

    def __post_init__(self) -> None:
        if (self.friction is None) == (self.soil is None):
            raise ConfigError(
                f"surface {self.name!r} needs either a friction curve (hard ground) or a soil "
                "(soft ground)"
            )
        c_rr = finite("rolling_resistance", self.rolling_resistance)
        if not 0.0 <= c_rr < 1.0:
            raise ConfigError(f"rolling_resistance must be in [0, 1) (got {c_rr:g})")
        if self.soil is not None and c_rr != 0.0:
            raise ConfigError(
                f"surface {self.name!r}: a soil's resistance is its compaction; give no "
                "rolling_resistance"
            )
        object.__setattr__(self, "rolling_resistance", c_rr)

    @property
    def is_soil(self) -> bool:
        """Whether this is soft ground."""
        return self.soil is not None

    @property
    def peak_friction(self) -> float:
        """μ_p of hard ground; on soil the largest thrust per load at zero cohesion, tan φ."""
        if self.friction is not None:
            return self.friction.peak
        return math.tan(self.soil.friction_angle)  # type: ignore[union-attr]

    def row(self) -> np.ndarray:
        """The surface as a row of the compiled plant: (kind, B, C, D, c_rr, n, k_c, k_φ, c,
        tan φ, K, 0), kind 0 hard, 1 soil."""
        out = np.zeros(SURFACE_ROW)
        if self.friction is not None:
            out[1:4] = self.friction.coefficients
            out[4] = self.rolling_resistance
        else:
            out[0] = 1.0
            out[5:11] = self.soil.parameters  # type: ignore[union-attr]
        return out

    def with_values(self, **values) -> Surface:
        """A copy with explicit coefficients (``peak``, ``sliding``, ``peak_slip``,
        ``rolling_resistance``; or ``soil``) replaced.

        Parameters
        ----------
        **values
            The coefficients to replace.
        """
        friction = self.friction
        curve_keys = {"peak", "sliding", "peak_slip"}
        if curve_keys & set(values):
            if friction is None:
                raise ConfigError(f"surface {self.name!r} is soil: it has no friction curve")
            friction = FrictionCurve(
                values.pop("peak", friction.peak),
                values.pop("sliding", friction.sliding),
                values.pop("peak_slip", friction.peak_slip),
            )
        soil = values.pop("soil", self.soil)
        c_rr = values.pop("rolling_resistance", self.rolling_resistance)
        if values:
            raise ConfigError(f"unknown surface coefficients: {', '.join(sorted(values))}")
        return Surface(self.name, friction, c_rr, soil)


SURFACES: dict[str, Surface] = {
    "dry_concrete": Surface(
        "dry_concrete",
        FrictionCurve(0.85, 0.75, burckhardt_peak_slip(1.1973, 25.168, 0.5373)),
        0.013,
    ),
    "wet_concrete": Surface(
        "wet_concrete",
        FrictionCurve(0.80, 0.70, burckhardt_peak_slip(0.857, 33.822, 0.347)),
        0.013,
    ),
    "ice": Surface(
        "ice", FrictionCurve(0.10, 0.07, burckhardt_peak_slip(0.1946, 94.129, 0.0646)), 0.013
    ),
    "grass": Surface("grass", FrictionCurve(0.24, 0.20, 0.20), 0.10),
    "dry_sand": Surface("dry_sand", soil=SOILS["dry_sand"]),
    "sandy_loam": Surface("sandy_loam", soil=SOILS["sandy_loam"]),
    "clay": Surface("clay", soil=SOILS["clay"]),
}
"""The named surfaces (module docstring for every source)."""
