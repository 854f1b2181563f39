"""Laws 2–6: driving a unicycle (or differential drive) to a reference *pose*.

Every controller here is called as ``controller(t, pose, goal) -> (v, ω)`` with poses of shape
``(..., 3)`` (a batch of robots is one call) and works in the goal frame: the goal at the
origin facing +x, the robot at (x, y) with heading θ. Document 002 lists the laws ("control to
reference pose", "… via an intermediate point", "… via an intermediate direction", "control by
a straight line and a circular arc"); the formulas are those of its references:

=====================  =============================================================  ==========
class                  law                                                            source
=====================  =============================================================  ==========
:class:`PolarPose`     v = k_ρ ρ, ω = k_α α + k_β β in polar coordinates              [SN] §3.6.2
:class:`Aicardi`       Lyapunov law on (e, α, θ)                                      [A95]
:class:`ViaPoint`      go-to-point to T = goal − r·(cos θ_g, sin θ_g), then goal      [K] §3.2.2
:class:`ViaDirection`  heading φ_T + α if |α| < |β| = atan(r/D), else φ_T + β·sgn α   [K] §3.2.2
:class:`LineArc`       a line tangent to a circle through the goal, then the arc      [K] §3.2.2
=====================  =============================================================  ==========

[SN] Siegwart, Nourbakhsh & Scaramuzza, *Introduction to Autonomous Mobile Robots*, 2011.
[A95] Aicardi, Casalino, Bicchi & Balestrino, "Closed loop steering of unicycle-like vehicles
via Lyapunov techniques", IEEE Robotics & Automation Magazine 2(1), 1995.
[K] Klančar, Zdešar, Blažič & Škrjanc, *Wheeled Mobile Robotics*, 2017.

Laws 4–6 end with an *alignment* phase: once the robot is within ``align_distance`` of the goal
it stops translating and turns in place, ω = k_align·wrap(θ_g − θ) — a differential drive can,
and it is what makes their final heading exact instead of asymptotic. Commands go through the
curvature-keeping :func:`~wheelbase.control.saturate_velocity`, a positive rescaling of time
that leaves every stability argument below intact.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass
from typing import Any

import numpy as np

from wheelbase._validate import check_choice, finite, positive
from wheelbase.control.base import GoalController
from wheelbase.control.point import GoToPoint, check_point_gains, go_to_point_law
from wheelbase.errors import ConfigError
from wheelbase.geometry import wrap_angle

__all__ = [
    "POSE_LAWS",
    "Aicardi",
    "LineArc",
    "PolarPose",
    "ViaDirection",
    "ViaPoint",
    "make_pose_law",
]


# --------------------------------------------------------------------------- law 2
@dataclass(frozen=True)
class PolarPose(GoalController):
    """Polar-coordinate pose law of Astolfi / Siegwart & Nourbakhsh (law 2).

    In the goal frame, ρ = √(x² + y²), α = wrap(atan2(−y, −x) − θ) (the bearing of the goal
    seen from the robot) and β = wrap(−θ − α) (minus the bearing of the robot seen from the
    goal); then v = k_ρ·ρ and ω = k_α·α + k_β·β ([SN] eqs. 3.70–3.72). The linearised closed
    loop is exponentially stable iff k_ρ > 0, k_β < 0 and k_α − k_ρ > 0 ([SN] eq. 3.73), and
    the robot never turns back through α = ±π/2 (strong stability) when
    k_α + (5/3)·k_β − (2/π)·k_ρ > 0 ([SN] eq. 3.74).

    With ``bidirectional`` (default) a robot that starts with the goal behind it
    (α ∉ (−π/2, π/2]) drives backwards for the whole episode: the law is applied to the
    robot turned by π (α = wrap(atan2(y, x) − θ), v = −k_ρ·ρ), as [SN] suggest.

    Parameters
    ----------
    k_rho : float
        k_ρ [1/s], > 0.
    k_alpha : float
        k_α [1/s], > k_ρ.
    k_beta : float
        k_β [1/s], < 0.
    bidirectional : bool
        Allow backward episodes.
    limits : VelocityLimits, optional
        Command limits.

    Raises
    ------
    ConfigError
        When the stability condition fails.

    Warns
    -----
    UserWarning
        When the (sufficient) strong-stability condition fails.
    """

    k_rho: float = 3.0
    k_alpha: float = 8.0
    k_beta: float = -1.5
    bidirectional: bool = True

    def __post_init__(self) -> None:
        k_rho = finite("k_rho", self.k_rho, "1/s")
        k_alpha = finite("k_alpha", self.k_alpha, "1/s")
        k_beta = finite("k_beta", self.k_beta, "1/s")
        if not (k_rho > 0 and k_beta < 0 and k_alpha - k_rho > 0):
            raise ConfigError(
                "PolarPose is stable only for k_rho > 0, k_beta < 0 and k_alpha - k_rho > 0 "
                f"(got k_rho={k_rho:g}, k_alpha={k_alpha:g}, k_beta={k_beta:g})"
            )
        strong = k_alpha + 5.0 / 3.0 * k_beta - 2.0 / math.pi * k_rho
        if strong <= 0:
            warnings.warn(
                "PolarPose: k_alpha + (5/3)k_beta - (2/π)k_rho = "
                f"{strong:g} <= 0; the robot may reverse its direction of travel",
                UserWarning,
                stacklevel=3,
            )
        for name, value in (("k_rho", k_rho), ("k_alpha", k_alpha), ("k_beta", k_beta)):
            object.__setattr__(self, name, value)

    def _start(self, x, y, theta):
        alpha = wrap_angle(np.arctan2(-y, -x) - theta)
        behind = (alpha <= -0.5 * np.pi) | (alpha > 0.5 * np.pi)
        self._state["sign"] = np.where(behind & self.bidirectional, -1.0, 1.0)

    def _law(self, t, x, y, theta):
        sign = self._state["sign"]
        rho = np.hypot(x, y)
        alpha = wrap_angle(np.arctan2(-sign * y, -sign * x) - theta)
        beta = wrap_angle(-theta - alpha)
        return sign * self.k_rho * rho, self.k_alpha * alpha + self.k_beta * beta


# --------------------------------------------------------------------------- law 3
@dataclass(frozen=True)
class Aicardi(GoalController):
    """Lyapunov pose law of Aicardi et al. 1995 (law 3).

    Goal frame: e = √(x² + y²), ψ = atan2(−y, −x) (direction from robot to goal; the paper's
    θ) and α = wrap(ψ − θ). For the unicycle ė = −u cos α, α̇ = −ω + u sin α/e,
    ψ̇ = u sin α/e. The law

        u = γ·cos α·e,   ω = k·α + γ·(cos α·sin α/α)·(α + h·ψ)

    makes V = ½(e² + α² + h·ψ²) decrease, V̇ = −γ cos²α·e² − k·α² ≤ 0, for any γ, k, h > 0,
    and the robot reaches the goal with the goal heading from every start but the goal itself
    ([A95]). It reverses (u < 0) while |α| > π/2.

    Parameters
    ----------
    gamma : float
        γ [1/s], > 0.
    k : float
        k [1/s], > 0.
    h : float
        h [-], > 0.
    limits : VelocityLimits, optional
        Command limits.
    """

    gamma: float = 1.0
    k: float = 3.0
    h: float = 1.0

    def __post_init__(self) -> None:
        for name, unit in (("gamma", "1/s"), ("k", "1/s"), ("h", "")):
            object.__setattr__(self, name, positive(name, getattr(self, name), unit))

    def _law(self, t, x, y, theta):
        e = np.hypot(x, y)
        psi = np.arctan2(-y, -x)
        alpha = wrap_angle(psi - theta)
        sinc = np.sinc(alpha / np.pi)  # sin α / α, 1 at α = 0
        v = self.gamma * np.cos(alpha) * e
        omega = self.k * alpha + self.gamma * np.cos(alpha) * sinc * (alpha + self.h * psi)
        return v, omega


# --------------------------------------------------------------------------- laws 4, 5
@dataclass(frozen=True)
class _Aligning(GoalController):
    """Shared final phase of laws 4–6: turn in place once within ``align_distance``."""

    align_distance: float = 0.005
    k_align: float = 2.0

    def _check_align(self) -> None:
        object.__setattr__(
            self, "align_distance", positive("align_distance", self.align_distance, "m")
        )
        object.__setattr__(self, "k_align", positive("k_align", self.k_align, "1/s"))

    def _aligned(self, x, y, theta, v, omega):
        """Latch the alignment phase and override the command where it is active."""
        near = self._state.get("align", np.zeros(x.shape, bool)) | (
            np.hypot(x, y) < self.align_distance
        )
        self._state["align"] = near
        return np.where(near, 0.0, v), np.where(near, self.k_align * wrap_angle(-theta), omega)


@dataclass(frozen=True)
class ViaPoint(_Aligning):
    """Pose control through an intermediate point (Klančar et al. §3.2.2; law 4).

    The robot first drives with the go-to-point law (law 1) to T, the point ``distance`` behind
    the goal along its heading (T = (−r, 0) in the goal frame); within ``switch_distance`` of T
    it drives to the goal itself, arriving roughly along the goal heading, and finally aligns.
    Convergence of each phase is law 1's (k_heading > (2/π)·k_speed, k_heading > k_speed).

    Parameters
    ----------
    distance : float
        r [m], > 0: how far behind the goal T lies.
    k_heading, k_speed : float
        K₁, K₂ of law 1 [1/s].
    switch_distance : float
        Distance to T [m] at which the robot heads for the goal, > 0.
    align_distance : float
        Distance to the goal [m] at which the robot turns in place, > 0.
    k_align : float
        Heading gain of the alignment phase [1/s], > 0.
    limits : VelocityLimits, optional
        Command limits.
    """

    distance: float = 0.4
    k_heading: float = 4.0
    k_speed: float = 1.0
    switch_distance: float = 0.05

    def __post_init__(self) -> None:
        object.__setattr__(self, "distance", positive("distance", self.distance, "m"))
        object.__setattr__(
            self, "switch_distance", positive("switch_distance", self.switch_distance, "m")
        )
        check_point_gains(self.k_heading, self.k_speed, name="ViaPoint")
        self._check_align()

    def _start(self, x, y, theta):
        self._state["to_goal"] = np.zeros(x.shape, bool)

    def _law(self, t, x, y, theta):
        to_goal = self._state["to_goal"] | (np.hypot(x + self.distance, y) < self.switch_distance)
        self._state["to_goal"] = to_goal
        target_x = np.where(to_goal, 0.0, -self.distance)
        v, omega = go_to_point_law(target_x - x, -y, theta, self.k_heading, self.k_speed)
        return self._aligned(x, y, theta, v, omega)


@dataclass(frozen=True)
class ViaDirection(_Aligning):
    """Pose control through an intermediate direction (Klančar et al. §3.2.2; law 5).

    φ_T is the bearing of the goal from the robot, α = wrap(φ_T − θ_g) and β = atan(r/D). The
    robot is steered to the heading φ_R = φ_T + α if |α| < |β|, else φ_T + β·sgn(α), with
    ω = K₁·wrap(φ_R − φ) and v = K₂·D·cos(φ_R − φ)⁺ (the cosine factor, an addition, lets the
    robot turn before it drives when the direction is behind it).

    Why it works: the bearing obeys φ̇_T = −v sin(φ − φ_T)/D. Steering along φ_T + α gives
    α̇ = −K₂ sin α: the bearing turns into the goal heading while Ḋ = −K₂ D cos α, so the
    robot arrives with heading φ = θ_g + 2α → θ_g. Far from the goal (|α| ≥ β) it keeps the
    goal at the fixed angle β off its nose, which also turns the bearing towards θ_g. The final
    alignment removes the residual 2α.

    Parameters
    ----------
    radius : float
        r [m], > 0: the lateral offset that sets β = atan(r/D).
    k_heading, k_speed : float
        K₁, K₂ [1/s] with K₁ > K₂ (law 1's conditions).
    align_distance, k_align : float
        Final alignment (see :class:`ViaPoint`).
    limits : VelocityLimits, optional
        Command limits.
    """

    radius: float = 0.3
    k_heading: float = 4.0
    k_speed: float = 1.0

    def __post_init__(self) -> None:
        object.__setattr__(self, "radius", positive("radius", self.radius, "m"))
        check_point_gains(self.k_heading, self.k_speed, name="ViaDirection")
        self._check_align()

    def _law(self, t, x, y, theta):
        distance = np.hypot(x, y)
        bearing = np.arctan2(-y, -x)  # φ_T in the goal frame, where θ_g = 0
        alpha = bearing
        beta = np.arctan2(self.radius, distance)
        heading_ref = np.where(
            np.abs(alpha) < beta, bearing + alpha, bearing + beta * np.sign(alpha)
        )
        error = wrap_angle(heading_ref - theta)
        v = self.k_speed * distance * np.maximum(np.cos(error), 0.0)
        return self._aligned(x, y, theta, v, self.k_heading * error)


# --------------------------------------------------------------------------- law 6
@dataclass(frozen=True)
class LineArc(_Aligning):
    """Pose control by a straight line and a circular arc (Klančar et al. §3.2.2; law 6).

    Construction (goal frame, first call of an episode): of the two circles of radius R through
    the goal and tangent to its heading — centre c = (0, σR), σ = +1 (left, driven
    counter-clockwise) or −1 (right, clockwise) — take those the start S lies outside of, and on
    each the tangent point T where the line S→T runs along the circle's direction of travel.
    The shorter of |S − T| + R·(arc angle from T to the goal) wins. (The circle on the side
    away from the start always contains it outside, so a plan exists whenever S ≠ goal.)

    Line phase: the segment law of reference path control (law 7): d = signed lateral offset
    (positive to the right of S→T), φ_ref = φ_line + atan(k_r·d),
    ω = k_heading·wrap(φ_ref − φ), v = v_ref·cos(φ_ref − φ)⁺.

    Switching rule: the line phase ends when the progress u = (P − S)·(T − S)/|T − S|² reaches
    1. The normal of the line at T is the radius through T (a tangent is perpendicular to its
    radius), so the switch happens exactly as the robot crosses the ray from c through T —
    where its polar angle about c equals the arc's start angle, so that the arc's progress
    starts at zero without a jump.

    Arc phase: feed-forward ω = v·σ/R plus the rear-wheel-feedback (Samson) correction on the
    lateral error e = σ(R − |P − c|) (positive to the left of the direction of travel) and the
    heading error θ_e = wrap(φ − φ_tangent):
    ω = v·κ·cos θ_e/(1 − κe) − k_theta·|v|·θ_e − k_e·v·sinc(θ_e)·e with κ = σ/R
    (1 − κe = |P − c|/R > 0 always). The speed is v = min(v_ref, k_speed·s) with s the arc
    length still to go, tracked by unwrapping the polar angle; the robot then aligns.

    Parameters
    ----------
    radius : float
        R [m], > 0.
    speed : float
        v_ref [m/s], > 0.
    k_r : float
        Lateral gain of the line law [1/m], > 0.
    k_heading : float
        Heading gain of the line law [1/s], > 0.
    k_e : float
        Lateral gain of the arc correction [1/m²], > 0.
    k_theta : float
        Heading gain of the arc correction [1/m], > 0.
    k_speed : float
        Deceleration gain on the remaining arc length [1/s], > 0.
    align_distance, k_align : float
        Final alignment (see :class:`ViaPoint`).
    limits : VelocityLimits, optional
        Command limits.
    """

    radius: float = 0.5
    speed: float = 0.5
    k_r: float = 5.0
    k_heading: float = 4.0
    k_e: float = 8.0
    k_theta: float = 4.0
    k_speed: float = 1.0

    def __post_init__(self) -> None:
        for name, unit in (
            ("radius", "m"),
            ("speed", "m/s"),
            ("k_r", "1/m"),
            ("k_heading", "1/s"),
            ("k_e", "1/m²"),
            ("k_theta", "1/m"),
            ("k_speed", "1/s"),
        ):
            object.__setattr__(self, name, positive(name, getattr(self, name), unit))
        self._check_align()

    def plan(self, x: np.ndarray, y: np.ndarray) -> dict[str, np.ndarray]:
        """The line and arc from start positions (x, y) in the goal frame [m].

        Parameters
        ----------
        x, y : numpy.ndarray
            Start positions in the goal frame (goal at the origin facing +x) [m].

        Returns a dict of arrays of the batch shape: ``sigma`` (±1, circle side), ``tangent``
        (..., 2) the point T, ``start`` (..., 2), ``arc_angle`` the arc's angle [rad] in [0, 2π)
        and ``length`` the total length [m].
        """
        x, y = np.asarray(x, float), np.asarray(y, float)
        best = None
        for sigma in (1.0, -1.0):
            cx, cy = 0.0, sigma * self.radius
            wx, wy = x - cx, y - cy
            dist = np.hypot(wx, wy)
            outside = dist > self.radius * (1 + 1e-9)
            half = np.arccos(np.clip(self.radius / np.maximum(dist, 1e-300), -1.0, 1.0))
            base = np.arctan2(wy, wx)
            # of the two tangent points, the one whose tangent (the direction of travel σ)
            # points away from S; for σ = +1 it is base + half, for σ = −1 base − half
            angle = base + sigma * half
            tx, ty = cx + self.radius * np.cos(angle), cy + self.radius * np.sin(angle)
            goal_angle = -sigma * 0.5 * np.pi
            arc = np.mod(sigma * (goal_angle - angle), 2.0 * np.pi)
            arc = np.where(arc > 2.0 * np.pi - 1e-9, 0.0, arc)  # rounding of a zero arc
            length = np.hypot(tx - x, ty - y) + self.radius * arc
            length = np.where(outside, length, np.inf)
            candidate = {
                "sigma": np.full(x.shape, sigma),
                "tangent": np.stack([tx, ty], -1),
                "arc_angle": arc,
                "length": length,
            }
            if best is None:
                best = candidate
            else:
                pick = candidate["length"] < best["length"]
                best = {
                    key: np.where(
                        pick.reshape(pick.shape + (1,) * (value.ndim - pick.ndim)), value, best[key]
                    )
                    for key, value in candidate.items()
                }
        best["start"] = np.stack([x, y], -1)
        return best

    def _start(self, x, y, theta):
        plan = self.plan(x, y)
        self._state.update(plan)
        self._state["on_arc"] = np.zeros(x.shape, bool)
        self._state["remaining"] = plan["arc_angle"].copy()
        self._state["last_angle"] = np.full(x.shape, np.nan)

    def _law(self, t, x, y, theta):
        st = self._state
        sigma = st["sigma"]
        start, tangent = st["start"], st["tangent"]
        # ---- line phase: segment law
        seg = tangent - start
        seg_len2 = np.maximum(np.sum(seg * seg, -1), 1e-300)
        rel_x, rel_y = x - start[..., 0], y - start[..., 1]
        progress = (rel_x * seg[..., 0] + rel_y * seg[..., 1]) / seg_len2
        line_heading = np.arctan2(seg[..., 1], seg[..., 0])
        offset_right = (rel_x * seg[..., 1] - rel_y * seg[..., 0]) / np.sqrt(seg_len2)
        heading_ref = line_heading + np.arctan(self.k_r * offset_right)
        error = wrap_angle(heading_ref - theta)
        v_line = self.speed * np.maximum(np.cos(error), 0.0)
        omega_line = self.k_heading * error
        on_arc = st["on_arc"] | (progress >= 1.0)
        # ---- arc phase
        cy = sigma * self.radius
        wx, wy = x, y - cy
        dist = np.hypot(wx, wy)
        angle = np.arctan2(wy, wx)
        last = st["last_angle"]
        started = ~np.isnan(last)
        step = np.where(started, wrap_angle(angle - np.where(started, last, 0.0)), 0.0)
        remaining = np.where(on_arc & started, st["remaining"] - sigma * step, st["remaining"])
        st["remaining"] = remaining
        st["last_angle"] = np.where(on_arc, angle, np.nan)
        st["on_arc"] = on_arc
        kappa = sigma / self.radius
        lateral = sigma * (self.radius - dist)
        theta_e = wrap_angle(theta - (angle + sigma * 0.5 * np.pi))
        v_arc = np.minimum(self.speed, self.k_speed * self.radius * remaining)
        omega_arc = (
            v_arc * kappa * np.cos(theta_e) / (1.0 - kappa * lateral)
            - self.k_theta * np.abs(v_arc) * theta_e
            - self.k_e * v_arc * np.sinc(theta_e / np.pi) * lateral
        )
        v = np.where(on_arc, v_arc, v_line)
        omega = np.where(on_arc, omega_arc, omega_line)
        return self._aligned(x, y, theta, v, omega)


POSE_LAWS: tuple[str, ...] = ("point", "polar", "aicardi", "via_point", "via_direction", "line_arc")
"""Names of the pose laws (document 002 control list, laws 1–6), in order."""


def make_pose_law(name: str, limits: Any = None) -> GoalController:
    """A pose law of :data:`POSE_LAWS` with its default gains and the given limits.

    Parameters
    ----------
    name : str
        One of :data:`POSE_LAWS`.
    limits : VelocityLimits, optional
        Command limits.
    """
    check_choice("law", name, POSE_LAWS)
    classes = {
        "point": GoToPoint,
        "polar": PolarPose,
        "aicardi": Aicardi,
        "via_point": ViaPoint,
        "via_direction": ViaDirection,
        "line_arc": LineArc,
    }
    return classes[name](limits=limits)
