"""Law 8: trajectory tracking — follow a reference pose that moves with time.

The reference gives, at each time t, a pose (x_r, y_r, θ_r) and the unicycle inputs (v_r, ω_r)
that produce it — document 002 eq. 10 computes them from a desired x(t), y(t)
(:func:`wheelbase.models.reference_from_xy`). The tracking error in the robot frame is

    e_x = cos θ·(x_r − x) + sin θ·(y_r − y)
    e_y = −sin θ·(x_r − x) + cos θ·(y_r − y)
    e_θ = wrap(θ_r − θ)

(Klančar et al. 2017 §3.3; Kanayama et al. 1990), and two laws close the loop:

=========================  =================================================================
:class:`LinearTracker`     v = v_r cos e_θ + K_x e_x, ω = ω_r + K_y e_y + K_θ e_θ with
                           K_x = K_θ = 2ζ√(ω_r² + g v_r²), K_y = g·v_r: the error dynamics
                           linearised about e = 0 get the poles −ζω_n ± ω_n√(ζ² − 1) and
                           −2ζω_n, ω_n = √(ω_r² + g v_r²) (Klančar et al. eq. 3.48)
:class:`Kanayama`          v = v_r cos e_θ + K_x e_x, ω = ω_r + v_r (K_y e_y + K_θ sin e_θ),
                           globally stable for K_x, K_y, K_θ > 0 and v_r > 0 (Lyapunov
                           V = (e_x² + e_y²)/2 + (1 − cos e_θ)/K_y; Kanayama et al. 1990)
=========================  =================================================================

The linear tracker's gains vanish with v_r = ω_r = 0 (no motion to track): it raises then.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, ClassVar

import numpy as np
from numpy.typing import ArrayLike

from wheelbase._validate import as_float_array, finite, nonnegative, positive
from wheelbase.control.base import VELOCITY_COMMAND, VelocityLimits, saturate_velocity
from wheelbase.errors import ConfigError, InputError
from wheelbase.geometry import wrap_angle

__all__ = ["Kanayama", "LinearTracker", "sample_reference", "tracking_errors"]


def sample_reference(reference: Any, t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Reference pose ``(..., 3)``, v_r and ω_r at time ``t`` [s].

    Parameters
    ----------
    reference : PoseTrajectory, callable or tuple
        - an object with arrays ``t`` (T,), ``poses`` (T, 3), ``v`` (T,), ``omega`` (T,), such
          as :class:`wheelbase.models.PoseTrajectory`: linearly interpolated in time (heading
          unwrapped), held at its ends;
        - a callable ``f(t) -> (pose, v_r, ω_r)``;
        - a tuple ``(pose, v_r, ω_r)`` already sampled.
    t : float
        Time [s].
    """
    if hasattr(reference, "poses") and hasattr(reference, "omega"):
        times = getattr(reference, "t", None)
        if times is None:
            raise InputError("a PoseTrajectory needs times t to be sampled by a tracker")
        poses = np.asarray(reference.poses, dtype=np.float64)
        heading = np.unwrap(poses[:, 2])
        x = np.interp(t, times, poses[:, 0])
        y = np.interp(t, times, poses[:, 1])
        theta = np.interp(t, times, heading)
        pose = np.array([x, y, float(wrap_angle(theta))])
        v = np.interp(t, times, np.asarray(reference.v, dtype=np.float64))
        omega = np.interp(t, times, np.asarray(reference.omega, dtype=np.float64))
        return pose, np.asarray(v), np.asarray(omega)
    if callable(reference):
        reference = reference(t)
    try:
        pose, v, omega = reference
    except (TypeError, ValueError):
        raise InputError(
            "a tracking reference must be a PoseTrajectory, a callable t -> (pose, v, omega) "
            f"or a tuple (pose, v, omega) (got {type(reference).__name__})"
        ) from None
    pose = as_float_array("reference pose", pose, 3)
    return pose, as_float_array("v_r", v), as_float_array("omega_r", omega)


def tracking_errors(pose: ArrayLike, reference_pose: ArrayLike) -> np.ndarray:
    """Errors ``(..., 3)`` = (e_x [m], e_y [m], e_θ [rad]) of the reference in the robot frame.

    e_x is along the robot's heading, e_y to its left (see the module docstring).

    Parameters
    ----------
    pose : array_like, shape (..., 3)
        Robot poses (x [m], y [m], θ [rad]).
    reference_pose : array_like, shape (..., 3)
        Reference poses, broadcast against ``pose``.
    """
    pose = as_float_array("pose", pose, 3)
    ref = as_float_array("reference pose", reference_pose, 3)
    dx, dy = ref[..., 0] - pose[..., 0], ref[..., 1] - pose[..., 1]
    c, s = np.cos(pose[..., 2]), np.sin(pose[..., 2])
    e_theta = wrap_angle(ref[..., 2] - pose[..., 2])
    return np.stack(np.broadcast_arrays(c * dx + s * dy, -s * dx + c * dy, e_theta), -1)


@dataclass(frozen=True)
class _Tracker:
    command_names: ClassVar[tuple[str, ...]] = VELOCITY_COMMAND
    limits: VelocityLimits | None = field(default=None, kw_only=True)

    def reset(self) -> None:
        """Nothing to forget: the trackers are static laws."""

    def __call__(
        self, t: float, pose: ArrayLike, reference: Any | Callable[[float], Any]
    ) -> np.ndarray:
        """Command ``(v [m/s], ω [rad/s])`` of shape ``(..., 2)``.

        Parameters
        ----------
        t : float
            Time [s].
        pose : array_like, shape (..., 3)
            Measured poses.
        reference : PoseTrajectory, callable or tuple
            See :func:`sample_reference`.
        """
        pose = as_float_array("pose", pose, 3)
        ref_pose, v_r, omega_r = sample_reference(reference, float(t))
        e = tracking_errors(pose, ref_pose)
        v, omega = self._law(e[..., 0], e[..., 1], e[..., 2], v_r, omega_r)
        return saturate_velocity(np.stack(np.broadcast_arrays(v, omega), -1), self.limits)


@dataclass(frozen=True)
class LinearTracker(_Tracker):
    """Tracking law from the error dynamics linearised about the reference (law 8a).

    Parameters
    ----------
    zeta : float
        Damping ratio ζ [-], > 0 (0 < ζ < 1 for the usual underdamped design).
    g : float
        g [1/m²], > 0; K_y = g·v_r.
    min_natural_frequency : float
        a_min [rad/s], >= 0: K_x = K_θ = 2ζ·max(√(ω_r² + g·v_r²), a_min). The textbook law
        (a_min = 0) has no gain at all when the reference stands still — at the start and the
        end of every trajectory — and could not even hold the final heading; with a_min > 0
        the x and heading errors keep being corrected there (K_y = g·v_r stays 0: a
        nonholonomic robot cannot correct a sideways error without moving).
    limits : VelocityLimits, optional
        Command limits.

    Raises
    ------
    InputError
        When called with v_r = ω_r = 0 and ``min_natural_frequency`` = 0: the gains vanish and
        nothing is controlled.
    """

    zeta: float = 0.7
    g: float = 60.0
    min_natural_frequency: float = 0.5

    def __post_init__(self) -> None:
        object.__setattr__(self, "zeta", positive("zeta", self.zeta, ""))
        object.__setattr__(self, "g", positive("g", self.g, "1/m²"))
        object.__setattr__(
            self,
            "min_natural_frequency",
            nonnegative("min_natural_frequency", self.min_natural_frequency, "rad/s"),
        )

    def gains(self, v_r: ArrayLike, omega_r: ArrayLike) -> tuple[np.ndarray, ...]:
        """(K_x, K_y, K_θ) for the reference inputs.

        Parameters
        ----------
        v_r : array_like
            Reference speed [m/s].
        omega_r : array_like
            Reference yaw rate [rad/s].
        """
        v_r, omega_r = np.asarray(v_r, float), np.asarray(omega_r, float)
        natural = np.maximum(np.sqrt(omega_r**2 + self.g * v_r**2), self.min_natural_frequency)
        k = 2.0 * self.zeta * natural
        return k, self.g * v_r, k

    def _law(self, e_x, e_y, e_theta, v_r, omega_r):
        if self.min_natural_frequency == 0.0 and np.any((v_r == 0.0) & (omega_r == 0.0)):
            raise InputError(
                "LinearTracker needs a moving reference: v_r = omega_r = 0 makes every gain 0 "
                "(use a pose controller to hold a pose)"
            )
        k_x, k_y, k_theta = self.gains(v_r, omega_r)
        v = v_r * np.cos(e_theta) + k_x * e_x
        return v, omega_r + k_y * e_y + k_theta * e_theta


@dataclass(frozen=True)
class Kanayama(_Tracker):
    """Kanayama et al. 1990 tracking law (law 8b).

    v = v_r·cos e_θ + K_x·e_x, ω = ω_r + v_r·K_y·e_y + |v_r|·K_θ·sin e_θ. The paper writes
    v_r·K_θ, derived for v_r > 0: linearised, the lateral/heading errors obey
    s² + v_r·K_θ·s + v_r²·K_y = 0, unstable when the reference reverses (a parking manoeuvre
    drifted 0.5 m off and ended 29° wrong). With |v_r| the damping keeps its sign both ways;
    forwards the two are the same law.

    Parameters
    ----------
    k_x : float
        K_x [1/s], > 0.
    k_y : float
        K_y [1/m²], > 0.
    k_theta : float
        K_θ [1/m], > 0.
    limits : VelocityLimits, optional
        Command limits.
    """

    k_x: float = 3.0
    k_y: float = 60.0
    k_theta: float = 12.0

    def __post_init__(self) -> None:
        for name, unit in (("k_x", "1/s"), ("k_y", "1/m²"), ("k_theta", "1/m")):
            value = finite(name, getattr(self, name), unit)
            if value <= 0:
                raise ConfigError(
                    f"Kanayama's law is stable for k_x, k_y, k_theta > 0; {name} must be > 0 "
                    f"{unit} (got {value:g})"
                )
            object.__setattr__(self, name, value)

    def _law(self, e_x, e_y, e_theta, v_r, omega_r):
        v = v_r * np.cos(e_theta) + self.k_x * e_x
        return v, omega_r + v_r * self.k_y * e_y + np.abs(v_r) * self.k_theta * np.sin(e_theta)
