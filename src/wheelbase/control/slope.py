"""Slope feed-forward: the wheel torques that hold the controller's model against gravity.

A computed-torque law models M·V̇ + C·V = τ on level ground. On a grade the weight pulls the
robot downhill with m·g·s along the ground (s = sin α·(cos β, sin β), the slope vector of
:mod:`wheelbase.terrain.map`); the law's integrators then take up m·g·sin α only after the
error has grown. With the PID of :class:`~wheelbase.control.torque.ComputedTorquePID`
(along-track poles at −ω, triple) a step of the slope's pull g·sin α, as an acceleration,
gives the error e(t) = g·sin α·t²·e^(−ωt)/2, largest at t = 2/ω:

    e_max = 2·e⁻²·g·sin α / ω²  (0.116 m on a 10 % grade at ω = 1.5 rad/s).

:class:`SlopeFeedForward` wraps a torque controller and adds, at the estimated pose, the wheel
torques that cancel the model's weight on the slope under it (the robot knows its floor's
grades, as traction control's ``friction="map"`` knows its friction). In the body frame the
weight's tangential part acts at the CG (x_c, y_c):

    F_g = −m·g·(cos ψ·s_x + sin ψ·s_y,  −sin ψ·s_x + cos ψ·s_y),   M_g = x_c·F_g,y − y_c·F_g,x,

and the wheels produce the force and moment (−F_g,x, −M_g) with

    Δτ_L = a·(−F_g,x/2 + M_g/(2d)),   Δτ_R = a·(−F_g,x/2 − M_g/(2d))

(document 000's τ* = Wᵀτ, the lateral part carried by the ground as in the no-slip model).
The sum is clipped to the wrapped law's ``max_torque``. On level ground the wrapper adds
nothing: the wrapped law's torques to the last bit.

**Rolling resistance** (``rolling_resistance=True``): the ground's other tangential force the
map gives, and the one a level floor has. Every contact k (the drive wheels at (0, ±d), the
casters at (x_k, y_k) of :class:`~wheelbase.terrain.contact.WheelContacts`) resists its rolling
with R_k = c_rr,k·N_k on hard ground (c_rr of the surface under the contact) or the compaction
resistance R_c(N_k) of Bekker on soil (:func:`wheelbase.terrain.soil.compaction_resistance`),
N_k the static loads of the model's weight m·g·cos α on the contacts
(:func:`~wheelbase.terrain.contact.normal_loads`, no load transfer). It acts against the
contact's direction of rolling

    e_k = h(w_k) + (1 − |h(w_k)|)·h(w_ref,k),   h(w) = w/|w|·tanh(|w| / 1 mm/s),

w_k the contact's velocity at the estimated twist (u − y_k·r, x_k·r) (a drive wheel's only
along x: its rolling moment c_rr·N·a turns with its spin): rolling, e_k is its direction (the
plant's own smoothing of the resistance). At rest, the way the reference asks to move: w_ref,k
the same at the reference's twist while the reference moves, and once it has stopped, the
contact's acceleration α_k that the wrapped law's own torques ask of the model,
(F_x/m − y_k·M_z/I_B, x_k·M_z/I_B), as h(α_k / 0.01 m/s² · 1 mm/s) — the feedback towards the
reference's pose:

    e_k = h(w_k) + (1 − |h(w_k)|)·[h(w_ref,k) + (1 − |h(w_ref,k)|)·h_α(α_k)].

Only the breakaway that motion needs: at rest the resistance is static, up to R_k against the
push, so the law's torques plus R_k·e_k leave it the net force its model (no resistance)
expects; a law that asks nothing (|α_k| ≪ 0.01 m/s²) gets nothing. The wheels then add the
torques that cancel the contacts' wrench, Δτ = Wᵀ·(Σ R_k·e_k, ·, Σ x_k·R_k·e_k,y − y_k·R_k·e_k,x):
a drive wheel rolling alone gets its own c_rr·N·a. On grass (c_rr 0.10) the RM100 needs
c_rr·m·g·a/2 = 0.84 N·m a wheel to roll at all, which the computed torque's model — no
resistance — never asks for near its goal.
"""

from __future__ import annotations

import math
from typing import Any, ClassVar

import numpy as np
from numpy.typing import ArrayLike

from wheelbase._validate import as_float_array
from wheelbase.control.base import WrappedLaw
from wheelbase.dynamics import GRAVITY, DiffDriveDynamics
from wheelbase.errors import ConfigError

__all__ = [
    "BREAKAWAY_ACCELERATION",
    "ROLLING_SPEED",
    "SlopeFeedForward",
    "rolling_torques",
    "slope_torques",
]

BREAKAWAY_ACCELERATION = 0.01
"""Contact acceleration [m/s²] asked by the law over which the breakaway at rest turns with its
direction, tanh(|α| / 0.01 m/s²): 0.26 N on the RM100, 8 mN·m a wheel."""

ROLLING_SPEED = 1e-3
"""Contact speed [m/s] over which a modelled rolling resistance turns with the direction of
rolling, tanh(w / 1 mm/s): the plant's smoothing (:mod:`wheelbase.terrain.dynamics`), used by
the fed-forward resistance here, traction control's torque window and the friction estimate."""


def slope_torques(model: DiffDriveDynamics, state: ArrayLike, slope: ArrayLike) -> np.ndarray:
    """Wheel torques (left, right) [N·m] that hold ``model`` still on ``slope`` (module docstring).

    Parameters
    ----------
    model : DiffDriveDynamics
        The controller's model: mass m [kg], CG (x_c, y_c) [m], wheel radius a and half track
        d [m].
    state : array_like, shape (..., 3) or (..., 6)
        Poses (x [m], y [m], ψ [rad]) (further columns ignored).
    slope : array_like, shape (..., 2)
        Slope vectors s = sin α·(cos β, sin β) under the poses (map frame).

    Returns
    -------
    numpy.ndarray, shape (..., 2)
        Δτ (left, right).

    Examples
    --------
    >>> from wheelbase.dynamics import RM100
    >>> tau = slope_torques(RM100, [0.0, 0.0, 0.0], [0.1, 0.0])
    >>> bool(np.isclose(tau[0], RM100.body.mass * GRAVITY * 0.1 * RM100.wheel_radius / 2))
    True
    """
    s = np.asarray(state, dtype=np.float64)
    g = np.asarray(slope, dtype=np.float64)
    body = model.body
    mass, (xc, yc) = body.mass, body.cg_offset
    c, sn = np.cos(s[..., 2]), np.sin(s[..., 2])
    fx = -mass * GRAVITY * (c * g[..., 0] + sn * g[..., 1])
    fy = -mass * GRAVITY * (-sn * g[..., 0] + c * g[..., 1])
    mz = xc * fy - yc * fx
    a, d = model.wheel_radius, model.half_track
    return np.stack([a * (-0.5 * fx + 0.5 * mz / d), a * (-0.5 * fx - 0.5 * mz / d)], axis=-1)


def _heading(w: np.ndarray) -> np.ndarray:
    """h(w) = w/|w|·tanh(|w| / 1 mm/s) over the last axis (module docstring)."""
    speed = np.linalg.norm(w, axis=-1, keepdims=True)
    return w * (np.tanh(speed / ROLLING_SPEED) / np.maximum(speed, 1e-300))


def rolling_torques(
    model: DiffDriveDynamics,
    contacts: Any,
    terrain: Any,
    state: ArrayLike,
    reference_twist: ArrayLike | None = None,
    asked: ArrayLike | None = None,
) -> np.ndarray:
    """Wheel torques (left, right) [N·m] that cancel the ground's rolling resistance on
    ``model`` (module docstring).

    Parameters
    ----------
    model : DiffDriveDynamics
        The controller's model: mass m [kg], CG (x_c, y_c) [m], wheel radius a and half track
        d [m].
    contacts : WheelContacts
        Where the robot touches the ground: casters, load sharing, wheel and caster sizes.
    terrain : TerrainMap
        The floor the robot knows: the surface under each contact, the slope under the
        centroid.
    state : array_like, shape (..., 6)
        Estimated (x [m], y [m], ψ [rad], u [m/s], v [m/s], r [rad/s]).
    reference_twist : array_like, shape (..., 3), optional
        The reference's body twist (u [m/s], v [m/s], r [rad/s]): the way to break away at
        rest while the reference moves (None: none).
    asked : array_like, shape (..., 2), optional
        The wrapped law's wheel torques (left, right) [N·m]: the way to break away at rest
        once the reference has stopped too (None: none).

    Returns
    -------
    numpy.ndarray, shape (..., 2)
        Δτ (left, right).

    Examples
    --------
    >>> from wheelbase.dynamics import GRAVITY, RM100
    >>> from wheelbase.terrain import RM100_CONTACTS, SURFACES, TerrainMap
    >>> grass = TerrainMap.uniform(SURFACES["grass"])
    >>> tau = rolling_torques(RM100, RM100_CONTACTS, grass, [0, 0, 0, 0.5, 0, 0])
    >>> c_rr = SURFACES["grass"].rolling_resistance
    >>> bool(np.allclose(tau, c_rr * RM100.body.mass * GRAVITY * RM100.wheel_radius / 2))
    True
    """
    from wheelbase.terrain.contact import normal_loads
    from wheelbase.terrain.soil import compaction_resistance

    s = np.asarray(state, dtype=np.float64)
    shape = s.shape[:-1]
    s = s.reshape(-1, 6)
    d = model.half_track
    layout = contacts.layout(d)  # (K, 3): drive wheels, then casters
    x, y = layout[:, 0], layout[:, 1]
    body = model.body
    unit = normal_loads(contacts, d, 1.0, body.cg_offset)  # static loads per newton of weight
    slope = np.asarray(terrain.slope_at(s[:, :2]), dtype=np.float64).reshape(-1, 2)
    cos_a = np.sqrt(np.maximum(1.0 - np.sum(slope**2, axis=-1), 0.0))
    loads = unit * (body.mass * GRAVITY * cos_a)[:, None]  # (N, K)
    c, sn = np.cos(s[:, 2:3]), np.sin(s[:, 2:3])
    world = np.stack([s[:, 0:1] + c * x - sn * y, s[:, 1:2] + sn * x + c * y], axis=-1)
    where = terrain.index(world)  # (N, K)
    resist = np.zeros_like(loads)
    for index in np.unique(where):
        surface = terrain.surfaces[int(index)]
        mask = where == index
        if surface.is_soil:
            radius = np.where(np.arange(x.size) < 2, model.wheel_radius, contacts.caster_radius)
            width = np.where(np.arange(x.size) < 2, contacts.wheel_width, contacts.caster_width)
            for k in np.flatnonzero(mask.any(axis=0)):
                rows = mask[:, k]
                resist[rows, k] = compaction_resistance(
                    loads[rows, k], float(radius[k]), float(width[k]), surface.soil
                )
        else:
            resist[mask] = surface.rolling_resistance * loads[mask]

    def velocities(twist: np.ndarray) -> np.ndarray:  # (N, K, 2) contact velocities, v = 0
        w = np.stack([twist[:, 0:1] - y * twist[:, 2:3], x * twist[:, 2:3]], axis=-1)
        w[:, :2, 1] = 0.0  # a drive wheel rolls along x only
        return w

    ahead = _heading(velocities(s[:, 3:6]))
    if reference_twist is not None:
        ref = np.broadcast_to(np.asarray(reference_twist, dtype=np.float64), (*shape, 3))
        spent = np.linalg.norm(ahead, axis=-1, keepdims=True)
        ahead = ahead + (1.0 - spent) * _heading(velocities(ref.reshape(-1, 3)))
    if asked is not None:
        wrench = model.body_force(np.broadcast_to(np.asarray(asked, np.float64), (*shape, 2)))
        wrench = wrench.reshape(-1, 3)
        accel = np.column_stack([wrench[:, 0] / body.mass, wrench[:, 0] * 0.0,
                                 wrench[:, 2] / body.inertia_centroid])  # fmt: skip
        asks = _heading(velocities(accel) * (ROLLING_SPEED / BREAKAWAY_ACCELERATION))
        spent = np.linalg.norm(ahead, axis=-1, keepdims=True)
        ahead = ahead + (1.0 - spent) * asks
    force = resist[..., None] * ahead  # (N, K, 2): what the wheels push against
    wrench = np.stack(
        [
            force[..., 0].sum(1),
            force[..., 1].sum(1),
            (x * force[..., 1] - y * force[..., 0]).sum(1),
        ],
        axis=-1,
    )
    return model.wheel_torques(wrench).reshape((*shape, 2))


class SlopeFeedForward(WrappedLaw):
    """Wrap a torque controller: add the torques that hold its model on the slope (module
    docstring).

    Parameters
    ----------
    law : callable
        A controller giving wheel torques (``command_names`` (tau_left, tau_right)), called as
        ``law(t, state, reference)``.
    model : DiffDriveDynamics
        The controller's model; when the law has a ``model`` attribute (a
        :class:`~wheelbase.control.schedule.ModelSchedule` changes it with a payload) that one
        is read at each call instead.
    terrain : TerrainMap
        The floor the robot knows: the slope under its estimated position (and the surface
        under each contact).
    rolling_resistance : bool
        Also feed forward the ground's rolling resistance under each contact (module
        docstring); False by default: the slope alone.
    contacts : WheelContacts, optional
        The robot's contacts for the rolling resistance (default
        :data:`~wheelbase.terrain.contact.RM100_CONTACTS`).

    Examples
    --------
    >>> from wheelbase.control.torque import ComputedTorquePID
    >>> from wheelbase.dynamics import RM100
    >>> from wheelbase.terrain import SURFACES, TerrainMap
    >>> law = ComputedTorquePID(RM100)
    >>> wrapped = SlopeFeedForward(law, RM100, TerrainMap.uniform(SURFACES["dry_concrete"]))
    >>> wrapped.command_names
    ('tau_left', 'tau_right')
    """

    command_names: ClassVar[tuple[str, ...]] = ("tau_left", "tau_right")

    def __init__(
        self,
        law: Any,
        model: DiffDriveDynamics,
        terrain: Any,
        *,
        rolling_resistance: bool = False,
        contacts: Any = None,
    ) -> None:
        from wheelbase.terrain.contact import RM100_CONTACTS, WheelContacts
        from wheelbase.terrain.map import TerrainMap

        if not callable(law) or tuple(getattr(law, "command_names", ())) != self.command_names:
            raise ConfigError("slope feed-forward wraps a controller that gives wheel torques")
        if not isinstance(model, DiffDriveDynamics):
            raise ConfigError(f"model must be a DiffDriveDynamics (got {type(model).__name__})")
        if not isinstance(terrain, TerrainMap):
            raise ConfigError(
                f"slope feed-forward needs the terrain map (got {type(terrain).__name__})"
            )
        if contacts is None:
            contacts = RM100_CONTACTS
        if not isinstance(contacts, WheelContacts):
            raise ConfigError(f"contacts must be WheelContacts (got {type(contacts).__name__})")
        self.law = law
        self._model = model
        self.terrain = terrain
        self.rolling_resistance = bool(rolling_resistance)
        self.contacts = contacts

    # ------------------------------------------------------------------ passed through
    @property
    def model(self) -> DiffDriveDynamics:
        """The model in force: the wrapped law's when it has one."""
        return getattr(self.law, "model", None) or self._model

    @property
    def max_torque(self) -> float:
        """The wrapped law's torque limit [N·m] (infinite without one)."""
        return float(getattr(self.law, "max_torque", math.inf))

    def __getattr__(self, name: str) -> Any:  # estimates, history, row: the wrapped law's
        if name.startswith("_") or name in {"law", "terrain", "rolling_resistance", "contacts"}:
            raise AttributeError(name)
        return getattr(self.law, name)

    def _row_sampler(self) -> Any:
        """The wrapped law's own row sampler (the scenario's tracking), None without one."""
        law = self.law
        while not hasattr(law, "row") and hasattr(law, "law"):
            law = law.law
        return getattr(law, "row", None)

    # ------------------------------------------------------------------ control
    def __call__(self, t: float, state: ArrayLike, reference: object) -> np.ndarray:
        """The wrapped law's wheel torques plus the slope's (and the rolling resistance's)
        (module docstring).

        Parameters
        ----------
        t : float
            Time [s].
        state : array_like, shape (..., 6)
            Estimated (x, y, θ, u, v, r).
        reference : object
            Passed to the law.
        """
        s = as_float_array("state", state, 6)
        raw = np.asarray(self.law(t, s.copy(), reference), dtype=np.float64)
        slope = self.terrain.slope_at(s[..., :2])
        if not self.rolling_resistance and not np.any(slope):
            return raw
        out = raw + slope_torques(self.model, s, slope).reshape(raw.shape)
        if self.rolling_resistance:
            twist = _reference_twist(t, reference, self._row_sampler())
            extra = rolling_torques(self.model, self.contacts, self.terrain, s, twist, raw)
            out = out + extra.reshape(raw.shape)
        limit = self.max_torque
        return np.clip(out, -limit, limit) if math.isfinite(limit) else out


def _reference_twist(t: float, reference: object, sampler: Any = None) -> np.ndarray | None:
    """The reference's body twist (u, v, r) at ``t``: from a row ``(..., 9)`` (a slowed clock's),
    :class:`~wheelbase.control.torque.TimedRows` or a
    :class:`~wheelbase.models.path.PoseTrajectory` (through the law's own row ``sampler`` when
    it has one); None for anything else (a path)."""
    from wheelbase.control.torque import TimedRows
    from wheelbase.models.path import PoseTrajectory

    if isinstance(reference, TimedRows):
        return reference.at(t)[3:6]
    if isinstance(reference, PoseTrajectory) and sampler is not None:
        return np.asarray(sampler(t, reference), dtype=np.float64)[3:6]
    if isinstance(reference, PoseTrajectory):
        return reference.at([t]).reference()[0, 3:6]
    if isinstance(reference, np.ndarray) and reference.shape[-1:] == (9,):
        return reference[..., 3:6]
    return None
