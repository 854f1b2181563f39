"""An online estimate of the friction under each drive wheel, from what the controller observes.

Traction control (:class:`~wheelbase.control.traction.TractionControl`, ``friction="estimate"``)
needs the peak friction μ_p of the ground, which the robot is not told. What it observes: the
wheel rates ω_k that its encoders imply (from the estimated twist, u ∓ d·r = a·ω_k), the torques
τ_k it commanded one control period before, and its own model (mass m̂, yaw inertia Î_B, wheel
radius a, half track d, the wheels' spin inertia J_w, the share s of the weight on the drive
wheels). Never the terrain.

**Ground force.** A wheel's own dynamics J_w·ω̇_k = τ_k − a·F_k − M_rr,k hold whether it slips
or not, so the force the ground gives it is F̂_k = (τ_k − J_w·Δω_k/Δt − M̂_k)/a, and its friction
utilisation F̂_k/N̂_k with N̂_k = s·m̂·g/2. M̂_k = c_rr·N̂_k·a·tanh(a·ω_k / 1 mm/s) is the wheel's
rolling-resistance moment (the plant's smoothing), with c_rr the ``rolling_resistance`` the robot
is told — a property of its tyres, measured on its own floor (at a steady speed on the level
τ_L + τ_R = a·c_rr·m·g), not of the ground it cannot see. The moment opposes the wheel's spin,
not the ground's grip: counted in F̂ (c_rr = 0) a spinning wheel's utilisation is μ + c_rr, and
on ice (μ_p 0.10, c_rr 0.013) the estimate was 0.114 — 13 % more grip than the ice gives, which
the torque window and the slowed reference then spent. It is not learnt online: the first spin
comes from rest, before the observer's bias has learnt anything, and that bias holds the
casters' drag, a slope and the model's mass error besides the wheels' moment, which the body's
motion cannot tell apart.

**Slip, as a traction control system measures it.** A car's TCS compares the driven wheels with
the undriven ones; a differential-drive robot has no undriven wheel it measures, so the ground
speed of each wheel's contact comes from the model instead: the body pushed by the forces F̂_k,

    u̇ = (F̂_L + F̂_R)/m̂,   ṙ = d·(F̂_R − F̂_L)/Î_B,   v̂̇_k = u̇ ∓ d·ṙ + b̂_k + L₁·e_k,
    ḃ_k = L₂·e_k,   e_k = a·ω_k − v̂_k,

a Luenberger observer of the contact speed v̂_k with a bias b̂_k that learns what the model lacks
(the casters' rolling resistance, a slope, a payload the model does not carry) at the bandwidth ω_o
(L₁ = 2ζω_o, L₂ = ω_o², ζ = 1). A wheel that rolls has e ≈ 0; a wheel that spins (or locks) turns
faster (or slower) than the body the forces push: its slip speed e grows. Where the filtered e_k
exceeds ``slip_speed`` + ``slip_ratio``·|v̂_k| *in the direction of the wheel's force* (driving:
faster; braking: slower), the wheel is *spinning*: the observer stops its corrections (so the spin
is not learnt as a bias), and the estimate of that wheel's peak friction becomes the largest
utilisation the ground gave during the spin, μ̂_k = max |F̂_k|/N̂_k (a wheel past its peak transmits
between its sliding and peak friction), never above what it was, and never below the utilisation it
transmitted without spinning over the last ``memory`` metres (fading with the distance): a false
alarm — the end of a slope, whose pull the bias still holds — cannot take away grip the wheel has
shown. The spin ends when e falls below half the threshold (or after ``max_spin_time``: a bias the
observer could not follow, not a spin).

**The other wheel.** A spin is news of the floor under both wheels, 2d apart and most often on
the same ground: while one wheel spins, the other's estimate falls to what the spinning one
learns, unless it has shown more itself (the utilisation it transmitted without spinning over
the last ``memory`` metres) — a split-μ start keeps the grip the concrete wheel has shown, and
its estimate relaxes after ``memory`` metres as a spun wheel's. Without it the wheel that had
not spun kept the prior, and on ice its torque's brief peaks (20 ms, too short for the 50 ms
filter to call a spin) slipped it to 0.15 on the demo after the start spin.

The directional test makes the model's errors err on the safe side: a heavier robot than the
model (a payload), rolling resistance or an uphill slow the body down, so its wheels turn slower
than the model says while driving and faster while braking — the opposite of a spin or a lock.

**Memory.** Friction only falls on evidence. After ``memory`` metres without a spin the
estimate relaxes back towards the prior ``initial`` (by the distance travelled over 1 m), so a
robot that has left the ice for concrete regains its grip — and on ice it probes the peak again,
a brief spin every ``memory`` metres.

**With an IMU** (``inertial=True`` and readings (ω_z, a_x, a_y) of
:class:`~wheelbase.sensors.Imu` passed to :meth:`~FrictionEstimator.update`): the ground speed
of each contact is measured instead of predicted from the model. A skid the encoders cannot see
— one wheel spinning as the other grips (the body turns less than the wheels say), or the axle
sliding sideways in a turn — is a disagreement between the wheels and the IMU. Per robot,

    û̇ = a_x − b̂_x + v̂·r̂ + L₁·(u_enc − û),   b̂̇_x = −L₂·(u_enc − û),
    v̂̇ = a_y − b̂_y − û·r̂ − L₁·v̂,             b̂̇_y = L₂·v̂,       r̂ = ω_z − b̂_r,

the ground speed û at the reference point (the accelerometer integrated, held to the encoders'
u_enc), the lateral speed v̂ (held to 0, the no-side-slip constraint of a gripping drive axle),
L₁ = 2·``imu_bandwidth``, corrected only while every wheel grips. The biases come from the
first reading (the start-up calibration: the start taken as steady motion), and then learn
what drifts: the accelerometers' at L₂ = (:data:`BIAS_RATE`·``imu_bandwidth``)² while every
wheel grips, the gyro's only at rest (no tick for :data:`REST_TIME`), where the whole reading
is bias — in motion a slow skid would be learnt as one. A wheel's slip speed is its rim speed
against its contact's, e_k = a·ω_k − (û ∓ d·r̂), with the yaw rate the gyro measures, not the
one the wheels imply: one wheel's spin shows even where the two rims' mean matches the body. A
skid starts where a wheel's e_k exceeds ``imu_slip_speed`` + ``imu_slip_ratio``·|û| in the
direction of its force (as without the IMU), or the lateral speed |v̂| exceeds as much (both
wheels: the axle slides; a lateral deficit Δ of the acceleration the wheels ask holds
|v̂| ≈ Δ/L₁). The ground's force is then measured too: the lateral force m̂·(a_y − b̂_y) is
shared by the two drive wheels (the casters swivel: they carry none), so a wheel's utilisation
is √(F̂_k² + (m̂·(a_y − b̂_y)/2)²)/N̂_k, the friction circle's — during a skid its largest value
is the estimate, and without one the evidence that the peak is at least that. A skid the IMU
saw is kept for ``imu_memory`` metres before the estimate relaxes to the prior (without a
false alarm from the model's errors to forget, longer than ``memory``). A skid that outlasts
``max_spin_time`` was the observer's drift, not a skid: it ends for both wheels and the
observer takes up again at the encoders. Rows without a finite reading use the model's
observer.

Encoder quantisation (one tick of 2048 at 100 Hz is 2 cm/s of rim speed on the RM100) sets the
threshold: ``slip_speed`` 3 cm/s on the 50 ms-filtered slip speed. A spin lasts at least
:data:`MIN_SPIN_TIME`. The first spin is how the robot learns the ground: from rest its slip
*ratio* is large (centimetres per second of rim speed over millimetres per second of body
speed) before the cut takes hold.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike

from wheelbase._validate import finite
from wheelbase.control.slope import ROLLING_SPEED
from wheelbase.dynamics import GRAVITY, DiffDriveDynamics
from wheelbase.errors import ConfigError

__all__ = ["BIAS_RATE", "MIN_SPIN_TIME", "REST_TIME", "FrictionEstimator"]

BIAS_RATE = 0.1
"""The IMU's biases learn in motion at this share of the inertial observer's bandwidth."""

REST_TIME = 0.5
"""Time constant [s] of the IMU's biases learnt at rest (no encoder tick): what it reads then."""

MIN_SPIN_TIME = 0.2
"""Shortest spin [s]: the torque stays cut this long, and the 50 ms-filtered ground force
settles to what the sliding wheel transmits."""


class FrictionEstimator:
    """Per-wheel peak friction μ̂ from wheel rates, commanded torques and the model.

    Parameters
    ----------
    model : DiffDriveDynamics
        The controller's model (mass, yaw inertia, wheel radius, half track).
    wheel_inertia : float
        Spin inertia J_w of a drive wheel [kg·m²], > 0.
    drive_load_share : float
        Share s of the weight on the drive wheels, in (0, 1].
    initial : float
        Prior peak friction μ̂ before any spin, in (0, 3].
    floor : float
        Lowest estimate, in (0, ``initial``].
    rolling_resistance : float
        The drive wheels' rolling-resistance coefficient c_rr [-], in [0, 1): its moment
        c_rr·N̂·a is taken out of the torque, so μ̂ is the ground's grip alone (module
        docstring). 0: the estimate holds the rolling moment too.
    bandwidth : float
        Observer bandwidth ω_o [rad/s], > 0.
    slip_speed : float
        Slip speed threshold [m/s], > 0.
    slip_ratio : float
        Slip ratio added to the threshold (times the contact speed), ≥ 0.
    memory : float
        Distance [m] without a spin after which μ̂ relaxes to ``initial``, > 0.
    max_spin_time : float
        Longest a spin may last [s] before it is taken for a model error, > 0.
    inertial : bool
        Read the IMU's readings passed to :meth:`update` (module docstring).
    imu_bandwidth : float
        With the IMU: the inertial observer's bandwidth [rad/s], > 0.
    imu_slip_speed : float
        With the IMU: slip speed threshold [m/s], > 0 (a wheel's, and the lateral one).
    imu_slip_ratio : float
        With the IMU: slip ratio added to the threshold (times the ground speed), ≥ 0.
    imu_memory : float
        With the IMU: ``memory`` [m], > 0 (module docstring).

    Attributes
    ----------
    friction : numpy.ndarray, shape (N, 2)
        The estimate μ̂ (None before the first update).
    spinning : numpy.ndarray of bool, shape (N, 2)
        Which wheels spin now.
    spins : list of (float, int, int, float)
        Every spin that ended: (time it ended [s], robot, wheel 0 left / 1 right, μ̂ learnt).
    """

    def __init__(
        self,
        model: DiffDriveDynamics,
        *,
        wheel_inertia: float = 0.01,
        drive_load_share: float = 0.5,
        initial: float = 1.0,
        floor: float = 0.02,
        rolling_resistance: float = 0.0,
        bandwidth: float = 2.0,
        slip_speed: float = 0.03,
        slip_ratio: float = 0.1,
        memory: float = 5.0,
        max_spin_time: float = 2.0,
        inertial: bool = False,
        imu_bandwidth: float = 1.0,
        imu_slip_speed: float = 0.02,
        imu_slip_ratio: float = 0.05,
        imu_memory: float = 20.0,
    ) -> None:
        if not isinstance(model, DiffDriveDynamics):
            raise ConfigError(f"model must be a DiffDriveDynamics (got {type(model).__name__})")
        self.model = model
        self.wheel_inertia = _positive("wheel_inertia", wheel_inertia, "kg·m²")
        share = finite("drive_load_share", drive_load_share)
        if not 0.0 < share <= 1.0:
            raise ConfigError(f"drive_load_share must be in (0, 1] (got {share:g})")
        self.drive_load_share = share
        self.initial = finite("initial_friction", initial)
        if not 0.0 < self.initial <= 3.0:
            raise ConfigError(f"initial_friction must be in (0, 3] (got {self.initial:g})")
        self.floor = finite("floor", floor)
        if not 0.0 < self.floor <= self.initial:
            raise ConfigError(
                f"floor must be in (0, initial_friction = {self.initial:g}] (got {self.floor:g})"
            )
        c_rr = finite("rolling_resistance", rolling_resistance)
        if not 0.0 <= c_rr < 1.0:
            raise ConfigError(f"rolling_resistance must be in [0, 1) (got {c_rr:g})")
        self.rolling_resistance = c_rr
        self.bandwidth = _positive("bandwidth", bandwidth, "rad/s")
        self.slip_speed = _positive("slip_speed", slip_speed, "m/s")
        self.slip_ratio = finite("slip_ratio", slip_ratio)
        if self.slip_ratio < 0:
            raise ConfigError(f"slip_ratio must be ≥ 0 (got {self.slip_ratio:g})")
        self.memory = _positive("memory", memory, "m")
        self.max_spin_time = _positive("max_spin_time", max_spin_time, "s")
        if not isinstance(inertial, bool):
            raise ConfigError(f"inertial must be true or false (got {inertial!r})")
        self.inertial = inertial
        self.imu_bandwidth = _positive("imu_bandwidth", imu_bandwidth, "rad/s")
        self.imu_slip_speed = _positive("imu_slip_speed", imu_slip_speed, "m/s")
        self.imu_slip_ratio = finite("imu_slip_ratio", imu_slip_ratio)
        if self.imu_slip_ratio < 0:
            raise ConfigError(f"imu_slip_ratio must be ≥ 0 (got {self.imu_slip_ratio:g})")
        self.imu_memory = _positive("imu_memory", imu_memory, "m")
        body = model.body
        self._mass = float(body.mass)
        self._inertia = float(body.inertia_centroid)
        self.reset()

    @property
    def normal_load(self) -> float:
        """N̂ = s·m̂·g/2 [N]: the static load the model puts on a drive wheel."""
        return self.drive_load_share * self._mass * GRAVITY / 2.0

    def reset(self) -> None:
        """Forget everything (a new run)."""
        self._t: float | None = None
        self.friction: np.ndarray | None = None
        self.spinning: np.ndarray | None = None
        self.slip_speed_estimate: np.ndarray | None = None
        self.spins: list[tuple[float, int, int, float]] = []

    def _start(self, rim: np.ndarray, t: float) -> None:
        n = rim.shape[0]
        self._t = t
        self._rim = rim.copy()
        self._v = rim.copy()
        self._bias = np.zeros((n, 2))
        self._error = np.zeros((n, 2))
        self._force = np.zeros((n, 2))
        self._since = np.zeros((n, 2))
        self._spin_time = np.zeros((n, 2))
        self._event_peak = np.zeros((n, 2))
        self._before = np.full((n, 2), self.initial)
        self._evidence = np.zeros((n, 2))
        self.friction = np.full((n, 2), self.initial)
        self.spinning = np.zeros((n, 2), bool)
        self.slip_speed_estimate = np.zeros((n, 2))
        # the inertial observer: ground speed, lateral speed, biases (a_x, a_y, ω_z), lateral
        # force [N] (filtered) and lateral slip speed (filtered)
        self._ground = 0.5 * (rim[:, 0] + rim[:, 1])
        self._lateral = np.zeros(n)
        self._imu_bias = np.zeros((n, 3))
        self._side_force = np.zeros(n)
        self._side_slip = np.zeros(n)
        self._still = np.zeros(n)
        self.lateral_slip_estimate = np.zeros(n)

    def update(
        self, t: float, state: ArrayLike, torques: ArrayLike, imu: ArrayLike | None = None
    ) -> np.ndarray:
        """Advance to time ``t`` with the estimated state and the torques applied since the last
        call; the estimate μ̂ ``(N, 2)`` (left, right).

        Parameters
        ----------
        t : float
            Time [s].
        state : array_like, shape (N, 6)
            Estimated (x, y, θ, u, v, r); only u [m/s] and r [rad/s] are read.
        torques : array_like, shape (N, 2)
            Wheel torques [N·m] applied since the last call.
        imu : array_like, shape (N, 3), optional
            The IMU's last readings (ω_z [rad/s], a_x, a_y [m/s²]); read with ``inertial``
            (module docstring), NaN rows: none yet.
        """
        s = np.asarray(state, dtype=np.float64).reshape(-1, 6)
        d, a = self.model.half_track, self.model.wheel_radius
        rim = np.column_stack([s[:, 3] - d * s[:, 5], s[:, 3] + d * s[:, 5]])  # a·ω [m/s]
        if self._t is None or self.friction is None or self.friction.shape[0] != rim.shape[0]:
            self._start(rim, t)
            self._calibrate(s, imu)
            return self.friction.copy()
        dt = t - self._t
        if not dt > 0.0:
            if dt < 0.0:  # time went back: a new run
                self._start(rim, t)
            return self.friction.copy()
        tau = np.asarray(torques, dtype=np.float64).reshape(-1, 2)
        # the force the ground gives each wheel, from the wheel's own dynamics: the rolling
        # moment opposes the spin, it is no grip
        moment = self.rolling_resistance * self.normal_load * a * np.tanh(rim / ROLLING_SPEED)
        force = (tau - self.wheel_inertia * (rim - self._rim) / (a * dt) - moment) / a
        gain = min(1.0, dt / 0.05)
        self._force += gain * (force - self._force)
        # the body those forces push, at each wheel's contact
        u_dot = (force[:, 0] + force[:, 1]) / self._mass
        r_dot = d * (force[:, 1] - force[:, 0]) / self._inertia
        accel = np.column_stack([u_dot - d * r_dot, u_dot + d * r_dot])
        error = rim - self._v
        free = ~self.spinning  # a spinning wheel: the model alone, no corrections
        l1, l2 = 2.0 * self.bandwidth, self.bandwidth**2
        self._v += (accel + np.where(free, self._bias + l1 * error, 0.0)) * dt
        self._bias += np.where(free, l2 * error * dt, 0.0)
        error = rim - self._v
        reading = None
        if self.inertial and imu is not None:
            reading = np.asarray(imu, dtype=np.float64).reshape(-1, 3)
            if reading.shape[0] != rim.shape[0]:
                raise ConfigError(f"imu has {reading.shape[0]} rows for {rim.shape[0]} robots")
        lateral = np.zeros(rim.shape[0])
        measured = np.isfinite(reading).all(axis=1) if reading is not None else None
        if measured is not None and measured.any():
            inertial_error, lateral = self._inertial(s, rim, reading, dt, gain)
            error = np.where(measured[:, None], inertial_error, error)
            lateral = np.where(measured, lateral, 0.0)
        self._error += min(1.0, dt / 0.05) * (error - self._error)
        self._rim = rim
        self._t = t
        # a spin (or a lock): slip in the direction of the wheel's force
        direction = np.sign(self._force)
        along = self._error * direction
        threshold = self.slip_speed + self.slip_ratio * np.abs(self._v)
        if measured is not None and measured.any():  # the IMU measures the ground speed
            imu_threshold = self.imu_slip_speed + self.imu_slip_ratio * np.abs(self._ground)
            threshold = np.where(measured[:, None], imu_threshold[:, None], threshold)
        utilisation = np.abs(self._force) / self.normal_load
        side = np.zeros(rim.shape[0], bool)
        sideways = np.zeros(rim.shape[0], bool)
        if measured is not None and measured.any():
            # the friction circle: the lateral force the IMU measures, shared by the two wheels
            utilisation = np.where(
                measured[:, None],
                np.hypot(self._force, 0.5 * self._side_force[:, None]) / self.normal_load,
                utilisation,
            )
            lateral_threshold = self.imu_slip_speed + self.imu_slip_ratio * np.abs(self._ground)
            side = measured & (lateral > lateral_threshold)
            sideways = measured & (lateral < 0.5 * lateral_threshold)
        starts = ~self.spinning & (
            ((along > threshold) & (direction != 0)) | side[:, None]
        )  # fmt: skip
        self._before = np.where(starts, self.friction, self._before)
        self._event_peak = np.where(starts, 0.0, self._event_peak)
        self._spin_time = np.where(starts, 0.0, self._spin_time)
        self.spinning = self.spinning | starts
        self._event_peak = np.where(
            self.spinning, np.maximum(self._event_peak, utilisation), self._event_peak
        )
        # the ground gave this much without a spin lately: the peak is at least that
        learnt = np.clip(np.maximum(self._event_peak, self._evidence), self.floor, self._before)
        self.friction = np.where(self.spinning, learnt, self.friction)
        # a spin is news of the floor under both wheels: the other keeps no more than it shows
        taught = np.where(self.spinning, self.friction, np.inf).min(axis=1, keepdims=True)
        shown = np.maximum(taught, np.maximum(self._evidence, self.floor))
        lowered = ~self.spinning & (shown < self.friction)
        self.friction = np.where(lowered, shown, self.friction)
        self._since = np.where(lowered, 0.0, self._since)
        self._spin_time += np.where(self.spinning, dt, 0.0)
        regripped = (along < 0.5 * threshold) & (self._spin_time >= MIN_SPIN_TIME)
        if measured is not None and measured.any():
            regripped &= np.where(measured, sideways, True)[:, None]
        timed_out = self.spinning & (self._spin_time > self.max_spin_time)
        if measured is not None and measured.any():  # the inertial observer lost the axle
            timed_out = self.spinning & (timed_out.any(axis=1) & measured)[:, None]
        ends = self.spinning & (regripped | timed_out)
        for robot, wheel in zip(*np.nonzero(ends), strict=True):
            self.spins.append((t, int(robot), int(wheel), float(self.friction[robot, wheel])))
        self.spinning = self.spinning & ~ends
        self._v = np.where(ends, rim, self._v)  # the observer takes up again where the wheel is
        if measured is not None and measured.any():  # and the inertial one where the axle is
            over = (ends.any(axis=1) & ~self.spinning.any(axis=1)) | timed_out.any(axis=1)
            self._ground = np.where(over, s[:, 3], self._ground)
            self._lateral = np.where(over, 0.0, self._lateral)
        # memory: friction relaxes to the prior after `memory` metres without a spin
        travelled = np.abs(rim) * dt
        fading = self._evidence * np.maximum(1.0 - travelled / self.memory, 0.0)
        self._evidence = np.where(self.spinning, fading, np.maximum(fading, utilisation))
        self._since = np.where(self.spinning, 0.0, self._since + travelled)
        memory = self.memory
        if measured is not None and measured.any():
            memory = np.where(measured, self.imu_memory, self.memory)[:, None]
        relax = (self._since > memory) & ~self.spinning
        self.friction = np.where(
            relax, self.friction + (self.initial - self.friction) * np.minimum(travelled, 1.0),
            self.friction,
        )  # fmt: skip
        self.slip_speed_estimate = self._error.copy()
        return self.friction.copy()

    def _calibrate(self, state: np.ndarray, imu: ArrayLike | None) -> None:
        """The IMU's biases from its first reading, the start taken as steady motion (at rest:
        the reading is all bias)."""
        if not self.inertial or imu is None:
            return
        z = np.asarray(imu, dtype=np.float64).reshape(-1, 3)
        if z.shape[0] != state.shape[0]:
            return
        steady = np.column_stack([np.zeros(state.shape[0]), state[:, 3] * state[:, 5],
                                  state[:, 5]])  # fmt: skip
        bias = z[:, [1, 2, 0]] - steady
        self._imu_bias = np.where(np.isfinite(bias), bias, 0.0)

    def _inertial(
        self, state: np.ndarray, rim: np.ndarray, reading: np.ndarray, dt: float, gain: float
    ) -> tuple[np.ndarray, np.ndarray]:
        """One step of the inertial observer (module docstring): each wheel's slip speed
        ``(N, 2)`` against its contact's ground speed, and the filtered lateral slip speed
        ``(N,)`` [m/s]. Rows without a finite reading are left as they were."""
        ok = np.isfinite(reading).all(axis=1)
        z = np.where(ok[:, None], reading, 0.0)
        d = self.model.half_track
        u_enc, r_enc = state[:, 3], state[:, 5]
        grip = ~self.spinning.any(axis=1) & ok  # every wheel grips: the biases may learn
        # the start-up calibration took the biases: in motion they learn only what drifts, ten
        # times slower than the observer follows the wheels
        l1, l2 = 2.0 * self.imu_bandwidth, (BIAS_RATE * self.imu_bandwidth) ** 2
        bias = self._imu_bias
        yaw = z[:, 0] - bias[:, 2]
        fx, fy = z[:, 1] - bias[:, 0], z[:, 2] - bias[:, 1]
        along = u_enc - self._ground
        ground = self._ground + (fx + self._lateral * yaw + np.where(grip, l1 * along, 0.0)) * dt
        lateral = self._lateral + (fy - self._ground * yaw - np.where(grip, l1 * self._lateral,
                                                                       0.0)) * dt  # fmt: skip
        learn = np.where(grip, dt, 0.0)
        # the accelerometers' biases are learnt while every wheel grips;
        # the gyro's only at rest, where it must read 0: in motion a slow skid would be learnt
        bias = bias + np.column_stack([-l2 * along * learn, l2 * self._lateral * learn,
                                       np.zeros_like(along)])  # fmt: skip
        # at rest: no tick on either wheel for REST_TIME (a start under torque is not rest)
        self._still = np.where(ok & (u_enc == 0.0) & (r_enc == 0.0), self._still + dt, 0.0)
        rest = self._still >= REST_TIME
        settle = min(1.0, dt / REST_TIME)
        at_rest = z[:, [1, 2, 0]]  # (a_x, a_y, ω_z): all bias at rest
        bias = np.where(rest[:, None], bias + settle * (at_rest - bias), bias)
        self._ground = np.where(ok & ~rest, ground, np.where(rest, 0.0, self._ground))
        self._lateral = np.where(ok & ~rest, lateral, np.where(rest, 0.0, self._lateral))
        self._imu_bias = np.where(ok[:, None], bias, self._imu_bias)
        side = self._mass * fy
        self._side_force = np.where(ok, self._side_force + gain * (side - self._side_force),
                                    self._side_force)  # fmt: skip
        self._side_slip = np.where(
            ok, self._side_slip + gain * (np.abs(self._lateral) - self._side_slip),
            self._side_slip,
        )  # fmt: skip
        self.lateral_slip_estimate = self._side_slip.copy()
        contact = np.column_stack([self._ground - d * yaw, self._ground + d * yaw])
        return rim - contact, self._side_slip.copy()


def _positive(name: str, value: float, unit: str) -> float:
    number = finite(name, value, unit)
    if not number > 0.0 or math.isinf(number):
        raise ConfigError(f"{name} must be > 0 {unit} (got {number:g})")
    return number
