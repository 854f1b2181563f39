"""Deformable soil under a rigid wheel: Bekker sinkage, compaction resistance, Janosi–Hanamoto
thrust (J. Y. Wong, *Theory of Ground Vehicles*, 4th ed., Wiley 2008, ch. 2).

A wheel of radius a and width b loaded by W sinks into soil until the soil's pressure carries it.
Bekker's pressure–sinkage relation

    p = (k_c/b + k_φ)·zⁿ                                                     (Wong eq. 2.36)

integrated over the rim of a rigid wheel (pressure acting vertically, small sinkage) gives the
static sinkage and the compaction resistance, the work of cutting a rut of depth z₀ per metre:

    z₀  = [3W / ((3 − n)(k_c + b·k_φ)·√D)]^(2/(2n+1)),     D = 2a,
    R_c = b·(k_c/b + k_φ)·z₀^(n+1)/(n + 1).                                  (Wong §2.4)

The soil's shear strength follows Mohr–Coulomb, τ_max = c + p·tan φ, and the shear stress a
slipping contact develops grows with the shear displacement j as Janosi and Hanamoto found,

    τ = (c + p·tan φ)·(1 − e^(−j/K)).                                        (Wong eq. 2.56)

Along a contact of length l at slip i the displacement grows as j = i·x, so with the pressure
uniform over the contact area A = b·l the thrust is

    F = (A·c + W·tan φ)·[1 − K/(i·l)·(1 − e^(−i·l/K))],                       (Wong eq. 2.62)

and the drawbar pull DP = F − R_c is what is left to pull with (or to climb, or to accelerate).
The contact of a wheel sunk by z₀ is taken as its rim from the entry angle θ₁ = acos(1 − z₀/a)
to the bottom: l = a·θ₁.

These closed forms are what the dynamic plant evaluates at every step. :func:`wong_reece` is the
fuller model it is checked against: the normal and shear stresses integrated around the rim with
the maximum stress at θ_m = (c₁ + c₂·i)·θ₁ (Wong and Reece, "Prediction of rigid wheel
performance based on the analysis of soil–wheel stresses, part I", J. Terramechanics 4(1), 1967).

Bekker's equations are fitted to wheels of 0.5 m diameter and more and to sinkage below D/6
(Wong §2.4): on a 13 cm robot wheel they are an extrapolation, adequate to say whether a robot
digs in, not to the newton.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from wheelbase._validate import finite
from wheelbase.errors import ConfigError, InputError

__all__ = [
    "SOILS",
    "Soil",
    "WongReeceResult",
    "compaction_resistance",
    "contact_length",
    "drawbar_pull",
    "shear_fraction",
    "sinkage",
    "thrust",
    "wong_reece",
]


@dataclass(frozen=True)
class Soil:
    """Bekker and Mohr–Coulomb parameters of a soil (SI units; Wong's tables give kN and kPa).

    Parameters
    ----------
    n : float
        Sinkage exponent, 0 < n < 2 (Wong's Table 2.3 spans 0.11–1.6).
    k_c : float
        Cohesive modulus of deformation [N/m^(n+1)], ≥ 0.
    k_phi : float
        Frictional modulus of deformation [N/m^(n+2)], > 0.
    cohesion : float
        Cohesion c [Pa], ≥ 0, ≤ 1 MPa.
    friction_angle : float
        Angle of internal shearing resistance φ [rad], 0 ≤ φ < 60°.
    shear_modulus : float
        Shear deformation modulus K [m], 0 < K ≤ 0.5.
    name : str
        What it is and where its values come from.

    Raises
    ------
    ConfigError
        A value outside its physical range, naming it, its unit and the range.
    """

    n: float
    k_c: float
    k_phi: float
    cohesion: float
    friction_angle: float
    shear_modulus: float
    name: str = ""

    def __post_init__(self) -> None:
        checks = (
            ("n", "", 0.0, 2.0, False, False),
            ("k_c", "N/m^(n+1)", 0.0, 1e9, True, True),
            ("k_phi", "N/m^(n+2)", 0.0, 1e10, False, True),
            ("cohesion", "Pa", 0.0, 1e6, True, True),
            ("friction_angle", "rad", 0.0, math.radians(60.0), True, False),
            ("shear_modulus", "m", 0.0, 0.5, False, True),
        )
        for name, unit, low, high, low_in, high_in in checks:
            value = finite(f"soil {name}", getattr(self, name), unit)
            above = value >= low if low_in else value > low
            below = value <= high if high_in else value < high
            if not (above and below):
                where = f"{'[' if low_in else '('}{low:g}, {high:g}{']' if high_in else ')'}"
                raise ConfigError(
                    f"soil {name} must be in {where}{' ' + unit if unit else ''} (got {value:g})"
                )
            object.__setattr__(self, name, value)

    def modulus(self, width: float) -> float:
        """k = k_c/b + k_φ [N/m^(n+2)] for a contact of width ``width`` [m].

        Parameters
        ----------
        width : float
            Contact width b [m], > 0.
        """
        return self.k_c / width + self.k_phi

    @property
    def parameters(self) -> np.ndarray:
        """(n, k_c, k_φ, c, tan φ, K): the layout of the compiled plant."""
        return np.array(
            [self.n, self.k_c, self.k_phi, self.cohesion, math.tan(self.friction_angle),
             self.shear_modulus]
        )  # fmt: skip


def _soil(name, n, k_c, k_phi, c, phi_deg, k_cm) -> Soil:
    """A row of Wong's Table 2.3 in its units (kN/m^(n+1), kN/m^(n+2), kPa, deg) and K [cm]."""
    return Soil(n, k_c * 1e3, k_phi * 1e3, c * 1e3, math.radians(phi_deg), k_cm * 1e-2, name)


SOILS: dict[str, Soil] = {
    "dry_sand": _soil("dry sand (Land Locomotion Lab., 0 % moisture)",
                      1.1, 0.99, 1528.43, 1.04, 28.0, 2.5),
    "sandy_loam": _soil("sandy loam (Land Locomotion Lab., 15 % moisture)",
                        0.7, 5.27, 1515.04, 1.72, 29.0, 1.0),
    "clay": _soil("clayey soil (Thailand, 38 % moisture)", 0.5, 13.19, 692.15, 4.14, 13.0, 0.6),
    "heavy_clay": _soil("heavy clay (WES, 25 % moisture)", 0.13, 12.70, 1555.95, 68.95, 34.0, 0.6),
    "lean_clay": _soil("lean clay (WES, 22 % moisture)", 0.2, 16.43, 1724.69, 68.95, 20.0, 0.6),
    "snow": _soil("snow (U.S.)", 1.6, 4.37, 196.72, 1.03, 19.7, 2.5),
}  # fmt: skip
"""Soils of J. Y. Wong, *Theory of Ground Vehicles* (4th ed., 2008), Table 2.3 (after Bekker):
n, k_c, k_φ, c and φ as printed there (converted to N, Pa, rad). The table gives no shear
deformation modulus K; it is taken from Wong's §2.3 text on typical values (after Bekker): about
2.5 cm for loose sand and snow, 1 cm for firm sandy terrain (here the sandy loam), 0.6 cm for
clay at maximum compaction."""


# --------------------------------------------------------------------------- closed forms
def _check(name: str, value, unit: str = "") -> np.ndarray:
    array = np.asarray(value, dtype=np.float64)
    if not np.all(np.isfinite(array)):
        raise InputError(f"{name} must be finite{' [' + unit + ']' if unit else ''}")
    return array


def _wheel(radius: float, width: float) -> tuple[float, float]:
    a = finite("wheel radius", radius, "m")
    b = finite("wheel width", width, "m")
    if a <= 0 or b <= 0:
        raise ConfigError(f"wheel radius and width must be > 0 m (got {a:g}, {b:g})")
    return a, b


def sinkage(load: ArrayLike, radius: float, width: float, soil: Soil) -> np.ndarray:
    """Static sinkage z₀ [m] of a rigid wheel under a load (Bekker; module docstring).

    Parameters
    ----------
    load : array_like
        Normal load W [N], ≥ 0 (negative loads count as 0: the wheel is lifted).
    radius : float
        Wheel radius a [m].
    width : float
        Wheel width b [m].
    soil : Soil
        The soil.
    """
    a, b = _wheel(radius, width)
    w = np.maximum(_check("load", load, "N"), 0.0)
    n = soil.n
    base = 3.0 * w / ((3.0 - n) * (soil.k_c + b * soil.k_phi) * math.sqrt(2.0 * a))
    return base ** (2.0 / (2.0 * n + 1.0))


def compaction_resistance(load: ArrayLike, radius: float, width: float, soil: Soil) -> np.ndarray:
    """Compaction (motion) resistance R_c [N] of a rigid wheel: b·k·z₀^(n+1)/(n+1).

    Parameters
    ----------
    load : array_like
        Normal load W [N].
    radius, width : float
        Wheel radius a and width b [m].
    soil : Soil
        The soil.
    """
    _a, b = _wheel(radius, width)
    z0 = sinkage(load, radius, width, soil)
    return b * soil.modulus(b) * z0 ** (soil.n + 1.0) / (soil.n + 1.0)


def contact_length(sinkage_m: ArrayLike, radius: float) -> np.ndarray:
    """Length l = a·θ₁ [m] of the rim in the soil, θ₁ = acos(1 − z₀/a) (at most a·π/2: a wheel
    sunk to its axle).

    Parameters
    ----------
    sinkage_m : array_like
        Sinkage z₀ [m].
    radius : float
        Wheel radius a [m].
    """
    a = finite("wheel radius", radius, "m")
    z = np.clip(_check("sinkage", sinkage_m, "m") / a, 0.0, 1.0)
    return a * np.arccos(1.0 - z)


def shear_fraction(x: ArrayLike) -> np.ndarray:
    """1 − (1 − e^(−x))/x: the mean of 1 − e^(−j/K) over a contact whose shear displacement
    grows linearly to j = x·K (x ≥ 0; the series x/2 − x²/6 + x³/24 near 0).

    Parameters
    ----------
    x : array_like
        i·l/K (dimensionless), ≥ 0.
    """
    x = np.abs(np.asarray(x, dtype=np.float64))
    small = x < 1e-4
    safe = np.where(small, 1.0, x)
    out = 1.0 - (-np.expm1(-safe)) / safe
    return np.where(small, x / 2.0 - x * x / 6.0 + x**3 / 24.0, out)


def thrust(load: ArrayLike, slip: ArrayLike, radius: float, width: float, soil: Soil):
    """Janosi–Hanamoto thrust F [N] of a rigid wheel at slip i (module docstring).

    Parameters
    ----------
    load : array_like
        Normal load W [N].
    slip : array_like
        Slip i = 1 − v/(a·ω), 0 ≤ i ≤ 1 (its magnitude is used).
    radius, width : float
        Wheel radius a and width b [m].
    soil : Soil
        The soil.
    """
    _a, b = _wheel(radius, width)
    w = np.maximum(_check("load", load, "N"), 0.0)
    i = np.abs(_check("slip", slip))
    length = contact_length(sinkage(w, radius, width, soil), radius)
    strength = b * length * soil.cohesion + w * math.tan(soil.friction_angle)
    return strength * shear_fraction(i * length / soil.shear_modulus)


def drawbar_pull(load: ArrayLike, slip: ArrayLike, radius: float, width: float, soil: Soil):
    """Drawbar pull DP = F − R_c [N] of a driven rigid wheel at slip i.

    Parameters
    ----------
    load : array_like
        Normal load W [N].
    slip : array_like
        Slip i, 0 ≤ i ≤ 1.
    radius, width : float
        Wheel radius a and width b [m].
    soil : Soil
        The soil.
    """
    return thrust(load, slip, radius, width, soil) - compaction_resistance(
        load, radius, width, soil
    )


# --------------------------------------------------------------------------- Wong–Reece
@dataclass(frozen=True)
class WongReeceResult:
    """A driven rigid wheel in steady state by Wong and Reece's stress integrals.

    Attributes
    ----------
    entry_angle : float
        θ₁ [rad] at which the rim enters the soil.
    sinkage : float
        z₀ = a(1 − cos θ₁) [m].
    drawbar_pull : float
        DP [N], the horizontal force left over.
    torque : float
        Driving torque T [N·m].
    """

    entry_angle: float
    sinkage: float
    drawbar_pull: float
    torque: float


def wong_reece(
    load: float,
    slip: float,
    radius: float,
    width: float,
    soil: Soil,
    *,
    c1: float = 0.43,
    c2: float = 0.32,
) -> WongReeceResult:
    """Steady state of a driven rigid wheel from the stresses around its rim (Wong and Reece 1967).

    Normal stress σ(θ) = k·aⁿ·(cos θ − cos θ₁)ⁿ ahead of the maximum at θ_m = (c₁ + c₂·i)·θ₁,
    mirrored behind it (θ → θ₁ − (θ/θ_m)(θ₁ − θ_m)); shear τ(θ) = (c + σ tan φ)(1 − e^(−j/K))
    with the displacement j(θ) = a[(θ₁ − θ) − (1 − i)(sin θ₁ − sin θ)]. θ₁ solves the vertical
    balance W = a·b∫(σ cos θ + τ sin θ)dθ; then DP = a·b∫(τ cos θ − σ sin θ)dθ and
    T = a²·b∫τ dθ, over 0 ≤ θ ≤ θ₁.

    Parameters
    ----------
    load : float
        Normal load W [N], > 0.
    slip : float
        Slip i, 0 ≤ i ≤ 1.
    radius, width : float
        Wheel radius a and width b [m].
    soil : Soil
        The soil.
    c1, c2 : float
        Position of the maximum stress (Wong and Reece's 0.43 and 0.32 for sand).

    Returns
    -------
    WongReeceResult
    """
    from scipy.integrate import quad
    from scipy.optimize import brentq

    a, b = _wheel(radius, width)
    w = finite("load", load, "N")
    i = finite("slip", slip)
    if w <= 0 or not 0.0 <= i <= 1.0:
        raise InputError(f"load must be > 0 N and slip in [0, 1] (got {w:g}, {i:g})")
    k, n = soil.modulus(b), soil.n
    tan_phi, c, shear_k = math.tan(soil.friction_angle), soil.cohesion, soil.shear_modulus

    def stresses(theta: float, theta1: float) -> tuple[float, float]:
        theta_m = (c1 + c2 * i) * theta1
        angle = theta if theta >= theta_m else theta1 - theta / theta_m * (theta1 - theta_m)
        sigma = k * a**n * max(math.cos(angle) - math.cos(theta1), 0.0) ** n
        j = a * ((theta1 - theta) - (1.0 - i) * (math.sin(theta1) - math.sin(theta)))
        tau = (c + sigma * tan_phi) * (1.0 - math.exp(-max(j, 0.0) / shear_k))
        return sigma, tau

    def integral(function, theta1: float) -> float:
        theta_m = (c1 + c2 * i) * theta1
        return quad(function, 0.0, theta1, points=[theta_m], limit=200)[0]

    def vertical(theta1: float) -> float:
        def f(theta):
            sigma, tau = stresses(theta, theta1)
            return sigma * math.cos(theta) + tau * math.sin(theta)

        return a * b * integral(f, theta1) - w

    top = math.pi / 2
    if vertical(top) < 0:
        raise InputError(f"the soil cannot carry {w:g} N on this wheel: it sinks beyond its axle")
    theta1 = brentq(vertical, 1e-6, top, xtol=1e-13)

    def horizontal(theta):
        sigma, tau = stresses(theta, theta1)
        return tau * math.cos(theta) - sigma * math.sin(theta)

    pull = a * b * integral(horizontal, theta1)
    torque = a * a * b * integral(lambda theta: stresses(theta, theta1)[1], theta1)
    return WongReeceResult(theta1, a * (1.0 - math.cos(theta1)), pull, torque)
