"""An online estimate of the friction under each drive wheel, from what the controller observes.

Traction control (:class:`~wheelbase.control.traction.TractionControl`, ``friction="estimate"``)
needs the peak friction μ_p of the ground, which the robot is not told. What it observes: the
wheel rates ω_k that its encoders imply (from the estimated twist, u ∓ d·r = a·ω_k), the torques
τ_k it commanded one control period before, and its own model (mass m̂, yaw inertia Î_B, wheel
radius a, half track d, the wheels' spin inertia J_w, the share s of the weight on the drive
wheels). Never the terrain.

**Ground force.** A wheel's own dynamics J_w·ω̇_k = τ_k − a·F_k hold whether it slips or not,
so the force the ground gives it is F̂_k = (τ_k − J_w·Δω_k/Δt)/a, and its friction utilisation
F̂_k/N̂_k with N̂_k = s·m̂·g/2.

**Slip, as a traction control system measures it.** A car's TCS compares the driven wheels with
the undriven ones; a differential-drive robot has no undriven wheel it measures, so the ground
speed of each wheel's contact comes from the model instead: the body pushed by the forces F̂_k,

    u̇ = (F̂_L + F̂_R)/m̂,   ṙ = d·(F̂_R − F̂_L)/Î_B,   v̂̇_k = u̇ ∓ d·ṙ + b̂_k + L₁·e_k,
    ḃ_k = L₂·e_k,   e_k = a·ω_k − v̂_k,

a Luenberger observer of the contact speed v̂_k with a bias b̂_k that learns what the model
lacks (rolling resistance, a slope, a payload the model does not carry) at the bandwidth ω_o
(L₁ = 2ζω_o, L₂ = ω_o², ζ = 1). A wheel that rolls has e ≈ 0; a wheel that spins (or locks)
turns faster (or slower) than the body the forces push: its slip speed e grows. Where the
filtered e_k exceeds ``slip_speed`` + ``slip_ratio``·|v̂_k| *in the direction of the wheel's
force* (driving: faster; braking: slower), the wheel is *spinning*: the observer stops its
corrections (so the spin is not learnt as a bias), and the estimate of that wheel's peak
friction becomes the largest utilisation the ground gave during the spin, μ̂_k =
max |F̂_k|/N̂_k (a wheel past its peak transmits between its sliding and peak friction), never
above what it was, and never below the utilisation it transmitted without spinning over the
last ``memory`` metres (fading with the distance): a false alarm — the end of a slope, whose
pull the bias still holds — cannot take away grip the wheel has shown. The spin ends when e
falls below half the threshold (or after ``max_spin_time``: a bias the observer could not
follow, not a spin).

The directional test makes the model's errors err on the safe side: a heavier robot than the
model (a payload), rolling resistance or an uphill slow the body down, so its wheels turn slower
than the model says while driving and faster while braking — the opposite of a spin or a lock.

**Memory.** Friction only falls on evidence. After ``memory`` metres without a spin the
estimate relaxes back towards the prior ``initial`` (by the distance travelled over 1 m), so a
robot that has left the ice for concrete regains its grip — and on ice it probes the peak again,
a brief spin every ``memory`` metres.

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
from wheelbase.dynamics import GRAVITY, DiffDriveDynamics
from wheelbase.errors import ConfigError

__all__ = ["MIN_SPIN_TIME", "FrictionEstimator"]

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
        bandwidth: float = 2.0,
        slip_speed: float = 0.03,
        slip_ratio: float = 0.1,
        memory: float = 5.0,
        max_spin_time: float = 2.0,
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
        self.bandwidth = _positive("bandwidth", bandwidth, "rad/s")
        self.slip_speed = _positive("slip_speed", slip_speed, "m/s")
        self.slip_ratio = finite("slip_ratio", slip_ratio)
        if self.slip_ratio < 0:
            raise ConfigError(f"slip_ratio must be ≥ 0 (got {self.slip_ratio:g})")
        self.memory = _positive("memory", memory, "m")
        self.max_spin_time = _positive("max_spin_time", max_spin_time, "s")
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

    def update(self, t: float, state: ArrayLike, torques: ArrayLike) -> np.ndarray:
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
        """
        s = np.asarray(state, dtype=np.float64).reshape(-1, 6)
        d, a = self.model.half_track, self.model.wheel_radius
        rim = np.column_stack([s[:, 3] - d * s[:, 5], s[:, 3] + d * s[:, 5]])  # a·ω [m/s]
        if self._t is None or self.friction is None or self.friction.shape[0] != rim.shape[0]:
            self._start(rim, t)
            return self.friction.copy()
        dt = t - self._t
        if not dt > 0.0:
            if dt < 0.0:  # time went back: a new run
                self._start(rim, t)
            return self.friction.copy()
        tau = np.asarray(torques, dtype=np.float64).reshape(-1, 2)
        # the force the ground gives each wheel, from the wheel's own dynamics
        force = (tau - self.wheel_inertia * (rim - self._rim) / (a * dt)) / a
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
        self._error += min(1.0, dt / 0.05) * (error - self._error)
        self._rim = rim
        self._t = t
        # a spin (or a lock): slip in the direction of the wheel's force
        direction = np.sign(self._force)
        along = self._error * direction
        threshold = self.slip_speed + self.slip_ratio * np.abs(self._v)
        utilisation = np.abs(self._force) / self.normal_load
        starts = ~self.spinning & (along > threshold) & (direction != 0)
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
        self._spin_time += np.where(self.spinning, dt, 0.0)
        regripped = (along < 0.5 * threshold) & (self._spin_time >= MIN_SPIN_TIME)
        ends = self.spinning & (regripped | (self._spin_time > self.max_spin_time))
        for robot, wheel in zip(*np.nonzero(ends), strict=True):
            self.spins.append((t, int(robot), int(wheel), float(self.friction[robot, wheel])))
        self.spinning = self.spinning & ~ends
        self._v = np.where(ends, rim, self._v)  # the observer takes up again where the wheel is
        # memory: friction relaxes to the prior after `memory` metres without a spin
        travelled = np.abs(rim) * dt
        fading = self._evidence * np.maximum(1.0 - travelled / self.memory, 0.0)
        self._evidence = np.where(self.spinning, fading, np.maximum(fading, utilisation))
        self._since = np.where(self.spinning, 0.0, self._since + travelled)
        relax = (self._since > self.memory) & ~self.spinning
        self.friction = np.where(
            relax, self.friction + (self.initial - self.friction) * np.minimum(travelled, 1.0),
            self.friction,
        )  # fmt: skip
        self.slip_speed_estimate = self._error.copy()
        return self.friction.copy()


def _positive(name: str, value: float, unit: str) -> float:
    number = finite(name, value, unit)
    if not number > 0.0 or math.isinf(number):
        raise ConfigError(f"{name} must be > 0 {unit} (got {number:g})")
    return number
