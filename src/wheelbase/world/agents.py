"""Moving agents: the groups a scenario spawns and the parameters of their behaviours.

An :class:`AgentGroup` is ``count`` discs of one ``radius`` that move at a preferred ``speed``
by one behaviour:

``straight``
    Constant velocity in a random direction; specular reflection (speed conserved) off walls,
    static obstacles and the edges of ``region``.
``wander``
    Straight at ``speed`` to a random goal in ``region``; a new goal on arrival. Walls and
    obstacles stop the motion along their normal (the agent slides along them).
``waypoints``
    Straight at ``speed`` through ``waypoints`` in a loop (each agent starts at a random one).
``social_force``
    The social force model (D. Helbing and P. Molnár, "Social force model for pedestrian
    dynamics", Phys. Rev. E 51, 4282, 1995) with the forces and parameters of D. Helbing,
    I. Farkas and T. Vicsek, "Simulating dynamical features of escape panic", Nature 407, 487,
    2000 (:class:`SocialForce`), towards goals drawn as ``wander`` does (or the
    ``waypoints`` when given).
``orca``
    Optimal reciprocal collision avoidance (J. van den Berg, S. J. Guy, M. Lin and
    D. Manocha, "Reciprocal n-body collision avoidance", ISRR 2011; :class:`ORCA`), towards
    goals as ``social_force``.

Agents never enter walls or static obstacles, whatever their behaviour. Non-reactive agents
(``reacts_to_robot: false``) ignore the robots and may walk into a stopped one; reactive ones
treat each robot as one more agent (a disc of its circumscribed radius moving at its
velocity) for social force and ORCA, and as an obstacle they reflect or slide off for the
other behaviours.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from wheelbase._validate import as_float_array, check_choice, flag, integer, positive
from wheelbase.errors import ConfigError, WheelbaseError
from wheelbase.limits import MAX_COORDINATE

__all__ = [
    "BEHAVIOURS",
    "MAX_AGENTS",
    "MAX_AGENT_RADIUS",
    "MAX_AGENT_SPEED",
    "MIN_AGENT_RADIUS",
    "ORCA",
    "AgentGroup",
    "SocialForce",
]

BEHAVIOURS: tuple[str, ...] = ("straight", "wander", "waypoints", "social_force", "orca")
"""Names of the agent behaviours (module docstring); their codes in the kernels are the
indices."""

MAX_AGENT_SPEED = 10.0
"""Fastest preferred speed [m/s] accepted: a sprinter's (a typo such as 50 is refused)."""

MAX_AGENT_RADIUS = 10.0
"""Largest agent radius [m]."""

MIN_AGENT_RADIUS = 0.01
"""Smallest agent radius [m] (an agent moves at most half its radius per substep: a 1e-9 m
agent would take 1e9 substeps a step)."""

MAX_AGENTS = 10_000
"""Most agents of one world (a social-force or ORCA step looks at every pair)."""


@dataclass(frozen=True)
class AgentGroup:
    """``count`` agents of one size, speed and behaviour (module docstring).

    Parameters
    ----------
    count : int
        Number of agents, in [0, :data:`MAX_AGENTS`].
    radius : float
        Disc radius [m], in [:data:`MIN_AGENT_RADIUS`, :data:`MAX_AGENT_RADIUS`].
    speed : float
        Preferred speed [m/s], in (0, :data:`MAX_AGENT_SPEED`].
    behaviour : str
        One of :data:`BEHAVIOURS`.
    region : tuple of float or None
        ``(x0, y0, x1, y1)`` [m]: where the agents start and draw their goals (their discs
        lie inside it); ``straight`` agents reflect off its edges. Default: the whole map.
    reacts_to_robot : bool
        Whether the agents see the robots (module docstring).
    waypoints : array_like or None
        ``(W, 2)`` [m]: the loop of ``waypoints`` agents (required there); optional for
        ``social_force`` and ``orca`` (then they follow it instead of random goals).

    Raises
    ------
    ConfigError
        A field out of range; the message starts with the field's name.

    Examples
    --------
    >>> AgentGroup(count=20, radius=0.3, speed=0.5, behaviour="wander").behaviour_code
    1
    """

    count: int = 1
    radius: float = 0.3
    speed: float = 0.5
    behaviour: str = "straight"
    region: tuple[float, float, float, float] | None = None
    reacts_to_robot: bool = False
    waypoints: np.ndarray | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "count", integer("count", self.count, 0, MAX_AGENTS))
        radius = positive("radius", self.radius, "m")
        if not MIN_AGENT_RADIUS <= radius <= MAX_AGENT_RADIUS:
            raise ConfigError(
                f"radius must be in [{MIN_AGENT_RADIUS:g}, {MAX_AGENT_RADIUS:g}] m (got "
                f"{radius:g}): an agent is a person or a robot, not a grain or a building"
            )
        object.__setattr__(self, "radius", radius)
        speed = positive("speed", self.speed, "m/s")
        if speed > MAX_AGENT_SPEED:
            raise ConfigError(
                f"speed must be <= {MAX_AGENT_SPEED:g} m/s (got {speed:g}): faster than a "
                "sprinter is absurd for a walker"
            )
        object.__setattr__(self, "speed", speed)
        if not isinstance(self.behaviour, str):
            raise ConfigError(
                f"behaviour must be one of {', '.join(BEHAVIOURS)} (got {self.behaviour!r})"
            )
        try:
            check_choice("behaviour", self.behaviour, BEHAVIOURS)
        except ConfigError:
            raise ConfigError(
                f"behaviour {self.behaviour!r} is unknown; allowed: {', '.join(BEHAVIOURS)}"
            ) from None
        object.__setattr__(self, "reacts_to_robot", flag("reacts_to_robot", self.reacts_to_robot))
        if self.region is not None:
            region = _numbers("region", self.region, "(x0, y0, x1, y1)")
            if region.shape != (4,):
                raise ConfigError(
                    f"region must be 4 numbers (x0, y0, x1, y1) [m] (got {region.tolist()})"
                )
            x0, y0, x1, y1 = region.tolist()
            if x1 - x0 < 2 * radius or y1 - y0 < 2 * radius:
                raise ConfigError(
                    f"region {[x0, y0, x1, y1]} must have x0 < x1 and y0 < y1, at least one "
                    f"agent diameter ({2 * radius:g} m) apart"
                )
            object.__setattr__(self, "region", (x0, y0, x1, y1))
        if self.waypoints is not None:
            points = _numbers("waypoints", self.waypoints, "[[x, y], ...]")
            if points.ndim != 2 or points.shape[1] != 2 or len(points) == 0:
                raise ConfigError(
                    f"waypoints must be a list of [x, y] points [m] (got shape {points.shape})"
                )
            points = np.ascontiguousarray(points)
            points.setflags(write=False)
            object.__setattr__(self, "waypoints", points)
        elif self.behaviour == "waypoints":
            raise ConfigError("waypoints are required for behaviour 'waypoints' (a list of "
                              "[x, y] points [m] the agents cycle through)")  # fmt: skip
        if self.waypoints is not None and self.behaviour in ("straight", "wander"):
            raise ConfigError(f"waypoints are not used by behaviour {self.behaviour!r}; use "
                              "'waypoints', 'social_force' or 'orca'")  # fmt: skip

    @property
    def behaviour_code(self) -> int:
        """Index of the behaviour in :data:`BEHAVIOURS`."""
        return BEHAVIOURS.index(self.behaviour)


def _numbers(name: str, value: object, shape: str) -> np.ndarray:
    try:
        array = as_float_array(name, value)
    except WheelbaseError:
        raise ConfigError(f"{name} must be finite numbers {shape} [m] (got {value!r})") from None
    if array.size and np.max(np.abs(array)) > MAX_COORDINATE:
        raise ConfigError(f"{name} must lie within ±{MAX_COORDINATE:g} m")
    return array


_SF_RANGES = {
    "mass": ("kg", 1.0, 1e3),
    "relaxation_time": ("s", 0.01, 100.0),
    "strength": ("N", 1e-6, 1e6),
    "range": ("m", 1e-3, 10.0),
    "body": ("kg/s²", 0.0, 1e8),
    "friction": ("kg/(m s)", 0.0, 1e8),
    "max_speed_factor": ("", 1.0, 10.0),
    "cutoff": ("m", 1e-3, 100.0),
    "max_substep": ("s", 1e-4, 0.1),
}
"""Accepted range of each SocialForce parameter (unit, low, high): physically plausible values,
so that no force overflows (the exponent is clipped at 50 as well)."""


@dataclass(frozen=True)
class SocialForce:
    """Parameters of the social force model (Helbing and Molnár 1995, Helbing, Farkas and
    Vicsek 2000).

    Agent α of mass m, radius r_α, position r_α, velocity v_α, goal direction e_α and
    preferred speed v⁰_α (its group's ``speed``) accelerates as (HFV 2000, eq. 1–3)::

        m dv_α/dt = m (v⁰_α e_α − v_α)/τ
                    + Σ_β [A exp((r_αβ − d_αβ)/B) + k g(r_αβ − d_αβ)] n_αβ
                          + κ g(r_αβ − d_αβ) Δv^t_βα t_αβ
                    + Σ_W [A exp((r_α − d_αW)/B) + k g(r_α − d_αW)] n_αW
                          − κ g(r_α − d_αW) (v_α · t_αW) t_αW

    with r_αβ = r_α + r_β, d_αβ the centres' distance, n_αβ the unit vector from β to α,
    t_αβ ⟂ n_αβ, Δv^t_βα = (v_β − v_α)·t_αβ, g(x) = max(x, 0) (the body force k and the
    sliding friction κ act only in contact), and W the nearest wall point (from the map's
    distance field) and each static obstacle. The speed is capped at ``max_speed_factor ×
    v⁰_α`` (v_max = 1.3 v⁰ in Helbing and Molnár 1995, eq. 6). Integration: semi-implicit
    Euler, velocities first, in substeps of at most ``max_substep`` (the contact stiffness
    k/m = 1500 s⁻² makes steps above 2/√1500 = 0.05 s unstable; the default 0.02 s keeps a
    factor 2.5). The forces are isotropic (HFV 2000): two walkers on exactly one line, head
    on, push straight back and stop face to face; any lateral offset (5 cm suffices) lets them
    pass.

    Parameters
    ----------
    mass : float
        m [kg] (HFV 2000: 80 kg).
    relaxation_time : float
        τ [s] (HFV 2000: 0.5 s).
    strength : float
        A [N] (HFV 2000: 2×10³ N).
    range : float
        B [m] (HFV 2000: 0.08 m).
    body : float
        k [kg/s²] (HFV 2000: 1.2×10⁵ kg s⁻²).
    friction : float
        κ [kg/(m s)] (HFV 2000: 2.4×10⁵ kg m⁻¹ s⁻¹).
    max_speed_factor : float
        v_max / v⁰ (Helbing and Molnár 1995: 1.3).
    cutoff : float
        Gap [m] d − r beyond which a neighbour or wall is ignored (A e^(−cutoff/B) = 7 mN at
        the default 1 m).
    max_substep : float
        Longest integration substep [s].
    """

    mass: float = 80.0
    relaxation_time: float = 0.5
    strength: float = 2.0e3
    range: float = 0.08
    body: float = 1.2e5
    friction: float = 2.4e5
    max_speed_factor: float = 1.3
    cutoff: float = 1.0
    max_substep: float = 0.02

    def __post_init__(self) -> None:
        for name, (unit, low, high) in _SF_RANGES.items():
            value = positive(name, getattr(self, name), unit)
            if not low <= value <= high:
                raise ConfigError(f"{name} must be in [{low:g}, {high:g}]"
                                  f"{' ' + unit if unit else ''} (got {value:g})")  # fmt: skip
            object.__setattr__(self, name, value)

    def packed(self) -> np.ndarray:
        """The parameters as the kernels read them: (1/τ, A/m, B, k/m, κ/m, factor, cutoff,
        max_substep)."""
        m = self.mass
        return np.array([1.0 / self.relaxation_time, self.strength / m, self.range,
                         self.body / m, self.friction / m, self.max_speed_factor, self.cutoff,
                         self.max_substep])  # fmt: skip


@dataclass(frozen=True)
class ORCA:
    """Parameters of optimal reciprocal collision avoidance (van den Berg et al. 2011).

    Each step, an ORCA agent A takes the velocity closest to its preferred one (``speed``
    towards its goal) inside the disc of radius ``max_speed_factor × speed`` and inside every
    half-plane ORCA^τ_A|B of its ``max_neighbours`` nearest neighbours within
    ``neighbour_distance``: with u the smallest change of the relative velocity that takes it
    out of the velocity obstacle VO^τ_A|B (the disc of radius r_A + r_B around
    (p_B − p_A)/τ, extended by the cone it subtends from the origin) and n the outward normal
    there, ORCA^τ_A|B = {v : (v − (v_A + c u))·n >= 0} (paper, eq. 5) with responsibility
    c = ½ for another ORCA agent and c = 1 for anything that does not reciprocate (other
    behaviours, robots). The 2-D linear program is solved exactly (incremental, section V-B);
    when it is infeasible, the velocity that least penetrates the agents' half-planes is
    taken (the paper's 3-D program, section V-C) while the walls' half-planes stay hard.

    Walls and static obstacles enter as one half-plane each, at the nearest point w at
    distance d: ``v · n_w >= −(d − r)/τ_obs`` (n_w from w to the agent), which keeps the agent
    at least r from the supporting line of that obstacle for ``obstacle_time_horizon`` (for a
    convex obstacle, from the obstacle itself; a simplification of the paper's obstacle
    velocity obstacles, which need polygon edges, not grid cells).

    Parameters
    ----------
    time_horizon : float
        τ [s] for other agents.
    obstacle_time_horizon : float
        τ_obs [s] for walls and obstacles.
    neighbour_distance : float
        Largest centre distance [m] of a neighbour considered.
    max_neighbours : int
        Most neighbours considered (the nearest).
    max_speed_factor : float
        Largest speed / preferred speed.
    perturbation : float
        Largest random change [m/s] of the preferred velocity each step (counter-based), which
        breaks the deadlocks of perfectly symmetric crowds (RVO2's examples perturb by 1e-4);
        0 for none.
    margin : float
        Distance [m] added to both radii in the agents' half-planes. When the program is
        infeasible (section V-C) the least-penetration velocity lets the planned discs overlap
        by millimetres (measured: up to 1.2 cm among 30 agents wandering in a 16 m square);
        the margin keeps that overlap outside the bodies.
    """

    time_horizon: float = 5.0
    obstacle_time_horizon: float = 2.0
    neighbour_distance: float = 10.0
    max_neighbours: int = 10
    max_speed_factor: float = 1.0
    perturbation: float = 0.01
    margin: float = 0.02

    def __post_init__(self) -> None:
        from wheelbase._validate import nonnegative

        object.__setattr__(self, "perturbation",
                           nonnegative("perturbation", self.perturbation, "m/s"))  # fmt: skip
        object.__setattr__(self, "margin", nonnegative("margin", self.margin, "m"))
        for name, high in (("time_horizon", 100.0), ("obstacle_time_horizon", 100.0),
                           ("neighbour_distance", 1000.0)):  # fmt: skip
            unit = "m" if name == "neighbour_distance" else "s"
            value = positive(name, getattr(self, name), unit)
            if not 0.01 <= value <= high:
                raise ConfigError(f"{name} must be in [0.01, {high:g}] {unit} (got {value:g})")
            object.__setattr__(self, name, value)
        for name, unit in (("perturbation", "m/s"), ("margin", "m")):
            if getattr(self, name) > 1.0:
                raise ConfigError(f"{name} must be <= 1 {unit} (got {getattr(self, name):g})")
        object.__setattr__(
            self, "max_neighbours", integer("max_neighbours", self.max_neighbours, 1, 1000)
        )
        factor = positive("max_speed_factor", self.max_speed_factor)
        if not 1.0 <= factor <= 10.0:
            raise ConfigError(f"max_speed_factor must be in [1, 10] (got {factor:g})")
        object.__setattr__(self, "max_speed_factor", factor)

    def packed(self) -> np.ndarray:
        """The parameters as the kernels read them: (τ, τ_obs, neighbour distance, max
        neighbours, factor, perturbation, margin)."""
        return np.array([self.time_horizon, self.obstacle_time_horizon,
                         self.neighbour_distance, float(self.max_neighbours),
                         self.max_speed_factor, self.perturbation, self.margin])  # fmt: skip
