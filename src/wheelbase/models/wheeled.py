"""A general wheeled base: any set of fixed, omni and mecanum wheels (document 000 §3.1).

Document 000 §3.1 ("Kinematics of wheel") gives, for wheel i of radius a_i centred at
(dx_i, dy_i) in the body frame, turned by θ_Bi from the body x axis and carrying passive rollers
at the angle φ_i, the wheel angular speed that a body twist ζ = (u, v, r) demands:

    ω_i = (1/a_i) [1, tan φ_i] · R(θ_Bi)ᵀ · [[1, 0, −dy_i], [0, 1, dx_i]] · ζ

The middle factor maps the velocity of the wheel centre in the body frame to the wheel frame
(ẋ_ci along the wheel, ẏ_ci across it). Document 000 prints it as [[cos, sin], [−sin, cos]],
which is R(θ_Bi)ᵀ, the inverse of the rotation it names. Stacking the rows gives ω = J_w·ζ.

A conventional ("fixed") wheel has no rollers, so it also cannot slide sideways: ẏ_ci = 0. Those
rows join the drive rows in the forward problem, which is solved by least squares; the part of
the wheel speeds that no rigid-body twist can explain is reported as a residual (the wheels
slip). The lateral rows are divided by a_i so that every row of the residual is in rad/s.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike

from wheelbase._validate import as_float_array, check_choice, finite, positive
from wheelbase.errors import ConfigError
from wheelbase.models.base import ModelBase

__all__ = ["WHEEL_KINDS", "Wheel", "WheeledBase", "mecanum4", "omni3"]

WHEEL_KINDS: tuple[str, ...] = ("fixed", "omni", "mecanum")


@dataclass(frozen=True)
class Wheel:
    """One wheel of a :class:`WheeledBase` (document 000 §3.1, figure 3.4).

    Parameters
    ----------
    x, y : float
        Position (dx, dy) of the wheel centre (contact point) in the body frame [m]
        (x forward, y left).
    mount_angle : float
        θ_B: angle from the body x axis to the wheel's rolling direction [rad], positive
        counter-clockwise. 0 for a wheel that rolls forward, π/2 for one that rolls to the left.
    radius : float
        Wheel radius a [m], > 0.
    roller_angle : float
        φ: angle between the passive roller axis and the wheel axis [rad] (document 000),
        |φ| < π/2. Must be 0 for "fixed" and "omni" wheels (omni rollers are perpendicular to the
        wheel plane), non-zero for "mecanum" wheels (typically ±π/4).
    kind : {"fixed", "omni", "mecanum"}
        A fixed wheel cannot slide sideways (ẏ_c = 0); omni and mecanum wheels can, along
        their rollers.
    name : str
        Optional label used in the input names (``omega_<name>``).

    Raises
    ------
    ConfigError
        On a non-finite position or angle, a radius <= 0, an unknown kind, or a roller angle
        that does not fit the kind.
    """

    x: float
    y: float
    mount_angle: float
    radius: float
    roller_angle: float = 0.0
    kind: str = "fixed"
    name: str = ""

    def __post_init__(self) -> None:
        object.__setattr__(self, "x", finite("wheel x", self.x, "m"))
        object.__setattr__(self, "y", finite("wheel y", self.y, "m"))
        object.__setattr__(self, "mount_angle", finite("mount_angle", self.mount_angle, "rad"))
        object.__setattr__(self, "radius", positive("wheel radius", self.radius, "m"))
        phi = finite("roller_angle", self.roller_angle, "rad")
        object.__setattr__(self, "roller_angle", phi)
        check_choice("wheel kind", self.kind, WHEEL_KINDS)
        if not isinstance(self.name, str):
            raise ConfigError(f"wheel name must be a string (got {self.name!r})")
        if abs(phi) >= math.pi / 2:
            raise ConfigError(
                f"roller_angle must be in (−90°, 90°) (got {math.degrees(phi):g}°): "
                "rollers along the wheel axis would transmit no drive"
            )
        if self.kind in ("fixed", "omni") and phi != 0.0:
            raise ConfigError(
                f"roller_angle must be 0 for a {self.kind} wheel (got {phi:g} rad); "
                "use kind='mecanum' for angled rollers"
            )
        if self.kind == "mecanum" and phi == 0.0:
            raise ConfigError("roller_angle must be non-zero for a mecanum wheel (got 0 rad)")

    @property
    def drive_row(self) -> np.ndarray:
        """Row of J_w: ω = drive_row · ζ [rad/s per (m/s, m/s, rad/s)] (document 000 §3.1)."""
        return np.array([1.0, math.tan(self.roller_angle)]) @ self._to_wheel_frame() / self.radius

    @property
    def lateral_row(self) -> np.ndarray:
        """Row giving the lateral contact velocity ẏ_c = lateral_row · ζ [m/s]."""
        return self._to_wheel_frame()[1]

    def _to_wheel_frame(self) -> np.ndarray:
        """R(θ_B)ᵀ · [[1, 0, −dy], [0, 1, dx]]: body twist → wheel-frame centre velocity."""
        c, s = math.cos(self.mount_angle), math.sin(self.mount_angle)
        rot_t = np.array([[c, s], [-s, c]])
        lever = np.array([[1.0, 0.0, -self.y], [0.0, 1.0, self.x]])
        return rot_t @ lever


@dataclass(frozen=True)
class WheeledBase(ModelBase):
    """A rigid base on any number of fixed, omni and mecanum wheels (document 000 §3.1).

    Parameters
    ----------
    wheels : tuple of Wheel
        The wheels; the inputs are their angular speeds [rad/s] in this order.

    Notes
    -----
    Inverse kinematics: ω = J_w·ζ (:attr:`jacobian`, n×3). Forward kinematics: the twist ζ that
    best explains the wheel speeds in the least-squares sense, subject also to the no-lateral-slip
    rows of the fixed wheels (target 0), see :meth:`forward`. The stacked constraint matrix
    (:attr:`constraint_matrix`) must have rank 3, otherwise the wheel speeds do not determine the
    twist (one wheel, or omni wheels that all roll the same way) and a ConfigError is raised. A
    differential drive has rank-2 drive rows (it cannot drive sideways), but the lateral rows of
    its fixed wheels pin v = 0, so its twist is determined.

    Input names are ``omega_<name>`` for named wheels and ``omega_<index>`` otherwise.

    Examples
    --------
    >>> base = mecanum4(wheel_radius=0.05, half_length=0.2, half_width=0.15)
    >>> speeds = base.inverse([0.0, 0.3, 0.0])  # straight to the left
    >>> twist, residual = base.forward(speeds)
    >>> (np.round(twist, 12) + 0.0).tolist(), float(residual) < 1e-12
    ([0.0, 0.3, 0.0], True)
    """

    wheels: tuple[Wheel, ...]
    _jacobian: np.ndarray = field(init=False, repr=False, compare=False)
    _constraints: np.ndarray = field(init=False, repr=False, compare=False)
    _pinv: np.ndarray = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        wheels = self.wheels
        if isinstance(wheels, Wheel):
            wheels = (wheels,)
        try:
            wheels = tuple(wheels)
        except TypeError:
            raise ConfigError(
                f"wheels must be a sequence of Wheel (got {type(self.wheels).__name__})"
            ) from None
        if not wheels:
            raise ConfigError("wheels must hold at least 1 wheel (got 0)")
        for index, wheel in enumerate(wheels):
            if not isinstance(wheel, Wheel):
                raise ConfigError(f"wheels[{index}] must be a Wheel (got {type(wheel).__name__})")
        names = [w.name for w in wheels if w.name]
        if len(set(names)) != len(names):
            raise ConfigError(f"wheel names must be unique (got {names})")
        object.__setattr__(self, "wheels", wheels)

        with np.errstate(over="ignore", invalid="ignore"):
            jacobian = np.array([w.drive_row for w in wheels])
            lateral = [w.lateral_row / w.radius for w in wheels if w.kind == "fixed"]
            constraints = np.vstack([jacobian, *lateral]) if lateral else jacobian.copy()
        if not np.all(np.isfinite(constraints)):
            extreme = max(wheels, key=lambda w: max(abs(w.x), abs(w.y)) / w.radius)
            raise ConfigError(
                "the wheel Jacobian overflows float64: a wheel at "
                f"({extreme.x:g}, {extreme.y:g}) m with radius {extreme.radius:g} m gives "
                "ω/v beyond 1e308 (bring the wheels nearer or make them larger)"
            )
        singular = np.linalg.svd(constraints, compute_uv=False)
        rank = int(np.sum(singular > 1e-10 * singular[0]))
        if rank < 3:
            raise ConfigError(
                f"the wheels do not determine the body twist: the constraint matrix has rank "
                f"{rank} < 3 (add wheels, or mount them so that they roll in different "
                "directions or sit at different places)"
            )
        for array in (jacobian, constraints):
            array.setflags(write=False)
        with np.errstate(over="ignore", divide="ignore", invalid="ignore"):
            pinv = np.linalg.pinv(constraints)
        if not np.all(np.isfinite(pinv)):
            largest = max(wheels, key=lambda w: w.radius)
            raise ConfigError(
                f"the wheel Jacobian's inverse overflows float64: a wheel radius of "
                f"{largest.radius:g} m makes the wheel speeds of any motion underflow (use "
                "radii below 1e10 m)"
            )
        pinv.setflags(write=False)
        object.__setattr__(self, "_jacobian", jacobian)
        object.__setattr__(self, "_constraints", constraints)
        object.__setattr__(self, "_pinv", pinv)

    # ------------------------------------------------------------------ protocol
    @property
    def input_names(self) -> tuple[str, ...]:  # type: ignore[override]
        """``omega_<name>`` (or ``omega_<index>``) for each wheel, in order."""
        return tuple(f"omega_{w.name or i}" for i, w in enumerate(self.wheels))

    @property
    def input_units(self) -> tuple[str, ...]:  # type: ignore[override]
        """``rad/s`` for each wheel."""
        return ("rad/s",) * len(self.wheels)

    def _twist(self, inputs: np.ndarray) -> np.ndarray:
        return self._solve(inputs)[0]

    # ------------------------------------------------------------------ kinematics
    @property
    def jacobian(self) -> np.ndarray:
        """J_w (n×3, read-only): wheel speeds ω = J_w·ζ (document 000 §3.1)."""
        return self._jacobian

    @property
    def constraint_matrix(self) -> np.ndarray:
        """J_w stacked on the fixed wheels' lateral rows ÷ a_i (read-only, (n + n_fixed)×3)."""
        return self._constraints

    @property
    def is_holonomic(self) -> bool:
        """Whether every body twist is reachable without slip (J_w has rank 3, no fixed wheel)."""
        return self._constraints.shape[0] == self._jacobian.shape[0]

    def inverse(self, twist: ArrayLike) -> np.ndarray:
        """Wheel speeds ``(..., n)`` [rad/s] for body twists ``(..., 3)``: ω = J_w·ζ.

        For a base with fixed wheels a twist that makes one of them slide sideways (e.g. v ≠ 0
        on a differential drive) cannot be followed; the sideways part is ignored here, as in
        document 000's pseudo-inverse of W. :meth:`lateral_slip` measures it.
        """
        twist = as_float_array("twist", twist, 3)
        return twist @ self._jacobian.T

    def lateral_slip(self, twist: ArrayLike) -> np.ndarray:
        """Lateral contact velocities ẏ_c ``(..., n_fixed)`` [m/s] of the fixed wheels."""
        twist = as_float_array("twist", twist, 3)
        rows = np.array([w.lateral_row for w in self.wheels if w.kind == "fixed"]).reshape(-1, 3)
        return twist @ rows.T

    def forward(self, wheel_speeds: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
        """Body twist and slip residual for wheel speeds ``(..., n)`` [rad/s].

        Returns
        -------
        twist : numpy.ndarray, shape (..., 3)
            The least-squares twist (u [m/s], v [m/s], r [rad/s]).
        residual : numpy.ndarray, shape (...)
            ‖A·ζ − (ω, 0)‖ [rad/s] with A the :attr:`constraint_matrix`: zero when the wheel
            speeds are consistent with a rigid-body motion, positive when the wheels slip.
        """
        return self._solve(self.validate_inputs(wheel_speeds))

    def _solve(self, speeds: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        n_extra = self._constraints.shape[0] - self._jacobian.shape[0]
        target = np.concatenate([speeds, np.zeros((*speeds.shape[:-1], n_extra))], axis=-1)
        twist = target @ self._pinv.T
        residual = np.linalg.norm(twist @ self._constraints.T - target, axis=-1)
        return twist, residual

    # ------------------------------------------------------------------ presets
    @classmethod
    def differential(cls, wheel_radius: float, half_track: float) -> WheeledBase:
        """Two fixed wheels, left at y = +d and right at y = −d (document 000 §3.1).

        The inputs are (omega_left, omega_right) [rad/s], as for
        :class:`~wheelbase.models.diffdrive.DiffDrive`, whose W matrix this reproduces.

        Parameters
        ----------
        wheel_radius : float
            a [m], > 0.
        half_track : float
            d: distance from the centre to each wheel [m], > 0.
        """
        a = positive("wheel_radius", wheel_radius, "m")
        d = positive("half_track", half_track, "m")
        return cls(
            (
                Wheel(0.0, d, 0.0, a, kind="fixed", name="left"),
                Wheel(0.0, -d, 0.0, a, kind="fixed", name="right"),
            )
        )


def mecanum4(wheel_radius: float, half_length: float, half_width: float) -> WheeledBase:
    """Four mecanum wheels at (±l_x, ±l_y) with 45° rollers in the usual "X" layout.

    Wheel order: front-left, front-right, rear-left, rear-right, with roller angles −45°, +45°,
    +45°, −45°, so that (a = wheel radius, l_x = half_length, l_y = half_width)

        ω_FL = (u − v − (l_x + l_y) r)/a,  ω_FR = (u + v + (l_x + l_y) r)/a,
        ω_RL = (u + v − (l_x + l_y) r)/a,  ω_RR = (u − v + (l_x + l_y) r)/a.

    Parameters
    ----------
    wheel_radius : float
        a [m], > 0.
    half_length : float
        l_x: distance from the centre to the front and rear axles [m], > 0.
    half_width : float
        l_y: distance from the centre to the left and right wheels [m], > 0.
    """
    a = positive("wheel_radius", wheel_radius, "m")
    lx = positive("half_length", half_length, "m")
    ly = positive("half_width", half_width, "m")
    q = math.pi / 4
    layout = (
        ("front_left", lx, ly, -q),
        ("front_right", lx, -ly, q),
        ("rear_left", -lx, ly, q),
        ("rear_right", -lx, -ly, -q),
    )
    return WheeledBase(
        tuple(
            Wheel(x, y, 0.0, a, roller_angle=phi, kind="mecanum", name=name)
            for name, x, y, phi in layout
        )
    )


def omni3(wheel_radius: float, base_radius: float) -> WheeledBase:
    """Three omni wheels 120° apart on a circle, rolling tangentially ("kiwi" drive).

    Wheel i sits at the polar angle β_i = 0°, 120°, 240° (front, rear-left, rear-right) at
    ``base_radius`` R from the centre and rolls counter-clockwise (θ_B = β_i + 90°), so that
    ω_i = (−sin β_i·u + cos β_i·v + R·r)/a.

    Parameters
    ----------
    wheel_radius : float
        a [m], > 0.
    base_radius : float
        R: distance from the centre to each wheel [m], > 0.
    """
    a = positive("wheel_radius", wheel_radius, "m")
    big_r = positive("base_radius", base_radius, "m")
    wheels = []
    for name, beta in (
        ("front", 0.0),
        ("rear_left", 2 * math.pi / 3),
        ("rear_right", -2 * math.pi / 3),
    ):
        wheels.append(
            Wheel(
                big_r * math.cos(beta),
                big_r * math.sin(beta),
                beta + math.pi / 2,
                a,
                kind="omni",
                name=name,
            )
        )
    return WheeledBase(tuple(wheels))
