"""A scenario's ground and loads: the schema of the ``terrain``, payload and coping-control keys.

- ``terrain``: the surface everywhere (``surface``), polygon ``regions`` of other surfaces and
  grades (a plane per region), a ``raster`` of surfaces (an image, a grey level per surface),
  wheel ``slip`` on or off, the ``stuck`` rule's time;
- ``robot.payload``: what the robot carries from the start; a goal may change it
  (``goals: [{pose: [x, y, deg], payload: {...}}, ...]``; ``payload: null`` drops it);
- ``robot.contacts``: drive-wheel width and spin inertia, casters, load sharing, CG height;
- ``controller.model_payload``: the payload the controller's model believes in (``true``: the
  robot's, as it changes; ``false``: none; or a payload of its own), so that a payload the
  controller does not know is a different payload in each;
- ``controller.law: adaptive_computed_torque``: computed torque that estimates mass, inertia
  and CG moment online (its options are gains, as every law's);
- ``controller.traction_control``: torque limited by the estimated friction.

Surfaces are named (:data:`wheelbase.terrain.SURFACES`) or given by coefficients
(``{like: dry_concrete, peak_friction: 0.6}``, or ``{soil: {n: ..., k_c: ..., ...}}``). Grades
are percent (rise over run, at most 100), directions degrees, as everywhere in scenario files.
"""

from __future__ import annotations

import math
from typing import Any, Literal

from pydantic import BaseModel, ConfigDict, Field, field_validator, model_validator

from wheelbase.limits import MAX_COORDINATE

__all__ = [
    "ContactsSpec",
    "PayloadSpec",
    "RasterSpec",
    "RegionSpec",
    "SlopeFeedForwardSpec",
    "SoilSpec",
    "SurfaceSpec",
    "TerrainSpec",
    "TractionSpec",
]

SURFACE_NAMES = (
    "dry_concrete",
    "wet_concrete",
    "ice",
    "grass",
    "dry_sand",
    "sandy_loam",
    "clay",
)


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True, validate_default=True)


def _finite_point(value: Any) -> Any:
    for number in value:
        if not math.isfinite(number) or abs(number) > MAX_COORDINATE:
            raise ValueError(f"must be finite and within ±{MAX_COORDINATE:g} m (got {value})")
    return value


class PayloadSpec(_Strict):
    """A load on the robot (:class:`wheelbase.inertial.Payload`)."""

    mass: float = Field(..., ge=0, le=1e5, description="Mass [kg] (0: nothing).")
    position: tuple[float, float] = Field(
        (0.0, 0.0), description="Its CG (x [m], y [m]) in the body frame at the axle centre."
    )
    inertia: float = Field(
        0.0, ge=0, le=1e5, description="Yaw inertia about its own CG [kg·m²] (0: a point)."
    )
    height: float | None = Field(
        None, ge=0, le=100, description="Height of its CG above the ground [m] (default: the "
        "robot's CG height)."
    )  # fmt: skip

    @field_validator("position")
    @classmethod
    def _finite(cls, value):
        return _finite_point(value)


class ContactsSpec(_Strict):
    """Where the robot touches the ground (:class:`wheelbase.terrain.WheelContacts`); unset
    fields take the RM100's (wheelbase.terrain.RM100_CONTACTS)."""

    wheel_width: float | None = Field(None, gt=0, le=10, description="Drive-wheel width [m].")
    wheel_inertia: float | None = Field(
        None, gt=0, le=1e3, description="Spin inertia of each drive wheel with its motor [kg·m²]."
    )
    casters: tuple[tuple[float, float], ...] | None = Field(
        None, min_length=1, description="Caster positions (x [m], y [m]) in the body frame."
    )
    caster_radius: float | None = Field(None, gt=0, le=10, description="[m]")
    caster_width: float | None = Field(None, gt=0, le=10, description="[m]")
    drive_load_share: float | None = Field(
        None, gt=0, lt=1, description="Share of the weight on the drive wheels at rest."
    )
    cg_height: float | None = Field(None, ge=0, le=100, description="CG height [m].")

    @field_validator("casters")
    @classmethod
    def _finite(cls, value):
        if value is not None:
            for point in value:
                _finite_point(point)
        return value


class SoilSpec(_Strict):
    """Bekker and Mohr–Coulomb parameters in the units of Wong's tables."""

    n: float = Field(..., gt=0, lt=2, description="Sinkage exponent.")
    k_c: float = Field(..., ge=0, le=1e6, description="Cohesive modulus [kN/m^(n+1)].")
    k_phi: float = Field(..., gt=0, le=1e7, description="Frictional modulus [kN/m^(n+2)].")
    cohesion: float = Field(..., ge=0, le=1e3, description="Cohesion c [kPa].")
    friction_angle_deg: float = Field(
        ..., ge=0, lt=60, description="Angle of internal shearing resistance φ [deg]."
    )
    shear_modulus: float = Field(..., gt=0, le=0.5, description="Shear deformation modulus K [m].")


class SurfaceSpec(_Strict):
    """A surface given by coefficients: a named one changed, or a new one."""

    like: Literal[SURFACE_NAMES] | None = Field(  # type: ignore[valid-type]
        None, description="The named surface whose coefficients the others replace."
    )
    peak_friction: float | None = Field(None, gt=0, le=3, description="μ_p.")
    sliding_friction: float | None = Field(None, gt=0, le=3, description="μ_s at full slip.")
    peak_slip: float | None = Field(None, gt=0, lt=1, description="Slip of the peak.")
    rolling_resistance: float | None = Field(None, ge=0, lt=1, description="c_rr.")
    soil: SoilSpec | None = Field(None, description="Soft ground (instead of friction).")

    @model_validator(mode="after")
    def _complete(self):
        curve = (self.peak_friction, self.sliding_friction, self.peak_slip)
        if self.soil is not None and (any(v is not None for v in curve) or self.rolling_resistance):
            raise ValueError("a soil has no friction curve or rolling resistance: give one or "
                             "the other")  # fmt: skip
        if self.like is None and self.soil is None and any(v is None for v in curve):
            raise ValueError(
                "a new hard surface needs peak_friction, sliding_friction and peak_slip (or "
                "like: a named surface)"
            )
        return self


class RegionSpec(_Strict):
    """A polygon of the floor with its surface and grade (a plane)."""

    polygon: tuple[tuple[float, float], ...] = Field(
        ..., min_length=3, description="Vertices (x [m], y [m]) in the map frame."
    )
    surface: Literal[SURFACE_NAMES] | SurfaceSpec = Field(  # type: ignore[valid-type]
        ..., description="A named surface or coefficients."
    )
    grade_percent: float = Field(
        0.0, ge=0, le=100, description="Grade, rise over run [%] (10: a 10 % ramp)."
    )
    uphill_deg: float = Field(0.0, description="Direction of steepest ascent [deg], map frame.")

    @field_validator("polygon")
    @classmethod
    def _finite(cls, value):
        for point in value:
            _finite_point(point)
        return value

    @field_validator("uphill_deg")
    @classmethod
    def _finite_angle(cls, value):
        if not math.isfinite(value):
            raise ValueError(f"must be finite (got {value})")
        return value


class RasterSpec(_Strict):
    """Surfaces painted in an image: each grey level a surface (aligned with the map)."""

    image: str = Field(..., description="An image file (PNG, PGM, ...); a path in a scenario "
                       "file is relative to that file.")  # fmt: skip
    legend: dict[int, Literal[SURFACE_NAMES] | SurfaceSpec] = Field(  # type: ignore[valid-type]
        ..., min_length=1, description="Grey level (0..255) → surface; every level in the "
        "image needs one."
    )  # fmt: skip
    resolution: float | None = Field(
        None, gt=0, description="Pixel size [m] (default: the map's cell size)."
    )
    origin: tuple[float, float] | None = Field(
        None, description="(x, y) of the image's lower-left corner [m] (default: the map's)."
    )

    @field_validator("legend")
    @classmethod
    def _levels(cls, value):
        bad = [level for level in value if not 0 <= level <= 255]
        if bad:
            raise ValueError(f"grey levels must be in [0, 255] (got {bad[0]})")
        return value

    @field_validator("origin")
    @classmethod
    def _finite(cls, value):
        return value if value is None else _finite_point(value)


class TerrainSpec(_Strict):
    """The ground (wheelbase.terrain): a surface everywhere, regions of others, slip."""

    surface: Literal[SURFACE_NAMES] | SurfaceSpec = Field(  # type: ignore[valid-type]
        "dry_concrete", description="The ground outside every region."
    )
    regions: tuple[RegionSpec, ...] = Field(
        (), description="Polygons of other surfaces or grades; where two overlap they must "
        "agree; they lie over the raster."
    )  # fmt: skip
    raster: RasterSpec | None = Field(
        None, description="Surfaces painted in an image aligned with the map (flat)."
    )
    slip: bool = Field(
        True, description="Wheel slip (the wheels' own dynamics, friction or soil shear); "
        "false: the wheels roll without slipping."
    )  # fmt: skip
    resolution: float | None = Field(
        None, gt=0, description="Cell size of the terrain raster [m] (default: the map's)."
    )
    slip_speed: float = Field(
        0.05, ge=1e-4, le=10, description="v_ε [m/s]: the slip ratio's denominator at standstill."
    )
    stuck_time: float = Field(
        5.0, gt=0, description="Seconds commanded to move without moving before 'stuck'."
    )


class SlopeFeedForwardSpec(_Strict):
    """The ground's forces on the controller's model fed forward
    (:class:`wheelbase.control.slope.SlopeFeedForward`): ``controller.slope_feedforward: true`` is
    this with its defaults (the slope alone); the mapping adds the rolling resistance."""

    rolling_resistance: bool = Field(
        False, description="Also feed forward the rolling resistance the terrain gives under "
        "each wheel and caster (c_rr·N on hard ground, Bekker's compaction resistance on soil), "
        "in each contact's direction of rolling; at rest only the breakaway to move the way the "
        "reference asks (its twist while it moves, the controller's feedback once it has "
        "stopped)."
    )  # fmt: skip


class TractionSpec(_Strict):
    """Wheel torques limited by the friction (:class:`wheelbase.control.TractionControl`)."""

    friction: Literal["map", "estimate"] | float = Field(
        "map", description="The friction coefficient to respect: 'map', the peak friction of "
        "the terrain under each wheel (the robot knows its floor); 'estimate', the robot's own "
        "online estimate from its encoders, its torques and its model, and with sensors.imu "
        "its IMU (it never reads the terrain); or a number."
    )  # fmt: skip
    margin: float = Field(
        0.8, gt=0, le=1, description="Share of the friction limit the torques may use."
    )
    initial_friction: float = Field(
        1.0, gt=0, le=3, description="With friction 'estimate': the peak friction believed "
        "before any wheel has spun."
    )  # fmt: skip
    slow_down: bool = Field(
        False, description="Drive the reference slower where the friction is low: the same "
        "path on a clock slowed along the whole reference, so that the wheel forces of its "
        "turns and accelerations stay within reference_share x margin of each wheel's friction "
        "circle (braking in time for a turn or a cusp ahead)."
    )  # fmt: skip
    reference_share: float = Field(
        0.8, gt=0, le=1, description="With slow_down: share of margin x the friction circle "
        "the slowed reference's own wheel forces may use; the rest is left to the feedback."
    )  # fmt: skip
    rolling_resistance: float = Field(
        0.0, ge=0, lt=1, description="With a friction coefficient or 'estimate': the rolling "
        "resistance c_rr, whose moment on each drive wheel the torques may add to the grip "
        "(with 'map' the map's is used). With 'estimate' the robot's own figure (its tyres on "
        "its floor): the estimate takes the moment out of the torque and learns the grip "
        "alone; 0: the estimate holds the rolling moment too."
    )  # fmt: skip

    hold_integrators: bool = Field(
        False, description="Lower the wrapped law's torque saturation to the friction limit, "
        "so that its anti-windup holds its integrators while traction clips the torques."
    )  # fmt: skip

    @field_validator("friction")
    @classmethod
    def _positive(cls, value):
        if value not in ("map", "estimate") and not (math.isfinite(value) and 0 < value <= 3):
            raise ValueError(f"must be 'map', 'estimate' or a coefficient in (0, 3] (got {value})")
        return value
