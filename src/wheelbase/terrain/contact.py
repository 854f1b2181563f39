"""Where a differential drive touches the ground, and how its weight is shared among the contacts.

The two drive wheels sit on the axle through the centroid B at (0, ±d); casters carry the rest.
With more than three contacts the normal loads are statically indeterminate; they are taken as
those of a rigid body on springs of stiffness k_i at the contacts (a rigid plate on a compliant
floor: every contact compresses by a plane's height, so N_i = k_i·(λ₀ + λ₁x_i + λ₂y_i)), which
is the equal-compliance solution of the three equilibrium equations

    Σ N_i = W_n,    Σ N_i·x_i = W_n·x_c − h·T_x,    Σ N_i·y_i = W_n·y_c − h·T_y,

W_n = m·g·cos α the weight normal to the ground, (x_c, y_c) the CG and h its height, T the
net tangential force of the ground on the robot (the body frame), which equals
m·a_CG − m·g_t. Accelerating forward (T_x > 0) unloads the front contacts; turning left
(T_y > 0) unloads the left wheel: load transfer. A negative load (a contact lifting) is set
to 0.

The drive wheels' stiffness is set by ``drive_load_share``: the share of the weight they carry
at rest when the CG is at B and the casters are placed symmetrically.
"""

from __future__ import annotations

from dataclasses import dataclass

import numba
import numpy as np
from numpy.typing import ArrayLike

from wheelbase._validate import as_float_array, finite, positive
from wheelbase.errors import ConfigError

__all__ = ["RM100_CONTACTS", "WheelContacts", "normal_loads"]


@dataclass(frozen=True)
class WheelContacts:
    """The robot's contacts with the ground besides its mass: drive wheels and casters.

    Parameters
    ----------
    wheel_width : float
        Width b of each drive wheel [m], > 0 (soil contact).
    wheel_inertia : float
        Spin inertia J_w of each drive wheel about its axle [kg·m²], > 0, with what turns with
        it (the motor's rotor times the gear ratio squared).
    casters : tuple of (float, float)
        Positions (x [m], y [m]) of the casters in the body frame at B; at least one off the
        axle, so that the contacts span a plane.
    caster_radius : float
        Caster wheel radius [m], > 0.
    caster_width : float
        Caster wheel width [m], > 0.
    drive_load_share : float
        Share of the weight on the drive wheels at rest (CG at B, symmetric casters), in
        (0, 1).
    cg_height : float
        Height h of the robot's CG above the ground [m], ≥ 0.

    Raises
    ------
    ConfigError
        Values out of range, or casters all on the axle line (the robot would tip).
    """

    wheel_width: float = 0.05
    wheel_inertia: float = 0.01
    casters: tuple[tuple[float, float], ...] = (
        (0.25, 0.17),
        (0.25, -0.17),
        (-0.25, 0.17),
        (-0.25, -0.17),
    )
    caster_radius: float = 0.0375
    caster_width: float = 0.03
    drive_load_share: float = 0.5
    cg_height: float = 0.1

    def __post_init__(self) -> None:
        for name, unit in (
            ("wheel_width", "m"),
            ("wheel_inertia", "kg·m²"),
            ("caster_radius", "m"),
            ("caster_width", "m"),
        ):
            object.__setattr__(self, name, positive(name, getattr(self, name), unit))
        height = finite("cg_height", self.cg_height, "m")
        if height < 0:
            raise ConfigError(f"cg_height must be >= 0 m (got {height:g})")
        object.__setattr__(self, "cg_height", height)
        share = finite("drive_load_share", self.drive_load_share)
        if not 0.0 < share < 1.0:
            raise ConfigError(f"drive_load_share must be in (0, 1) (got {share:g})")
        object.__setattr__(self, "drive_load_share", share)
        casters = as_float_array("casters", self.casters, 2, min_ndim=2, max_ndim=2)
        if casters.shape[0] == 0 or np.all(np.abs(casters[:, 0]) < 1e-6):
            raise ConfigError(
                "casters must hold at least one caster off the drive axle (x != 0 m): on "
                "its wheels alone a differential drive tips over"
            )
        object.__setattr__(self, "casters", tuple(tuple(map(float, c)) for c in casters))

    def layout(self, half_track: float) -> np.ndarray:
        """Contacts ``(2 + C, 3)``: (x [m], y [m], stiffness), rows left wheel, right wheel,
        then the casters (stiffness relative to a caster's).

        Parameters
        ----------
        half_track : float
            Half distance d between the drive wheels [m].
        """
        d = positive("half_track", half_track, "m")
        n = len(self.casters)
        share = self.drive_load_share
        drive = share * n / (2.0 * (1.0 - share))
        rows = [(0.0, d, drive), (0.0, -d, drive)] + [(x, y, 1.0) for x, y in self.casters]
        return np.array(rows)

    def load_matrix(self, half_track: float) -> np.ndarray:
        """Inverse of Σ k_i·φ_iφ_iᵀ, φ_i = (1, x_i, y_i): λ = A⁻¹·(W_n, X, Y) (3×3).

        Parameters
        ----------
        half_track : float
            Half distance d between the drive wheels [m].
        """
        layout = self.layout(half_track)
        phi = np.column_stack([np.ones(len(layout)), layout[:, 0], layout[:, 1]])
        matrix = (phi * layout[:, 2:3]).T @ phi
        if np.linalg.cond(matrix) > 1e12:
            raise ConfigError("the contacts are (nearly) collinear: the robot would tip")
        return np.linalg.inv(matrix)


RM100_CONTACTS = WheelContacts()
"""Contacts chosen for the RM100 (document 000 gives none): 5 cm wide drive wheels of spin
inertia 0.01 kg·m² (a 1 kg wheel, 0.002 kg·m², plus a 20:1 gearmotor's rotor of 2e-5 kg·m²
reflected), four 75 mm casters at (±0.25, ±0.17) m inside the 0.66 × 0.455 m body, half the
weight on the drive wheels (a sprung drive unit), the CG 0.1 m up (half the body height)."""


@numba.njit(cache=True)
def _loads(layout, ainv, weight, xc, yc, height, tx, ty, out):
    """Normal loads ``out`` (K,) of the contacts ``layout`` (K, 3) (module docstring)."""
    b0 = weight
    b1 = weight * xc - height * tx
    b2 = weight * yc - height * ty
    l0 = ainv[0, 0] * b0 + ainv[0, 1] * b1 + ainv[0, 2] * b2
    l1 = ainv[1, 0] * b0 + ainv[1, 1] * b1 + ainv[1, 2] * b2
    l2 = ainv[2, 0] * b0 + ainv[2, 1] * b1 + ainv[2, 2] * b2
    for k in range(layout.shape[0]):
        value = layout[k, 2] * (l0 + l1 * layout[k, 0] + l2 * layout[k, 1])
        out[k] = value if value > 0.0 else 0.0


def normal_loads(
    contacts: WheelContacts,
    half_track: float,
    weight: float,
    cg: ArrayLike = (0.0, 0.0),
    cg_height: float | None = None,
    tangential: ArrayLike = (0.0, 0.0),
) -> np.ndarray:
    """Normal loads [N] of the contacts (left wheel, right wheel, casters…).

    Parameters
    ----------
    contacts : WheelContacts
        The contacts.
    half_track : float
        Half track d [m].
    weight : float
        Weight normal to the ground W_n [N], ≥ 0.
    cg : array_like, shape (2,)
        CG (x_c, y_c) in the body frame [m].
    cg_height : float, optional
        CG height [m] (default ``contacts.cg_height``).
    tangential : array_like, shape (2,)
        Net tangential ground force T (body frame) [N].

    Examples
    --------
    >>> normal_loads(RM100_CONTACTS, 0.2275, 600.0).round(1).tolist()
    [150.0, 150.0, 75.0, 75.0, 75.0, 75.0]
    """
    layout = contacts.layout(half_track)
    ainv = contacts.load_matrix(half_track)
    c = as_float_array("cg", cg, 2, max_ndim=1)
    t = as_float_array("tangential", tangential, 2, max_ndim=1)
    h = contacts.cg_height if cg_height is None else finite("cg_height", cg_height, "m")
    out = np.empty(len(layout))
    _loads(layout, ainv, finite("weight", weight, "N"), c[0], c[1], h, t[0], t[1], out)
    return out
