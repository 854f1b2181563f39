"""DC gear-motors driving the wheels, and the wheel speed loop of document 003.

Document 003 (§II, Fig. 1) splits the work between a microprocessor that computes wheel-speed
set-points in RPM and an 8-bit microcontroller that counts encoder ticks, measures the RPM and
drives each motor with PWM. This module models that lower level:

:class:`DCMotor`
    A permanent-magnet DC motor with its gearbox, all quantities referred to the wheel shaft.
    State ``(i, ω, φ)``: armature current [A], wheel speed [rad/s], wheel angle [rad]::

        L di/dt = V − R i − k_e ω            V = duty · V_supply, duty ∈ [−1, 1]
        J dω/dt = k_t i − b ω − τ_load
          dφ/dt = ω

    With ``inductance = 0`` the current follows the voltage at once, i = (V − k_e ω)/R, and the
    state keeps i only as an output. The equations are linear, so a step with the duty and load
    held constant (the PWM is updated once per speed-loop period: a zero-order hold) is solved
    exactly with a matrix exponential (:meth:`DCMotor.step`); no step-size limit applies.
:class:`SpeedLoop`
    A PI controller from RPM error to duty with a feed-forward term and anti-windup by
    conditional integration, run at its own period as the microcontroller does.

The PWM is averaged (the motor sees the mean voltage duty·V_supply; the electrical time constant
L/R is much longer than a PWM period of a few tens of microseconds).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

import numpy as np
from numpy.typing import ArrayLike
from scipy.linalg import expm

from wheelbase._validate import as_float_array, nonnegative, positive
from wheelbase.errors import ConfigError

__all__ = ["MOTOR_PRESETS", "DCMotor", "SpeedLoop"]


@dataclass(frozen=True)
class DCMotor:
    """A DC gear-motor driving one wheel; parameters referred to the wheel shaft.

    Parameters
    ----------
    resistance : float
        Armature resistance R [Ω], > 0.
    torque_constant : float
        k_t [N·m/A] at the wheel (motor constant × gear ratio × gearbox efficiency), > 0.
    back_emf_constant : float
        k_e [V·s/rad] at the wheel (motor constant × gear ratio), > 0.
    inertia : float
        J [kg·m²] at the wheel: rotor × gear ratio² + wheel + the share of the robot's mass
        (m·r²/2 for two driven wheels), > 0.
    viscous_friction : float
        b [N·m·s/rad] at the wheel, >= 0.
    supply_voltage : float
        V_supply [V], > 0; duty 1 applies it in full.
    inductance : float
        L [H], >= 0 (0: the current follows the voltage instantly).

    Examples
    --------
    >>> motor = MOTOR_PRESETS["gearmotor_12v"]
    >>> round(motor.no_load_speed * 60 / (2 * np.pi))  # RPM at full duty
    374
    """

    resistance: float
    torque_constant: float
    back_emf_constant: float
    inertia: float
    viscous_friction: float = 0.0
    supply_voltage: float = 12.0
    inductance: float = 0.0

    def __post_init__(self) -> None:
        for name, unit in (
            ("resistance", "ohm"),
            ("torque_constant", "N*m/A"),
            ("back_emf_constant", "V*s/rad"),
            ("inertia", "kg*m^2"),
            ("supply_voltage", "V"),
        ):
            object.__setattr__(self, name, positive(name, getattr(self, name), unit))
        object.__setattr__(
            self,
            "viscous_friction",
            nonnegative("viscous_friction", self.viscous_friction, "N*m*s/rad"),
        )
        object.__setattr__(self, "inductance", nonnegative("inductance", self.inductance, "H"))

    @property
    def no_load_speed(self) -> float:
        """Steady wheel speed [rad/s] at full duty and no load: k_t V/(k_t k_e + b R)."""
        return self.steady_speed(1.0)

    @property
    def stall_torque(self) -> float:
        """Torque [N·m] at full duty with the wheel held: k_t V/R."""
        return self.torque_constant * self.supply_voltage / self.resistance

    @property
    def time_constant(self) -> float:
        """Mechanical time constant [s] J R/(k_t k_e + b R) (with L = 0)."""
        r = self.resistance
        return (
            self.inertia
            * r
            / (self.torque_constant * self.back_emf_constant + self.viscous_friction * r)
        )

    def steady_speed(self, duty: ArrayLike, load_torque: ArrayLike = 0.0) -> np.ndarray:
        """Steady wheel speed [rad/s] for a duty held constant.

        Parameters
        ----------
        duty : array_like
            PWM duty, clipped to [−1, 1].
        load_torque : array_like
            Load torque at the wheel [N·m].
        """
        volts = self.voltage(duty)
        load = as_float_array("load_torque", load_torque)
        r, kt = self.resistance, self.torque_constant
        return (kt * volts / r - load) / (kt * self.back_emf_constant / r + self.viscous_friction)

    def voltage(self, duty: ArrayLike) -> np.ndarray:
        """Mean armature voltage [V] = clip(duty, −1, 1)·V_supply."""
        return np.clip(as_float_array("duty", duty), -1.0, 1.0) * self.supply_voltage

    def derivative(
        self, state: ArrayLike, duty: ArrayLike, load_torque: ArrayLike = 0.0
    ) -> np.ndarray:
        """Time derivative of the state ``(..., 3)`` = (i, ω, φ).

        Parameters
        ----------
        state : array_like, shape (..., 3)
            Current [A], wheel speed [rad/s], wheel angle [rad].
        duty : array_like
            PWM duty in [−1, 1] (clipped), broadcast against ``state[..., 0]``.
        load_torque : array_like
            Load torque at the wheel [N·m].

        Returns
        -------
        numpy.ndarray, shape (..., 3)
            (di/dt, dω/dt, dφ/dt); with L = 0, di/dt is 0 and i is taken as (V − k_e ω)/R.
        """
        state = as_float_array("state", state, 3)
        volts = self.voltage(duty)
        load = as_float_array("load_torque", load_torque)
        omega = state[..., 1]
        if self.inductance == 0.0:
            current = (volts - self.back_emf_constant * omega) / self.resistance
            di = np.zeros_like(current)
        else:
            current = state[..., 0]
            di = (volts - self.resistance * current - self.back_emf_constant * omega) / (
                self.inductance
            )
        domega = (self.torque_constant * current - self.viscous_friction * omega - load) / (
            self.inertia
        )
        return np.stack(np.broadcast_arrays(di, domega, omega), -1)

    def step(
        self,
        state: ArrayLike,
        duty: ArrayLike,
        dt: float,
        load_torque: ArrayLike = 0.0,
    ) -> np.ndarray:
        """Advance the state exactly over ``dt`` with duty and load held constant.

        Parameters
        ----------
        state : array_like, shape (..., 3)
            (i [A], ω [rad/s], φ [rad]) at the start.
        duty : array_like
            PWM duty in [−1, 1] (clipped), held over the step.
        dt : float
            Step [s], > 0 (any length: the solution is the matrix exponential).
        load_torque : array_like
            Load torque at the wheel [N·m], held over the step.

        Returns
        -------
        numpy.ndarray, shape (..., 3)
            The state at the end of the step.
        """
        state = as_float_array("state", state, 3)
        dt = positive("dt", dt, "s")
        volts = self.voltage(duty)
        load = as_float_array("load_torque", load_torque)
        a_d, b_d = _discrete(self, dt)
        if self.inductance == 0.0:
            x = state[..., 1:]
            new = x @ a_d.T + volts[..., None] * b_d[:, 0] + load[..., None] * b_d[:, 1]
            current = (volts - self.back_emf_constant * new[..., 0]) / self.resistance
            out = np.concatenate([np.asarray(current)[..., None], new], -1)
            return np.broadcast_to(out, np.broadcast_shapes(out.shape, state.shape)).copy()
        new = state @ a_d.T + volts[..., None] * b_d[:, 0] + load[..., None] * b_d[:, 1]
        return new


@lru_cache(maxsize=64)
def _discrete(motor: DCMotor, dt: float) -> tuple[np.ndarray, np.ndarray]:
    """Zero-order-hold discretisation (A_d, B_d) of the motor, inputs (V, τ_load)."""
    r, kt, ke, j, b = (
        motor.resistance,
        motor.torque_constant,
        motor.back_emf_constant,
        motor.inertia,
        motor.viscous_friction,
    )
    if motor.inductance == 0.0:
        a = np.array([[-(b + kt * ke / r) / j, 0.0], [1.0, 0.0]])
        bm = np.array([[kt / (r * j), -1.0 / j], [0.0, 0.0]])
    else:
        ind = motor.inductance
        a = np.array([[-r / ind, -ke / ind, 0.0], [kt / j, -b / j, 0.0], [0.0, 1.0, 0.0]])
        bm = np.array([[1.0 / ind, 0.0], [0.0, -1.0 / j], [0.0, 0.0]])
    n = a.shape[0]
    block = np.zeros((n + 2, n + 2))
    block[:n, :n], block[:n, n:] = a, bm
    full = expm(block * dt)
    return full[:n, :n], full[:n, n:]


# Presets with plausible small-robot values, referred to the wheel shaft:
# - "gearmotor_12v": a 12 V brushed gear-motor of the 37 mm class (≈ 30:1), on a robot of about
#   2 kg with 35 mm wheels: R = 2 Ω, k_t = k_e = 0.3 (ideal gearbox), L = 1 mH (L/R = 0.5 ms),
#   J = 2e-3 kg·m² (rotor reflected + wheel + m r²/2), b = 1e-3 N·m·s/rad. No-load speed
#   ≈ 374 RPM, stall torque 1.8 N·m, mechanical time constant ≈ 43 ms.
# - "tt_6v": the yellow 1:48 "TT" hobby gear-motor at 6 V: R = 4 Ω, k_e = 0.28 V·s/rad,
#   k_t = 0.1 N·m/A (the plastic gearbox loses about two thirds), J = 5e-4 kg·m², b = 2e-4,
#   L = 0: ≈ 200 RPM no-load, 0.15 N·m stall.
MOTOR_PRESETS: dict[str, DCMotor] = {
    "gearmotor_12v": DCMotor(
        resistance=2.0,
        torque_constant=0.3,
        back_emf_constant=0.3,
        inertia=2e-3,
        viscous_friction=1e-3,
        supply_voltage=12.0,
        inductance=1e-3,
    ),
    "tt_6v": DCMotor(
        resistance=4.0,
        torque_constant=0.1,
        back_emf_constant=0.28,
        inertia=5e-4,
        viscous_friction=2e-4,
        supply_voltage=6.0,
        inductance=0.0,
    ),
}


@dataclass(frozen=True)
class SpeedLoop:
    """PI wheel-speed loop on RPM with feed-forward and anti-windup (document 003 §II).

    duty = k_ff·RPM* + k_p·e + k_i·∫e dt, with e = RPM* − RPM_measured, saturated to [−1, 1].
    Anti-windup by conditional integration: the integral is not advanced in a period where the
    output is saturated and the error would push it further into saturation.

    Parameters
    ----------
    kp : float
        Proportional gain [duty/RPM], >= 0 (a negative gain would be positive feedback).
    ki : float
        Integral gain [duty/(RPM·s)], >= 0 (0: a P loop, as document 003's proportional control).
    period : float
        Loop period [s], > 0: the microcontroller measures the RPM over it (eq. 6 generalised)
        and holds the duty for it.
    feedforward : float
        k_ff [duty/RPM], >= 0, typically 1/(no-load RPM at full duty).

    Examples
    --------
    >>> loop = SpeedLoop(kp=0.01, ki=0.1, period=0.01)
    >>> duty, integral = loop.update(0.0, setpoint_rpm=100.0, measured_rpm=90.0)
    >>> round(float(duty), 3), round(float(integral), 3)
    (0.11, 0.1)
    """

    kp: float
    ki: float = 0.0
    period: float = 0.01
    feedforward: float = 0.0

    def __post_init__(self) -> None:
        for name, unit in (("kp", "duty/RPM"), ("ki", "duty/(RPM*s)"), ("feedforward", "duty/RPM")):
            value = getattr(self, name)
            number = nonnegative(name, value, unit)
            object.__setattr__(self, name, number)
        if self.kp == 0.0 and self.ki == 0.0 and self.feedforward == 0.0:
            raise ConfigError("kp, ki and feedforward cannot all be 0 (the loop would do nothing)")
        object.__setattr__(self, "period", positive("period", self.period, "s"))

    @classmethod
    def for_motor(cls, motor: DCMotor, period: float = 0.01) -> SpeedLoop:
        """A PI loop tuned for ``motor``: feed-forward 1/no-load RPM, PI on the time constant.

        Parameters
        ----------
        motor : DCMotor
            The motor to drive.
        period : float
            Loop period [s], > 0.
        """
        rpm_max = motor.no_load_speed * 60.0 / (2.0 * math.pi)
        tau = max(motor.time_constant, positive("period", period, "s"))
        kp = 2.0 / rpm_max  # closed-loop bandwidth about 3× the open loop
        return cls(kp=kp, ki=kp / tau, period=period, feedforward=1.0 / rpm_max)

    def update(
        self, integral: ArrayLike, setpoint_rpm: ArrayLike, measured_rpm: ArrayLike
    ) -> tuple[np.ndarray, np.ndarray]:
        """One period of the loop.

        Parameters
        ----------
        integral : array_like
            ∫e dt so far [RPM·s] (0 at start), one per wheel.
        setpoint_rpm : array_like
            Wheel-speed set-points [RPM].
        measured_rpm : array_like
            Measured wheel speeds [RPM] over the last period.

        Returns
        -------
        tuple of numpy.ndarray
            The duty in [−1, 1] to hold for the next period, and the new integral.
        """
        integral = as_float_array("integral", integral)
        setpoint = as_float_array("setpoint_rpm", setpoint_rpm)
        measured = as_float_array("measured_rpm", measured_rpm)
        error = setpoint - measured
        base = self.feedforward * setpoint + self.kp * error
        trial = integral + error * self.period
        raw = base + self.ki * trial
        winding = (np.abs(raw) > 1.0) & (np.sign(error) == np.sign(raw))
        integral = np.where(winding, integral, trial)
        duty = np.clip(base + self.ki * integral, -1.0, 1.0)
        return duty, integral
