"""Traction control: wheel torques limited by the friction the ground gives, so wheels don't spin.

A wheel transmits at most μ·N to the ground, along and across together (the friction circle);
a torque beyond what is left of it only spins the wheel up, and a spinning wheel both loses
traction (past the peak of the friction curve) and drives the odometry off. The wheel's own
rolling resistance is a moment M_rr = c_rr·N·a on the wheel, against its spin, not a force
of the ground's: J_w·ω̇ = τ − a·F_x − M_rr, so the torque that makes the ground force F_x is
τ = a·F_x + M_rr, and grip limits F_x, not τ. :class:`TractionControl` wraps any torque
controller and clips each wheel's torque to the window

    −margin·a·G_i − M̂_i·h(−v_i) ≤ τ_i ≤ margin·a·G_i + M̂_i·h(v_i)   (widened to hold τ_i = 0),
    G_i = √((μ̂_i·N̂_i)² − F_y²),   N̂_i = s·m̂·g/2,   F_y = m̂·|u·r|/2,
    M̂_i = c_rr,i·N̂_i·a,   h(v) = min(1, 1 + 2·tanh(v / 1 mm/s)),   v_i = u ∓ d·r,

N̂ the static load of a drive wheel (share s of the weight m̂·g of the controller's model: an
unknown payload only adds grip), F_y its share of the centripetal force of a turn (the casters take
none), at least a fifth of the circle left for braking, M̂ the rolling moment (c_rr the map's under
the wheel with ``friction="map"``, else ``rolling_resistance``), and μ̂ the friction it believes in
(with ``friction="estimate"`` and ``rolling_resistance`` > 0 the estimate leaves the rolling moment
out, as the window counts it: the grip alone). A wheel rolling forward (v_i ≫ 1 mm/s, the plant's
smoothing of the moment) may be driven up to (margin·μ̂ + c_rr)·N̂·a and braked down to
−(margin·μ̂ − c_rr)·N̂·a, since the moment helps it brake; backward the same, mirrored; at rest
either way up to (margin·μ̂ + c_rr)·N̂·a, since a wheel that starts to turn meets its moment
whichever way it turns (without that a robot whose ground force at rest does not overcome its
casters would never roll far enough to widen its window). The window always holds 0 (where c_rr
exceeds margin·μ̂: traction control never adds a torque the law did not ask for). On grass
(μ_p 0.24, c_rr 0.10) a clip of margin·μ̂·N̂·a alone left the RM100 0.092·N̂ of ground force
per wheel against its casters' 0.10·N̂: it did not move. μ̂:

- ``friction="estimate"``: its own online estimate, per wheel, from the wheel rates its
  encoders give, the torques it commanded and its model — never the terrain
  (:class:`~wheelbase.control.friction_estimate.FrictionEstimator`: a wheel whose slip speed
  against the body the model predicts grows in the direction of its force is spinning, and the
  friction the ground gave it meanwhile is the estimate). While a wheel spins its torque is cut
  to ``regrip`` times what the ground gave (below the sliding friction, so it grips again).
  With ``imu=True`` the wrapper reads the robot's IMU (``reads_imu``: the engine passes its
  readings, never the truth) and the estimate compares the wheels with what it measures —
  the yaw rate and the ground speed of each contact, the body's lateral slide — so that a
  sideways skid or one wheel's spin in a turn, which the encoders cannot see, lowers it too;
- a coefficient it is given (``friction=0.1`` on ice);
- the peak friction of the floor it knows, looked up under each wheel's estimated position in
  its terrain map (``friction="map"``: :attr:`wheelbase.terrain.Surface.peak_friction`).

**Holding the integrators** (``hold_integrators=True``): a clipped torque is a saturation the
wrapped law does not see, so its integrators wind up while traction clips and the robot
overshoots once grip allows (on ice the demo's computed-torque PID reached 1.4 m/s on a
0.6 m/s reference, skidded and collided). With it the law's own torque limit is lowered to the
smallest friction limit during the call, so its anti-windup (conditional integration) holds.

Up to the peak slip the friction curve rises with the slip, so a wheel whose force stays below
margin·μ_p·N settles below its peak slip and never spins.

**Slowing down** (``slow_down=True``): the lateral grip a turn needs, m·|u·r|/2 per drive
wheel, and the force of the reference's own accelerations cannot be limited by torque alone: the
reference goes round the turn at its speed, and a clipped torque only lets the tracking error
grow (on ice the demo skidded wide of its turns and could not brake for its cusp). With
``slow_down`` the wrapper runs the reference on a clock of its own, slowed along the whole
reference to the friction (:class:`~wheelbase.control.friction_timing.FrictionTiming`): the same
path, timed so that every wheel's force of the reference — longitudinal, from its accelerations,
and lateral, from its turns — stays within ``reference_share``·``margin`` of the friction circle
μ̂·N̂, braking in time for a turn or a cusp ahead; the rest of the circle is the feedback's. μ̂ is
the map's under each wheel along the reference (``"map"``), or the present estimate or given
coefficient, planned again when the estimate changes. The wrapped law must sample a timed
reference (:class:`~wheelbase.control.torque.ComputedTorquePID` and the adaptive law, through the
scenario's tracking wrapper).
"""

from __future__ import annotations

from typing import ClassVar

import numpy as np
from numpy.typing import ArrayLike

from wheelbase._validate import as_float_array, finite
from wheelbase.control.base import WrappedLaw
from wheelbase.control.slope import ROLLING_SPEED
from wheelbase.dynamics import GRAVITY, DiffDriveDynamics
from wheelbase.errors import ConfigError

__all__ = ["REPLAN_CHANGE", "TractionControl"]

REPLAN_CHANGE = 0.02
"""Relative change of the friction estimate [-] after which ``slow_down`` plans its clock again."""


class TractionControl(WrappedLaw):
    """Wrap a torque controller: each wheel's torque limited by the friction (module docstring).

    Parameters
    ----------
    law : callable
        A controller giving wheel torques (``command_names`` (tau_left, tau_right)).
    model : DiffDriveDynamics
        The controller's model (mass, wheel radius, half track).
    friction : float, "map" or "estimate"
        The friction coefficient to respect, in (0, 3]; ``"map"``: the peak friction under
        each wheel in ``terrain``; ``"estimate"``: the online estimate (module docstring).
    margin : float
        Share of the friction limit the torques may use, in (0, 1].
    drive_load_share : float
        Share s of the weight on the drive wheels, in (0, 1].
    wheel_inertia : float
        J_w of a drive wheel [kg·m²], > 0 (for the observer).
    terrain : TerrainMap, optional
        The floor the robot knows (``friction="map"``; never read with ``"estimate"``).
    initial_friction : float
        The estimate's prior μ̂ before any spin (``friction="estimate"``), in (0, 3].
    regrip : float
        Share of the transmitted force a spinning wheel's torque is cut to, in (0, 1].
    slow_down : bool
        Drive the reference slower where the friction is low (module docstring).
    reference_share : float
        With ``slow_down``: share of ``margin`` times the friction circle that the slowed
        reference's own wheel forces may use, in (0, 1]; the rest is left to the feedback.
    rolling_resistance : float
        The rolling-resistance coefficient c_rr [-], in [0, 1), with a friction coefficient or
        ``"estimate"`` (with ``"map"`` the map's c_rr under each wheel is used): the wheels'
        rolling moment widens the torque window and the casters' share loads the slowed
        reference's circles (module docstring). With ``"estimate"`` it is the robot's own
        figure (its tyres, measured on its floor), and the estimator takes the moment out of
        the torque, so that μ̂ is the ground's grip alone; 0 (the default): μ̂ holds the
        wheels' rolling moment too, c_rr above the grip.
    casters : array_like, shape (C, 2)
        Caster positions (x [m], y [m]) in the body frame, sharing (1 − s) of the weight
        equally; with ``slow_down`` their rolling resistance along each caster's own velocity
        (a force and, in a turn, a yaw moment) is what the drive wheels' ground forces must
        overcome besides the inertia. Empty (the default): c_rr·(1 − s)·m̂·g/2 a wheel along the
        travel.
    hold_integrators : bool
        Give the wrapped law (the innermost one with a ``max_torque``) the smallest friction
        limit as its torque saturation during the call, so that its anti-windup stops its
        integrators while traction clips (module docstring).
    imu : bool
        With ``friction="estimate"``: the estimate also reads the IMU's readings the engine
        passes (``imu=`` of each call; module docstring).
    """

    command_names: ClassVar[tuple[str, ...]] = ("tau_left", "tau_right")

    def __init__(
        self,
        law: object,
        model: DiffDriveDynamics,
        *,
        friction: float | str = "map",
        margin: float = 0.8,
        drive_load_share: float = 0.5,
        wheel_inertia: float = 0.01,
        terrain: object = None,
        initial_friction: float = 1.0,
        regrip: float = 0.5,
        slow_down: bool = False,
        hold_integrators: bool = False,
        reference_share: float = 0.8,
        rolling_resistance: float = 0.0,
        casters: ArrayLike = (),
        imu: bool = False,
    ) -> None:
        if not callable(law) or tuple(getattr(law, "command_names", ())) != self.command_names:
            raise ConfigError("traction control wraps a controller that gives wheel torques")
        if not isinstance(model, DiffDriveDynamics):
            raise ConfigError(f"model must be a DiffDriveDynamics (got {type(model).__name__})")
        self.law = law
        self.model = model
        if friction == "map":
            from wheelbase.terrain.map import TerrainMap

            if not isinstance(terrain, TerrainMap):
                raise ConfigError("friction 'map' needs the terrain map (a TerrainMap)")
            self._peaks = np.array([surface.peak_friction for surface in terrain.surfaces])
            self._rolling = np.array([surface.rolling_resistance for surface in terrain.surfaces])
        elif friction == "estimate":
            terrain = None  # the estimate never reads the floor
        else:
            friction = finite("friction", friction)
            if not 0.0 < friction <= 3.0:
                raise ConfigError(
                    f"friction must be 'map', 'estimate' or in (0, 3] (got {friction:g})"
                )
        self.friction = friction
        self.terrain = terrain
        self.margin = _share("margin", margin)
        self.drive_load_share = _share("drive_load_share", drive_load_share)
        self.regrip = _share("regrip", regrip)
        if not isinstance(slow_down, bool):
            raise ConfigError(f"slow_down must be true or false (got {slow_down!r})")
        self.slow_down = slow_down
        if not isinstance(hold_integrators, bool):
            raise ConfigError(f"hold_integrators must be true or false (got {hold_integrators!r})")
        self.hold_integrators = hold_integrators
        self.reference_share = _share("reference_share", reference_share)
        c_rr = finite("rolling_resistance", rolling_resistance)
        if not 0.0 <= c_rr < 1.0:
            raise ConfigError(f"rolling_resistance must be in [0, 1) (got {c_rr:g})")
        if c_rr > 0.0 and friction == "map":
            raise ConfigError(
                "rolling_resistance goes with a friction coefficient or 'estimate': with 'map' "
                "the map's is used"
            )
        self.rolling_resistance = c_rr
        where = np.asarray(casters, dtype=np.float64)
        if where.size == 0:
            where = np.zeros((0, 2))
        if where.ndim != 2 or where.shape[1] != 2 or not np.all(np.isfinite(where)):
            raise ConfigError(f"casters must be finite (x, y) pairs in m (got shape {where.shape})")
        self.casters = where
        if not isinstance(imu, bool):
            raise ConfigError(f"imu must be true or false (got {imu!r})")
        if imu and friction != "estimate":
            raise ConfigError("imu goes with friction 'estimate': only the estimate reads it")
        self.reads_imu = imu
        self.estimator = None
        if friction == "estimate":
            from wheelbase.control.friction_estimate import FrictionEstimator

            self.estimator = FrictionEstimator(
                model, wheel_inertia=wheel_inertia, drive_load_share=self.drive_load_share,
                initial=initial_friction, rolling_resistance=c_rr, inertial=imu,
            )  # fmt: skip
        self._last: np.ndarray | None = None
        self._timing: tuple[object, object] | None = None  # (reference, FrictionTiming)

    # ------------------------------------------------------------------ passed through
    def reset(self) -> None:
        """Reset the wrapped law and the friction estimate."""
        self._last = None
        self._timing = None
        if self.estimator is not None:
            self.estimator.reset()
        super().reset()

    # ------------------------------------------------------------------ limits
    def friction_at(self, state: ArrayLike) -> np.ndarray:
        """μ̂ ``(N, 2)`` under each wheel of the estimated states ``(N, 6)``.

        Parameters
        ----------
        state : array_like, shape (N, 6)
            Estimated (x, y, θ, u, v, r).
        """
        s = np.asarray(state, dtype=np.float64).reshape(-1, 6)
        if self.friction == "estimate":
            known = self.estimator.friction
            if known is None or known.shape[0] != s.shape[0]:
                return np.full((s.shape[0], 2), self.estimator.initial)
            return known.copy()
        if self.friction != "map":
            return np.full((s.shape[0], 2), float(self.friction))
        return self._peaks[self.terrain.under_wheels(s, self.model.half_track)]

    def rolling_at(self, state: ArrayLike) -> np.ndarray:
        """c_rr ``(N, 2)`` under each wheel of the estimated states ``(N, 6)``: the map's with
        ``friction="map"``, else ``rolling_resistance``.

        Parameters
        ----------
        state : array_like, shape (N, 6)
            Estimated (x, y, θ, u, v, r).
        """
        s = np.asarray(state, dtype=np.float64).reshape(-1, 6)
        if self.friction != "map":
            return np.full((s.shape[0], 2), self.rolling_resistance)
        return self._rolling[self.terrain.under_wheels(s, self.model.half_track)]

    def rolling_moments(self, state: ArrayLike) -> np.ndarray:
        """M̂ ``(N, 2)`` [N·m]: the rolling moment c_rr·N̂·a on each drive wheel, against its
        spin (module docstring).

        Parameters
        ----------
        state : array_like, shape (N, 6)
            Estimated (x, y, θ, u, v, r).
        """
        s = np.asarray(state, dtype=np.float64).reshape(-1, 6)
        load = self.drive_load_share * self.model.body.mass * GRAVITY / 2.0
        return self.rolling_at(s) * load * self.model.wheel_radius

    def bounds(self, state: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
        """The torque window (low, high), each ``(N, 2)`` [N·m], at the estimated states:
        :meth:`limits` widened by the rolling moment on the side it opposes (both at rest),
        and to hold 0 (module docstring).

        Parameters
        ----------
        state : array_like, shape (N, 6)
            Estimated states (position: the floor; u and r: the turn's lateral force and the
            wheels' rolling direction).
        """
        s = np.asarray(state, dtype=np.float64).reshape(-1, 6)
        grip = self.limits(s)
        moment = self.rolling_moments(s)
        d = self.model.half_track
        ahead = np.tanh(np.column_stack([s[:, 3] - d * s[:, 5], s[:, 3] + d * s[:, 5]])
                        / ROLLING_SPEED)  # fmt: skip
        high = grip + moment * np.minimum(1.0, 1.0 + 2.0 * ahead)
        low = -grip - moment * np.minimum(1.0, 1.0 - 2.0 * ahead)
        return np.minimum(low, 0.0), np.maximum(high, 0.0)

    def limits(self, state: ArrayLike) -> np.ndarray:
        """The share of the friction circle as a torque, margin·a·G ``(N, 2)`` [N·m], at the
        estimated states: the half-width of the window :meth:`bounds` (module docstring).

        Parameters
        ----------
        state : array_like, shape (N, 6)
            Estimated states (position: the floor; u and r: the turn's lateral force).
        """
        s = np.asarray(state, dtype=np.float64).reshape(-1, 6)
        mass = self.model.body.mass
        grip = self.friction_at(s) * self.drive_load_share * mass * GRAVITY / 2.0
        lateral = 0.5 * mass * np.abs(s[:, 3] * s[:, 5])[:, None]
        grip = np.sqrt(np.maximum(grip**2 - lateral**2, (0.2 * grip) ** 2))
        share = np.full(grip.shape, self.margin)
        spinning = None if self.estimator is None else self.estimator.spinning
        if spinning is not None and spinning.shape == share.shape:
            share = np.where(spinning, self.regrip, share)
        return share * self.model.wheel_radius * grip

    # ------------------------------------------------------------------ control
    def __call__(
        self, t: float, state: ArrayLike, reference: object, imu: ArrayLike | None = None
    ) -> np.ndarray:
        """The wrapped law's wheel torques, each clipped to its friction limit.

        Parameters
        ----------
        t : float
            Time [s].
        state : array_like, shape (..., 6)
            Estimated (x, y, θ, u, v, r).
        reference : object
            Passed to the law.
        imu : array_like, shape (..., 3), optional
            The IMU's last readings (ω_z, f_x, f_y) with ``imu=True`` (ignored otherwise).
        """
        s = as_float_array("state", state, 6)
        flat = s.reshape(-1, 6)
        if self.estimator is not None:
            last = self._last
            if last is None or last.shape != (flat.shape[0], 2):
                last = np.zeros((flat.shape[0], 2))
            readings = None
            if self.reads_imu and imu is not None:
                readings = np.asarray(imu, dtype=np.float64).reshape(-1, 3)
            self.estimator.update(t, flat, last, readings)
        if self.slow_down:
            reference = self._slowed(t, flat, reference)
        inner = self._saturated_law() if self.hold_integrators else None
        nominal = None if inner is None else inner.max_torque
        if inner is not None:  # a symmetric saturation: the window's wider side
            low, high = self.bounds(flat)
            inner.max_torque = min(nominal, float(np.min(np.maximum(high, -low))))
        try:
            raw = np.asarray(self.law(t, s.copy(), reference), dtype=np.float64)
        finally:
            if inner is not None:
                inner.max_torque = nominal
        raw = raw.reshape(flat.shape[0], 2)
        low, high = self.bounds(flat)
        out = np.clip(raw, low, high)
        self._last = out.copy()
        return out.reshape((*s.shape[:-1], 2))

    def _saturated_law(self) -> object | None:
        """The innermost wrapped law with a ``max_torque`` (None without one)."""
        law = self.law
        while not hasattr(law, "max_torque") and hasattr(law, "law"):
            law = law.law
        return law if hasattr(law, "max_torque") else None

    # ------------------------------------------------------------------ slowing down
    @property
    def timing(self) -> object | None:
        """The :class:`~wheelbase.control.friction_timing.FrictionTiming` of the present
        reference with ``slow_down`` (None before the first call)."""
        return None if self._timing is None else self._timing[1]

    def _slowed(self, t: float, flat: np.ndarray, reference: object) -> object:
        """The reference's row on the wrapper's own clock (module docstring)."""
        from wheelbase.control.friction_timing import FrictionTiming
        from wheelbase.control.torque import TimedRows
        from wheelbase.models.path import PoseTrajectory

        if not isinstance(reference, TimedRows | PoseTrajectory):
            return reference  # a path, not a timed reference: nothing to slow
        if self._timing is None or self._timing[0] is not reference:
            if isinstance(reference, TimedRows):
                times, rows = reference.times, reference.rows
            else:
                times = np.asarray(reference.t, dtype=np.float64)
                sampler = self._row_sampler()
                rows = (
                    reference.reference()
                    if sampler is None
                    else np.array([sampler(time, reference) for time in times])
                )
            timing = FrictionTiming(
                self.model, times, rows, share=self.margin * self.reference_share,
                drive_load_share=self.drive_load_share,
            )  # fmt: skip
            if self.friction == "map":  # the floor under each wheel along the reference
                where = self.terrain.under_wheels(timing.rows[:, :6], self.model.half_track)
                timing.plan(self._peaks[where], forces=self._caster_forces(timing.rows))
            else:
                timing.plan(np.min(self.friction_at(flat), axis=0),
                            forces=self._caster_forces(timing.rows))  # fmt: skip
            self._timing = (reference, timing)
        timing = self._timing[1]
        if self.friction != "map":  # a new estimate: plan again from here
            now = np.min(self.friction_at(flat), axis=0)
            planned = timing.friction[0]
            if np.any(np.abs(now - planned) > REPLAN_CHANGE * planned):
                timing.advance(t)
                timing.plan(now)
        return timing.advance(t)

    def _caster_forces(self, rows: np.ndarray) -> np.ndarray:
        """The ground forces ``(T, 2)`` [N] the (left, right) drive wheels give against the
        casters' rolling resistance along the reference rows ``(T, 9)``: the wheel's own
        rolling moment is the torque's, not the grip's (module docstring), so the slowed
        reference's circles leave it out.

        Each caster of load (1 − s)·m̂·g/C resists with c_rr·N_c along its own velocity
        (u − y·r, v + x·r), smoothed as the plant's; the drive wheels take the wrench's F_x and
        M_z (the lateral part is left to the ground, as the model's F_y). Without casters given,
        c_rr·(1 − s)·m̂·g/2 a wheel along the travel. c_rr is the map's under each caster (under
        each wheel without casters), or ``rolling_resistance``.
        """
        weight = (1.0 - self.drive_load_share) * self.model.body.mass * GRAVITY
        d = self.model.half_track
        pose, twist = rows[:, :3], rows[:, 3:6]
        if self.casters.shape[0] == 0:
            if self.friction == "map":
                c_rr = self._rolling[self.terrain.under_wheels(pose, d)]
            else:
                c_rr = np.full((rows.shape[0], 2), self.rolling_resistance)
            return c_rr * weight / 2.0 * np.tanh(twist[:, 0:1] / ROLLING_SPEED)
        x, y = self.casters[:, 0], self.casters[:, 1]
        if self.friction == "map":
            c, sn = np.cos(pose[:, 2:3]), np.sin(pose[:, 2:3])
            world = np.stack([pose[:, 0:1] + c * x - sn * y, pose[:, 1:2] + sn * x + c * y], -1)
            c_rr = self._rolling[self.terrain.index(world)]  # (T, C)
        else:
            c_rr = np.full((rows.shape[0], x.size), self.rolling_resistance)
        vx = twist[:, 0:1] - y * twist[:, 2:3]
        vy = twist[:, 1:2] + x * twist[:, 2:3]
        speed = np.hypot(vx, vy)
        scale = c_rr * weight / x.size * np.tanh(speed / ROLLING_SPEED) / np.maximum(speed, 1e-15)
        fx, fy = -scale * vx, -scale * vy  # on the body, against each caster's velocity
        wrench = np.column_stack([fx.sum(1), fy.sum(1), (x * fy - y * fx).sum(1)])
        return -self.model.wheel_torques(wrench) / self.model.wheel_radius

    def _row_sampler(self) -> object | None:
        """The wrapped law's own row sampler (its bounded feed-forward), None without one."""
        law = self.law
        while not hasattr(law, "row") and hasattr(law, "law"):
            law = law.law
        return getattr(law, "row", None)


def _share(name: str, value: float) -> float:
    number = finite(name, value)
    if not 0.0 < number <= 1.0:
        raise ConfigError(f"{name} must be in (0, 1] (got {number:g})")
    return number
