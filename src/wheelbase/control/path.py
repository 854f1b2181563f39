"""Law 7: following a reference path given as a polyline, forwards and in reverse.

The path is a :class:`~wheelbase.planning.PlannedPath` (a planner's, or
``PlannedPath.from_points(points, directions)``) or an array of points: the followers read it
as points in the order of travel with a direction (+1 forward, −1 reverse) per segment; maximal
runs of one direction are *sections*, joined at cusps (as in the paths of Hybrid A*, document
002). Four followers share one machinery:

==========================  ==================================================================
:class:`SegmentFollower`    reference path control of document 002 / Klančar et al. §3.2.3:
                            segment progress u, normalised lateral offset d, φ_ref =
                            φ_line + atan(K_r·d), ω = K_φ·wrap(φ_ref − φ)
:class:`PurePursuit`        Coulter 1992: κ = 2 sin α / ℓ to a look-ahead point ℓ = k_v·v + ℓ_min
                            ahead along the path
:class:`Stanley`            Hoffmann et al. 2007: δ = θ_e + atan(k·e/(k_s + v)) at the front axle
:class:`RearWheelFeedback`  Samson 1993 / Paden et al. 2016 §V.B: ω = vκcos θ_e/(1 − κe)
                            − K_θ|v|θ_e − K_e·v·(sin θ_e/θ_e)·e
==========================  ==================================================================

How it works. Each follower keeps, per robot, the index of its active segment; the segment
advances when the progress u = (P − A)·(B − A)/|B − A|² of the reference point P reaches 1
(document 002's switching rule), so a path that crosses itself or doubles back is followed in
order. Inside a section the law sees the path in the *travel frame*: on a reverse section the
robot's travel heading is φ' = θ + π and its travel speed v' = −v > 0. The law computes a
forward command (v', ω') or (v', δ') there, and the command sent is (−v', ω') for a unicycle —
the heading rate is the same — or (−v', −δ') for a steered vehicle: θ̇ = v·tan δ/L must equal
v'·tan δ'/L. Reversing negates the speed *and* the steering, not the speed alone.

The speed is ``speed`` [m/s], scaled down linearly over the last ``slow_distance`` metres of
each section (to at least 10 %), so the robot creeps into cusps and the path end; it switches
to the next section when it passes a cusp and stops (command 0) at the end of the path.
Commands go through :func:`~wheelbase.control.saturate_velocity` (``output="velocity"``) or
:func:`~wheelbase.control.saturate_steering` with the steering-rate limit
(``output="steering"``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike

from wheelbase._validate import as_float_array, check_choice, nonnegative, positive
from wheelbase.control.base import (
    STEERING_COMMAND,
    VELOCITY_COMMAND,
    SteeringLimits,
    VelocityLimits,
    saturate_steering,
    saturate_velocity,
)
from wheelbase.errors import ConfigError, InputError
from wheelbase.geometry import wrap_angle
from wheelbase.limits import MAX_COORDINATE

__all__ = [
    "PathFollower",
    "PurePursuit",
    "RearWheelFeedback",
    "SegmentFollower",
    "Stanley",
]

OUTPUTS: tuple[str, ...] = ("velocity", "steering")


# --------------------------------------------------------------------------- polyline
@dataclass(frozen=True)
class _Polyline:
    """The followers' view of a path (private): points in the order of travel and a direction
    per segment. Users give a :class:`~wheelbase.planning.PlannedPath` (e.g.
    ``PlannedPath.from_points``) or an array of points.

    Parameters
    ----------
    points : array_like, shape (M, 2)
        Path points [m]; repeated consecutive points are dropped. At least two distinct points.
    directions : array_like, shape (M − 1,), optional
        +1 (drive forwards) or −1 (reverse) for each segment, in the order of ``points``
        (before duplicates are dropped); default all +1.

    Raises
    ------
    InputError
        Fewer than two distinct points, a bad shape, non-finite values, or directions that are
        not ±1.

    Examples
    --------
    >>> path = _Polyline([[0, 0], [1, 0], [1, 1]])
    >>> path.length, path.sections.tolist()
    (2.0, [[0, 2]])
    """

    points: np.ndarray
    directions: np.ndarray = field(default=None)  # type: ignore[assignment]

    def __post_init__(self) -> None:
        points = as_float_array("path points", self.points, 2, min_ndim=2, max_ndim=2)
        if self.directions is None:
            directions = np.ones(max(points.shape[0] - 1, 0))
        else:
            directions = as_float_array("directions", self.directions, min_ndim=1, max_ndim=1)
            if directions.shape[0] != points.shape[0] - 1:
                raise InputError(
                    f"directions must have one entry per segment, {points.shape[0] - 1} "
                    f"(got {directions.shape[0]})"
                )
            if not np.all(np.isin(directions, (-1.0, 1.0))):
                raise InputError("directions must be +1 (forward) or -1 (reverse)")
        keep = np.ones(points.shape[0], bool)
        if points.shape[0] > 1:
            keep[1:] = np.hypot(*np.diff(points, axis=0).T) > 1e-12
        points = points[keep]
        directions = directions[keep[1:]] if directions.size else directions
        if points.shape[0] < 2:
            raise InputError(
                f"a path needs at least two distinct points (got {points.shape[0]} distinct)"
            )
        points.setflags(write=False)
        directions = np.ascontiguousarray(directions)
        directions.setflags(write=False)
        object.__setattr__(self, "points", points)
        object.__setattr__(self, "directions", directions)

    @classmethod
    def from_poses(cls, poses: ArrayLike, directions: ArrayLike | None = None) -> _Polyline:
        """A polyline through the positions of poses ``(M, 3)`` (the headings are not used)."""
        poses = as_float_array("poses", poses, 3, min_ndim=2, max_ndim=2)
        return cls(poses[:, :2], directions)

    @property
    def n_segments(self) -> int:
        """Number of segments."""
        return self.points.shape[0] - 1

    @property
    def segments(self) -> np.ndarray:
        """Segment vectors B − A, shape (S, 2) [m]."""
        return np.diff(self.points, axis=0)

    @property
    def segment_lengths(self) -> np.ndarray:
        """Segment lengths, shape (S,) [m]."""
        return np.hypot(*self.segments.T)

    @property
    def length(self) -> float:
        """Total length [m]."""
        return float(np.sum(self.segment_lengths))

    @property
    def arc_length(self) -> np.ndarray:
        """Arc length at each point, shape (M,) [m], from 0."""
        return np.concatenate([[0.0], np.cumsum(self.segment_lengths)])

    @property
    def sections(self) -> np.ndarray:
        """``[first, last + 1]`` segment indices of each run of one direction, shape (K, 2)."""
        change = np.flatnonzero(np.diff(self.directions) != 0) + 1
        starts = np.concatenate([[0], change])
        ends = np.concatenate([change, [self.n_segments]])
        return np.stack([starts, ends], -1)

    @property
    def curvature(self) -> np.ndarray:
        """Signed curvature at each point [1/m], shape (M,), of the path in its travel direction.

        At an interior point of a section, the turn of the travel heading divided by the mean
        of the two segment lengths; at a section's ends, that of its neighbouring point (0 for
        a one-segment section).
        """
        seg = self.segments
        heading = np.arctan2(seg[:, 1], seg[:, 0])
        lengths = self.segment_lengths
        kappa = np.zeros(self.points.shape[0])
        for first, end in self.sections:
            if end - first < 2:
                continue
            turn = wrap_angle(np.diff(heading[first:end]))
            mean = 0.5 * (lengths[first : end - 1] + lengths[first + 1 : end])
            inner = turn / mean
            kappa[first + 1 : end] = inner
            kappa[first] = inner[0]
            kappa[end] = inner[-1]
        return kappa

    def resample(self, step: float) -> _Polyline:
        """The same path with points every ``step`` metres or less along each section."""
        step = positive("step", step, "m")
        points, directions = [self.points[:1]], []
        for (a, b), direction in zip(
            zip(self.points[:-1], self.points[1:], strict=True), self.directions, strict=True
        ):
            count = max(1, math.ceil(float(np.hypot(*(b - a))) / step - 1e-9))
            fractions = np.arange(1, count + 1)[:, None] / count
            points.append(a + fractions * (b - a))
            directions.extend([direction] * count)
        return _Polyline(np.concatenate(points), np.asarray(directions))

    def distance(self, xy: ArrayLike) -> np.ndarray:
        """Distance [m] from points ``(..., 2)`` to the nearest point of the path.

        Parameters
        ----------
        xy : array_like, shape (..., 2)
            Points [m].
        """
        from wheelbase.polyline import distance_to_polyline

        return distance_to_polyline(xy, self.points)


def _as_polyline(reference: object) -> _Polyline:
    if isinstance(reference, _Polyline):
        return reference
    poses = getattr(reference, "poses", None)
    if poses is not None:  # a planned path (wheelbase.planning.PlannedPath) or a PoseTrajectory
        directions = getattr(reference, "directions", None)
        if directions is not None:
            directions = np.asarray(directions, dtype=np.float64).ravel()
            if directions.size == np.shape(poses)[0]:
                # one direction per sample, "of the motion that reaches it": segment k → k + 1
                # is driven in the direction of sample k + 1
                directions = directions[1:]
        return _Polyline.from_poses(poses, directions)
    return _Polyline(as_float_array("path", reference, 2, min_ndim=2, max_ndim=2))


def _final_heading(reference: object) -> float | None:
    """The heading [rad] of the last pose of a reference that has poses (a planned path), else
    ``None``: a polyline of positions cannot say which way the goal faces."""
    poses = getattr(reference, "poses", None)
    return None if poses is None else float(np.asarray(poses, dtype=np.float64)[-1, 2])


def path_key(line: _Polyline, reference: object) -> tuple[np.ndarray, np.ndarray, float | None]:
    """What identifies a followed path: its points, directions and final heading."""
    return (np.asarray(line.points), np.asarray(line.directions), _final_heading(reference))


def same_path(a: tuple, b: tuple) -> bool:
    """Whether two :func:`path_key` values describe the same path (exactly)."""
    return (
        a[2] == b[2]
        and a[0].shape == b[0].shape
        and np.array_equal(a[0], b[0])
        and np.array_equal(a[1], b[1])
    )


# --------------------------------------------------------------------------- follower base
@dataclass(frozen=True)
class PathFollower:
    """Shared machinery of the path followers (see the module docstring).

    Parameters
    ----------
    speed : float
        Travel speed v_ref [m/s], > 0.
    output : {"velocity", "steering"}
        Command (v, ω) for a unicycle / differential drive or (v, δ) for a steered vehicle.
    wheel_base : float
        L [m], > 0: converts curvature to steering (``output="steering"``) and places
        Stanley's front axle.
    slow_distance : float
        Length [m] before a cusp or the path end over which the speed ramps down, > 0.
    align_gain : float
        k_ψ [1/s], >= 0: at the end of a path that knows its final heading (a planned path's
        last pose), a velocity-output follower turns in place with ω = k_ψ·wrap(ψ_goal − ψ)
        (saturated) — a polyline of positions cannot say that the goal faces the other way.
        0 stops without turning; a steered vehicle always just stops.
    limits : VelocityLimits or SteeringLimits, optional
        Command limits, matching ``output`` (keyword only).
    """

    speed: float = 0.3
    output: str = "velocity"
    wheel_base: float = 0.5
    slow_distance: float = 0.3
    align_gain: float = 2.0
    limits: VelocityLimits | SteeringLimits | None = field(default=None, kw_only=True)
    _state: dict = field(default_factory=dict, init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        check_choice("output", self.output, OUTPUTS)
        for name, unit in (("speed", "m/s"), ("wheel_base", "m"), ("slow_distance", "m")):
            object.__setattr__(self, name, positive(name, getattr(self, name), unit))
        object.__setattr__(self, "align_gain", nonnegative("align_gain", self.align_gain, "1/s"))
        expected = VelocityLimits if self.output == "velocity" else SteeringLimits
        if self.limits is not None and not isinstance(self.limits, expected):
            raise ConfigError(
                f"output={self.output!r} needs limits of type {expected.__name__} "
                f"(got {type(self.limits).__name__})"
            )
        self._check_gains()

    def _check_gains(self) -> None:
        """Hook: validate the law's own gains."""

    @property
    def command_names(self) -> tuple[str, ...]:
        """``("v", "omega")`` or ``("speed", "steering")`` according to ``output``."""
        return VELOCITY_COMMAND if self.output == "velocity" else STEERING_COMMAND

    def reset(self) -> None:
        """Forget the active segments and the last command."""
        self._state.clear()

    def __call__(self, t: float, pose: ArrayLike, reference: object) -> np.ndarray:
        """Command ``(..., 2)`` to follow the path ``reference``.

        Parameters
        ----------
        t : float
            Time [s] (used by the steering-rate limit).
        pose : array_like, shape (..., 3)
            Measured poses (x [m], y [m], θ [rad]) of the reference point (the rear axle of a
            steered vehicle).
        reference : PlannedPath or array_like, shape (M, 2)
            The path: a :class:`~wheelbase.planning.PlannedPath`, points, or anything with
            ``poses`` (M, 3) and optional ``directions`` per segment (M − 1) or per sample (M,
            the direction of the motion reaching each sample, as a ``PlannedPath`` has).
        """
        pose = as_float_array("pose", pose, 3)
        path = self._state.get("path")
        if path is None or reference is not self._state.get("reference"):
            # Known by content: a fresh array of the same path keeps the progress.
            line = _as_polyline(reference)
            key = path_key(line, reference)
            if path is not None and same_path(self._state["key"], key):
                self._state["reference"] = reference
            else:
                self._state.clear()
                self._state.update(
                    path=line,
                    reference=reference,
                    key=key,
                    tables=_tables(line),
                    final_heading=key[2],
                )
        shape = pose.shape[:-1]
        flat = pose.reshape(-1, 3)
        if self._state.get("shape") != shape:
            self._state["shape"] = shape
            self._state["segment"] = np.zeros(flat.shape[0], np.int64)
            self._state["done"] = np.zeros(flat.shape[0], bool)
            self._state["last"] = None
        command = self._command(float(t), flat)
        return command.reshape((*shape, 2))

    # ------------------------------------------------------------------ internals
    def _command(self, t: float, pose: np.ndarray) -> np.ndarray:
        tab = self._state["tables"]
        seg = self._state["segment"]
        done = self._state["done"]
        direction0 = tab["direction"][seg]
        travel_heading = pose[:, 2] + np.where(direction0 < 0, np.pi, 0.0)
        point = pose[:, :2]
        # advance along the path: next segment while u >= 1 (into the next section at a cusp)
        for _ in range(tab["direction"].size):
            u = _progress(point, seg, tab)
            move = (u >= 1.0) & ~done
            if not move.any():
                break
            last = seg == tab["n"] - 1
            done = done | (move & last)
            seg = np.where(move & ~last, seg + 1, seg)
        self._state["segment"], self._state["done"] = seg, done
        direction = tab["direction"][seg]
        travel_heading = pose[:, 2] + np.where(direction < 0, np.pi, 0.0)
        u = _progress(point, seg, tab)
        section_end = tab["arc"][tab["section_end"][seg]]
        s_here = tab["arc"][seg] + np.clip(u, 0.0, 1.0) * tab["length"][seg]
        remaining = section_end - s_here
        speed = self.speed * np.clip(remaining / self.slow_distance, 0.1, 1.0)
        speed = np.where(done, 0.0, speed)
        omega, delta = self._law(point, travel_heading, speed, seg, u, tab)
        if self.output == "velocity":
            if omega is None:
                omega = speed * np.tan(delta) / self.wheel_base
            final = self._state.get("final_heading")
            turn = np.zeros_like(speed)
            if final is not None:  # at the end, turn in place to the goal heading
                turn = self.align_gain * wrap_angle(final - pose[:, 2])
            command = np.stack([direction * speed, np.where(done, turn, omega)], -1)
            return saturate_velocity(command, self.limits)  # type: ignore[arg-type]
        if delta is None:
            with np.errstate(divide="ignore", invalid="ignore"):
                delta = np.arctan2(self.wheel_base * omega, speed)
        command = np.stack([direction * speed, np.where(done, 0.0, direction * delta)], -1)
        previous, t_last = self._state.get("last") or (None, None)
        dt = None if t_last is None or t <= t_last else t - t_last
        command = saturate_steering(
            command,
            self.limits,  # type: ignore[arg-type]
            previous if dt is not None else None,
            dt,
        )
        self._state["last"] = (command[:, 1].copy(), t)
        return command

    def _law(
        self,
        point: np.ndarray,
        heading: np.ndarray,
        speed: np.ndarray,
        seg: np.ndarray,
        u: np.ndarray,
        tab: dict,
    ) -> tuple[np.ndarray | None, np.ndarray | None]:  # pragma: no cover - abstract
        """Return (ω', None) or (None, δ') in the travel frame."""
        raise NotImplementedError


def _tables(path: _Polyline) -> dict:
    seg = path.segments
    lengths = path.segment_lengths
    section_end = np.empty(path.n_segments, np.int64)  # index of the section's end point
    for first, end in path.sections:
        section_end[first:end] = end
    return {
        "n": path.n_segments,
        "a": path.points[:-1],
        "b": path.points[1:],
        "seg": seg,
        "length": lengths,
        "heading": np.arctan2(seg[:, 1], seg[:, 0]),
        "direction": path.directions,
        "arc": path.arc_length,
        "section_end": section_end,
        "curvature": path.curvature,
        "points": path.points,
    }


def _progress(point: np.ndarray, seg: np.ndarray, tab: dict) -> np.ndarray:
    rel = point - tab["a"][seg]
    vec = tab["seg"][seg]
    return np.sum(rel * vec, -1) / tab["length"][seg] ** 2


def _offset_right(point: np.ndarray, seg: np.ndarray, tab: dict) -> np.ndarray:
    """Signed distance [m] of ``point`` from the line of segment ``seg``, positive to the right."""
    rel = point - tab["a"][seg]
    vec = tab["seg"][seg]
    return (rel[:, 0] * vec[:, 1] - rel[:, 1] * vec[:, 0]) / tab["length"][seg]


# --------------------------------------------------------------------------- the laws
@dataclass(frozen=True)
class SegmentFollower(PathFollower):
    """Reference path control on polyline segments (document 002; Klančar et al. §3.2.3).

    On the active segment A→B: progress u (switching to the next segment at u ≥ 1), the
    lateral offset normalised by the segment length d = ((P − A) × (B − A))/|B − A|² (positive
    to the right), φ_ref = φ_line + atan(K_r·d) and ω = K_φ·wrap(φ_ref − φ) at speed v_ref.

    The offset is normalised by ``length_scale`` ℓ [m]; ``length_scale=None`` normalises by
    each segment's length as Klančar et al. do, which makes the gain depend on how the path was
    sampled (long segments converge slowly, short ones aggressively). Near the line
    ḋ ≈ −(v/ℓ)·atan(K_r d): the offset decays at the rate v·K_r/ℓ, which the heading loop must
    outpace, K_φ > v·K_r/ℓ (checked for the fixed ℓ; a ConfigError otherwise).

    Parameters
    ----------
    k_r : float
        K_r [-], > 0.
    k_heading : float
        K_φ [1/s], > 0.
    length_scale : float or None
        ℓ [m] for the normalisation (None: each segment's length).
    """

    k_r: float = 1.0
    k_heading: float = 4.0
    length_scale: float | None = 0.25

    def _check_gains(self) -> None:
        object.__setattr__(self, "k_r", positive("k_r", self.k_r, ""))
        object.__setattr__(self, "k_heading", positive("k_heading", self.k_heading, "1/s"))
        if self.length_scale is not None:
            scale = positive("length_scale", self.length_scale, "m")
            object.__setattr__(self, "length_scale", scale)
            rate = self.speed * self.k_r / scale
            if self.k_heading <= rate:
                raise ConfigError(
                    f"SegmentFollower: k_heading must be > speed·k_r/length_scale = {rate:g} 1/s "
                    f"so that the heading settles before the offset (got {self.k_heading:g})"
                )

    def _law(self, point, heading, speed, seg, u, tab):
        scale = tab["length"][seg] if self.length_scale is None else self.length_scale
        d = _offset_right(point, seg, tab) / scale
        heading_ref = tab["heading"][seg] + np.arctan(self.k_r * d)
        return self.k_heading * wrap_angle(heading_ref - heading), None


@dataclass(frozen=True)
class PurePursuit(PathFollower):
    """Pure pursuit (Coulter 1992) with a speed-scaled look-ahead.

    The goal point lies ℓ = k_v·v + ℓ_min further along the active section than the
    projection of the robot (beyond the section's end: on the extension of its last segment,
    so the robot drives straight into a cusp). With α its bearing from the robot's travel
    heading and ℓ' its distance, the arc through it has curvature κ = 2 sin α/ℓ'.

    Parameters
    ----------
    lookahead_gain : float
        k_v [s], >= 0.
    min_lookahead : float
        ℓ_min [m], > 0.
    """

    lookahead_gain: float = 0.2
    min_lookahead: float = 0.1

    def _check_gains(self) -> None:
        gain = nonnegative("lookahead_gain", self.lookahead_gain, "s")
        object.__setattr__(self, "lookahead_gain", gain)
        object.__setattr__(
            self, "min_lookahead", positive("min_lookahead", self.min_lookahead, "m")
        )

    def _law(self, point, heading, speed, seg, u, tab):
        with np.errstate(over="ignore"):  # a wild speed: the lookahead runs to the path's end
            lookahead = np.minimum(self.lookahead_gain * np.abs(speed), MAX_COORDINATE)
        lookahead = np.copysign(lookahead, speed) + self.min_lookahead
        s_here = tab["arc"][seg] + np.clip(u, 0.0, 1.0) * tab["length"][seg]
        end = tab["section_end"][seg]
        s_end = tab["arc"][end]
        s_goal = np.minimum(s_here + lookahead, s_end)
        index = np.clip(np.searchsorted(tab["arc"], s_goal, side="right") - 1, 0, tab["n"] - 1)
        index = np.minimum(index, end - 1)
        frac = (s_goal - tab["arc"][index]) / tab["length"][index]
        goal = tab["a"][index] + frac[:, None] * tab["seg"][index]
        beyond = s_here + lookahead - s_end
        last_dir = tab["seg"][end - 1] / tab["length"][end - 1][:, None]
        goal = goal + np.maximum(beyond, 0.0)[:, None] * last_dir
        rel = goal - point
        distance = np.maximum(np.hypot(rel[:, 0], rel[:, 1]), 1e-9)
        alpha = wrap_angle(np.arctan2(rel[:, 1], rel[:, 0]) - heading)
        curvature = 2.0 * np.sin(alpha) / distance
        return speed * curvature, None


@dataclass(frozen=True)
class Stanley(PathFollower):
    """Stanley steering (Hoffmann, Tomlin, Montemerlo & Thrun 2007), measured at the front axle.

    δ = θ_e + atan(k·e/(k_s + v)) with θ_e = wrap(φ_path − φ) and e the offset of the front
    axle (``wheel_base`` ahead of the reference point) to the right of the path; k_s softens
    the law at low speed. A unicycle gets ω = v·tan(δ)/L of the virtual front axle.
    For the kinematic bicycle e decays as ė = −v sin(atan(k e/v)) — exponentially, at rate k,
    for small errors (Hoffmann et al. 2007).

    Parameters
    ----------
    k : float
        Cross-track gain [1/s], > 0.
    k_soft : float
        Softening speed k_s [m/s], > 0.
    max_steering : float
        |δ| limit [rad] of the law, in (0, π/2): the mechanism's stop for a steered vehicle,
        and for a unicycle the virtual one that keeps ω = v·tan(δ)/L finite.
    """

    k: float = 2.0
    k_soft: float = 0.1
    max_steering: float = 1.0

    def _check_gains(self) -> None:
        object.__setattr__(self, "k", positive("k", self.k, "1/s"))
        object.__setattr__(self, "k_soft", positive("k_soft", self.k_soft, "m/s"))
        limit = positive("max_steering", self.max_steering, "rad")
        if limit >= 0.5 * math.pi:
            raise ConfigError(f"max_steering must be < π/2 rad (got {limit:g})")
        object.__setattr__(self, "max_steering", limit)

    def _law(self, point, heading, speed, seg, u, tab):
        # the front axle's own segment: from the robot's, forward within the section (past the
        # section's end it projects on the extension of the last segment)
        front = point + self.wheel_base * np.stack([np.cos(heading), np.sin(heading)], -1)
        last = tab["section_end"][seg] - 1
        for _ in range(tab["n"]):
            move = (_progress(front, seg, tab) >= 1.0) & (seg < last)
            if not move.any():
                break
            seg = np.where(move, seg + 1, seg)
        theta_e = wrap_angle(tab["heading"][seg] - heading)
        e = _offset_right(front, seg, tab)
        delta = theta_e + np.arctan(self.k * e / (self.k_soft + speed))
        return None, np.clip(delta, -self.max_steering, self.max_steering)


@dataclass(frozen=True)
class RearWheelFeedback(PathFollower):
    """Rear-wheel feedback path following (Samson 1993; Paden et al. 2016 §V.B).

    With e the offset of the reference point to the left of the path, θ_e = wrap(φ − φ_path)
    and κ the path curvature at the projection,

        ω = v·κ·cos θ_e/(1 − κe) − K_θ·|v|·θ_e − K_e·v·(sin θ_e/θ_e)·e.

    V = e² + θ_e²/K_e decreases, V̇ = −2K_θ|v|θ_e²/K_e, for K_e, K_θ > 0 while 1 − κe > 0 (the
    robot stays on the inner side of the path's centre of curvature). The law clamps 1 − κe to
    at least 0.1 where that fails, so the command stays finite.

    Parameters
    ----------
    k_e : float
        K_e [1/m²], > 0.
    k_theta : float
        K_θ [1/m], > 0.
    """

    k_e: float = 20.0
    k_theta: float = 6.0

    def _check_gains(self) -> None:
        object.__setattr__(self, "k_e", positive("k_e", self.k_e, "1/m²"))
        object.__setattr__(self, "k_theta", positive("k_theta", self.k_theta, "1/m"))

    def _law(self, point, heading, speed, seg, u, tab):
        frac = np.clip(u, 0.0, 1.0)
        kappa = (1.0 - frac) * tab["curvature"][seg] + frac * tab["curvature"][seg + 1]
        e = -_offset_right(point, seg, tab)
        theta_e = wrap_angle(heading - tab["heading"][seg])
        margin = np.maximum(1.0 - kappa * e, 0.1)
        omega = (
            speed * kappa * np.cos(theta_e) / margin
            - self.k_theta * np.abs(speed) * theta_e
            - self.k_e * speed * np.sinc(theta_e / np.pi) * e
        )
        return omega, None
