"""The ground under a wheeled robot: surfaces, friction curves, soils, terrain maps, and the
robot's dynamics on them (wheel slip, traction limits, load transfer, slopes, soil).

- :mod:`wheelbase.terrain.friction`: the magic-formula friction curve through a peak and a
  sliding value;
- :mod:`wheelbase.terrain.soil`: Bekker sinkage, compaction resistance, Janosi–Hanamoto thrust,
  Wong's soils (Table 2.3), and Wong–Reece's stress integrals;
- :mod:`wheelbase.terrain.surfaces`: the named surfaces and their sources;
- :mod:`wheelbase.terrain.map`: which surface and slope lie where (regions, rasters);
- :mod:`wheelbase.terrain.contact`: drive wheels, casters and their normal loads;
- :mod:`wheelbase.terrain.dynamics`: the robot on the terrain, rigid contact or slip.
"""

from typing import TYPE_CHECKING

from wheelbase._lazy import attach

if TYPE_CHECKING:  # the names, for type checkers and IDEs; imported on first use
    from wheelbase.terrain.contact import RM100_CONTACTS, WheelContacts, normal_loads
    from wheelbase.terrain.dynamics import TerrainDynamics
    from wheelbase.terrain.friction import FrictionCurve
    from wheelbase.terrain.map import Region, TerrainMap, grade_slope
    from wheelbase.terrain.soil import SOILS, Soil, drawbar_pull, wong_reece
    from wheelbase.terrain.surfaces import SURFACES, Surface

_EXPORTS = {
    "RM100_CONTACTS": "wheelbase.terrain.contact",
    "WheelContacts": "wheelbase.terrain.contact",
    "normal_loads": "wheelbase.terrain.contact",
    "TerrainDynamics": "wheelbase.terrain.dynamics",
    "FrictionCurve": "wheelbase.terrain.friction",
    "Region": "wheelbase.terrain.map",
    "TerrainMap": "wheelbase.terrain.map",
    "grade_slope": "wheelbase.terrain.map",
    "SOILS": "wheelbase.terrain.soil",
    "Soil": "wheelbase.terrain.soil",
    "drawbar_pull": "wheelbase.terrain.soil",
    "wong_reece": "wheelbase.terrain.soil",
    "SURFACES": "wheelbase.terrain.surfaces",
    "Surface": "wheelbase.terrain.surfaces",
}
__getattr__, __dir__ = attach(__name__, _EXPORTS)

__all__ = [
    "RM100_CONTACTS",
    "SOILS",
    "SURFACES",
    "FrictionCurve",
    "Region",
    "Soil",
    "Surface",
    "TerrainDynamics",
    "TerrainMap",
    "WheelContacts",
    "drawbar_pull",
    "grade_slope",
    "normal_loads",
    "wong_reece",
]
